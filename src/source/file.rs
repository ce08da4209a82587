//! A source file: its path and its bytes, held in memory when small and read
//! from disk in windows when large, so a big program streams through in
//! bounded memory.

use std::borrow::Cow;
use std::fs::File;
use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, OnceLock};

use super::locate::{Block, LineCol, LineSamples, block_pieces, file_pieces, memory_pieces};
use super::marked_lines::{Marked, MarkedLines};

/// Bounds on reading a program.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct InputLimits {
    /// Most bytes of a program (`--max-input-bytes`; offsets are 32-bit, so
    /// never more than 4 GiB - 1).
    pub max_bytes: u64,
    /// Longest line read from a pipe or device (`--max-line-bytes`); lines
    /// of regular files are never read whole (they are read through 1 MB
    /// windows and cut at 4 kB).
    pub max_line: u64,
}

impl Default for InputLimits {
    fn default() -> Self {
        InputLimits {
            max_bytes: 2 << 30,
            max_line: 1 << 20,
        }
    }
}

impl InputLimits {
    fn max_bytes(&self) -> u64 {
        self.max_bytes.min(u32::MAX as u64)
    }

    fn too_large(&self) -> io::Error {
        let hard = self.max_bytes > u32::MAX as u64;
        io::Error::other(if hard {
            "programs of 4 GiB or more are not supported".to_string()
        } else {
            format!(
                "the program is larger than {} bytes (raise with --max-input-bytes, up to 4 GiB - 1)",
                self.max_bytes
            )
        })
    }
}

/// Files up to this size are kept in memory.
pub const IN_MEMORY_LIMIT: u64 = 8 << 20;
/// Bytes read from disk at a time.
const CHUNK: usize = 1 << 20;
/// Lines handed on by a scan of part of a file, with their raw bytes.
type KeptHits = Vec<(Marked, Vec<u8>)>;

/// Reads until `buf` is full or the file ends; returns the bytes read.
fn read_full(file: &mut impl Read, buf: &mut [u8]) -> io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        let n = file.read(&mut buf[got..])?;
        if n == 0 {
            break;
        }
        got += n;
    }
    Ok(got)
}

/// Streamed files from this size are scanned for marked lines on two cores.
const SPLIT_SCAN: u64 = 16 << 20;
/// Longest line kept whole; longer lines are errors anyway.
const LONG_LINE: usize = 4096;

/// A line's first `LONG_LINE` bytes: what a scan hands on of a line, the
/// same whether the line is held in memory, lies inside one chunk read from
/// disk or runs across chunks.
fn cut(line: &[u8]) -> &[u8] {
    &line[..line.len().min(LONG_LINE)]
}

#[derive(Debug)]
enum Text {
    Memory(Vec<u8>),
    /// Read on demand through the handle opened first, never by path
    /// again (a file renamed or replaced meanwhile is not read). Standard
    /// input is spooled to an unnamed temporary file.
    Disk(File),
}

#[derive(Debug)]
pub struct SourceFile {
    /// Path as given or found (used to read it again for diagnostics).
    pub path: PathBuf,
    /// Name shown in diagnostics.
    pub name: String,
    text: Text,
    len: u64,
    /// Modification time when opened (streamed files), to notice a change.
    modified: Option<std::time::SystemTime>,
    /// Sampled line starts, made on the first diagnostic that needs them.
    samples: OnceLock<LineSamples>,
    /// Bytes read from the start to locate offsets before the samples were
    /// made: while that stays below the file's length, reading up to an
    /// offset costs less than sampling the file.
    scanned: AtomicU64,
    /// The block of a streamed file read last for a diagnostic (diagnostics
    /// come mostly in file order: a million warnings read the file about
    /// once, not a piece each).
    block: Mutex<Block>,
}

/// Reads a file from an offset on without moving a shared cursor, so that
/// several readers (threads) can use one handle.
pub struct At<'a> {
    file: &'a File,
    pos: u64,
}

impl Read for At<'_> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        use std::os::unix::fs::FileExt;
        let n = self.file.read_at(buf, self.pos)?;
        self.pos += n as u64;
        Ok(n)
    }
}

impl SourceFile {
    /// An in-memory source.
    pub fn new(path: PathBuf, name: String, data: Vec<u8>) -> SourceFile {
        let len = data.len() as u64;
        SourceFile {
            path,
            name,
            text: Text::Memory(data),
            len,
            modified: None,
            samples: OnceLock::new(),
            scanned: AtomicU64::new(0),
            block: Mutex::default(),
        }
    }

    /// Opens a file: small files are read, large ones streamed.
    pub fn open(path: &Path) -> io::Result<SourceFile> {
        Self::open_limited(path, InputLimits::default())
    }

    /// [`SourceFile::open`] within `lim`: a regular file over the size bound
    /// is refused before it is read; a FIFO or device is read as a stream.
    pub fn open_limited(path: &Path, lim: InputLimits) -> io::Result<SourceFile> {
        Self::from_file(path, File::open(path)?, lim)
    }

    /// Opens a regular file without waiting on it: a FIFO, device or socket
    /// (given by path, or swapped in for a file) is refused at once instead
    /// of blocking until a writer comes (check mode).
    pub fn open_regular(path: &Path, lim: InputLimits) -> io::Result<SourceFile> {
        use std::os::unix::fs::OpenOptionsExt;
        let file = File::options()
            .read(true)
            .custom_flags(libc::O_NONBLOCK)
            .open(path)?;
        if !file.metadata()?.is_file() {
            return Err(io::Error::other(
                "not a regular file (a FIFO, device or socket); only regular files are checked",
            ));
        }
        Self::from_file(path, file, lim)
    }

    fn from_file(path: &Path, mut file: File, lim: InputLimits) -> io::Result<SourceFile> {
        let meta = file.metadata()?;
        let name = path.display().to_string();
        if !meta.is_file() {
            let mut s = Self::read_stream_limited(file, &name, lim)?;
            s.path = path.to_path_buf();
            return Ok(s);
        }
        if meta.len() > lim.max_bytes() {
            return Err(lim.too_large());
        }
        if meta.len() <= IN_MEMORY_LIMIT {
            let mut data = Vec::new();
            file.read_to_end(&mut data)?;
            return Ok(SourceFile::new(path.to_path_buf(), name, data));
        }
        Ok(SourceFile {
            path: path.to_path_buf(),
            name,
            text: Text::Disk(file),
            len: meta.len(),
            modified: meta.modified().ok(),
            samples: OnceLock::new(),
            scanned: AtomicU64::new(0),
            block: Mutex::default(),
        })
    }

    /// A file read from disk on demand whatever its size (tests of the
    /// streamed path with small files).
    #[cfg(test)]
    pub fn open_streamed(path: &Path) -> io::Result<SourceFile> {
        let file = File::open(path)?;
        let meta = file.metadata()?;
        Ok(SourceFile {
            path: path.to_path_buf(),
            name: path.display().to_string(),
            text: Text::Disk(file),
            len: meta.len(),
            modified: meta.modified().ok(),
            samples: OnceLock::new(),
            scanned: AtomicU64::new(0),
            block: Mutex::default(),
        })
    }

    /// Reads a stream; spills to a temporary file when it is large.
    pub fn read_stream(input: impl Read, name: &str) -> io::Result<SourceFile> {
        Self::read_stream_limited(input, name, InputLimits::default())
    }

    /// Reads a stream within `lim` (its size and line length are checked as
    /// it arrives, so `/dev/zero` or `yes` stop at the bound); spills to an
    /// unnamed temporary file when it is large.
    pub fn read_stream_limited(
        mut input: impl Read,
        name: &str,
        lim: InputLimits,
    ) -> io::Result<SourceFile> {
        let mut data = Vec::new();
        // An unnamed file: no name to guess or plant a link at, and gone
        // with the process however it ends.
        let mut spool: Option<io::BufWriter<File>> = None;
        let mut buf = vec![0u8; 1 << 16];
        let (mut total, mut line_len, mut line_no) = (0u64, 0u64, 1u64);
        let mut prefix: Vec<u8> = Vec::new();
        loop {
            let n = match input.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => n,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(e),
            };
            let chunk = &buf[..n];
            total += n as u64;
            if total > lim.max_bytes() {
                return Err(lim.too_large());
            }
            // Lines inside the chunk are shorter than the chunk; with a bound
            // below the chunk size every line is measured.
            let first = memchr::memchr(b'\n', chunk);
            let over = match first {
                None => line_len + n as u64 > lim.max_line,
                Some(f) => {
                    line_len + f as u64 > lim.max_line
                        || (lim.max_line < buf.len() as u64
                            && chunk[f + 1..]
                                .split(|&b| b == b'\n')
                                .any(|l| l.len() as u64 > lim.max_line))
                }
            };
            if over {
                // Where: the first line that is too long.
                let mut len = line_len;
                for seg in chunk.split_inclusive(|&b| b == b'\n') {
                    let body = seg.strip_suffix(b"\n").unwrap_or(seg);
                    if len == 0 {
                        prefix.clear();
                    }
                    let room = 40usize.saturating_sub(prefix.len());
                    prefix.extend_from_slice(&body[..body.len().min(room)]);
                    len += body.len() as u64;
                    if len > lim.max_line {
                        break;
                    }
                    if body.len() < seg.len() {
                        len = 0;
                        line_no += 1;
                    }
                }
                return Err(io::Error::other(format!(
                    "line {line_no} is longer than {} bytes (raise with --max-line-bytes); it starts: {}...",
                    lim.max_line,
                    String::from_utf8_lossy(&prefix)
                )));
            }
            match memchr::memrchr(b'\n', chunk) {
                Some(last) => {
                    line_no += chunk.iter().filter(|&&b| b == b'\n').count() as u64;
                    let tail = &chunk[last + 1..];
                    line_len = tail.len() as u64;
                    prefix.clear();
                    prefix.extend_from_slice(&tail[..tail.len().min(40)]);
                }
                None => {
                    line_len += n as u64;
                    let room = 40usize.saturating_sub(prefix.len());
                    prefix.extend_from_slice(&chunk[..n.min(room)]);
                }
            }
            match &mut spool {
                None if data.len() + n <= IN_MEMORY_LIMIT as usize => data.extend_from_slice(chunk),
                None => {
                    let mut f = io::BufWriter::with_capacity(1 << 20, tempfile::tempfile()?);
                    f.write_all(&data)?;
                    f.write_all(chunk)?;
                    data = Vec::new();
                    spool = Some(f);
                }
                Some(f) => f.write_all(chunk)?,
            }
        }
        let Some(f) = spool else {
            return Ok(SourceFile::new(PathBuf::from(name), name.to_string(), data));
        };
        let f = f.into_inner().map_err(|e| e.into_error())?;
        let modified = f.metadata()?.modified().ok();
        Ok(SourceFile {
            path: PathBuf::from(name),
            name: name.to_string(),
            text: Text::Disk(f),
            len: total,
            modified,
            samples: OnceLock::new(),
            scanned: AtomicU64::new(0),
            block: Mutex::default(),
        })
    }

    pub fn display_name(&self) -> String {
        self.name.clone()
    }

    pub fn len(&self) -> u64 {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether a streamed file still has the size and modification time it
    /// had when opened.
    pub fn unchanged(&self) -> io::Result<bool> {
        let Text::Disk(f) = &self.text else {
            return Ok(true);
        };
        let meta = f.metadata()?;
        Ok(meta.len() == self.len && meta.modified().ok() == self.modified)
    }

    /// A reader of the streamed file from `pos` on (an error for a file held
    /// in memory).
    fn disk_reader(&self, pos: u64) -> io::Result<At<'_>> {
        self.reader_at(pos)
            .ok_or_else(|| io::Error::other("not a streamed file"))
    }

    /// A reader of the streamed file from `pos` on (None: held in memory).
    pub fn reader_at(&self, pos: u64) -> Option<At<'_>> {
        match &self.text {
            Text::Disk(file) => Some(At { file, pos }),
            Text::Memory(_) => None,
        }
    }

    /// The streamed file's bytes from `pos` on into `buf`, as many as there
    /// are (fewer only at its end); empty for a file held in memory.
    pub fn read_at(&self, buf: &mut [u8], pos: u64) -> io::Result<usize> {
        match self.reader_at(pos) {
            Some(mut r) => read_full(&mut r, buf),
            None => Ok(0),
        }
    }

    /// The bytes, when held in memory.
    pub fn memory(&self) -> Option<&[u8]> {
        match &self.text {
            Text::Memory(d) => Some(d),
            Text::Disk { .. } => None,
        }
    }

    /// Line, column and line text of a byte offset, for a diagnostic. The
    /// file is read from its start up to the offset while the bytes read so
    /// add up to less than the file; after that it is read once for line
    /// samples, then only from the sample nearest the offset.
    pub fn locate(&self, offset: u32) -> LineCol {
        let offset = u64::from(offset).min(self.len);
        // Near the start, or for the first few diagnostics, read from the
        // start instead of sampling the whole file.
        let early = self.samples.get().is_none()
            && self
                .scanned
                .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |n| {
                    (n + offset <= self.len).then_some(n + offset)
                })
                .is_ok();
        if early {
            let none = LineSamples::default();
            return match &self.text {
                Text::Memory(d) => none.locate(offset, &mut memory_pieces(d)),
                Text::Disk(f) => match self.block.lock() {
                    Ok(mut block) => none.locate(offset, &mut block_pieces(f, &mut block)),
                    Err(_) => none.locate(offset, &mut file_pieces(f)),
                },
            };
        }
        match &self.text {
            Text::Memory(d) => {
                let samples = self
                    .samples
                    .get_or_init(|| LineSamples::read(&d[..]).unwrap_or_default());
                samples.locate(offset, &mut memory_pieces(d))
            }
            Text::Disk(f) => {
                let samples = self.samples.get_or_init(|| {
                    LineSamples::read(io::BufReader::new(At { file: f, pos: 0 }))
                        .unwrap_or_default()
                });
                match self.block.lock() {
                    Ok(mut block) => samples.locate(offset, &mut block_pieces(f, &mut block)),
                    Err(_) => samples.locate(offset, &mut file_pieces(f)),
                }
            }
        }
    }

    /// The first `n` bytes (fewer when the file is shorter or cannot be
    /// read again).
    pub fn head(&self, n: usize) -> Vec<u8> {
        if let Some(d) = self.memory() {
            return d[..d.len().min(n)].to_vec();
        }
        let mut buf = vec![0u8; n];
        let got = self.read_at(&mut buf, 0).unwrap_or(0);
        buf.truncate(got);
        buf
    }

    /// All bytes (read from disk for streamed files).
    pub fn bytes(&self) -> Cow<'_, [u8]> {
        match &self.text {
            Text::Memory(d) => Cow::Borrowed(d),
            Text::Disk(f) => {
                let mut data = Vec::new();
                let _ = At { file: f, pos: 0 }.read_to_end(&mut data);
                Cow::Owned(data)
            }
        }
    }

    /// Folder of the file (for the last step of the subroutine search).
    pub fn dir(&self) -> Option<&Path> {
        self.path.parent()
    }

    /// Calls `f(line, raw)` for the lines `MarkedLines` hands on (lines
    /// with `o`, `m` or `%`, lines longer than `long`, leading blank lines),
    /// in order; `raw` is cut at 4096 bytes however the file is held or
    /// read (the line's true length is `line.end - line.start`). Returns the
    /// number of lines.
    ///
    /// `matters(raw, terminated)` tells which of the lines after the leading
    /// blank lines `f` acts on: a large file's second half is scanned ahead
    /// on another thread, which keeps only those (in memory until their
    /// turn), so they must be few.
    pub fn scan_marked_lines(
        &self,
        long: usize,
        matters: &(dyn Fn(&[u8], bool) -> bool + Sync),
        f: impl FnMut(Marked, &[u8]),
    ) -> io::Result<u32> {
        self.scan_marked(long, SPLIT_SCAN, matters, f)
    }

    /// `scan_marked_lines`, on two cores for streamed files from `split_at`
    /// bytes.
    fn scan_marked(
        &self,
        long: usize,
        split_at: u64,
        matters: &(dyn Fn(&[u8], bool) -> bool + Sync),
        mut f: impl FnMut(Marked, &[u8]),
    ) -> io::Result<u32> {
        let mut s = MarkedLines::new(long);
        match &self.text {
            Text::Memory(data) => {
                let mut hit = |m: Marked| f(m, cut(&data[m.start as usize..m.end as usize]));
                s.feed(data, 0, &mut hit);
                Ok(s.finish(data.len() as u64, &mut hit))
            }
            Text::Disk { .. } => {
                if self.len >= split_at {
                    return self.scan_marked_split(long, matters, f);
                }
                self.scan_to_end(&mut s, 0, &mut f)
            }
        }
    }

    /// `scan_marked_lines` of a large file on two cores: a second thread
    /// scans the second half (from a line start) and keeps its hits, which
    /// are handed on after the first half's, their line numbers moved on by
    /// its line count.
    fn scan_marked_split(
        &self,
        long: usize,
        matters: &(dyn Fn(&[u8], bool) -> bool + Sync),
        mut f: impl FnMut(Marked, &[u8]),
    ) -> io::Result<u32> {
        // The second half starts after the first newline from the middle.
        let mid = self.len / 2;
        let mut file = self.disk_reader(mid)?;
        let mut probe = vec![0u8; LONG_LINE];
        let n = read_full(&mut file, &mut probe)?;
        let mut s = MarkedLines::new(long);
        let Some(k) = memchr::memchr(b'\n', &probe[..n]) else {
            return self.scan_to_end(&mut s, 0, &mut f);
        };
        let split = mid + k as u64 + 1;
        let second = std::thread::scope(|scope| {
            let job = std::thread::Builder::new().spawn_scoped(
                scope,
                move || -> io::Result<(KeptHits, u32)> {
                    let mut hits = Vec::new();
                    let mut t = MarkedLines::after_leading(long, split);
                    let mut keep = |m: Marked, raw: &[u8]| {
                        if matters(raw, m.terminated) {
                            hits.push((m, raw.to_vec()));
                        }
                    };
                    let count = self.scan_to_end(&mut t, split, &mut keep)?;
                    Ok((hits, count))
                },
            );
            // No second thread could be started: one scan does it all.
            let Ok(job) = job else {
                return None;
            };
            let first = self.scan_disk(&mut s, 0, split, &mut f);
            Some((first, job.join()))
        });
        let Some((first, second)) = second else {
            return self.scan_to_end(&mut s, 0, &mut f);
        };
        first?;
        let (hits, count) = match second {
            Ok(r) => r?,
            Err(_) => return Err(io::Error::other("the scanning thread failed")),
        };
        if s.leading() {
            // The whole first half is blank: its state carries into the
            // second, which is scanned again.
            return self.scan_to_end(&mut s, split, &mut f);
        }
        let lines = s.finish(split, &mut |_| {});
        for (m, raw) in &hits {
            let m = Marked {
                idx: m.idx + lines,
                ..*m
            };
            f(m, raw);
        }
        Ok(lines + count)
    }

    /// Feeds the file from `from` (a line start) to its end to `s` and ends
    /// the scan; returns the number of lines.
    fn scan_to_end(
        &self,
        s: &mut MarkedLines,
        from: u64,
        f: &mut impl FnMut(Marked, &[u8]),
    ) -> io::Result<u32> {
        let carry = self.scan_disk(s, from, self.len, f)?;
        let mut hit = |m: Marked| f(m, &carry);
        Ok(s.finish(self.len, &mut hit))
    }

    /// Feeds bytes [from, to) of the file (`from` a line start) to `s`,
    /// handing each hit on with its raw bytes (cut at `LONG_LINE`). Returns
    /// the start of the line still open at `to`.
    fn scan_disk(
        &self,
        s: &mut MarkedLines,
        from: u64,
        to: u64,
        f: &mut impl FnMut(Marked, &[u8]),
    ) -> io::Result<Vec<u8>> {
        let mut file = self.disk_reader(from)?;
        let mut buf = vec![0u8; CHUNK];
        // The part of the current line read in earlier chunks.
        let mut carry: Vec<u8> = Vec::new();
        let mut base = from;
        while base < to {
            let want = ((to - base) as usize).min(CHUNK);
            let n = file.read(&mut buf[..want])?;
            if n == 0 {
                break;
            }
            let chunk = &buf[..n];
            let mut hit = |m: Marked| {
                let end = (m.end - base) as usize;
                if m.start >= base {
                    f(m, cut(&chunk[(m.start - base) as usize..end]));
                } else {
                    let mut raw = carry.clone();
                    let room = LONG_LINE.saturating_sub(raw.len());
                    raw.extend_from_slice(&chunk[..end.min(room)]);
                    f(m, &raw);
                }
            };
            s.feed(chunk, base, &mut hit);
            let ls = s.line_start();
            let end = base + n as u64;
            if ls >= end {
                carry.clear();
            } else if ls >= base {
                carry.clear();
                let rest = &chunk[(ls - base) as usize..];
                carry.extend_from_slice(&rest[..rest.len().min(LONG_LINE)]);
            } else {
                let room = LONG_LINE.saturating_sub(carry.len());
                carry.extend_from_slice(&chunk[..n.min(room)]);
            }
            base = end;
        }
        Ok(carry)
    }

    /// Calls `f(index, start, raw, terminated)` for every line, in order.
    pub fn scan_lines(&self, mut f: impl FnMut(u32, u32, &[u8], bool)) -> io::Result<()> {
        match &self.text {
            Text::Memory(data) => {
                let mut pos = 0usize;
                let mut idx = 0u32;
                while pos < data.len() {
                    let (end, next, term) = next_line(data, pos);
                    f(idx, pos as u32, &data[pos..end], term);
                    pos = next;
                    idx += 1;
                }
                Ok(())
            }
            Text::Disk { .. } => {
                let mut file = self.disk_reader(0)?;
                let mut buf = vec![0u8; CHUNK];
                let mut carry: Vec<u8> = Vec::new();
                let mut carry_len = 0u64; // true length of the partial line
                let mut line_start = 0u64;
                let mut chunk_base = 0u64;
                let mut idx = 0u32;
                loop {
                    let n = file.read(&mut buf)?;
                    if n == 0 {
                        break;
                    }
                    let base = chunk_base;
                    chunk_base += n as u64;
                    let chunk = &buf[..n];
                    let mut p = 0usize;
                    while p < n {
                        match memchr::memchr(b'\n', &chunk[p..]) {
                            Some(i) => {
                                if carry_len == 0 {
                                    f(idx, line_start as u32, &chunk[p..p + i], true);
                                } else {
                                    let room = LONG_LINE.saturating_sub(carry.len());
                                    carry.extend_from_slice(&chunk[p..p + i.min(room)]);
                                    f(idx, line_start as u32, &carry, true);
                                    carry.clear();
                                    carry_len = 0;
                                }
                                line_start = base + (p + i + 1) as u64;
                                p += i + 1;
                                idx += 1;
                            }
                            None => {
                                let rest = &chunk[p..];
                                let room = LONG_LINE.saturating_sub(carry.len());
                                carry.extend_from_slice(&rest[..rest.len().min(room)]);
                                carry_len += rest.len() as u64;
                                p = n;
                            }
                        }
                    }
                }
                if carry_len > 0 || !carry.is_empty() {
                    f(idx, line_start as u32, &carry, false);
                }
                Ok(())
            }
        }
    }
}

#[cfg(test)]
fn unique() -> u64 {
    use std::sync::atomic::{AtomicU64, Ordering};
    static N: AtomicU64 = AtomicU64::new(0);
    N.fetch_add(1, Ordering::Relaxed)
}

/// Splits `data` at `start`: (end without terminator, next start, terminated).
pub fn next_line(data: &[u8], start: usize) -> (usize, usize, bool) {
    match memchr::memchr(b'\n', &data[start..]) {
        Some(i) => (start + i, start + i + 1, true),
        None => (data.len(), data.len(), false),
    }
}

/// Random access to the lines of a streamed file through a window of it.
#[derive(Default)]
pub struct Window {
    buf: Vec<u8>,
    /// File offset of `buf[0]`.
    start: u64,
    /// The window before the last refill, and its offset: a call and its
    /// return go back and forth between two places of a file, each read
    /// once instead of at every jump.
    other: Vec<u8>,
    other_start: u64,
}

/// One line read through a window: bytes are `buf[a..b]`.
pub struct WindowLine {
    pub a: usize,
    pub b: usize,
    pub next: u32,
    pub terminated: bool,
}

impl Window {
    pub fn bytes(&self, l: &WindowLine) -> &[u8] {
        &self.buf[l.a..l.b]
    }

    /// Makes the window hold `at`: the previous window if it does, else a
    /// read from `at` (the current window becomes the previous one).
    fn hold(&mut self, src: &SourceFile, at: u64) -> io::Result<()> {
        std::mem::swap(&mut self.buf, &mut self.other);
        std::mem::swap(&mut self.start, &mut self.other_start);
        if at >= self.start && at < self.start + self.buf.len() as u64 {
            return Ok(());
        }
        self.fill(src, at)
    }

    fn fill(&mut self, src: &SourceFile, at: u64) -> io::Result<()> {
        let mut f = src.disk_reader(at)?;
        self.buf.resize(CHUNK, 0);
        let got = read_full(&mut f, &mut self.buf)?;
        self.buf.truncate(got);
        self.start = at;
        Ok(())
    }

    /// The window's bytes from file offset `pos` on (refilled if `pos` is
    /// outside it); they may end inside a line.
    pub fn from(&mut self, src: &SourceFile, pos: u32) -> io::Result<&[u8]> {
        let pos64 = pos as u64;
        if pos64 < self.start || pos64 >= self.start + self.buf.len() as u64 {
            self.hold(src, pos64)?;
        }
        Ok(&self.buf[(pos64 - self.start) as usize..])
    }

    /// The line starting at file offset `pos`.
    pub fn line(&mut self, src: &SourceFile, pos: u32) -> io::Result<WindowLine> {
        let pos64 = pos as u64;
        let len = src.len();
        let inside = pos64 >= self.start && pos64 < self.start + self.buf.len() as u64;
        if !inside {
            self.hold(src, pos64)?;
        }
        let mut a = (pos64 - self.start) as usize;
        if let Some(i) = memchr::memchr(b'\n', &self.buf[a..]) {
            return Ok(WindowLine {
                a,
                b: a + i,
                next: pos + i as u32 + 1,
                terminated: true,
            });
        }
        // The line runs past the window: refill from its start.
        if a > 0 && self.start + self.buf.len() as u64 != len {
            self.fill(src, pos64)?;
            a = 0;
            if let Some(i) = memchr::memchr(b'\n', &self.buf[a..]) {
                return Ok(WindowLine {
                    a,
                    b: a + i,
                    next: pos + i as u32 + 1,
                    terminated: true,
                });
            }
        }
        if self.start + self.buf.len() as u64 >= len {
            // Last line, no terminator.
            let b = self.buf.len();
            return Ok(WindowLine {
                a,
                b,
                next: len as u32,
                terminated: false,
            });
        }
        // A line longer than the window: an error anyway; find its end.
        let mut scan = self.start + self.buf.len() as u64;
        let keep = self.buf.len().min(a + LONG_LINE);
        let mut f = src.disk_reader(scan)?;
        let mut tmp = vec![0u8; CHUNK];
        loop {
            let n = f.read(&mut tmp)?;
            if n == 0 {
                return Ok(WindowLine {
                    a,
                    b: keep,
                    next: len as u32,
                    terminated: false,
                });
            }
            if let Some(i) = memchr::memchr(b'\n', &tmp[..n]) {
                let next = (scan + i as u64 + 1) as u32;
                return Ok(WindowLine {
                    a,
                    b: keep,
                    next,
                    terminated: true,
                });
            }
            scan += n as u64;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Offsets located by reading from the start (the first ones) and
    /// from the samples (once that would read more than the file) give the
    /// same lines, columns and texts as counting.
    #[test]
    fn located_from_the_start_or_the_samples_alike() {
        let mut text = Vec::new();
        for k in 0..3000 {
            text.extend_from_slice(format!("G1 X{k} Y{}\n", k % 7).as_bytes());
        }
        let f = SourceFile::new("t".into(), "t".into(), text.clone());
        let count = |offset: usize| {
            let before = &text[..offset];
            let line = before.iter().filter(|&&b| b == b'\n').count() as u32 + 1;
            let start = before
                .iter()
                .rposition(|&b| b == b'\n')
                .map_or(0, |p| p + 1);
            (line, (offset - start) as u32 + 1)
        };
        let offsets: Vec<usize> = (0..40).map(|k| (k * 7919) % text.len()).collect();
        for &o in &offsets {
            let got = f.locate(o as u32);
            assert_eq!((got.line, got.col), count(o), "offset {o}");
        }
        // Forty offsets read more than the file: the later ones were
        // located from the samples.
        assert!(f.samples.get().is_some());
    }

    type Hits = (KeptHits, u32);

    /// The lines handed on that hold an `o`, or all with `every`.
    fn hits(src: &SourceFile, long: usize, split_at: u64, every: bool) -> Hits {
        let mut out = Vec::new();
        let matters = |raw: &[u8], _: bool| every || raw.contains(&b'o');
        let n = src
            .scan_marked(long, split_at, &matters, |m, raw| {
                if matters(raw, m.terminated) {
                    out.push((m, raw.to_vec()))
                }
            })
            .expect("scan");
        (out, n)
    }

    fn on_disk(data: &[u8]) -> SourceFile {
        let path =
            std::env::temp_dir().join(format!("scan-{}-{}.ngc", std::process::id(), unique()));
        std::fs::write(&path, data).expect("write");
        let file = File::open(&path).expect("open");
        let _ = std::fs::remove_file(&path);
        SourceFile {
            path,
            name: "t".into(),
            text: Text::Disk(file),
            len: data.len() as u64,
            modified: None,
            samples: OnceLock::new(),
            scanned: AtomicU64::new(0),
            block: Mutex::default(),
        }
    }

    /// A line longer than `LONG_LINE` is handed on cut at `LONG_LINE`
    /// bytes from memory as from disk: unterminated at the end (the case
    /// proptest found: 4200 bytes), terminated inside one chunk, across a
    /// chunk, and where the split point of the two-core scan falls inside
    /// or just after it.
    #[test]
    fn overlong_lines_are_cut_alike_from_memory_and_disk() {
        let long = |n: usize| -> Vec<u8> { (0..n).map(|i| b'a' + (i % 26) as u8).collect() };
        let line = |n: usize| -> Vec<u8> { [long(n), b"\n".to_vec()].concat() };
        let cases: Vec<Vec<u8>> = vec![
            long(4200),
            line(5000),
            [b"G0 X1\n".repeat(100), line(9000), b"o1 sub\n".to_vec()].concat(),
            [long(CHUNK - 100), b"\n".to_vec(), line(6000)].concat(),
            [line(3000), line(5000), long(4200)].concat(),
            [b"\n".to_vec(), long(8190), b"\nM2\n".to_vec()].concat(),
            [b"  \n".to_vec(), b" ".repeat(4500), b"G0\n%\n".to_vec()].concat(),
        ];
        for data in &cases {
            let mem = SourceFile::new("m".into(), "m".into(), data.clone());
            let disk = on_disk(data);
            for every in [true, false] {
                let want = hits(&mem, 167, u64::MAX, every);
                assert!(want.0.iter().all(|(_, raw)| raw.len() <= LONG_LINE));
                let any_cut = want
                    .0
                    .iter()
                    .any(|(m, raw)| m.end - m.start > raw.len() as u64);
                assert!(any_cut || !every);
                assert_eq!(
                    hits(&disk, 167, u64::MAX, every),
                    want,
                    "{} bytes",
                    data.len()
                );
                assert_eq!(
                    hits(&disk, 167, 0, every),
                    want,
                    "{} bytes, split",
                    data.len()
                );
            }
        }
    }

    /// The first non-blank line is told even when its non-blank bytes lie
    /// past the cut.
    #[test]
    fn the_first_nonblank_line_is_told_past_the_cut() {
        let data = [
            b"\n \n".to_vec(),
            b" ".repeat(5000),
            b"G0\nG1\n%\n".to_vec(),
        ]
        .concat();
        let disk = on_disk(&data);
        let (lines, n) = hits(&disk, 167, 0, true);
        assert_eq!(n, 5);
        let first: Vec<u32> = lines
            .iter()
            .filter(|(m, _)| m.first_nonblank)
            .map(|(m, _)| m.idx)
            .collect();
        assert_eq!(first, [2]);
        assert!(lines[2].1.iter().all(u8::is_ascii_whitespace));
    }

    proptest! {
        /// Streamed and split, a file gives the lines and count it gives
        /// from memory.
        #[test]
        fn split_scan_agrees_with_the_memory_scan(
            parts in proptest::collection::vec(
                prop_oneof![
                    "[gG0-9. xXyY-]{0,30}",
                    Just("\n".to_string()),
                    "[oOmM%\n \t]",
                    "[a-z]{300}",
                ],
                0..80,
            ),
            long in prop_oneof![1usize..50, 60usize..300],
        ) {
            let data = parts.concat().into_bytes();
            let mem = SourceFile::new("m".into(), "m".into(), data.clone());
            let disk = on_disk(&data);
            for every in [true, false] {
                let want = hits(&mem, long, 0, every);
                prop_assert_eq!(&hits(&disk, long, 0, every), &want);
                prop_assert_eq!(&hits(&disk, long, u64::MAX, every), &want);
            }
        }
    }
}
