//! The source map: for each output line, the file, line and column that
//! made it and the chain of calls that led there, as JSON lines; and the
//! same as a comment for `--annotate`.

use std::collections::HashMap;
use std::io::{self, Write};
use std::sync::Arc;

use serde::Serialize;

use crate::program::SourceFile;

/// A place in a program: a file and a byte offset in it.
#[derive(Debug, Clone)]
pub(crate) struct Place {
    pub file: Arc<SourceFile>,
    pub offset: u32,
}

/// A file kept for locating: the file, its bytes and its line starts.
type Lines = (Arc<SourceFile>, Vec<u8>, Vec<u32>);

/// Line starts of the files seen so far, keyed by the file's address.
#[derive(Default)]
pub(crate) struct Locator {
    files: HashMap<usize, Lines>,
}

/// A located place.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub(crate) struct Located {
    pub file: String,
    pub line: u32,
    pub column: u32,
}

impl Locator {
    /// File name, 1-based line and column (in characters) of a place.
    pub(crate) fn locate(&mut self, p: &Place) -> Located {
        let key = Arc::as_ptr(&p.file) as usize;
        let (file, bytes, starts) = self.files.entry(key).or_insert_with(|| {
            let bytes = p.file.bytes().into_owned();
            let mut starts = vec![0u32];
            starts.extend(memchr::memchr_iter(b'\n', &bytes).map(|i| (i + 1) as u32));
            (Arc::clone(&p.file), bytes, starts)
        });
        let k = starts.partition_point(|&s| s <= p.offset).max(1) - 1;
        let start = starts.get(k).copied().unwrap_or(0) as usize;
        let end = (p.offset as usize).min(bytes.len()).max(start);
        let col = bytes
            .get(start..end)
            .map_or(0, |b| b.iter().filter(|&&c| (c & 0xC0) != 0x80).count());
        Located {
            file: file.display_name(),
            line: k as u32 + 1,
            column: col as u32 + 1,
        }
    }
}

#[derive(Serialize)]
struct Entry<'a> {
    output_line: u64,
    #[serde(flatten)]
    at: &'a Located,
    /// Call sites, innermost first.
    calls: &'a [Located],
    /// When the line starts on the machine (s from the program's start),
    /// as the run-time model plans it.
    #[serde(skip_serializing_if = "Option::is_none")]
    t: Option<f64>,
    /// How long the line takes (s).
    #[serde(skip_serializing_if = "Option::is_none")]
    dt: Option<f64>,
}

/// Writes the JSON-lines source map.
pub(crate) struct SourceMap<W: Write> {
    out: W,
    locator: Locator,
    line: u64,
}

impl<W: Write> SourceMap<W> {
    pub(crate) fn new(out: W) -> SourceMap<W> {
        SourceMap {
            out,
            locator: Locator::default(),
            line: 0,
        }
    }

    /// Records the next output line, made at `at` with the call sites
    /// `calls` (innermost first), and its planned time when known.
    pub(crate) fn line(
        &mut self,
        at: &Place,
        calls: &[Place],
        time: Option<crate::runtime::LineTime>,
    ) -> io::Result<()> {
        self.line += 1;
        let at = self.locator.locate(at);
        let calls: Vec<Located> = calls.iter().map(|c| self.locator.locate(c)).collect();
        let e = Entry {
            output_line: self.line,
            at: &at,
            calls: &calls,
            t: time.map(|t| round_ms(t.start)),
            dt: time.map(|t| round_ms(t.seconds)),
        };
        serde_json::to_writer(&mut self.out, &e).map_err(io::Error::other)?;
        self.out.write_all(b"\n")
    }

    pub(crate) fn out_mut(&mut self) -> &mut W {
        &mut self.out
    }

    #[cfg(test)]
    pub(crate) fn finish(mut self) -> io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

/// Seconds to the microsecond (the model is not finer than that).
fn round_ms(s: f64) -> f64 {
    (s * 1e6).round() / 1e6
}

/// The planned time of a line for `--annotate`: ` t=START dt=DURATION`
/// (seconds).
pub(crate) fn time_note(t: &crate::runtime::LineTime) -> String {
    format!(" t={:.3} dt={:.3}", t.start, t.seconds)
}

/// What an `--annotate` comment may hold and how long a line may grow,
/// for the controller that reads the output.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct NoteRules {
    /// Bytes the controller acts on wherever they appear (GRBL's `?`, `!`,
    /// `~`, ctrl-X), written as `_` in a file name.
    pub realtime: Vec<u8>,
    /// Bytes above 0x7F are acted on too: a name's other characters are
    /// written as `_`.
    pub ascii_only: bool,
    /// The longest line with its comment (bytes, terminator excluded);
    /// `None`: comments do not count against the controller's buffer.
    pub limit: Option<usize>,
}

impl NoteRules {
    /// LinuxCNC's: lines of at most 252 bytes.
    pub(crate) fn linuxcnc() -> NoteRules {
        NoteRules {
            realtime: Vec::new(),
            ascii_only: false,
            limit: Some(252),
        }
    }

    /// A target controller's, from its profile.
    pub(crate) fn for_profile(p: &crate::controller::Profile) -> NoteRules {
        use crate::controller::LineCount;
        NoteRules {
            realtime: p.realtime.clone(),
            ascii_only: p.high_bytes,
            limit: match p.line_limit {
                Some((n, LineCount::AllBytes)) => Some(n.saturating_sub(1).min(252)),
                // Comments are dropped before the buffer: LinuxCNC's
                // 252 bytes still keep lines readable.
                Some((_, LineCount::Significant)) | None => Some(252),
            },
        }
    }

    /// Whether a line of `line` bytes may carry a comment of `note` bytes.
    pub(crate) fn fits(&self, line: usize, note: usize) -> bool {
        self.limit.is_none_or(|n| line + note <= n)
    }

    fn clean(&self, s: &str) -> String {
        s.chars()
            .map(|c| {
                if c.is_control() {
                    if self.realtime.contains(&b'?') {
                        '_'
                    } else {
                        '?'
                    }
                } else if (self.ascii_only && !c.is_ascii())
                    || (c.is_ascii() && self.realtime.contains(&(c as u8)))
                {
                    '_'
                } else {
                    c
                }
            })
            .collect()
    }
}

/// The `--annotate` comment for a line: ` ;from file:line:col <
/// caller:line:col`. A `;` comment, not a parenthesised one: LinuxCNC acts
/// only on the last parenthesised comment of a line, so one added after a
/// `(MSG,...)` would silence the message (GRBL, grblHAL, FluidNC and
/// g2core read `;` comments too). Control characters in file names become
/// `?`, and whatever the controller would act on `_`.
pub(crate) fn annotation(at: &Located, calls: &[Located], rules: &NoteRules) -> String {
    let mut s = format!(" ;from {}:{}:{}", rules.clean(&at.file), at.line, at.column);
    for c in calls {
        s.push_str(&format!(
            " < {}:{}:{}",
            rules.clean(&c.file),
            c.line,
            c.column
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    #[test]
    fn lines_columns_and_chain() {
        let f = Arc::new(SourceFile::new(
            PathBuf::from("p.ngc"),
            "p.ngc".into(),
            "G0 X1\n  G1 X2 (é)\nG1 X3\n".as_bytes().to_vec(),
        ));
        let mut m = SourceMap::new(Vec::new());
        m.line(
            &Place {
                file: f.clone(),
                offset: 0,
            },
            &[],
            None,
        )
        .unwrap();
        m.line(
            &Place {
                file: f.clone(),
                offset: 8,
            },
            &[Place {
                file: f.clone(),
                offset: 19,
            }],
            Some(crate::runtime::LineTime {
                line: 2,
                start: 1.5,
                seconds: 0.25,
            }),
        )
        .unwrap();
        let text = String::from_utf8(m.finish().unwrap()).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines[0],
            r#"{"output_line":1,"file":"p.ngc","line":1,"column":1,"calls":[]}"#
        );
        assert_eq!(
            lines[1],
            r#"{"output_line":2,"file":"p.ngc","line":2,"column":3,"calls":[{"file":"p.ngc","line":3,"column":1}],"t":1.5,"dt":0.25}"#
        );
        let mut loc = Locator::default();
        let a = loc.locate(&Place {
            file: f.clone(),
            offset: 17,
        });
        // The ')' after "  G1 X2 (é": the é is one column.
        assert_eq!((a.line, a.column), (2, 11));
        assert_eq!(
            annotation(&a, std::slice::from_ref(&a), &NoteRules::linuxcnc()),
            " ;from p.ngc:2:11 < p.ngc:2:11"
        );
    }

    /// For GRBL, a file name's real-time bytes (`?`, `!`, `~`), control
    /// characters and non-ASCII characters become `_`: GRBL acts on them
    /// even inside a comment.
    #[test]
    fn notes_hold_nothing_the_controller_acts_on() {
        let grbl = NoteRules {
            realtime: b"?!~\x18".to_vec(),
            ascii_only: true,
            limit: Some(252),
        };
        let at = Located {
            file: "a?b!\u{7}é~.ngc".into(),
            line: 3,
            column: 1,
        };
        assert_eq!(annotation(&at, &[], &grbl), " ;from a_b____.ngc:3:1");
        assert_eq!(
            annotation(&at, &[], &NoteRules::linuxcnc()),
            " ;from a?b!?é~.ngc:3:1"
        );
    }
}
