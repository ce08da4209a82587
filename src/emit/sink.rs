//! Where flattened lines go before they are released: memory while small, a
//! temporary file once large. Nothing reaches the destination until the whole
//! program has been flattened without error.

use std::fs::File;
use std::io::{self, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};

/// Bytes kept in memory before spilling to a temporary file.
const SPILL_AT: usize = 4 << 20;

static COUNTER: AtomicU32 = AtomicU32::new(0);

/// A temporary file removed on drop unless persisted.
struct TempFile {
    path: PathBuf,
    file: BufWriter<File>,
    keep: bool,
}

impl TempFile {
    fn create_in(dir: &Path) -> io::Result<TempFile> {
        for _ in 0..100 {
            let n = COUNTER.fetch_add(1, Ordering::Relaxed);
            let path = dir.join(format!(".ngcflat-{}-{n}.tmp", std::process::id()));
            match File::options()
                .read(true)
                .write(true)
                .create_new(true)
                .open(&path)
            {
                Ok(f) => {
                    return Ok(TempFile {
                        path,
                        file: BufWriter::with_capacity(1 << 16, f),
                        keep: false,
                    });
                }
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(e),
            }
        }
        Err(io::Error::other("cannot create a temporary file"))
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        if !self.keep {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

/// Where the finished output goes.
#[derive(Debug, Clone)]
pub enum Destination {
    Stdout,
    File(PathBuf),
    /// Thrown away (check mode).
    Discard,
}

pub struct Sink {
    mem: Vec<u8>,
    spill: Option<TempFile>,
    dest: Destination,
}

impl Sink {
    pub fn new(dest: Destination) -> io::Result<Sink> {
        let spill = match &dest {
            Destination::File(p) => {
                let dir = match p.parent() {
                    Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
                    _ => PathBuf::from("."),
                };
                Some(TempFile::create_in(&dir)?)
            }
            _ => None,
        };
        Ok(Sink {
            mem: Vec::with_capacity(1 << 16),
            spill,
            dest,
        })
    }

    /// Appends bytes (whole lines).
    #[inline]
    pub fn write(&mut self, bytes: &[u8]) -> io::Result<()> {
        if matches!(self.dest, Destination::Discard) {
            return Ok(());
        }
        self.mem.extend_from_slice(bytes);
        if self.mem.len() >= SPILL_AT {
            self.spill_now()?;
        }
        Ok(())
    }

    fn spill_now(&mut self) -> io::Result<()> {
        if self.spill.is_none() {
            self.spill = Some(TempFile::create_in(&std::env::temp_dir())?);
        }
        let t = self.spill.as_mut().expect("spill file");
        t.file.write_all(&self.mem)?;
        self.mem.clear();
        Ok(())
    }

    /// Releases everything to the destination. A closed pipe on stdout counts
    /// as success.
    pub fn finish(mut self) -> io::Result<()> {
        match self.dest.clone() {
            Destination::Discard => Ok(()),
            Destination::File(target) => {
                self.spill_now()?;
                let mut t = self.spill.take().expect("spill file");
                t.file.flush()?;
                t.file.get_ref().sync_all()?;
                std::fs::rename(&t.path, &target)?;
                t.keep = true;
                Ok(())
            }
            Destination::Stdout => {
                let stdout = io::stdout();
                let mut out = BufWriter::with_capacity(1 << 16, stdout.lock());
                let r = (|| -> io::Result<()> {
                    if let Some(t) = self.spill.as_mut() {
                        t.file.flush()?;
                        let f = t.file.get_mut();
                        f.seek(SeekFrom::Start(0))?;
                        let mut buf = vec![0u8; 1 << 16];
                        loop {
                            let n = f.read(&mut buf)?;
                            if n == 0 {
                                break;
                            }
                            out.write_all(&buf[..n])?;
                        }
                    }
                    out.write_all(&self.mem)?;
                    out.flush()
                })();
                match r {
                    Err(e) if e.kind() == io::ErrorKind::BrokenPipe => Ok(()),
                    other => other,
                }
            }
        }
    }
}
