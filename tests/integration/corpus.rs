//! LinuxCNC's own example corpus, as the `linuxcnc-uspace` package installs
//! it (`/usr/share/linuxcnc/ncfiles` and the sample configurations'
//! programs), through ngcflat on every target and through rs274: each
//! program, and each subroutine library called with the arguments it
//! declares, must move the machine as the original does under rs274, or
//! have its difference listed in `tests/corpus/known.txt` with a reason.
//!
//! * A program is run as it is; a library (a file whose first O-line is
//!   `o<name> sub`) is called from a one-line program with its declared
//!   defaults: the lathe macros' `MACRODEFAULTS=` comment (true/false are
//!   1/0), ngcgui's `#<name> = #n (=default)` header lines, or else the
//!   argument list `tests/corpus/calls.txt` states for it.
//! * Both run with the same INI (the file's folder and the libraries'
//!   folders as SUBROUTINE_PATH), the tool table `tests/corpus/tools.tbl`
//!   and ngcflat's `--zero-start`; the target's output goes through rs274
//!   again and the two canon streams are compared by machine motion
//!   (`motion.rs`).
//! * rs274 refusing the original and ngcflat refusing it too is agreement.
//!   Anything else that is not the same motion must match an entry of the
//!   known list, and every entry must still match something, so the list
//!   stays true.
//!
//! Identical files (the sample configurations repeat some) run once.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use crate::oracle;

/// The installed corpus: a short name and the folder.
const ROOTS: [(&str, &str); 2] = [
    ("ncfiles", "/usr/share/linuxcnc/ncfiles"),
    (
        "sample-configs",
        "/usr/share/doc/linuxcnc/examples/sample-configs",
    ),
];

/// Library folders every run may call into (relative to the ncfiles root).
const LIBRARY_DIRS: [&str; 3] = [
    "ngcgui_lib",
    "ngcgui_lib/utilitysubs",
    "remap_lib/common_nc_subs",
];

/// Sibling folders of a file's folder that hold its configuration's
/// subroutines.
const SIBLING_DIRS: [&str; 3] = ["nc_subroutines", "remap_subs", "macros"];

/// Motion tolerance, mm (rs274 prints 4 decimals; inch programs 0.00254 mm).
const TOL: f64 = 0.004;

fn corpus_dir() -> PathBuf {
    crate::root().join("tests/corpus")
}

/// One file of the corpus: its short name (`ncfiles/macros/lathe/boring.ngc`),
/// its path, and for a library the subroutine's name and arguments.
#[derive(Clone)]
struct Case {
    name: String,
    path: PathBuf,
    call: Option<(String, Vec<String>)>,
}

/// The subroutine name of a library: its first O-line (only blank lines and
/// comments before it) is `o<name> sub`.
fn library_name(text: &str) -> Option<String> {
    for line in text.lines() {
        let t = line.trim();
        if t.is_empty() || t.starts_with(';') || t.starts_with('(') || t == "%" {
            continue;
        }
        let low = t.to_ascii_lowercase();
        let rest = low.strip_prefix('o')?.trim_start();
        let rest = rest.strip_prefix('<')?;
        let close = rest.find('>')?;
        let after = rest[close + 1..].trim_start();
        let word = after.split(|c: char| !c.is_ascii_alphabetic()).next()?;
        return (word == "sub").then(|| rest[..close].trim().to_string());
    }
    None
}

/// A MACRODEFAULTS value as a number (`true`/`false`: 1/0).
fn macro_value(v: &str) -> Option<String> {
    let v = v.trim();
    match v.to_ascii_lowercase().as_str() {
        "true" => Some("1".into()),
        "false" => Some("0".into()),
        _ => v.parse::<f64>().ok().map(|_| v.to_string()),
    }
}

/// The arguments a library declares: `MACRODEFAULTS=a,b,c`, or ngcgui's
/// `#<name> = #n (=default ...)` lines (an index without a line is 0).
/// Err names a declaration that cannot be read.
fn declared_args(text: &str) -> Result<Option<Vec<String>>, String> {
    for line in text.lines() {
        if let Some(i) = line.find("MACRODEFAULTS=") {
            let list = line[i + "MACRODEFAULTS=".len()..].trim();
            if list.is_empty() {
                return Ok(Some(Vec::new()));
            }
            return list
                .split(',')
                .map(|v| macro_value(v).ok_or_else(|| format!("MACRODEFAULTS value `{v}`")))
                .collect::<Result<_, _>>()
                .map(Some);
        }
    }
    let mut found: BTreeMap<usize, String> = BTreeMap::new();
    for line in text.lines() {
        let Some((index, default)) = ngcgui_line(line) else {
            continue;
        };
        let value = default
            .split_whitespace()
            .next()
            .and_then(|v| v.parse::<f64>().ok().map(|_| v.to_string()))
            .ok_or_else(|| format!("ngcgui default `{}`", line.trim()))?;
        found.entry(index).or_insert(value);
    }
    let Some(&last) = found.keys().next_back() else {
        return Ok(None);
    };
    Ok(Some(
        (1..=last)
            .map(|i| found.get(&i).cloned().unwrap_or_else(|| "0".into()))
            .collect(),
    ))
}

/// `#<name> = #n (=default)` → (n, "default ...").
fn ngcgui_line(line: &str) -> Option<(usize, &str)> {
    let t = line.trim_start().strip_prefix("#<")?;
    let t = &t[t.find('>')? + 1..];
    let t = t.trim_start().strip_prefix('=')?.trim_start();
    let t = t.strip_prefix('#')?;
    let digits = t.bytes().take_while(u8::is_ascii_digit).count();
    let index: usize = t[..digits].parse().ok()?;
    let t = t[digits..].trim_start().strip_prefix('(')?.trim_start();
    let t = t.strip_prefix('=')?;
    Some((index, t.split(')').next().unwrap_or_default()))
}

/// A glob of `/`-separated names where `*` in a name matches any text and
/// a name `**` any number of names.
fn glob(pattern: &str, name: &str) -> bool {
    fn names(p: &[&str], n: &[&str]) -> bool {
        match p.split_first() {
            None => n.is_empty(),
            Some((&"**", rest)) => (0..=n.len()).any(|k| names(rest, &n[k..])),
            Some((first, rest)) => n
                .split_first()
                .is_some_and(|(h, t)| one(first, h) && names(rest, t)),
        }
    }
    fn one(p: &str, n: &str) -> bool {
        match p.split_once('*') {
            None => p == n,
            Some((head, tail)) => {
                n.starts_with(head)
                    && (0..=n.len() - head.len()).any(|k| {
                        n.is_char_boundary(head.len() + k) && one(tail, &n[head.len() + k..])
                    })
            }
        }
    }
    let p: Vec<&str> = pattern.split('/').collect();
    let n: Vec<&str> = name.split('/').collect();
    names(&p, &n)
}

/// The lines of a data file without comments (`#` first) and blank lines,
/// with their line numbers.
fn data_lines(file: &str) -> Vec<(usize, String)> {
    let text = std::fs::read_to_string(corpus_dir().join(file))
        .unwrap_or_else(|e| panic!("tests/corpus/{file}: {e}"));
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
        .map(|(i, l)| (i + 1, l.trim().to_string()))
        .collect()
}

/// `calls.txt`: `GLOB ARG...` (no arguments: the call has none).
fn stated_calls() -> Vec<(String, Vec<String>)> {
    data_lines("calls.txt")
        .into_iter()
        .map(|(_, l)| {
            let mut it = l.split_whitespace().map(str::to_string);
            let g = it.next().expect("a glob");
            (g, it.collect())
        })
        .collect()
}

/// Every file of the corpus, identical ones once, in name order. Err lists
/// the libraries without a way to call them.
fn cases() -> Result<Vec<Case>, String> {
    let calls = stated_calls();
    let mut seen = std::collections::HashSet::new();
    let mut out = Vec::new();
    let mut problems = Vec::new();
    for (short, root) in ROOTS {
        let mut files: Vec<PathBuf> = walkdir::WalkDir::new(root)
            .into_iter()
            .filter_map(Result::ok)
            .filter(|e| e.file_type().is_file())
            .map(|e| e.into_path())
            .filter(|p| {
                p.extension()
                    .is_some_and(|e| matches!(e.to_str(), Some("ngc" | "nc" | "tap")))
            })
            .collect();
        files.sort();
        for path in files {
            let bytes = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?;
            if !seen.insert(bytes.clone()) {
                continue;
            }
            let rel = path.strip_prefix(root).expect("under the root");
            let name = format!("{short}/{}", rel.display());
            let text = String::from_utf8_lossy(&bytes);
            let call = match library_name(&text) {
                None => None,
                Some(sub) => {
                    let stated = calls.iter().find(|(g, _)| glob(g, &name));
                    match (declared_args(&text), stated) {
                        (Ok(Some(args)), _) => Some((sub, args)),
                        (Ok(None), Some((_, args))) => Some((sub, args.clone())),
                        (Ok(None), None) => {
                            problems.push(format!(
                                "{name}: a library that declares no defaults and has no line in tests/corpus/calls.txt"
                            ));
                            continue;
                        }
                        (Err(e), _) => {
                            problems.push(format!("{name}: cannot read its {e}"));
                            continue;
                        }
                    }
                }
            };
            out.push(Case { name, path, call });
        }
    }
    if problems.is_empty() {
        Ok(out)
    } else {
        Err(problems.join("\n"))
    }
}

/// The targets `ngcflat targets` lists (a name at the start of a line).
fn targets() -> Vec<String> {
    let out = Command::new(crate::bin())
        .arg("targets")
        .output()
        .expect("ngcflat targets");
    assert!(out.status.success(), "ngcflat targets failed");
    let list: Vec<String> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| l.starts_with(|c: char| c.is_ascii_alphanumeric()))
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .collect();
    assert!(list.iter().any(|t| t == "linuxcnc"), "targets: {list:?}");
    list
}

/// What became of one file on one target.
#[derive(Debug, Clone, PartialEq)]
enum Outcome {
    /// The same motion.
    Agree,
    /// rs274 refuses the original, ngcflat refuses it too.
    BothRefuse,
    /// ngcflat refuses (with this error code and message) what rs274 runs.
    Refused(String, String),
    /// ngcflat flattens what rs274 refuses.
    Accepts(String),
    /// rs274 refuses ngcflat's output.
    Rejected(String),
    /// The motion differs (where); ngcflat's warning codes.
    Differs(String, Vec<String>),
}

impl Outcome {
    fn kind(&self) -> String {
        match self {
            Outcome::Agree => "agree".into(),
            Outcome::BothRefuse => "both-refuse".into(),
            Outcome::Refused(code, _) => format!("refused:{code}"),
            Outcome::Accepts(_) => "accepts".into(),
            Outcome::Rejected(_) => "rejected".into(),
            Outcome::Differs(..) => "differs".into(),
        }
    }

    fn detail(&self) -> &str {
        match self {
            Outcome::Accepts(d)
            | Outcome::Rejected(d)
            | Outcome::Differs(d, _)
            | Outcome::Refused(_, d) => d,
            _ => "",
        }
    }
}

/// A line of `known.txt`: `OUTCOME TARGETS GLOB -- reason`, OUTCOME one of
/// `refused:CODE`, `accepts`, `rejected`, `differs` or `differs:WCODE`
/// (ngcflat must give that warning), TARGETS `*` or a comma list.
struct Known {
    line: usize,
    outcome: String,
    warning: Option<String>,
    targets: Option<Vec<String>>,
    glob: String,
}

fn known() -> Vec<Known> {
    data_lines("known.txt")
        .into_iter()
        .map(|(line, l)| {
            let (head, reason) = l
                .split_once(" -- ")
                .unwrap_or_else(|| panic!("known.txt:{line}: no ` -- reason`"));
            assert!(
                !reason.trim().is_empty(),
                "known.txt:{line}: an empty reason"
            );
            let f: Vec<&str> = head.split_whitespace().collect();
            assert_eq!(
                f.len(),
                3,
                "known.txt:{line}: OUTCOME TARGETS GLOB -- reason"
            );
            let (outcome, warning) = match f[0].split_once(':') {
                Some(("differs", w)) => ("differs".to_string(), Some(w.to_string())),
                _ => (f[0].to_string(), None),
            };
            assert!(
                outcome.starts_with("refused:")
                    || ["accepts", "rejected", "differs"].contains(&outcome.as_str()),
                "known.txt:{line}: unknown outcome {}",
                f[0]
            );
            let targets = (f[1] != "*").then(|| f[1].split(',').map(str::to_string).collect());
            Known {
                line,
                outcome,
                warning,
                targets,
                glob: f[2].to_string(),
            }
        })
        .collect()
}

impl Known {
    fn covers(&self, name: &str, target: &str, o: &Outcome) -> bool {
        self.outcome == o.kind()
            && self
                .targets
                .as_ref()
                .is_none_or(|t| t.iter().any(|x| x == target))
            && glob(&self.glob, name)
            && match (&self.warning, o) {
                (Some(w), Outcome::Differs(_, warnings)) => warnings.contains(w),
                _ => true,
            }
    }
}

/// A run's private folder: the INI, symbolic links to the search folders
/// (short paths, as rs274 reads at most 255 characters of an INI line),
/// the caller of a library.
struct Workspace {
    dir: tempfile::TempDir,
    ini: PathBuf,
    program: PathBuf,
}

fn workspace(case: &Case) -> Workspace {
    let dir = crate::tmp();
    let own = case.path.parent().expect("a folder").to_path_buf();
    let mut folders = vec![own.clone()];
    if let Some(up) = own.parent() {
        for s in SIBLING_DIRS {
            folders.push(up.join(s));
        }
    }
    for l in LIBRARY_DIRS {
        folders.push(Path::new(ROOTS[0].1).join(l));
    }
    let mut links = Vec::new();
    for f in folders {
        if f.is_dir() && !links.iter().any(|(_, g): &(PathBuf, PathBuf)| *g == f) {
            let link = dir.path().join(format!("d{}", links.len()));
            std::os::unix::fs::symlink(&f, &link).expect("symlink");
            links.push((link, f));
        }
    }
    let list: Vec<String> = links.iter().map(|(l, _)| l.display().to_string()).collect();
    let ini = dir.path().join("corpus.ini");
    std::fs::write(
        &ini,
        format!("[RS274NGC]\nSUBROUTINE_PATH = {}\n", list.join(":")),
    )
    .expect("write ini");
    let program = match &case.call {
        None => case.path.clone(),
        Some((sub, args)) => {
            let words: String = args.iter().map(|a| format!(" [{a}]")).collect();
            let p = dir.path().join("caller.ngc");
            std::fs::write(&p, format!("o<{sub}> call{words}\nM2\n")).expect("write caller");
            p
        }
    };
    Workspace { dir, ini, program }
}

/// rs274's stdout lines for `program` (Err: its message).
fn rs274(ws: &Workspace, program: &Path) -> Result<Vec<String>, String> {
    let home = ws.dir.path().join(format!("home{}", std::process::id()));
    let _ = std::fs::create_dir_all(&home);
    let out = Command::new(oracle::RS274)
        .current_dir(ws.dir.path())
        .env("HOME", &home)
        .arg("-g")
        .arg("-i")
        .arg(&ws.ini)
        .arg("-t")
        .arg(corpus_dir().join("tools.tbl"))
        .arg(program)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .output()
        .map_err(|e| e.to_string())?;
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        return Err(err.lines().skip(1).take(2).collect::<Vec<_>>().join(" | "));
    }
    Ok(String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(str::to_string)
        .collect())
}

/// The codes (`E1000`, `W0110`) of ngcflat's diagnostics of a severity.
fn codes(stderr: &str, severity: &str) -> Vec<String> {
    let mut v: Vec<String> = stderr
        .lines()
        .filter_map(|l| {
            let rest = l.strip_prefix(severity)?.strip_prefix('[')?;
            Some(rest[..rest.find(']')?].to_string())
        })
        .collect();
    v.sort();
    v.dedup();
    v
}

/// Runs one file on every target.
fn run_case(case: &Case, targets: &[String]) -> Vec<(String, Outcome)> {
    let ws = workspace(case);
    let original = rs274(&ws, &ws.program);
    let tbl = corpus_dir().join("tools.tbl");
    targets
        .iter()
        .map(|target| {
            let args: Vec<String> = [
                "--target",
                target,
                "--zero-start",
                "--ini",
                &ws.ini.display().to_string(),
                "--tool-table",
                &tbl.display().to_string(),
                &ws.program.display().to_string(),
            ]
            .iter()
            .map(|s| s.to_string())
            .collect();
            let (code, out, err) = crate::outcome(crate::ngcflat(ws.dir.path(), &args, None));
            let outcome = match (&original, code) {
                (Err(_), 0) => Outcome::Accepts(original.clone().unwrap_err()),
                (Err(_), _) => Outcome::BothRefuse,
                (Ok(_), 0) => {
                    let flat = ws.dir.path().join(format!("flat-{target}.ngc"));
                    std::fs::write(&flat, crate::as_rs274_reads(target, &out))
                        .expect("write output");
                    match rs274(&ws, &flat) {
                        Err(e) => Outcome::Rejected(e),
                        Ok(b) => match crate::motion::same_canon_motion(
                            original.as_ref().expect("ok"),
                            &b,
                            TOL,
                        ) {
                            Ok(()) => Outcome::Agree,
                            Err(e) => Outcome::Differs(e, codes(&err, "warning")),
                        },
                    }
                }
                (Ok(_), _) => Outcome::Refused(
                    codes(&err, "error")
                        .first()
                        .cloned()
                        .unwrap_or_else(|| format!("exit{code}")),
                    err.lines().next().unwrap_or_default().to_string(),
                ),
            };
            (target.clone(), outcome)
        })
        .collect()
}

#[test]
fn linuxcnc_corpus_moves_as_rs274_on_every_target() {
    let test = "linuxcnc_corpus_moves_as_rs274_on_every_target";
    if !oracle::available(test) {
        return;
    }
    if !Path::new(ROOTS[0].1).is_dir() {
        panic!(
            "{test}: rs274 is installed but LinuxCNC's ncfiles ({}) are not",
            ROOTS[0].1
        );
    }
    let mut cases = cases().unwrap_or_else(|e| panic!("{e}"));
    // NGCFLAT_CORPUS_ONLY=GLOB runs the matching files alone (the known
    // list is then checked only for what ran).
    let only = std::env::var("NGCFLAT_CORPUS_ONLY").ok();
    if let Some(g) = &only {
        cases.retain(|c| glob(g, &c.name));
    }
    let mut targets = targets();
    // NGCFLAT_CORPUS_TARGETS=a,b runs on those targets alone (the known
    // list is then checked only for them).
    let only_targets = std::env::var("NGCFLAT_CORPUS_TARGETS").ok();
    if let Some(t) = &only_targets {
        let want: Vec<&str> = t.split(',').collect();
        targets.retain(|n| want.contains(&n.as_str()));
    }
    let known = known();
    let results = oracle::on_threads(0..cases.len() as u64, 1, |i| {
        let started = std::time::Instant::now();
        let r = run_case(&cases[i as usize], &targets);
        let took = started.elapsed().as_secs_f64();
        if took > 5.0 {
            eprintln!("slow: {} took {took:.1} s", cases[i as usize].name);
        }
        r
    });
    let mut used = vec![false; known.len()];
    let mut unexpected = Vec::new();
    // target → outcome kind → count
    let mut tally: BTreeMap<&str, BTreeMap<String, usize>> = BTreeMap::new();
    for (i, per_target) in &results {
        let case = &cases[*i as usize];
        for (target, o) in per_target {
            *tally
                .entry(target.as_str())
                .or_default()
                .entry(o.kind())
                .or_default() += 1;
            if matches!(o, Outcome::Agree | Outcome::BothRefuse) {
                continue;
            }
            let hits: Vec<usize> = (0..known.len())
                .filter(|&k| known[k].covers(&case.name, target, o))
                .collect();
            for &k in &hits {
                used[k] = true;
            }
            if hits.is_empty() {
                let call = case
                    .call
                    .as_ref()
                    .map(|(s, a)| format!(" (o<{s}> call {})", a.join(" ")))
                    .unwrap_or_default();
                unexpected.push(format!(
                    "{} {target} {}{call}: {}",
                    o.kind(),
                    case.name,
                    o.detail()
                ));
            }
        }
    }
    let libraries = cases.iter().filter(|c| c.call.is_some()).count();
    eprintln!(
        "LinuxCNC corpus: {} files ({} programs, {} libraries called), targets {}",
        cases.len(),
        cases.len() - libraries,
        libraries,
        targets.join(", ")
    );
    for (t, kinds) in &tally {
        let parts: Vec<String> = kinds.iter().map(|(k, n)| format!("{k} {n}")).collect();
        eprintln!("  {t}: {}", parts.join(", "));
    }
    let stale: Vec<String> = known
        .iter()
        .zip(&used)
        .filter(|(k, u)| {
            !**u
                && only.is_none()
                // Under a choice of targets, entries for those alone.
                && only_targets.as_ref().is_none_or(|t| {
                    k.targets
                        .as_ref()
                        .is_some_and(|ks| ks.iter().all(|k| t.split(',').any(|x| x == k)))
                })
        })
        .map(|(k, _)| {
            format!(
                "known.txt:{}: {} {} no longer happens",
                k.line, k.outcome, k.glob
            )
        })
        .collect();
    assert!(
        unexpected.is_empty() && stale.is_empty(),
        "{} outcomes not in tests/corpus/known.txt:\n{}\n{} entries of known.txt that match nothing:\n{}",
        unexpected.len(),
        unexpected.join("\n"),
        stale.len(),
        stale.join("\n")
    );
}

#[test]
fn library_defaults_are_read_as_declared() {
    let macro_text = "; MACRODEFAULTS=1,500,.02,true,False\n\no<boring> sub\no<boring> endsub\n";
    assert_eq!(library_name(macro_text).as_deref(), Some("boring"));
    assert_eq!(
        declared_args(macro_text),
        Ok(Some(vec![
            "1".into(),
            "500".into(),
            ".02".into(),
            "1".into(),
            "0".into()
        ]))
    );
    let gui = "(info: a sub)\no<x> sub\n  #<r> = #1 (=  1 R) ; radius\n#<f> = #3 (=-0.5 feed)\no<x> endsub\n";
    assert_eq!(library_name(gui).as_deref(), Some("x"));
    assert_eq!(
        declared_args(gui),
        Ok(Some(vec!["1".into(), "0".into(), "-0.5".into()]))
    );
    assert_eq!(
        declared_args("o<y> sub\n#<a> = #1 (=abc)\n").map(|_| ()),
        Err("ngcgui default `#<a> = #1 (=abc)`".into())
    );
    assert_eq!(declared_args("o<y> sub\nG0 X1\n"), Ok(None));
    assert_eq!(library_name("G0 X1\no<y> sub\n"), None);
    assert_eq!(library_name("o100 sub\n").as_deref(), None);
    assert!(glob("ncfiles/**/*.ngc", "ncfiles/a/b/c.ngc"));
    assert!(glob("ncfiles/*.ngc", "ncfiles/c.ngc"));
    assert!(!glob("ncfiles/*.ngc", "ncfiles/a/c.ngc"));
    assert!(glob(
        "**/remap_subs/4*remap.ngc",
        "sample-configs/sim/x/remap_subs/428remap.ngc"
    ));
}
