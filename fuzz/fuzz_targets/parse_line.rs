//! One raw line, any bytes, with and without a terminating newline: the line
//! parser must return `Ok` or `Err`, never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use ngcflat::parse::LineParser;

fuzz_target!(|data: &[u8]| {
    let mut parser = LineParser::default();
    let _ = parser.parse(data, false);
    // Reuse the same scratch space, as the file index does.
    let _ = parser.parse(data, true);
    // A line never contains its terminator; feed the part before the first
    // newline as well so long multi-line inputs still reach the grammar.
    if let Some(i) = data.iter().position(|&b| b == b'\n') {
        let _ = parser.parse(&data[..i], true);
    }
});
