//! pest pairs → typed AST. One `lower_<rule>` function per grammar rule.

use crate::diag::{OWordError, SyntaxError};
use pest::iterators::Pair;

use super::Name;
use super::ast::*;
use super::code::compile;
use super::grammar::Rule;
use super::normalize::Normalized;
use crate::diag::ErrorKind;

/// Error while lowering: kind and span in raw-line offsets.
pub(super) type LowerError = (ErrorKind, Span);

pub(super) struct Lowerer<'n> {
    pub norm: &'n Normalized,
}

impl Lowerer<'_> {
    fn raw_end(&self, pair: &Pair<'_, Rule>) -> u32 {
        // Offset just after the last processed byte of the pair.
        let e = pair.as_span().end();
        if e == 0 {
            0
        } else {
            self.norm.raw_offset(e - 1) + 1
        }
    }

    fn tight_span(&self, pair: &Pair<'_, Rule>) -> Span {
        let s = pair.as_span();
        Span::new(self.norm.raw_offset(s.start()), self.raw_end(pair))
    }

    pub(super) fn lower_line(&self, pair: Pair<'_, Rule>) -> Result<Line, LowerError> {
        let mut block_delete = false;
        let mut line_number = None;
        let mut kind = LineKind::Blank;
        for p in pair.into_inner() {
            match p.as_rule() {
                Rule::block_delete => block_delete = true,
                Rule::line_number => line_number = Some(self.tight_span(&p)),
                Rule::items => {
                    let items = self.lower_items(p)?;
                    if !items.is_empty() {
                        kind = LineKind::Items(items);
                    }
                }
                Rule::o_line => kind = LineKind::O(self.lower_o_line(p)?),
                Rule::m98_line => kind = LineKind::M98(self.lower_m98_line(p)?),
                Rule::EOI => {}
                r => unreachable!("{r:?} in lower_line"),
            }
        }
        Ok(Line {
            kind,
            block_delete,
            line_number,
        })
    }

    fn lower_items(&self, pair: Pair<'_, Rule>) -> Result<Vec<Item>, LowerError> {
        let mut out = Vec::new();
        for p in pair.into_inner() {
            out.push(self.lower_item(p)?);
        }
        Ok(out)
    }

    fn lower_item(&self, p: Pair<'_, Rule>) -> Result<Item, LowerError> {
        Ok(match p.as_rule() {
            Rule::word => Item::Word(self.lower_word(p)?),
            Rule::assignment => Item::Assign(self.lower_assignment(p)?),
            Rule::paren_comment | Rule::semi_comment => Item::Comment(self.lower_comment(p)),
            r => unreachable!("{r:?} in lower_item"),
        })
    }

    fn lower_word(&self, p: Pair<'_, Rule>) -> Result<Word, LowerError> {
        let span = self.tight_span(&p);
        let mut it = p.into_inner();
        let letter = it.next().expect("letter").as_str().as_bytes()[0];
        let vp = it.next().expect("value");
        let literal = vp.as_rule() == Rule::number;
        let value = compile(self.lower_value(vp)?);
        Ok(Word {
            letter,
            span,
            value,
            literal,
        })
    }

    fn lower_assignment(&self, p: Pair<'_, Rule>) -> Result<Assign, LowerError> {
        let span = self.tight_span(&p);
        let mut it = p.into_inner();
        let tp = it.next().expect("target");
        let target_span = self.tight_span(&tp);
        let target = self.lower_param_target(tp)?;
        let value = compile(self.lower_value(it.next().expect("value"))?);
        Ok(Assign {
            target,
            target_span,
            value,
            span,
        })
    }

    fn lower_comment(&self, p: Pair<'_, Rule>) -> Comment {
        let span = self.tight_span(&p);
        if p.as_rule() == Rule::semi_comment {
            return Comment {
                kind: CommentKind::Semicolon,
                span,
                body: span,
            };
        }
        let inner = p.into_inner().next().expect("comment_text");
        let text = inner.as_str();
        let text_start = self.norm.raw_offset(inner.as_span().start());
        let trimmed = text.trim_start_matches([' ', '\t']);
        let lead = (text.len() - trimmed.len()) as u32;
        let lower = trimmed
            .get(..trimmed.len().min(10))
            .unwrap_or("")
            .to_ascii_lowercase();
        let keywords: [(&str, CommentKind); 10] = [
            ("msg,", CommentKind::Msg),
            ("debug,", CommentKind::Debug),
            ("print,", CommentKind::Print),
            ("logopen,", CommentKind::LogOpen),
            ("logappend,", CommentKind::LogAppend),
            ("log,", CommentKind::Log),
            ("abort,", CommentKind::Abort),
            ("pyrun,", CommentKind::Python),
            ("py,", CommentKind::Python),
            ("pyreload", CommentKind::Python),
        ];
        for (kw, kind) in keywords {
            if lower.starts_with(kw) {
                let body_start = text_start + lead + kw.len() as u32;
                let body_end = text_start + text.len() as u32;
                return Comment {
                    kind,
                    span,
                    body: Span::new(body_start, body_end),
                };
            }
        }
        if trimmed.eq_ignore_ascii_case("logclose") {
            return Comment {
                kind: CommentKind::LogClose,
                span,
                body: span,
            };
        }
        Comment {
            kind: CommentKind::Plain,
            span,
            body: span,
        }
    }

    fn lower_param_target(&self, p: Pair<'_, Rule>) -> Result<ParamRef, LowerError> {
        if p.as_rule() == Rule::named {
            let s = p.as_str();
            let name = &s[1..s.len() - 1];
            return Ok(ParamRef::Named(Name::new(name)));
        }
        Ok(ParamRef::Numbered(self.lower_value(p)?))
    }

    pub(super) fn lower_value(&self, p: Pair<'_, Rule>) -> Result<Expr, LowerError> {
        let span = self.tight_span(&p);
        let kind = match p.as_rule() {
            Rule::number => ExprKind::Num(self.lower_number(&p)?),
            Rule::unary_minus => {
                let inner = self.lower_value(p.into_inner().next().expect("operand"))?;
                match inner.kind {
                    // `-0.1`: the negated literal (same value, same checks).
                    ExprKind::Num(v) => ExprKind::Num(-v),
                    _ => ExprKind::Neg(Box::new(inner)),
                }
            }
            Rule::unary_plus => return self.lower_value(p.into_inner().next().expect("operand")),
            Rule::param => {
                let t = p.into_inner().next().expect("target");
                match self.lower_param_target(t)? {
                    ParamRef::Numbered(Expr {
                        kind: ExprKind::Num(v),
                        ..
                    }) if v.fract() == 0.0 && (1.0..5000.0).contains(&v) => {
                        ExprKind::Slot(v as u16)
                    }
                    r => ExprKind::Param(Box::new(r)),
                }
            }
            Rule::bracket => {
                let e = p.into_inner().next().expect("expr");
                let mut inner = self.lower_expr(e)?;
                inner.span = span;
                if let ExprKind::Bin(_, _, checked) = &mut inner.kind {
                    *checked = true;
                }
                return Ok(inner);
            }
            Rule::atan => {
                let mut it = p.into_inner();
                let y = self.lower_value(it.next().expect("y"))?;
                let x = self.lower_value(it.next().expect("x"))?;
                ExprKind::Atan(Box::new((y, x)))
            }
            Rule::exists => {
                let param = p.into_inner().next().expect("param");
                let t = param.into_inner().next().expect("target");
                ExprKind::Exists(Box::new(self.lower_param_target(t)?))
            }
            Rule::unary_fn => {
                let mut it = p.into_inner();
                let f = match it.next().expect("name").as_str() {
                    "abs" => Func::Abs,
                    "acos" => Func::Acos,
                    "asin" => Func::Asin,
                    "cos" => Func::Cos,
                    "exp" => Func::Exp,
                    "fix" => Func::Fix,
                    "fup" => Func::Fup,
                    "ln" => Func::Ln,
                    "round" => Func::Round,
                    "sin" => Func::Sin,
                    "sqrt" => Func::Sqrt,
                    "tan" => Func::Tan,
                    other => unreachable!("{other} in lower_unary_fn"),
                };
                ExprKind::Func(f, Box::new(self.lower_value(it.next().expect("arg"))?))
            }
            r => unreachable!("{r:?} in lower_value"),
        };
        Ok(Expr { kind, span })
    }

    fn lower_number(&self, p: &Pair<'_, Rule>) -> Result<f64, LowerError> {
        let text = p.as_str();
        parse_number(text).map_err(|k| (k, self.tight_span(p)))
    }

    fn lower_expr(&self, p: Pair<'_, Rule>) -> Result<Expr, LowerError> {
        let mut operands: Vec<Expr> = Vec::new();
        let mut ops: Vec<BinOp> = Vec::new();
        for q in p.into_inner() {
            if q.as_rule() == Rule::binop {
                let op = match q.as_str() {
                    "**" => BinOp::Pow,
                    "*" => BinOp::Mul,
                    "/" => BinOp::Div,
                    "mod" => BinOp::Mod,
                    "+" => BinOp::Add,
                    "-" => BinOp::Sub,
                    "eq" => BinOp::Eq,
                    "ne" => BinOp::Ne,
                    "gt" => BinOp::Gt,
                    "ge" => BinOp::Ge,
                    "lt" => BinOp::Lt,
                    "le" => BinOp::Le,
                    "and" => BinOp::And,
                    "or" => BinOp::Or,
                    "xor" => BinOp::Xor,
                    other => unreachable!("{other} in lower_expr"),
                };
                while let Some(&top) = ops.last() {
                    if op.precedence() <= top.precedence() {
                        reduce(&mut operands, &mut ops);
                    } else {
                        break;
                    }
                }
                ops.push(op);
            } else {
                operands.push(self.lower_value(q)?);
            }
        }
        while !ops.is_empty() {
            reduce(&mut operands, &mut ops);
        }
        Ok(operands.pop().expect("expression operand"))
    }

    fn lower_o_line(&self, p: Pair<'_, Rule>) -> Result<OLine, LowerError> {
        let mut it = p.into_inner();
        let lp = it.next().expect("o_label");
        let label_span = self.tight_span(&lp);
        let inner = lp.into_inner().next().expect("label");
        let label = if inner.as_rule() == Rule::named {
            let s = inner.as_str();
            Label::Static(Name::new(&s[1..s.len() - 1]))
        } else if inner.as_rule() == Rule::number {
            let v = self.lower_number(&inner)?;
            let n = integer_value(v).map_err(|k| (k, label_span))?;
            Label::Static(Name::new(&n.to_string()))
        } else {
            Label::Dynamic(self.lower_value(inner)?)
        };
        let cp = it.next().expect("o_cmd");
        let cmd_span = self.tight_span(&cp);
        let rule = cp.as_rule();
        let Some(kind) = o_kind(rule) else {
            return Err((
                ErrorKind::OWord(OWordError::UnknownOCommand {
                    word: cp.as_str().to_string(),
                }),
                cmd_span,
            ));
        };
        let mut expr = None;
        let mut args = Vec::new();
        let mut exec_error = None;
        let mut active_comment = false;
        let cmd_end = self.raw_end(&cp);
        for q in cp.into_inner() {
            match q.as_rule() {
                Rule::bracket => {
                    let e = compile(self.lower_value(q)?);
                    if kind == OKind::Call {
                        args.push(e);
                    } else {
                        expr = Some(e);
                    }
                }
                Rule::paren_comment => {
                    active_comment |= self.lower_comment(q).kind != CommentKind::Plain;
                }
                r => unreachable!("{r:?} in lower_o_line args"),
            }
        }
        if args.len() > 30 {
            exec_error = Some((ErrorKind::OWord(OWordError::TooManyArgs), args[30].span));
        }
        let needs_bracket = match kind {
            OKind::While => Some("while"),
            OKind::Repeat => Some("repeat"),
            OKind::If => Some("if"),
            OKind::ElseIf => Some("elseif"),
            _ => None,
        };
        if let (Some(keyword), None) = (needs_bracket, &expr) {
            // A bracket that is there but holds no valid expression, or none.
            let bracket = it
                .clone()
                .next()
                .and_then(|t| t.into_inner().find(|q| q.as_rule() == Rule::o_garbage))
                .filter(|g| g.as_str().starts_with('['));
            exec_error = Some(match bracket {
                Some(g) => (
                    ErrorKind::OWord(OWordError::BadCondition { keyword }),
                    Span::new(self.norm.raw_offset(g.as_span().start()), self.raw_end(&g)),
                ),
                None => (
                    ErrorKind::OWord(OWordError::MissingBracket { keyword }),
                    Span::new(cmd_end, cmd_end + 1),
                ),
            });
        }
        let trail = it.next().expect("o_trail");
        for q in trail.into_inner() {
            match q.as_rule() {
                Rule::paren_comment => {
                    active_comment |= self.lower_comment(q).kind != CommentKind::Plain;
                }
                Rule::semi_comment => {}
                Rule::o_garbage => {
                    if !q.as_str().is_empty() && exec_error.is_none() {
                        let kind =
                            if kind == OKind::Call && q.as_str().starts_with(|c: char| c != '[') {
                                ErrorKind::OWord(OWordError::CallArgNotBracketed)
                            } else {
                                ErrorKind::OWord(OWordError::UnexpectedAfterOWord)
                            };
                        exec_error = Some((kind, self.tight_span(&q)));
                    }
                }
                r => unreachable!("{r:?} in lower_o_trail"),
            }
        }
        Ok(OLine {
            label,
            label_span,
            kind,
            expr,
            args,
            active_comment,
            exec_error: exec_error.map(Box::new),
        })
    }

    fn lower_m98_line(&self, p: Pair<'_, Rule>) -> Result<M98Line, LowerError> {
        let items = self.lower_items(p.into_inner().next().expect("items"))?;
        let mut pw = None;
        let mut lw = None;
        for it in &items {
            if let Item::Word(w) = it {
                match w.letter {
                    b'p' if pw.is_none() => pw = Some(w.value.clone()),
                    b'l' if lw.is_none() => lw = Some(w.value.clone()),
                    b'p' | b'l' => {
                        return Err((
                            ErrorKind::Syntax(SyntaxError::DuplicateWord {
                                letter: w.letter as char,
                            }),
                            w.value.span,
                        ));
                    }
                    _ => {}
                }
            }
        }
        Ok(M98Line {
            p: pw,
            l: lw,
            items,
        })
    }
}

fn reduce(operands: &mut Vec<Expr>, ops: &mut Vec<BinOp>) {
    let op = ops.pop().expect("operator");
    let b = operands.pop().expect("right operand");
    let a = operands.pop().expect("left operand");
    let span = Span::new(a.span.start, b.span.end);
    operands.push(Expr {
        kind: ExprKind::Bin(op, Box::new((a, b)), false),
        span,
    });
}

/// Reads a number lexeme (`-1.5`, `.5`, `+3.`).
pub fn parse_number(text: &str) -> Result<f64, ErrorKind> {
    let digits = text.trim_start_matches(['+', '-']);
    if digits.bytes().filter(|&b| b == b'.').count() > 1 {
        return Err(ErrorKind::Syntax(SyntaxError::TrailingNumber {
            text: text.to_string(),
        }));
    }
    if !digits.bytes().any(|b| b.is_ascii_digit()) {
        return Err(ErrorKind::Syntax(SyntaxError::BadNumber {
            text: text.to_string(),
        }));
    }
    text.parse::<f64>().map_err(|_| {
        ErrorKind::Syntax(SyntaxError::BadNumber {
            text: text.to_string(),
        })
    })
}

/// The reference's integer rule: within 0.0001 of an integer.
pub fn integer_value(v: f64) -> Result<i64, ErrorKind> {
    // Whole numbers (nearly all) without a call to floor.
    let i = v as i64;
    if i as f64 == v && v.abs() < 9.0e15 {
        return Ok(i);
    }
    let f = v.floor();
    let frac = v - f;
    if frac > 0.9999 {
        Ok(f as i64 + 1)
    } else if frac > 0.0001 || !v.is_finite() {
        Err(ErrorKind::Syntax(SyntaxError::NonInteger { value: v }))
    } else {
        Ok(f as i64)
    }
}

/// The O-word command a grammar rule stands for (`None`: an unknown one).
fn o_kind(rule: Rule) -> Option<OKind> {
    Some(match rule {
        Rule::o_sub => OKind::Sub,
        Rule::o_endsub => OKind::EndSub,
        Rule::o_call => OKind::Call,
        Rule::o_do => OKind::Do,
        Rule::o_while => OKind::While,
        Rule::o_repeat => OKind::Repeat,
        Rule::o_if => OKind::If,
        Rule::o_elseif => OKind::ElseIf,
        Rule::o_else => OKind::Else,
        Rule::o_endif => OKind::EndIf,
        Rule::o_break => OKind::Break,
        Rule::o_continue => OKind::Continue,
        Rule::o_endwhile => OKind::EndWhile,
        Rule::o_endrepeat => OKind::EndRepeat,
        Rule::o_return => OKind::Return,
        Rule::o_bare => OKind::Bare,
        Rule::o_unknown => return None,
        r => unreachable!("{r:?} in lower_o_line"),
    })
}
