//! The random source of the generated suites: splitmix64, seeded from a
//! case number so that a failing case can be run again alone.

pub struct Rng(pub u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x2545_F491_4F6C_DD1D) ^ 0x9E37_79B9_7F4A_7C15)
    }

    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [0, n) (0 when n is 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    pub fn chance(&mut self, p: f64) -> bool {
        self.unit() < p
    }

    /// Uniform in [lo, hi).
    pub fn float(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    /// Uniform in [lo, hi], both included.
    pub fn int(&mut self, lo: usize, hi: usize) -> usize {
        lo + self.below(hi - lo + 1)
    }

    /// A value in [lo, hi] with three decimals.
    pub fn milli(&mut self, lo: f64, hi: f64) -> f64 {
        let (lo, hi) = ((lo * 1000.0).round() as i64, (hi * 1000.0).round() as i64);
        (lo + self.below((hi - lo + 1) as usize) as i64) as f64 / 1000.0
    }

    pub fn pick<'a, T>(&mut self, xs: &'a [T]) -> &'a T {
        &xs[self.below(xs.len())]
    }
}

#[test]
fn ranges_hold_and_streams_repeat() {
    let (mut a, mut b) = (Rng::new(7), Rng::new(7));
    for _ in 0..10_000 {
        assert_eq!(a.next(), b.next());
        let u = a.unit();
        assert!((0.0..1.0).contains(&u));
        let i = a.int(3, 5);
        assert!((3..=5).contains(&i));
        let f = a.float(-2.0, 2.0);
        assert!((-2.0..2.0).contains(&f));
        let m = a.milli(0.5, 0.7);
        assert!((0.5..=0.7).contains(&m));
        assert!((m * 1000.0 - (m * 1000.0).round()).abs() < 1e-9);
        b = Rng(a.0);
    }
    assert_eq!(Rng::new(1).below(0), 0);
}
