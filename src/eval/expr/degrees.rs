//! Trigonometry in degrees as LinuxCNC computes it: the argument and the
//! result pass through x87 extended precision (64-bit significand) before
//! the final rounding to double. Emulated with double-double arithmetic, so
//! that `SIN[30]` is exactly 0.5, `TAN[45]` exactly 1 and `TAN[90]` the same
//! huge finite value the reference gives.

#[derive(Debug, Clone, Copy)]
struct Dd {
    hi: f64,
    lo: f64,
}

/// M_PIl: π rounded to a 64-bit significand, as hi + lo exactly.
const PI64: Dd = Dd {
    hi: std::f64::consts::PI,
    lo: 1.22514845490862e-16,
};
/// π/2 to about 160 bits, for argument reduction.
const PIO2: [f64; 3] = [
    std::f64::consts::FRAC_PI_2,
    6.123233995736766e-17,
    -1.4973849048591698e-33,
];

fn two_sum(a: f64, b: f64) -> Dd {
    let s = a + b;
    let bb = s - a;
    Dd {
        hi: s,
        lo: (a - (s - bb)) + (b - bb),
    }
}

fn quick(a: f64, b: f64) -> Dd {
    let s = a + b;
    Dd {
        hi: s,
        lo: b - (s - a),
    }
}

fn two_prod(a: f64, b: f64) -> Dd {
    let p = a * b;
    Dd {
        hi: p,
        lo: a.mul_add(b, -p),
    }
}

fn add(x: Dd, y: Dd) -> Dd {
    let s = two_sum(x.hi, y.hi);
    let t = two_sum(x.lo, y.lo);
    let s = quick(s.hi, s.lo + t.hi);
    quick(s.hi, s.lo + t.lo)
}

fn neg(x: Dd) -> Dd {
    Dd {
        hi: -x.hi,
        lo: -x.lo,
    }
}

fn mul(x: Dd, y: Dd) -> Dd {
    let p = two_prod(x.hi, y.hi);
    quick(p.hi, p.lo + (x.hi * y.lo + x.lo * y.hi))
}

fn mul_f(x: Dd, f: f64) -> Dd {
    let p = two_prod(x.hi, f);
    quick(p.hi, p.lo + x.lo * f)
}

fn div(x: Dd, y: Dd) -> Dd {
    let q1 = x.hi / y.hi;
    let r = add(x, neg(mul_f(y, q1)));
    let q2 = r.hi / y.hi;
    let r = add(r, neg(mul_f(y, q2)));
    let q3 = r.hi / y.hi;
    add(quick(q1, q2), Dd { hi: q3, lo: 0.0 })
}

fn dd(x: f64) -> Dd {
    Dd { hi: x, lo: 0.0 }
}

/// Rounds to a 64-bit significand (round half to even).
fn round64(x: Dd) -> Dd {
    // Tiny values: the 64-bit grid is finer than doubles can express.
    if x.hi.abs() < 1e-280 || !x.hi.is_finite() {
        return x;
    }
    let mut e = x.hi.abs().log2().floor() as i32;
    // Guard against log2 rounding at powers of two.
    if 2f64.powi(e) > x.hi.abs() {
        e -= 1;
    } else if 2f64.powi(e + 1) <= x.hi.abs() {
        e += 1;
    }
    // A power of two with a negative tail lies in the binade below.
    if x.hi.abs() == 2f64.powi(e) && x.lo != 0.0 && (x.lo < 0.0) == (x.hi > 0.0) {
        e -= 1;
    }
    let ulp = 2f64.powi(e - 63);
    let q = x.lo / ulp;
    let r = q.round_ties_even();
    quick(x.hi, r * ulp)
}

fn to_f64(x: Dd) -> f64 {
    x.hi + x.lo
}

/// A double-double argument in radians reduced by multiples of π/2: the
/// remainder, its square and the quadrant (0 to 3).
fn reduce(a: Dd) -> (Dd, Dd, i64) {
    let k = (a.hi / PIO2[0]).round();
    let mut r = add(a, neg(two_prod(k, PIO2[0])));
    r = add(r, neg(two_prod(k, PIO2[1])));
    r = add(r, dd(-k * PIO2[2]));
    (r, mul(r, r), (k as i64).rem_euclid(4))
}

/// The sine series of a reduced argument `r` (`r2` its square).
fn sin_series(r: Dd, r2: Dd) -> Dd {
    let mut s = r;
    let mut term = r;
    for i in 1..40 {
        let n = (2 * i) as f64 * (2 * i + 1) as f64;
        term = neg(div(mul(term, r2), dd(n)));
        s = add(s, term);
        if term.hi.abs() < 1e-36 {
            break;
        }
    }
    s
}

/// The cosine series of a reduced argument whose square is `r2`.
fn cos_series(r2: Dd) -> Dd {
    let mut c = dd(1.0);
    let mut term = dd(1.0);
    for i in 1..40 {
        let n = (2 * i - 1) as f64 * (2 * i) as f64;
        term = neg(div(mul(term, r2), dd(n)));
        c = add(c, term);
        if term.hi.abs() < 1e-36 {
            break;
        }
    }
    c
}

/// sin and cos of a double-double argument in radians.
fn sin_cos(a: Dd) -> (Dd, Dd) {
    let (r, r2, q) = reduce(a);
    let (s, c) = (sin_series(r, r2), cos_series(r2));
    match q {
        0 => (s, c),
        1 => (c, neg(s)),
        2 => (neg(s), neg(c)),
        _ => (neg(c), s),
    }
}

/// sin of a double-double argument in radians: `sin_cos(a).0`, with only
/// the series it takes.
fn sin_only(a: Dd) -> Dd {
    let (r, r2, q) = reduce(a);
    match q {
        0 => sin_series(r, r2),
        1 => cos_series(r2),
        2 => neg(sin_series(r, r2)),
        _ => neg(cos_series(r2)),
    }
}

/// cos of a double-double argument in radians: `sin_cos(a).1`, with only
/// the series it takes.
fn cos_only(a: Dd) -> Dd {
    let (r, r2, q) = reduce(a);
    match q {
        0 => cos_series(r2),
        1 => neg(sin_series(r, r2)),
        2 => neg(cos_series(r2)),
        _ => sin_series(r, r2),
    }
}

/// `x * M_PIl / 180.0` in extended precision.
fn radians(x: f64) -> Dd {
    let p = add(two_prod(x, PI64.hi), two_prod(x, PI64.lo));
    round64(div(round64(p), dd(180.0)))
}

/// Whether the extended-precision kernel can be trusted for this argument.
fn in_range(x: f64) -> bool {
    x.is_finite() && x.abs() < 1.0e9
}

pub(crate) fn sin_deg(x: f64) -> f64 {
    // A zero keeps its sign (the double-double sum would lose it).
    if x == 0.0 {
        return x;
    }
    if !in_range(x) {
        return (x * (std::f64::consts::PI / 180.0)).sin();
    }
    to_f64(round64(sin_only(radians(x))))
}

pub(crate) fn cos_deg(x: f64) -> f64 {
    if !in_range(x) {
        return (x * (std::f64::consts::PI / 180.0)).cos();
    }
    to_f64(round64(cos_only(radians(x))))
}

pub(crate) fn tan_deg(x: f64) -> f64 {
    if x == 0.0 {
        return x;
    }
    if !in_range(x) {
        return (x * (std::f64::consts::PI / 180.0)).tan();
    }
    let (s, c) = sin_cos(radians(x));
    if c.hi == 0.0 {
        return f64::INFINITY;
    }
    to_f64(round64(div(s, c)))
}

/// `(r * 180.0) / M_PIl` for a result `r` in radians from the double libm.
pub(crate) fn to_degrees(r: f64) -> f64 {
    if r == 0.0 {
        return r;
    }
    let p = r * 180.0;
    to_f64(round64(div(dd(p), PI64)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn special_angles_match_the_reference() {
        // Values measured with LinuxCNC 2.9's rs274.
        assert_eq!(sin_deg(30.0), 0.5);
        assert_eq!(cos_deg(60.0), 0.5);
        assert_eq!(tan_deg(45.0), 1.0);
        let cases: &[(f64, f64, f64)] = &[
            (tan_deg(90.0), -3.986798e19, 1e13),
            (tan_deg(-90.0), 3.986798e19, 1e13),
            (sin_deg(180.0), -5.016558e-20, 1e-26),
            (cos_deg(90.0), -2.508279e-20, 1e-26),
            (tan_deg(270.0), -0.544459e19, 1e13),
            (sin_deg(360.0), 10.033115e-20, 1e-26),
        ];
        for &(got, want, tol) in cases {
            assert!((got - want).abs() < tol, "{got:e} vs {want:e}");
        }
        assert_eq!(to_degrees(0.5f64.acos()), 60.0);
        // Tiny and huge arguments stay numbers (found by the generator).
        for x in [1e-300, -1e-310, 5e-324, 1e-20, 1e8, -7.5e8] {
            assert!(sin_deg(x).is_finite() && cos_deg(x).is_finite(), "{x:e}");
        }
        assert_eq!(to_degrees(0.5f64.asin()), 30.0);
        assert_eq!(to_degrees(1f64.atan2(3f64.sqrt())), 30.0);
    }

    /// The sine or cosine alone is bit for bit the one of the pair, in
    /// every quadrant and for arguments of every size.
    #[test]
    fn one_series_gives_the_value_of_the_pair() {
        let mut args = vec![
            0.0, 30.0, 45.0, 90.0, 180.0, 270.0, 360.0, -90.0, 1e-300, 7.5e8,
        ];
        // Every quadrant near zero, then sizes growing to the kernel's
        // bound.
        for k in 0..2000 {
            args.push(k as f64 * 0.731 - 400.0);
        }
        let mut x = 1.0e-3_f64;
        while x < 1.0e9 {
            args.extend([x, -x]);
            x *= 1.37;
        }
        for a in args {
            let r = radians(a);
            let (s, c) = sin_cos(r);
            let (s1, c1) = (sin_only(r), cos_only(r));
            assert_eq!(
                (s.hi.to_bits(), s.lo.to_bits()),
                (s1.hi.to_bits(), s1.lo.to_bits()),
                "sin {a}"
            );
            assert_eq!(
                (c.hi.to_bits(), c.lo.to_bits()),
                (c1.hi.to_bits(), c1.lo.to_bits()),
                "cos {a}"
            );
        }
    }
}
