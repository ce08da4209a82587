//! The pest parser generated from `grammar/ngc.pest`.

#[derive(pest_derive::Parser)]
#[grammar = "../grammar/ngc.pest"]
pub(super) struct NgcParser;
