//! Where flattened lines go before they are released: memory while small, a
//! temporary file once large. Nothing reaches the destination until the whole
//! program has been flattened without error. For stdout, output copied
//! unchanged from a streamed input file is recorded as a range of that file
//! instead of being spooled, and copied from it on release.
//!
//! Released bytes are the bytes that were evaluated: each recorded range
//! carries the CRC-32 of the bytes the evaluator read (adjacent ranges merge
//! and their CRCs combine). On release every range is read again and checked
//! before anything is written, keeping a CRC per 1 MB block; the copy then
//! checks each block again before writing it. A file changed during the run
//! (rewritten, truncated, even with its modification time restored) is an
//! error and nothing is written. A change in the moment between the check
//! and the copy stops the copy before the first changed block, with an error
//! (the reader gets a cut output and exit status 2, never an unchecked byte).

use std::fs::File;
use std::io::{self, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use crate::source::SourceFile;

/// Most ranges recorded; past this, input bytes are spooled like others.
const MAX_PARTS: usize = 1 << 14;
/// Block size of the release check.
const BLOCK: u64 = 1 << 20;

/// A piece of the output, in order.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Part {
    /// The next bytes of the spooled stream.
    Spooled(u64),
    /// A range of the input file and the CRC-32 of its bytes as evaluated.
    Input { start: u64, len: u64, crc: u32 },
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
    /// a FIFO or a device is opened and written (see [`resolve_output`]).
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
pub fn resolve_output(path: &Path) -> io::Result<(PathBuf, bool)> {
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
    /// The file output may refer to.
    input: Option<Arc<SourceFile>>,
    /// A streamed input file, watched for changes until the release.
    watch: Option<Arc<SourceFile>>,
    /// Output as pieces; empty while no range was recorded (all spooled).
    parts: Vec<Part>,
    spooled: u64,
    /// Bytes recorded as input ranges.
    ranged: u64,
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
            input: None,
            watch: None,
            parts: Vec::new(),
            spooled: 0,
            ranged: 0,
            byte_budget: u64::MAX,
        })
    }

    /// Lets output refer to ranges of `input` (a streamed file) when it goes
    /// to stdout; a streamed input is watched for changes in any case.
    pub fn refer_to(&mut self, input: Arc<SourceFile>) {
        if input.memory().is_some() {
            return;
        }
        if matches!(self.dest, Destination::Stdout) {
            self.input = Some(input.clone());
        }
        self.watch = Some(input);
    }

    /// Bounds the output to `extra` bytes beyond the input's `input_len`.
    pub fn limit_bytes(&mut self, extra: u64, input_len: u64) {
        self.byte_budget = extra.saturating_add(input_len);
    }

    /// Why [`Sink::record_input`] refused `len` bytes.
    #[cold]
    pub fn not_recorded(&self, len: u64) -> io::Error {
        if self.spooled + self.ranged + len > self.byte_budget {
            self.too_large()
        } else {
            io::Error::other("an input range could not be recorded")
        }
    }

    #[cold]
    fn too_large(&self) -> io::Error {
        io::Error::other(OutputTooLarge {
            limit: self.byte_budget,
            room: self.room(),
        })
    }

    /// Bytes written so far (spooled and recorded as ranges).
    pub fn used(&self) -> u64 {
        self.spooled + self.ranged
    }

    /// Bytes that may still be written before `--max-output-bytes`.
    pub fn room(&self) -> u64 {
        self.byte_budget.saturating_sub(self.used())
    }

    /// The file output may refer to, if any.
    pub fn input(&self) -> Option<&Arc<SourceFile>> {
        self.input.as_ref()
    }

    /// Output is thrown away (check mode).
    pub fn discards(&self) -> bool {
        matches!(self.dest, Destination::Discard)
    }

    /// How many more ranges [`Sink::record_input`] is sure to accept,
    /// whatever is written between them: each range adds at most one part
    /// and the bytes written after it one more, and the first range may add
    /// a part for the bytes before it.
    pub fn range_room(&self) -> usize {
        MAX_PARTS.saturating_sub(self.parts.len() + 3) / 2
    }

    /// Appends bytes that are `file`'s bytes from offset `start` on.
    pub fn write_input(
        &mut self,
        file: &Arc<SourceFile>,
        start: u64,
        bytes: &[u8],
    ) -> io::Result<()> {
        let ours = self.input.as_ref().is_some_and(|f| Arc::ptr_eq(f, file));
        if ours && self.record_input(start, bytes.len() as u64, crc32fast::hash(bytes)) {
            Ok(())
        } else {
            self.write(bytes)
        }
    }

    /// Appends `len` bytes of the input file from offset `start` on as a
    /// range of it; `crc` is the CRC-32 of those bytes as they were read.
    /// False when there is no input file to refer to or no room for another
    /// range: nothing was appended, the bytes must be written.
    pub fn record_input(&mut self, start: u64, len: u64, crc: u32) -> bool {
        if self.input.is_none() || self.parts.len() >= MAX_PARTS {
            return false;
        }
        if self.spooled + self.ranged + len > self.byte_budget {
            // Written instead, and refused there.
            return false;
        }
        self.ranged += len;
        if self.parts.is_empty() && self.spooled > 0 {
            self.parts.push(Part::Spooled(self.spooled));
        }
        match self.parts.last_mut() {
            Some(Part::Input {
                start: s,
                len: l,
                crc: c,
            }) if *s + *l == start => {
                *c = crc_concat(*c, crc, len);
                *l += len;
            }
            _ => self.parts.push(Part::Input { start, len, crc }),
        }
        true
    }

    /// Appends bytes (whole lines).
    #[inline]
    pub fn write(&mut self, bytes: &[u8]) -> io::Result<()> {
        if matches!(self.dest, Destination::Discard) {
            return Ok(());
        }
        let len = bytes.len() as u64;
        if self.spooled + self.ranged + len > self.byte_budget {
            return Err(self.too_large());
        }
        self.mem.extend_from_slice(bytes);
        self.spooled += len;
        match self.parts.last_mut() {
            None => {}
            Some(Part::Spooled(n)) => *n += len,
            Some(Part::Input { .. }) => self.parts.push(Part::Spooled(len)),
        }
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

    /// The watched input still has its size and modification time.
    fn check_unchanged(&self) -> io::Result<()> {
        match &self.watch {
            Some(w) if !w.unchanged()? => Err(changed(w)),
            _ => Ok(()),
        }
    }

    /// Reads every recorded range of the input again and checks it against
    /// the CRC taken when it was evaluated; returns a CRC per block.
    fn verify_ranges(&self, input: &SourceFile, buf: &mut [u8]) -> io::Result<Vec<u32>> {
        let mut blocks = Vec::new();
        for part in &self.parts {
            let Part::Input { start, len, crc } = *part else {
                continue;
            };
            let (mut off, end, mut all) = (start, start + len, 0u32);
            while off < end {
                let n = (end - off).min(BLOCK) as usize;
                if input.read_at(&mut buf[..n], off)? != n {
                    return Err(changed(input));
                }
                let b = crc32fast::hash(&buf[..n]);
                blocks.push(b);
                all = crc_concat(all, b, n as u64);
                off += n as u64;
            }
            if all != crc {
                return Err(changed(input));
            }
        }
        Ok(blocks)
    }

    /// Writes the pieces in order: spooled bytes from the spool, ranges from
    /// the input file, each block checked before it is written.
    fn release_parts(&mut self, out: &mut impl Write) -> io::Result<()> {
        let input = self
            .input
            .clone()
            .ok_or_else(|| io::Error::other("no input file to copy from"))?;
        test_pause("verify");
        self.check_unchanged()?;
        let mut buf = vec![0u8; BLOCK as usize];
        let blocks = self.verify_ranges(&input, &mut buf)?;
        test_pause("copy");
        let mut blocks = blocks.into_iter();
        let mut spool: Box<dyn Read + '_> = match self.spill.as_mut() {
            Some(t) => {
                t.file.flush()?;
                let f = t.file.get_mut();
                f.seek(SeekFrom::Start(0))?;
                Box::new(f.chain(&self.mem[..]))
            }
            None => Box::new(&self.mem[..]),
        };
        for part in &self.parts {
            match *part {
                Part::Spooled(n) => {
                    if io::copy(&mut (&mut spool).take(n), out)? != n {
                        return Err(io::Error::other("the spool file was cut short"));
                    }
                }
                Part::Input { start, len, .. } => {
                    let (mut off, end) = (start, start + len);
                    while off < end {
                        let n = (end - off).min(BLOCK) as usize;
                        let got = input.read_at(&mut buf[..n], off)?;
                        if got != n || blocks.next() != Some(crc32fast::hash(&buf[..n])) {
                            return Err(io::Error::other(format!(
                                "{} changed while it was being copied to the output; the output is incomplete",
                                input.display_name()
                            )));
                        }
                        out.write_all(&buf[..n])?;
                        off += n as u64;
                    }
                }
            }
        }
        out.flush()
    }

    /// Releases everything to the destination. A closed pipe on stdout counts
    /// as success.
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
                let f = File::options().write(true).open(&target)?;
                let mut out = BufWriter::with_capacity(1 << 16, f);
                self.release(&mut out)
            }
            Destination::Stdout => {
                let stdout = io::stdout();
                let mut out = BufWriter::with_capacity(1 << 16, stdout.lock());
                match self.release(&mut out) {
                    Err(e) if e.kind() == io::ErrorKind::BrokenPipe => Ok(()),
                    other => other,
                }
            }
        }
    }

    /// Writes the whole output to `out` (the release to stdout).
    pub(super) fn release(&mut self, out: &mut impl Write) -> io::Result<()> {
        if !self.parts.is_empty() {
            return self.release_parts(out);
        }
        self.check_unchanged()?;
        if let Some(t) = self.spill.as_mut() {
            t.file.flush()?;
            let f = t.file.get_mut();
            f.seek(SeekFrom::Start(0))?;
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

    #[test]
    fn ranges_of_the_input_come_back_in_order() {
        let dir = tempfile::tempdir().unwrap();
        let src = big_source(dir.path(), 800_000);
        let data = std::fs::read(&src.path).unwrap();
        let mut sink = Sink::new(Destination::Stdout).unwrap();
        sink.refer_to(src.clone());
        let mut want = Vec::new();
        sink.write(b"%\n").unwrap();
        want.extend_from_slice(b"%\n");
        // Adjacent ranges merge; literal bytes in between stay in place.
        for (a, b, lit) in [(0, 100, false), (100, 5000, true), (9000, 9100, true)] {
            sink.write_input(&src, a as u64, &data[a..b]).unwrap();
            want.extend_from_slice(&data[a..b]);
            if lit {
                sink.write(b"G0 Z1\n").unwrap();
                want.extend_from_slice(b"G0 Z1\n");
            }
        }
        // Enough literal bytes to spill to the temporary file.
        let filler = vec![b'x'; SPILL_AT + 10];
        sink.write(&filler).unwrap();
        want.extend_from_slice(&filler);
        sink.write_input(&src, 20, &data[20..30]).unwrap();
        want.extend_from_slice(&data[20..30]);
        assert_eq!(sink.parts.len(), 6);
        let mut out = Vec::new();
        sink.release_parts(&mut out).unwrap();
        assert!(out == want);
    }

    #[test]
    fn a_changed_input_is_not_released() {
        let dir = tempfile::tempdir().unwrap();
        let src = big_source(dir.path(), 800_000);
        let mut sink = Sink::new(Destination::Stdout).unwrap();
        sink.refer_to(src.clone());
        sink.write_input(&src, 0, b"G1 X0 Y0\n").unwrap();
        std::fs::OpenOptions::new()
            .append(true)
            .open(&src.path)
            .unwrap()
            .write_all(b"G1 X9\n")
            .unwrap();
        let mut out = Vec::new();
        let e = sink.release_parts(&mut out).unwrap_err();
        assert!(
            e.to_string()
                .contains("changed while it was being flattened"),
            "{e}"
        );
        assert!(out.is_empty());
    }

    #[test]
    fn other_files_and_memory_files_are_spooled() {
        let dir = tempfile::tempdir().unwrap();
        let src = big_source(dir.path(), 800_000);
        let small = Arc::new(SourceFile::new(
            "s.ngc".into(),
            "s.ngc".into(),
            b"G0 X1\n".to_vec(),
        ));
        let mut sink = Sink::new(Destination::Stdout).unwrap();
        sink.refer_to(small.clone());
        assert!(sink.input.is_none());
        sink.refer_to(src.clone());
        sink.write_input(&small, 0, b"G0 X1\n").unwrap();
        assert!(sink.parts.is_empty());
        assert_eq!(sink.mem, b"G0 X1\n");
    }
}
