//! ngcflat: LinuxCNC-dialect G-code in, straight-line G-code out.
//!
//! Pipeline: `source` (program text) → [`parse`] (typed line AST) →
//! [`program`] (file index, subroutine loader) → [`eval`] (machine state,
//! control flow, parameters and expressions) → [`emit`] (numbers, output
//! sink), or a consumer: [`controller`] lowering, `view`. The `flatten` module ties
//! them together; [`diag`] holds every error and warning; [`cli`] is the
//! command line. The modules form layers without cycles, listed in
//! ARCHITECTURE.md.

#![deny(unreachable_pub)]

pub mod block;
pub mod cli;
mod codes;
pub(crate) mod config;
pub mod controller;
pub mod diag;
pub mod emit;
pub(crate) mod eval;
mod flatten;
mod fx_hasher;
pub mod geom;
mod library;
mod machine;
mod number;
pub mod parse;
pub mod program;
mod rules;
mod runtime;
pub mod settings;
mod source;
mod view;

pub use diag::{report, report_summary, write_stderr};
pub use flatten::{
    flatten, flatten_memory, flatten_str, flatten_with, lowering, read_source, read_source_limited,
    refuse_binary,
};
