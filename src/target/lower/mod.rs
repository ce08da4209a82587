//! Exact lowerings: constructs a simple controller lacks, rewritten into
//! blocks it has (G0/G1/G2/G3/G4 and spindle words), with the motion
//! LinuxCNC would make. Pure functions of typed inputs; the target profile
//! decides which of them apply.

/// One word of a plain block.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Word {
    /// Upper-case letter.
    pub letter: u8,
    pub value: f64,
}

/// A block to write: words in order, values in program units, absolute
/// distance mode unless a lowering says otherwise.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PlainLine {
    pub words: Vec<Word>,
}
