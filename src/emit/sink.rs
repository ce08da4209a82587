//! Where flattened lines go before they are released: memory while small, a
//! temporary file once large. Nothing reaches the destination until the whole
//! program has been flattened without error. For stdout, output copied
//! unchanged from a streamed input file is recorded as a range of that file
//! instead of being spooled, and copied from it on release (after checking
//! the file has not changed).

use std::fs::File;
use std::io::{self, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU32, Ordering};

use crate::program::SourceFile;

/// Most ranges recorded; past this, input bytes are spooled like others.
const MAX_PARTS: usize = 1 << 14;

/// A piece of the output, in order.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Part {
    /// The next bytes of the spooled stream.
    Spooled(u64),
    /// A range of the input file.
    Input { start: u64, len: u64 },
}

/// Bytes kept in memory before spilling to a temporary file.
const SPILL_AT: usize = 1 << 20;

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

/// Flattened output held back until the program is known to be good.
pub struct Sink {
    mem: Vec<u8>,
    spill: Option<TempFile>,
    dest: Destination,
    /// The file output may refer to.
    input: Option<Arc<SourceFile>>,
    /// Output as pieces; empty while no range was recorded (all spooled).
    parts: Vec<Part>,
    spooled: u64,
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
            input: None,
            parts: Vec::new(),
            spooled: 0,
        })
    }

    /// Lets output refer to ranges of `input` (a streamed file) when it goes
    /// to stdout.
    pub fn refer_to(&mut self, input: Arc<SourceFile>) {
        if matches!(self.dest, Destination::Stdout) && input.memory().is_none() {
            self.input = Some(input);
        }
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
        if ours && self.record_input(start, bytes.len() as u64) {
            Ok(())
        } else {
            self.write(bytes)
        }
    }

    /// Appends `len` bytes of the input file from offset `start` on as a
    /// range of it. False when there is no input file to refer to or no room
    /// for another range: nothing was appended, the bytes must be written.
    pub fn record_input(&mut self, start: u64, len: u64) -> bool {
        if self.input.is_none() || self.parts.len() >= MAX_PARTS {
            return false;
        }
        if self.parts.is_empty() && self.spooled > 0 {
            self.parts.push(Part::Spooled(self.spooled));
        }
        match self.parts.last_mut() {
            Some(Part::Input { start: s, len: l }) if *s + *l == start => *l += len,
            _ => self.parts.push(Part::Input { start, len }),
        }
        true
    }

    /// Appends bytes (whole lines).
    #[inline]
    pub fn write(&mut self, bytes: &[u8]) -> io::Result<()> {
        if matches!(self.dest, Destination::Discard) {
            return Ok(());
        }
        self.mem.extend_from_slice(bytes);
        let len = bytes.len() as u64;
        self.spooled += len;
        match self.parts.last_mut() {
            None => {}
            Some(Part::Spooled(n)) => *n += len,
            Some(Part::Input { .. }) => self.parts.push(Part::Spooled(len)),
        }
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

    /// Writes the pieces in order: spooled bytes from the spool, ranges from
    /// the input file, which must be as it was when read.
    fn release_parts(&mut self, out: &mut impl Write) -> io::Result<()> {
        let input = self.input.as_ref().expect("input file");
        if !input.unchanged()? {
            return Err(io::Error::other(format!(
                "{} changed while it was being flattened; nothing was written",
                input.display_name()
            )));
        }
        let mut file = File::open(&input.path)?;
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
            let (copied, want) = match *part {
                Part::Spooled(n) => (io::copy(&mut (&mut spool).take(n), out)?, n),
                Part::Input { start, len } => {
                    file.seek(SeekFrom::Start(start))?;
                    (io::copy(&mut (&mut file).take(len), out)?, len)
                }
            };
            if copied != want {
                return Err(io::Error::other(
                    "the input file was cut short while being copied",
                ));
            }
        }
        out.flush()
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
