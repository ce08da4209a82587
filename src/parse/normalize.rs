//! LinuxCNC-style line processing: blanks removed and letters lower-cased
//! outside comments, comments kept verbatim, comment nesting checked.

use crate::diag::ErrorKind;
use crate::diag::SyntaxError;

/// A processed line and, for each of its bytes, the byte offset of that byte in
/// the raw line (plus one final entry for the end of the line).
#[derive(Debug, Default)]
pub(crate) struct Normalized {
    pub text: String,
    pub map: Vec<u32>,
}

impl Normalized {
    /// Offset in the raw line of processed byte `i` (`i == len` is the end).
    pub(crate) fn raw_offset(&self, i: usize) -> u32 {
        self.map[i.min(self.map.len() - 1)]
    }
}

/// Lexical error found while processing: kind and raw byte offset in the line.
pub(crate) type LexError = (ErrorKind, u32);

/// Processes a raw line (without its line terminator; trailing blanks allowed).
pub(crate) fn normalize(raw: &[u8], out: &mut Normalized) -> Result<(), LexError> {
    out.text.clear();
    out.map.clear();
    let mut bytes: Vec<u8> = std::mem::take(&mut out.text).into_bytes();
    let mut i = 0;
    let mut paren_start: Option<usize> = None;
    while i < raw.len() {
        let c = raw[i];
        if let Some(start) = paren_start {
            if c == b'(' {
                return Err((ErrorKind::Syntax(SyntaxError::NestedComment), i as u32));
            }
            bytes.push(c);
            out.map.push(i as u32);
            if c == b')' {
                let _ = start;
                paren_start = None;
            }
            i += 1;
            continue;
        }
        match c {
            b' ' | b'\t' | b'\r' => {}
            b'(' => {
                paren_start = Some(i);
                bytes.push(c);
                out.map.push(i as u32);
            }
            b';' => {
                // The rest of the line is a comment, copied verbatim.
                for (k, &b) in raw[i..].iter().enumerate() {
                    bytes.push(b);
                    out.map.push((i + k) as u32);
                }
                i = raw.len();
                continue;
            }
            _ => {
                bytes.push(c.to_ascii_lowercase());
                out.map.push(i as u32);
            }
        }
        i += 1;
    }
    if let Some(start) = paren_start {
        return Err((
            ErrorKind::Syntax(SyntaxError::UnclosedComment),
            start as u32,
        ));
    }
    out.map.push(raw.len() as u32);
    // Bytes that are not UTF-8 are kept (as '?') inside comments, whose raw
    // text is what gets written; outside comments they are bad characters.
    loop {
        match std::str::from_utf8(&bytes) {
            Ok(_) => break,
            Err(e) => {
                let pos = e.valid_up_to();
                let raw_pos = out.map[pos] as usize;
                if in_comment(&bytes, pos) {
                    let len = e.error_len().unwrap_or(bytes.len() - pos);
                    for b in &mut bytes[pos..pos + len] {
                        *b = b'?';
                    }
                } else {
                    let byte = raw[raw_pos];
                    return Err((
                        ErrorKind::Syntax(SyntaxError::BadCharacter {
                            ch: byte as char,
                            byte,
                        }),
                        raw_pos as u32,
                    ));
                }
            }
        }
    }
    out.text = String::from_utf8(bytes).unwrap_or_default();
    Ok(())
}

/// Whether byte `pos` of a processed line lies inside a comment.
fn in_comment(processed: &[u8], pos: usize) -> bool {
    let mut paren = false;
    for &b in &processed[..pos] {
        match b {
            b'(' if !paren => paren = true,
            b')' if paren => paren = false,
            b';' if !paren => return true,
            _ => {}
        }
    }
    paren
}

#[cfg(test)]
mod tests {
    use super::*;

    fn norm(s: &str) -> String {
        let mut n = Normalized::default();
        normalize(s.as_bytes(), &mut n).unwrap();
        n.text
    }

    #[test]
    fn folds_blanks_and_case_outside_comments() {
        assert_eq!(norm("G0 X 1 0"), "g0x10");
        assert_eq!(norm("G0 (Keep Case) X1"), "g0(Keep Case)x1");
        assert_eq!(
            norm("#<P a R am > = 1 ; Rest Here"),
            "#<param>=1; Rest Here"
        );
        assert_eq!(norm("\tG1\r"), "g1");
    }

    #[test]
    fn maps_back_to_raw_offsets() {
        let mut n = Normalized::default();
        normalize(b"G0 X 1", &mut n).unwrap();
        assert_eq!(n.raw_offset(2), 3);
        assert_eq!(n.raw_offset(3), 5);
        assert_eq!(n.raw_offset(4), 6);
    }

    #[test]
    fn comment_errors() {
        let mut n = Normalized::default();
        assert!(matches!(
            normalize(b"(a (b))", &mut n),
            Err((ErrorKind::Syntax(SyntaxError::NestedComment), 3))
        ));
        assert!(matches!(
            normalize(b"G0 (open", &mut n),
            Err((ErrorKind::Syntax(SyntaxError::UnclosedComment), 3))
        ));
        assert!(normalize(b"; ( unbalanced", &mut n).is_ok());
        assert!(normalize(b"G0 (\xff\xfe) X1", &mut n).is_ok());
        assert!(normalize(b"G0 ;\xc3", &mut n).is_ok());
        assert!(matches!(
            normalize(b"G0 X1 \xc3", &mut n),
            Err((ErrorKind::Syntax(SyntaxError::BadCharacter { .. }), 6))
        ));
    }
}
