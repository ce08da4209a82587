//! The look-ahead planner that GRBL-family firmware (and, approximately,
//! LinuxCNC) runs: a window of straight blocks, each with a length, an
//! acceleration, a cruise (nominal) speed and the highest speed it may be
//! entered at; the speeds at the junctions are planned so that the machine
//! can always stop at the end of the last block in the window.
//!
//! Speeds are in mm/s, accelerations in mm/s², lengths in mm.
//!
//! How the window moves, as GRBL 1.1h does it (`planner.c`,
//! `planner_recalculate()`, and `stepper.c`, `st_prep_buffer()`): blocks
//! arrive while the window has room; when it is full, the first block is
//! run (its speed profile is fixed from its entry speed to the entry speed
//! the plan gives the next block) and leaves, and the next block comes in.
//! Each arrival replans the window: a reverse pass (each block must be
//! able to slow down to the next block's entry speed, the last one to a
//! stop) and a forward pass (each block can only speed up so much over its
//! length). The first block's entry speed is fixed: the block before it
//! has already run to it. GRBL skips parts of these passes that cannot
//! change; the result is the same plan.

use std::collections::VecDeque;

/// One straight block of the plan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Block {
    /// Length (mm).
    pub(crate) mm: f64,
    /// Acceleration along the block (mm/s²).
    pub(crate) accel: f64,
    /// Cruise speed (mm/s).
    pub(crate) nominal: f64,
    /// Square of the highest entry speed: the junction limit, and neither
    /// this nor the previous block's cruise speed.
    pub(crate) max_entry_sqr: f64,
    /// Square of the planned entry speed.
    pub(crate) entry_sqr: f64,
    /// Square of the entry speed the reverse pass last gave it (NaN: not
    /// planned yet): where it comes out the same again, the blocks before
    /// it are planned as before.
    pub(crate) rev_sqr: f64,
    /// What the time of this block is charged to (see [`super::Charge`]).
    pub(crate) charge: super::Charge,
}

/// The window of planned blocks.
#[derive(Debug, Clone)]
pub(crate) struct Window {
    blocks: VecDeque<Block>,
    capacity: usize,
}

/// A block that has run: the block and its time (s).
pub(crate) type Ran = (Block, f64);

impl Window {
    /// A window holding at most `capacity` blocks (at least 1).
    pub(crate) fn new(capacity: usize) -> Window {
        Window {
            blocks: VecDeque::with_capacity(capacity.max(1)),
            capacity: capacity.max(1),
        }
    }

    /// Adds a block; when the window was full, the first block runs first
    /// and is returned with its time.
    pub(crate) fn push(&mut self, mut b: Block) -> Option<Ran> {
        let ran = if self.blocks.len() >= self.capacity {
            self.run_first()
        } else {
            None
        };
        if self.blocks.is_empty() {
            // From rest: nothing before it to blend with.
            b.max_entry_sqr = 0.0;
            b.entry_sqr = 0.0;
        }
        b.rev_sqr = f64::NAN;
        self.blocks.push_back(b);
        self.replan();
        ran
    }

    /// Runs the first block of the window to the entry speed the plan
    /// gives the next one (a stop when it is the last).
    pub(crate) fn run_first(&mut self) -> Option<Ran> {
        let b = self.blocks.pop_front()?;
        let exit_sqr = self.blocks.front().map_or(0.0, |n| n.entry_sqr);
        Some((b, block_time(&b, exit_sqr)))
    }

    /// Replans after an arrival, back from the new block until a block's
    /// reverse-pass entry comes out as it was (the blocks before it then
    /// plan as before: a block's reverse entry depends only on the blocks
    /// after it), and forward from there: the same plan as replanning the
    /// whole window, in O(capacity) at worst and a few blocks when the
    /// speeds are not limited by the window.
    fn replan(&mut self) {
        let n = self.blocks.len();
        if n < 2 {
            return;
        }
        // Reverse pass: the last block ends at rest; the first block's
        // entry is fixed.
        let mut from = 1;
        let mut next_rev = 0.0;
        for i in (1..n).rev() {
            let b = &mut self.blocks[i];
            let rev = b.max_entry_sqr.min(next_rev + 2.0 * b.accel * b.mm);
            if rev == b.rev_sqr {
                from = i + 1;
                break;
            }
            b.rev_sqr = rev;
            next_rev = rev;
        }
        // Forward pass: no block enters faster than the one before can
        // speed up to.
        for i in from.max(1)..n {
            let p = self.blocks[i - 1];
            let reach = p.entry_sqr + 2.0 * p.accel * p.mm;
            let b = &mut self.blocks[i];
            b.entry_sqr = b.rev_sqr.min(reach);
        }
    }
}

/// The time (s) of a block that enters at its planned entry speed, leaves
/// at `sqrt(exit_sqr)` and cruises at most at its nominal speed in between,
/// speeding up and slowing down at its acceleration: the trapezoid (or
/// triangle) GRBL's step-segment generator follows.
pub(crate) fn block_time(b: &Block, exit_sqr: f64) -> f64 {
    if b.mm <= 0.0 {
        return 0.0;
    }
    let v0s = b.entry_sqr.max(0.0);
    let v1s = exit_sqr.max(0.0);
    let vn = b.nominal;
    let a = b.accel;
    if !a.is_finite() || a <= 0.0 {
        return b.mm / vn;
    }
    let vns = vn * vn;
    let (v0, v1) = (v0s.sqrt(), v1s.sqrt());
    let up = (vns - v0s).max(0.0) / (2.0 * a);
    let down = (vns - v1s).max(0.0) / (2.0 * a);
    if up + down <= b.mm {
        return (vn - v0).max(0.0) / a + (vn - v1).max(0.0) / a + (b.mm - up - down) / vn;
    }
    // No cruise: the peak where the two ramps meet (never below either end:
    // the plan keeps |v1² - v0²| <= 2·a·mm up to rounding).
    let peak = ((2.0 * a * b.mm + v0s + v1s) / 2.0)
        .max(v0s)
        .max(v1s)
        .sqrt();
    (peak - v0) / a + (peak - v1) / a
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block(mm: f64, accel: f64, nominal: f64, max_entry: f64) -> Block {
        Block {
            mm,
            accel,
            nominal,
            max_entry_sqr: max_entry * max_entry,
            entry_sqr: 0.0,
            rev_sqr: f64::NAN,
            charge: super::super::Charge::default(),
        }
    }

    #[test]
    fn trapezoid_from_rest_to_rest() {
        // 100 mm at 10 mm/s with 10 mm/s²: 1 s and 5 mm to speed up, the
        // same to slow down, 90 mm cruising take 9 s: 11 s.
        let b = block(100.0, 10.0, 10.0, 0.0);
        assert!((block_time(&b, 0.0) - 11.0).abs() < 1e-12);
        // 1 mm never reaches 10 mm/s: a triangle peaking at
        // sqrt(a·mm) = sqrt(10) mm/s, 2·sqrt(10)/10 = 0.6325 s.
        let b = block(1.0, 10.0, 10.0, 0.0);
        assert!((block_time(&b, 0.0) - 2.0 * 10f64.sqrt() / 10.0).abs() < 1e-12);
    }

    #[test]
    fn collinear_blocks_run_as_one() {
        // Two 50 mm blocks in line (junction without limit) take what one
        // 100 mm block takes: 11 s as above.
        let mut w = Window::new(15);
        let mut total = 0.0;
        for _ in 0..2 {
            if let Some((_, t)) = w.push(block(50.0, 10.0, 10.0, f64::INFINITY)) {
                total += t;
            }
        }
        while let Some((_, t)) = w.run_first() {
            total += t;
        }
        assert!((total - 11.0).abs() < 1e-9, "{total}");
    }

    #[test]
    fn the_window_limits_the_speed() {
        // 100 blocks of 0.1 mm in line at 10 mm/s², window of 3. When a
        // block runs, the window holds it and two more; the last must end
        // at rest: its entry² is 2·10·0.1 = 2, the next-to-last's
        // 2 + 2 = 4. So every block in the middle of the run enters and
        // leaves at 2 mm/s (never near its 10 mm/s cruise) and peaks in
        // between at sqrt((2·10·0.1 + 4 + 4)/2) = sqrt(5): it takes
        // 2·(sqrt(5) − 2)/10 = 0.047214 s, where 0.1 mm at 10 mm/s would
        // take 0.01 s.
        let mut w = Window::new(3);
        let mut times = Vec::new();
        for _ in 0..100 {
            if let Some((_, t)) = w.push(block(0.1, 10.0, 10.0, f64::INFINITY)) {
                times.push(t);
            }
        }
        while let Some((_, t)) = w.run_first() {
            times.push(t);
        }
        assert_eq!(times.len(), 100);
        let expect = 2.0 * (5f64.sqrt() - 2.0) / 10.0;
        assert!((times[50] - expect).abs() < 1e-12, "{}", times[50]);
    }
}
