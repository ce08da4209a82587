//! Lathe diameter mode (G7) into radius mode (G8, the only mode of
//! GRBL-class controllers).
//!
//! The rule (LinuxCNC 2.9, checked against rs274): in G7 an X word of a
//! motion block is a diameter, so the X position it names is half of it —
//! in G90 the X coordinate, in G91 the X step. Nothing else is halved: an
//! arc's I offset is a radius offset both in incremental (G91.1) and
//! absolute (G90.1) arc-centre mode, and R is a radius. The lowered block
//! is the same block with each X word halved, run in radius mode.

use super::PlainLine;

/// The X position or step an X word names in G7.
pub fn radius_from_diameter(x_word: f64) -> f64 {
    x_word / 2.0
}

/// Rewrites a motion block written for G7 into the same block for radius
/// mode: every X word halved, every other word (I, K, R, …) unchanged.
pub fn radius_words(line: &mut PlainLine) {
    for w in &mut line.words {
        if w.letter == b'X' {
            w.value = radius_from_diameter(w.value);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::controller::lower::Word;

    #[test]
    fn only_x_is_halved() {
        let mut l = PlainLine {
            words: vec![
                Word {
                    letter: b'G',
                    value: 2.0,
                },
                Word {
                    letter: b'X',
                    value: 20.0,
                },
                Word {
                    letter: b'Z',
                    value: 3.0,
                },
                Word {
                    letter: b'I',
                    value: 5.0,
                },
            ],
        };
        radius_words(&mut l);
        let v: Vec<f64> = l.words.iter().map(|w| w.value).collect();
        assert_eq!(v, [2.0, 10.0, 3.0, 5.0]);
    }
}
