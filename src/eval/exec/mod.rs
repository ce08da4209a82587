//! The evaluator's steps: what running a line, a statement or a call does
//! across the parts of [`super::Interp`]. Each part (the machine model in
//! `state`, parameters and expressions in `expr`, control flow in `flow`,
//! the reader in `read`, the output in `out`) has its own methods and
//! knows nothing of `Interp`; only the steps here (and the entry points in
//! `eval/mod.rs`) hold all of them, and each hands a part method the
//! other parts it reads or changes as arguments. The steps also read the
//! parts' fields and set single ones (the cursor, a flag, a buffer taken
//! and put back); a change of more than one field is the part's method. One file a
//! kind of step; ARCHITECTURE.md says what each holds.

mod call;
mod control;
mod expr;
mod handoff;
mod lathe;
mod line;
mod restore;
mod straight;
mod words;
