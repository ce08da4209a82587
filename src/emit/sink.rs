//! Where flattened lines go before they are released: memory while small, a
//! temporary file once large. Nothing reaches the destination until the whole
//! program has been flattened without error.
//!
//! Released bytes are the bytes that were evaluated: every byte of the
//! output, the lines copied unchanged from the input included, is written
//! into the spool as the evaluator had it, and the release copies the spool;
//! the input file is never read for the output. A streamed input is also
//! checked for changes before anything is released: each range of it copied
//! to the output carries the CRC-32 of its bytes as evaluated (adjacent
//! ranges merge and their CRCs combine), and the release reads every range
//! again and compares, after comparing size and modification time. A file
//! changed during the run (rewritten, truncated, even with its modification
//! time restored) is an error and nothing is written. A change after that
//! check cannot reach the output, which no longer depends on the file: the
//! release goes on whole.

use std::fs::File;
use std::io::{self, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use crate::source::SourceFile;

/// Most separate ranges checked; bytes copied past this are still the
/// evaluated bytes, and the size and modification time are still checked.
const MAX_CHECKS: usize = 1 << 14;
/// Block size of the release check.
const BLOCK: u64 = 1 << 20;

/// A range of the input file copied to the output, and the CRC-32 of its
/// bytes as evaluated.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Check {
    start: u64,
    len: u64,
    crc: u32,
}

/// Bytes kept in memory before spilling to a temporary file.
const SPILL_AT: usize = 1 << 20;

/// The CRC-32 of the concatenation of two byte strings from theirs.
fn crc_concat(a: u32, b: u32, b_len: u64) -> u32 {
    let mut h = crc32fast::Hasher::new_with_initial_len(a, 0);
    h.combine(&crc32fast::Hasher::new_with_initial_len(b, b_len));
    h.finalize()
}

/// A spool file: unnamed for stdout (gone with the process, however it
/// ends), or named in the target's folder for `-o` (renamed onto the target
/// on release, removed on drop otherwise).
struct Spool {
    file: BufWriter<File>,
    path: Option<tempfile::TempPath>,
}

impl Spool {
    fn anonymous() -> io::Result<Spool> {
        Ok(Spool {
            file: BufWriter::with_capacity(1 << 16, tempfile::tempfile()?),
            path: None,
        })
    }

    /// A spool in `dir` to be renamed onto `target`: with the target's
    /// permissions if it exists, else those of a new file (0666 less the
    /// umask).
    fn named_in(dir: &Path, target: &Path) -> io::Result<Spool> {
        use std::os::unix::fs::PermissionsExt;
        let keep = std::fs::metadata(target).ok().map(|m| m.permissions());
        let (file, path) = tempfile::Builder::new()
            .prefix(".ngcflat-")
            .suffix(".tmp")
            .permissions(std::fs::Permissions::from_mode(0o666))
            .tempfile_in(dir)
            .map_err(|e| {
                io::Error::new(
                    e.kind(),
                    format!(
                        "cannot create a temporary file in the folder {} (the output is written there, then renamed): {e}",
                        dir.display()
                    ),
                )
            })?
            .into_parts();
        if let Some(p) = keep {
            file.set_permissions(p)?;
        }
        crate::emit::interrupt::register(&path);
        Ok(Spool {
            file: BufWriter::with_capacity(1 << 16, file),
            path: Some(path),
        })
    }
}

impl Drop for Spool {
    fn drop(&mut self) {
        if let Some(p) = &self.path {
            crate::emit::interrupt::unregister(p);
        }
    }
}

/// Where the finished output goes.
#[derive(Debug, Clone)]
pub enum Destination {
    Stdout,
    /// `-o`: a regular file is replaced atomically (a temporary file in its
    /// folder renamed onto it; through a symbolic link, the link's target);
    /// a FIFO or a device is opened and written (see `resolve_output`).
    File(PathBuf),
    /// Thrown away (check mode).
    Discard,
    /// A FIFO, device or socket named by `-o` (after links): opened for
    /// writing on release, not replaced.
    Special(PathBuf),
    /// Memory (library use, tests, fuzzing): the output is put into the
    /// buffer on release; nothing is spilled to a file, the byte limit
    /// bounds it.
    Memory(MemoryOut),
}

/// The buffer a [`Destination::Memory`] output is released into.
#[derive(Debug, Clone, Default)]
pub struct MemoryOut(Arc<Mutex<Vec<u8>>>);

impl MemoryOut {
    /// The released output (empty until then), taken out of the buffer.
    pub fn take(&self) -> Vec<u8> {
        match self.0.lock() {
            Ok(mut v) => std::mem::take(&mut *v),
            Err(poisoned) => std::mem::take(&mut *poisoned.into_inner()),
        }
    }

    fn put(&self, bytes: Vec<u8>) {
        match self.0.lock() {
            Ok(mut v) => *v = bytes,
            Err(poisoned) => *poisoned.into_inner() = bytes,
        }
    }
}

/// Where `-o PATH` really writes: the file a chain of symbolic links ends
/// at (the link is kept, its target replaced), and whether that is a FIFO,
/// device or socket, written in place rather than replaced.
pub(super) fn resolve_output(path: &Path) -> io::Result<(PathBuf, bool)> {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                let to = std::fs::read_link(&p)?;
                p = match p.parent() {
                    Some(dir) => dir.join(to),
                    None => to,
                };
            }
            Ok(m) => {
                let ft = m.file_type();
                if ft.is_dir() {
                    return Err(io::Error::other("is a folder"));
                }
                return Ok((p, !ft.is_file()));
            }
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok((p, false)),
            Err(e) => return Err(e),
        }
    }
    Err(io::Error::other("too many levels of symbolic links"))
}

/// Flattened output held back until the program is known to be good.
pub struct Sink {
    mem: Vec<u8>,
    spill: Option<Spool>,
    dest: Destination,
    /// A streamed input file, checked for changes before the release.
    watch: Option<Arc<SourceFile>>,
    /// Ranges of `watch` copied to the output.
    checks: Vec<Check>,
    /// Bytes written.
    written: u64,
    /// Most bytes of output (`--max-output-bytes` plus the input's size).
    byte_budget: u64,
}

/// The output grew past `--max-output-bytes` (carried in an `io::Error`
/// from the sink to the evaluator).
#[derive(Debug)]
pub struct OutputTooLarge {
    pub limit: u64,
    /// How many bytes of the refused write still fit: the write's byte
    /// at this index is the first past the limit.
    pub room: u64,
}

impl std::fmt::Display for OutputTooLarge {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "the output grew past {} bytes", self.limit)
    }
}

impl std::error::Error for OutputTooLarge {}

/// Test hook: with `NGCFLAT_TEST_PAUSE_DIR` set and `PHASE.wait` in that
/// folder, the release stops at `phase`, creates `PHASE.paused` and waits
/// until `PHASE.wait` is removed (at most a minute), so that a test can
/// change the input at a known moment.
fn test_pause(phase: &str) {
    let Some(dir) = std::env::var_os("NGCFLAT_TEST_PAUSE_DIR") else {
        return;
    };
    let dir = PathBuf::from(dir);
    let wait = dir.join(format!("{phase}.wait"));
    if !wait.exists() {
        return;
    }
    let _ = std::fs::write(dir.join(format!("{phase}.paused")), b"");
    let start = std::time::Instant::now();
    while wait.exists() && start.elapsed() < std::time::Duration::from_secs(60) {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
}

fn changed(input: &SourceFile) -> io::Error {
    io::Error::other(format!(
        "{} changed while it was being flattened; nothing was written",
        input.display_name()
    ))
}

impl Sink {
    pub fn new(dest: Destination) -> io::Result<Sink> {
        let mut dest = dest;
        let spill = match &dest {
            Destination::File(p) => {
                let (target, special) = resolve_output(p)?;
                if special {
                    // Written in place on release; spooled like stdout.
                    dest = Destination::Special(target);
                    None
                } else {
                    let dir = match target.parent() {
                        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
                        _ => PathBuf::from("."),
                    };
                    let spool = Spool::named_in(&dir, &target)?;
                    dest = Destination::File(target);
                    Some(spool)
                }
            }
            _ => None,
        };
        Ok(Sink {
            mem: Vec::with_capacity(1 << 16),
            spill,
            dest,
            watch: None,
            checks: Vec::new(),
            written: 0,
            byte_budget: u64::MAX,
        })
    }

    /// Watches `input` (a streamed file) for changes until the release:
    /// ranges of it copied to the output are checked against it again.
    pub fn refer_to(&mut self, input: Arc<SourceFile>) {
        if input.memory().is_none() {
            self.watch = Some(input);
        }
    }

    /// Bounds the output to `extra` bytes beyond the input's `input_len`.
    pub fn limit_bytes(&mut self, extra: u64, input_len: u64) {
        self.byte_budget = extra.saturating_add(input_len);
    }

    #[cold]
    fn too_large(&self) -> io::Error {
        io::Error::other(OutputTooLarge {
            limit: self.byte_budget,
            room: self.room(),
        })
    }

    /// Bytes written so far.
    pub fn used(&self) -> u64 {
        self.written
    }

    /// Bytes that may still be written before `--max-output-bytes`.
    pub fn room(&self) -> u64 {
        self.byte_budget.saturating_sub(self.used())
    }

    /// The watched input file, if any.
    pub fn input(&self) -> Option<&Arc<SourceFile>> {
        self.watch.as_ref()
    }

    /// Output is thrown away (check mode).
    pub fn discards(&self) -> bool {
        matches!(self.dest, Destination::Discard)
    }

    /// How many more ranges [`Sink::write_checked`] is sure to check (each
    /// adds at most one).
    pub fn check_room(&self) -> usize {
        MAX_CHECKS.saturating_sub(self.checks.len())
    }

    /// Appends bytes that are `file`'s bytes from offset `start` on (whole
    /// lines), checked on release if `file` is the watched input.
    pub fn write_input(
        &mut self,
        file: &Arc<SourceFile>,
        start: u64,
        bytes: &[u8],
    ) -> io::Result<()> {
        if self.watch.as_ref().is_some_and(|f| Arc::ptr_eq(f, file)) {
            self.write_checked(start, bytes)
        } else {
            self.write(bytes)
        }
    }

    /// Appends bytes of the watched input from offset `start` on, and
    /// notes their range and CRC to check on release.
    pub fn write_checked(&mut self, start: u64, bytes: &[u8]) -> io::Result<()> {
        self.write(bytes)?;
        if matches!(self.dest, Destination::Discard) || bytes.is_empty() {
            return Ok(());
        }
        let (len, crc) = (bytes.len() as u64, crc32fast::hash(bytes));
        let room = self.checks.len() < MAX_CHECKS;
        match self.checks.last_mut() {
            Some(c) if c.start + c.len == start => {
                c.crc = crc_concat(c.crc, crc, len);
                c.len += len;
            }
            _ if room => self.checks.push(Check { start, len, crc }),
            _ => {}
        }
        Ok(())
    }

    /// Takes the lines held so far out of a [`Destination::Memory`] sink
    /// (nothing for any other destination), for a reader that consumes the
    /// output as it is made.
    pub(crate) fn drain_memory(&mut self) -> Vec<u8> {
        if matches!(self.dest, Destination::Memory(_)) {
            std::mem::take(&mut self.mem)
        } else {
            Vec::new()
        }
    }

    /// Appends bytes (whole lines).
    #[inline]
    pub fn write(&mut self, bytes: &[u8]) -> io::Result<()> {
        if matches!(self.dest, Destination::Discard) {
            return Ok(());
        }
        let len = bytes.len() as u64;
        if self.written + len > self.byte_budget {
            return Err(self.too_large());
        }
        self.mem.extend_from_slice(bytes);
        self.written += len;
        if self.mem.len() >= SPILL_AT && !matches!(self.dest, Destination::Memory(_)) {
            self.spill_now()?;
        }
        Ok(())
    }

    fn spill_now(&mut self) -> io::Result<()> {
        let t = match &mut self.spill {
            Some(t) => t,
            None => self.spill.insert(Spool::anonymous()?),
        };
        t.file.write_all(&self.mem)?;
        self.mem.clear();
        Ok(())
    }

    /// The watched input still has its size and modification time, and
    /// every checked range its bytes as evaluated.
    fn check_unchanged(&self) -> io::Result<()> {
        let Some(input) = &self.watch else {
            return Ok(());
        };
        if !input.unchanged()? {
            return Err(changed(input));
        }
        let mut buf =
            vec![0u8; BLOCK.min(self.checks.iter().map(|c| c.len).max().unwrap_or(0)) as usize];
        for c in &self.checks {
            let (mut off, end, mut all) = (c.start, c.start + c.len, 0u32);
            while off < end {
                let n = (end - off).min(BLOCK) as usize;
                if input.read_at(&mut buf[..n], off)? != n {
                    return Err(changed(input));
                }
                all = crc_concat(all, crc32fast::hash(&buf[..n]), n as u64);
                off += n as u64;
            }
            if all != c.crc {
                return Err(changed(input));
            }
        }
        Ok(())
    }

    /// Releases everything to the destination, after checking the input.
    /// A closed pipe on stdout counts as success.
    pub fn finish(mut self) -> io::Result<()> {
        match self.dest.clone() {
            Destination::Discard => Ok(()),
            Destination::Memory(buf) => {
                self.check_unchanged()?;
                buf.put(std::mem::take(&mut self.mem));
                Ok(())
            }
            Destination::File(target) => {
                self.spill_now()?;
                let mut t = self
                    .spill
                    .take()
                    .ok_or_else(|| io::Error::other("no spool file"))?;
                t.file.flush()?;
                t.file.get_ref().sync_all()?;
                test_pause("finish");
                self.check_unchanged()?;
                let path = t
                    .path
                    .take()
                    .ok_or_else(|| io::Error::other("no spool file"))?;
                crate::emit::interrupt::persist(path, &target)
            }
            Destination::Special(target) => {
                test_pause("verify");
                self.check_unchanged()?;
                let f = File::options().write(true).open(&target)?;
                let mut out = BufWriter::with_capacity(1 << 16, f);
                self.release(&mut out)
            }
            Destination::Stdout => {
                test_pause("verify");
                self.check_unchanged()?;
                let stdout = io::stdout();
                let mut out = BufWriter::with_capacity(1 << 16, stdout.lock());
                match self.release(&mut out) {
                    Err(e) if e.kind() == io::ErrorKind::BrokenPipe => Ok(()),
                    other => other,
                }
            }
        }
    }

    /// Writes the whole output to `out`: the spool, then what is still in
    /// memory. Reads nothing but the spool.
    pub(super) fn release(&mut self, out: &mut impl Write) -> io::Result<()> {
        test_pause("copy");
        if let Some(t) = self.spill.as_mut() {
            t.file.flush()?;
            let f = t.file.get_mut();
            f.seek(SeekFrom::Start(0))?;
            // The first block, then a test may change the input mid-copy.
            io::copy(&mut Read::by_ref(f).take(BLOCK), out)?;
            out.flush()?;
            test_pause("copying");
            io::copy(f, out)?;
        }
        out.write_all(&self.mem)?;
        out.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A streamed source file of `n` lines.
    fn big_source(dir: &Path, n: usize) -> Arc<SourceFile> {
        let path = dir.join("in.ngc");
        let mut text = String::new();
        for i in 0..n {
            text.push_str(&format!("G1 X{i} Y{}\n", i % 7));
        }
        std::fs::write(&path, &text).unwrap();
        let f = SourceFile::open(&path).unwrap();
        assert!(f.memory().is_none(), "test file must be streamed");
        Arc::new(f)
    }

    /// Input bytes and other bytes come back in order, from the spool
    /// (spilled to its file) and memory; adjacent ranges merge.
    #[test]
    fn input_bytes_come_back_in_order() {
        let dir = tempfile::tempdir().unwrap();
        let src = big_source(dir.path(), 800_000);
        let data = std::fs::read(&src.path).unwrap();
        let mut sink = Sink::new(Destination::Stdout).unwrap();
        sink.refer_to(src.clone());
        let mut want = Vec::new();
        sink.write(b"%\n").unwrap();
        want.extend_from_slice(b"%\n");
        for (a, b, lit) in [(0, 100, false), (100, 5000, true), (9000, 9100, true)] {
            sink.write_input(&src, a as u64, &data[a..b]).unwrap();
            want.extend_from_slice(&data[a..b]);
            if lit {
                sink.write(b"G0 Z1\n").unwrap();
                want.extend_from_slice(b"G0 Z1\n");
            }
        }
        let filler = vec![b'x'; SPILL_AT + 10];
        sink.write(&filler).unwrap();
        want.extend_from_slice(&filler);
        sink.write_input(&src, 20, &data[20..30]).unwrap();
        want.extend_from_slice(&data[20..30]);
        assert_eq!(sink.checks.len(), 3);
        sink.check_unchanged().unwrap();
        let mut out = Vec::new();
        sink.release(&mut out).unwrap();
        assert!(out == want);
    }

    /// A range rewritten with its size and modification time kept is seen
    /// by the check.
    #[test]
    fn a_changed_range_is_seen() {
        let dir = tempfile::tempdir().unwrap();
        let src = big_source(dir.path(), 800_000);
        let data = std::fs::read(&src.path).unwrap();
        let mut sink = Sink::new(Destination::Stdout).unwrap();
        sink.refer_to(src.clone());
        sink.write_input(&src, 0, &data[..3 << 20]).unwrap();
        sink.check_unchanged().unwrap();
        let mtime = std::fs::metadata(&src.path).unwrap().modified().unwrap();
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .open(&src.path)
            .unwrap();
        f.seek(SeekFrom::Start(2 << 20)).unwrap();
        f.write_all(b"G1 X[1/0]").unwrap();
        f.set_modified(mtime).unwrap();
        assert!(src.unchanged().unwrap());
        let e = sink.check_unchanged().unwrap_err();
        assert!(
            e.to_string()
                .contains("changed while it was being flattened"),
            "{e}"
        );
    }

    /// Once the input was checked the release reads only the spool: the
    /// input truncated then changes nothing.
    #[test]
    fn the_release_never_reads_the_input() {
        let dir = tempfile::tempdir().unwrap();
        let src = big_source(dir.path(), 800_000);
        let data = std::fs::read(&src.path).unwrap();
        let mut sink = Sink::new(Destination::Stdout).unwrap();
        sink.refer_to(src.clone());
        sink.write_input(&src, 0, &data).unwrap();
        sink.check_unchanged().unwrap();
        std::fs::OpenOptions::new()
            .write(true)
            .open(&src.path)
            .unwrap()
            .set_len(10)
            .unwrap();
        let mut out = Vec::new();
        sink.release(&mut out).unwrap();
        assert!(out == data);
    }

    /// Past the most ranges checked, bytes are still written (unchecked).
    #[test]
    fn ranges_past_the_list_are_written() {
        let dir = tempfile::tempdir().unwrap();
        let src = big_source(dir.path(), 800_000);
        let data = std::fs::read(&src.path).unwrap();
        let mut sink = Sink::new(Destination::Memory(MemoryOut::default())).unwrap();
        sink.refer_to(src.clone());
        let mut want = Vec::new();
        for i in 0..MAX_CHECKS + 10 {
            // Every range apart from the one before.
            let a = 3 * i;
            sink.write_input(&src, a as u64, &data[a..a + 2]).unwrap();
            want.extend_from_slice(&data[a..a + 2]);
        }
        assert_eq!(sink.check_room(), 0);
        let mut out = Vec::new();
        sink.release(&mut out).unwrap();
        assert!(out == want);
    }

    /// A file held in memory is not watched.
    #[test]
    fn memory_files_are_not_watched() {
        let small = Arc::new(SourceFile::new(
            "s.ngc".into(),
            "s.ngc".into(),
            b"G0 X1\n".to_vec(),
        ));
        let mut sink = Sink::new(Destination::Stdout).unwrap();
        sink.refer_to(small.clone());
        assert!(sink.watch.is_none());
        sink.write_input(&small, 0, b"G0 X1\n").unwrap();
        assert!(sink.checks.is_empty());
        assert_eq!(sink.mem, b"G0 X1\n");
    }
}
