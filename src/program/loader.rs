//! Finds and loads subroutine files on the search path; each file is read and
//! indexed once however often it is called.

use crate::diag::{OWordError, SetupError};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::Arc;

use crate::diag::{Diagnostic, ErrorKind, WarningKind};

use super::{FileIndex, SourceFile};

/// Where subroutine files are looked for, in order.
#[derive(Debug, Clone, Default)]
pub struct SearchPath {
    /// PROGRAM_PREFIX, then SUBROUTINE_PATH entries, in search order.
    pub dirs: Vec<PathBuf>,
    /// WIZARD_ROOT folders, searched recursively.
    pub recursive: Vec<PathBuf>,
    /// Search the folder of the program being flattened last.
    pub program_dir: bool,
}

pub struct Loader {
    pub path: SearchPath,
    main_dir: Option<PathBuf>,
    by_path: HashMap<PathBuf, Rc<FileIndex>>,
    by_name: HashMap<String, Option<Rc<FileIndex>>>,
    /// Subroutine files held in memory (`name` without `.ngc` → text),
    /// found before any folder is searched.
    memory: HashMap<String, Vec<u8>>,
    pub warnings: Vec<Diagnostic>,
    /// Files are read in the 2007 named-parameter syntax too.
    named2007: bool,
}

/// Whether a subroutine name is safe to turn into a file name.
pub fn check_name(name: &str) -> Result<(), ErrorKind> {
    // LinuxCNC's rule for names of subroutine files: letters, digits, '-'
    // and '_'. No separator or dot, so a name cannot walk out of a search
    // folder (`o<root/etc/x> call` through a link named root); a link the
    // user put inside a search folder may point anywhere.
    let bad = name.is_empty()
        || !name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b"_-".contains(&b));
    if bad {
        Err(ErrorKind::OWord(OWordError::UnsafeSubName {
            name: name.to_string(),
        }))
    } else {
        Ok(())
    }
}

impl Loader {
    pub fn new(path: SearchPath, main_dir: Option<PathBuf>) -> Loader {
        Loader {
            path,
            main_dir,
            by_path: HashMap::new(),
            by_name: HashMap::new(),
            memory: HashMap::new(),
            warnings: Vec::new(),
            named2007: false,
        }
    }

    /// Subroutine files are read in the 2007 named-parameter syntax too.
    pub fn named2007(mut self, on: bool) -> Loader {
        self.named2007 = on;
        self
    }

    /// Subroutine files held in memory (`name` → text), found by
    /// `o<name> call` before the search path; no file is read for them.
    pub fn with_files(mut self, files: HashMap<String, Vec<u8>>) -> Loader {
        self.memory = files;
        self
    }

    /// Folders searched, in order.
    pub fn searched(&self) -> Vec<PathBuf> {
        let mut v: Vec<PathBuf> = self.path.dirs.clone();
        v.extend(self.path.recursive.iter().cloned());
        if self.path.program_dir
            && let Some(d) = &self.main_dir
        {
            v.push(d.clone());
        }
        v
    }

    fn candidates(&self, file_name: &str) -> Vec<PathBuf> {
        let mut found = Vec::new();
        for d in &self.path.dirs {
            let p = d.join(file_name);
            if p.is_file() {
                found.push(p);
            }
        }
        for root in &self.path.recursive {
            let base = Path::new(file_name).file_name().map(|s| s.to_owned());
            for entry in walkdir::WalkDir::new(root)
                .follow_links(true)
                .into_iter()
                .filter_map(Result::ok)
            {
                if entry.file_type().is_file() && Some(entry.file_name().to_owned()) == base {
                    found.push(entry.path().to_path_buf());
                    break;
                }
            }
        }
        if self.path.program_dir
            && let Some(d) = &self.main_dir
        {
            let p = d.join(file_name);
            if p.is_file() {
                found.push(p);
            }
        }
        found
    }

    /// Finds `name.ngc` and loads it (once). `Ok(None)` when there is no file.
    pub fn find(&mut self, name: &str) -> Result<Option<Rc<FileIndex>>, ErrorKind> {
        if let Some(hit) = self.by_name.get(name) {
            return Ok(hit.clone());
        }
        check_name(name)?;
        let file_name = format!("{name}.ngc");
        if let Some(data) = self.memory.remove(name) {
            let file = Arc::new(SourceFile::new(PathBuf::from(&file_name), file_name, data));
            let index = Some(Rc::new(FileIndex::build(file, self.named2007)));
            self.by_name.insert(name.to_string(), index.clone());
            return Ok(index);
        }
        let found = self.candidates(&file_name);
        let result = match found.first() {
            None => None,
            Some(p) => {
                if let Some(other) = found.iter().skip(1).find(|o| !same_file(o, p)) {
                    self.warnings.push(Diagnostic::warning(
                        WarningKind::ShadowedSubFile {
                            name: name.to_string(),
                            used: p.parent().unwrap_or(Path::new("")).to_path_buf(),
                            shadowed: other.parent().unwrap_or(Path::new("")).to_path_buf(),
                        },
                        None,
                    ));
                }
                Some(self.load(p)?)
            }
        };
        self.by_name.insert(name.to_string(), result.clone());
        Ok(result)
    }

    fn load(&mut self, p: &Path) -> Result<Rc<FileIndex>, ErrorKind> {
        let canon = p.canonicalize().unwrap_or_else(|_| p.to_path_buf());
        if let Some(f) = self.by_path.get(&canon) {
            return Ok(f.clone());
        }
        let data = std::fs::read(p).map_err(|e| {
            ErrorKind::Setup(SetupError::Io {
                path: p.to_path_buf(),
                message: e.to_string(),
            })
        })?;
        let file = Arc::new(SourceFile::new(
            p.to_path_buf(),
            p.display().to_string(),
            data,
        ));
        let index = Rc::new(FileIndex::build(file, self.named2007));
        self.by_path.insert(canon, index.clone());
        Ok(index)
    }
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    }
}
