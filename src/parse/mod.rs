//! Line parsing: raw bytes → processed line → pest pairs → typed AST.

pub(crate) mod ast;
pub(crate) mod code;
mod grammar;
mod lower;
mod name;
pub(crate) mod named2007;
pub(crate) mod normalize;
mod quick;

use crate::diag::SyntaxError;
use pest::Parser as _;

pub use lower::{integer_value, parse_number};
pub use name::Name;

use crate::diag::ErrorKind;
use ast::{Line, LineKind, Span};
use grammar::{NgcParser, Rule};
use normalize::{Normalized, normalize};

/// The longest raw line the reference accepts (without the newline).
pub const MAX_LINE: usize = 252;

/// A line that could not be parsed.
#[derive(Debug, Clone, PartialEq)]
pub struct LineError {
    pub kind: ErrorKind,
    pub span: Span,
    /// The reference reports this even on lines it skips (comment and length
    /// checks, malformed O-words).
    pub when_skipped: bool,
}

impl LineError {
    fn new(kind: ErrorKind, span: Span, when_skipped: bool) -> LineError {
        LineError {
            kind,
            span,
            when_skipped,
        }
    }
}

/// Reusable scratch space for parsing, and the syntax it reads.
#[derive(Default)]
pub struct LineParser {
    norm: Normalized,
    /// Whether lines are read in the 2007 named-parameter syntax too.
    named2007: bool,
}

fn describe(rules: &[Rule]) -> String {
    let mut parts: Vec<&str> = Vec::new();
    let mut add = |s: &'static str| {
        if !parts.contains(&s) {
            parts.push(s);
        }
    };
    for r in rules {
        match r {
            Rule::binop => add("an operator or ']'"),
            Rule::number
            | Rule::param
            | Rule::bracket
            | Rule::unary_minus
            | Rule::unary_plus
            | Rule::atan
            | Rule::exists
            | Rule::unary_fn
            | Rule::fn_name
            | Rule::named => add("a value (number, #parameter, [expression] or function)"),
            Rule::word | Rule::letter => add("a word (letter and value)"),
            Rule::assignment => add("a parameter setting"),
            Rule::paren_comment | Rule::semi_comment | Rule::comment_text => add("a comment"),
            Rule::o_label => add("an O-word label"),
            Rule::EOI => add("end of line"),
            _ => add("valid G-code"),
        }
    }
    if parts.is_empty() {
        "valid G-code".to_string()
    } else {
        parts.join(" or ")
    }
}

fn is_gcode_char(c: u8) -> bool {
    c.is_ascii_alphanumeric() || b".+-*/#<>[]()=;%$@^_".contains(&c)
}

impl LineParser {
    /// A parser of LinuxCNC's syntax, and with `named2007` of the 2007
    /// named-parameter syntax too.
    pub fn new(named2007: bool) -> LineParser {
        LineParser {
            named2007,
            ..LineParser::default()
        }
    }

    /// Whether it reads the 2007 named-parameter syntax.
    pub fn named2007(&self) -> bool {
        self.named2007
    }

    /// Parses one raw line (without terminator). `terminated` tells whether a
    /// newline followed it, which matters for the length limit.
    pub fn parse(&mut self, raw: &[u8], terminated: bool) -> Result<Line, LineError> {
        self.parse_with(raw, terminated, true)
    }

    /// [`LineParser::parse`]; with `quick`, a call with plain numbers as
    /// arguments is read without the grammar (see [`quick`]).
    fn parse_with(&mut self, raw: &[u8], terminated: bool, quick: bool) -> Result<Line, LineError> {
        let len = raw.len() + terminated as usize;
        if len > MAX_LINE + 1 {
            return Err(LineError::new(
                ErrorKind::Syntax(SyntaxError::CommandTooLong),
                Span::new(MAX_LINE as u32, raw.len() as u32),
                true,
            ));
        }
        if let Err((kind, at)) = normalize(raw, &mut self.norm) {
            return Err(LineError::new(kind, Span::new(at, at + 1), true));
        }
        if self.named2007
            && let Some((text, map)) = named2007::rewrite(&self.norm.text, &self.norm.map)
        {
            self.norm.text = text;
            self.norm.map = map;
        }
        let text = self.norm.text.as_str();
        if text.is_empty() {
            return Ok(Line {
                kind: LineKind::Blank,
                block_delete: false,
                line_number: None,
            });
        }
        if text == "%" {
            return Ok(Line {
                kind: LineKind::Percent,
                block_delete: false,
                line_number: None,
            });
        }
        if quick && let Some(line) = quick::call_line(&self.norm) {
            return Ok(line);
        }
        match NgcParser::parse(Rule::line, text) {
            Ok(mut pairs) => {
                let pair = pairs.next().expect("line");
                let lowerer = lower::Lowerer { norm: &self.norm };
                let is_o = pair
                    .clone()
                    .into_inner()
                    .any(|p| p.as_rule() == Rule::o_line);
                lowerer
                    .lower_line(pair)
                    .map_err(|(kind, span)| LineError::new(kind, span, is_o))
            }
            Err(e) => {
                let pos = match e.location {
                    pest::error::InputLocation::Pos(p) => p,
                    pest::error::InputLocation::Span((p, _)) => p,
                };
                let raw_at = self.norm.raw_offset(pos);
                let span = Span::new(raw_at, raw_at + 1);
                let bytes = text.as_bytes();
                // An O-line the grammar rejects is malformed even when skipped.
                let start = text.trim_start_matches('/');
                let start =
                    start.trim_start_matches(|c: char| c == 'n' || c.is_ascii_digit() || c == '.');
                let is_o = start.starts_with('o');
                if pos < bytes.len() {
                    let c = bytes[pos];
                    if !is_gcode_char(c) || c == b'%' || c == b'o' || c == b'n' {
                        let ch = text[pos..].chars().next().unwrap_or('?');
                        return Err(LineError::new(
                            ErrorKind::Syntax(SyntaxError::BadCharacter { ch, byte: c }),
                            span,
                            is_o,
                        ));
                    }
                }
                let expected = match &e.variant {
                    pest::error::ErrorVariant::ParsingError { positives, .. } => {
                        describe(positives)
                    }
                    pest::error::ErrorVariant::CustomError { message } => message.clone(),
                };
                Err(LineError::new(
                    ErrorKind::Syntax(SyntaxError::Syntax { expected }),
                    span,
                    is_o,
                ))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A call written with blanks and letter case anywhere, and arguments
    /// that are numbers (some malformed), sometimes followed by something
    /// else.
    fn call_text() -> impl Strategy<Value = String> {
        let arg = prop_oneof![
            "[+-]?[0-9]{0,4}(\\.[0-9]{0,4})?",
            "[+-]?\\.?[0-9]{1,3}\\.?",
            Just("1+2".to_string()),
            Just("#1".to_string()),
        ];
        (
            prop_oneof![
                "[a-zA-Z0-9_]{1,8}".prop_map(|n| format!("<{n}>")),
                Just("<a b>".to_string()),
                Just("<>".to_string()),
                Just("100".to_string()),
            ],
            proptest::collection::vec(arg, 0..33),
            prop_oneof![
                4 => Just(String::new()),
                1 => Just(" (c)".to_string()),
                1 => Just(" x".to_string()),
                1 => Just(" ;c".to_string()),
            ],
            proptest::collection::vec(0usize..3, 48),
            any::<bool>(),
        )
            .prop_map(|(label, args, tail, blanks, upper)| {
                let mut s = format!("o{label} call");
                for a in &args {
                    s.push_str(&format!(" [{a}]"));
                }
                s.push_str(&tail);
                // Blanks spread over the line (outside the comment).
                let mut out = String::new();
                for (k, c) in s.char_indices() {
                    if c == '(' || c == ';' {
                        out.push_str(&s[k..]);
                        break;
                    }
                    out.push_str(&" ".repeat(blanks[k % blanks.len()] & usize::from(k % 5 == 0)));
                    out.push(if upper { c.to_ascii_uppercase() } else { c });
                }
                out
            })
    }

    proptest! {
        /// A call read the quick way is the line the grammar makes of it,
        /// and so is the error of one that is not.
        #[test]
        fn quick_calls_read_as_the_grammar_reads_them(text in call_text(), named2007 in any::<bool>()) {
            let mut p = LineParser::new(named2007);
            let quick = p.parse_with(text.as_bytes(), true, true);
            let grammar = p.parse_with(text.as_bytes(), true, false);
            prop_assert_eq!(quick, grammar, "{:?}", text);
        }
    }

    #[test]
    fn a_call_of_numbers_is_read_quickly() {
        let mut norm = Normalized::default();
        normalize::normalize(b"O<Hole> Call [1.5] [-2] [+.5]", &mut norm).unwrap();
        let line = quick::call_line(&norm).expect("quick");
        let LineKind::O(o) = line.kind else {
            panic!("{line:?}")
        };
        assert_eq!(o.label, ast::Label::Static(Name::new("hole")));
        let values: Vec<_> = o.args.iter().map(|a| a.kind.clone()).collect();
        use ast::ExprKind::Num;
        assert_eq!(values, [Num(1.5), Num(-2.0), Num(0.5)]);
        assert_eq!(o.args[1].span, Span::new(19, 23));
        for other in [
            "o<a>call[1+2]",
            "o100call[1]",
            "o<a>call[1](c)",
            "o<a>call[.]",
        ] {
            normalize::normalize(other.as_bytes(), &mut norm).unwrap();
            assert!(quick::call_line(&norm).is_none(), "{other}");
        }
    }
}
