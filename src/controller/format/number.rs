//! Numbers as a target reads them: at most the profile's decimals and
//! significant digits, trailing zeros dropped, never an exponent or `-0`;
//! written through integers where that is exact (no float formatting).

/// Writes `v` with at most `decimals` decimals and `max_digits`
/// significant digits (zeros after the point count), trailing zeros
/// dropped, never an exponent or `-0`.
pub fn format_number(out: &mut String, v: f64, decimals: u8, max_digits: u8) {
    let mut b = Vec::with_capacity(24);
    write_number(&mut b, v, decimals, max_digits);
    // Digits, a point and a sign: always text.
    out.push_str(&String::from_utf8_lossy(&b));
}

/// [`format_number`] into bytes.
pub(super) fn write_number(out: &mut Vec<u8>, v: f64, decimals: u8, max_digits: u8) {
    let a = v.abs();
    if v.fract() == 0.0 && a < 1e15 {
        write_fixed(out, v < 0.0, a as i64 as u64, 0);
        return;
    }
    let int_digits = int_digits(a);
    let d = (max_digits as i32 - int_digits).clamp(0, decimals as i32) as usize;
    let x = a * pow10(d);
    if d <= 12 && x < 9.0e15 {
        // Fixed point through an integer: no float formatting.
        let n = round_u64(x);
        write_fixed(out, n != 0 && v < 0.0, n, d);
        return;
    }
    use std::fmt::Write;
    let mut s = String::new();
    let _ = write!(s, "{:.*}", d, v);
    if s.contains('.') {
        while s.ends_with('0') {
            s.pop();
        }
        if s.ends_with('.') {
            s.pop();
        }
    }
    if s.trim_start_matches('-').bytes().all(|b| b == b'0') {
        s.clear();
        s.push('0');
    }
    out.extend_from_slice(s.as_bytes());
}

/// `x.round()` (halves away from zero) for `0 <= x < 2^53`: the part
/// after the point is exact, so comparing it with one half decides.
#[inline]
pub(super) fn round_u64(x: f64) -> u64 {
    // Through i64: one instruction each way on x86-64, unlike u64.
    let i = x as i64;
    (i + i64::from(x - i as f64 >= 0.5)) as u64
}

/// `n / 10^d` written with `d` decimals, trailing zeros (and a point left
/// alone) dropped, `-` first when `neg`.
#[inline]
pub(super) fn write_fixed(out: &mut Vec<u8>, neg: bool, mut n: u64, mut d: usize) {
    while d > 0 && n.is_multiple_of(10) {
        n /= 10;
        d -= 1;
    }
    // At most 30 decimals, 20 digits before the point, the point, the sign.
    let mut tmp = [0u8; 64];
    let mut i = tmp.len();
    let mut put = |i: &mut usize, c: u8| {
        *i -= 1;
        if let Some(slot) = tmp.get_mut(*i) {
            *slot = c;
        }
    };
    for _ in 0..d.min(30) {
        put(&mut i, b'0' + (n % 10) as u8);
        n /= 10;
    }
    if d > 0 {
        put(&mut i, b'.');
    }
    loop {
        put(&mut i, b'0' + (n % 10) as u8);
        n /= 10;
        if n == 0 {
            break;
        }
    }
    if neg {
        put(&mut i, b'-');
    }
    out.extend_from_slice(tmp.get(i..).unwrap_or_default());
}

/// Digits before the point of `a` (0 below 1): `floor(log10(a)) + 1`,
/// counted against exact powers of ten.
fn int_digits(a: f64) -> i32 {
    if a < 1.0 {
        return 0;
    }
    if !a.is_finite() {
        return i32::MAX / 2;
    }
    let mut n = 1;
    let mut p = 10.0;
    while a >= p && n < 400 {
        n += 1;
        p *= 10.0;
    }
    n
}

/// `10^d` for the decimals of a number (exact up to 22).
pub(super) fn pow10(d: usize) -> f64 {
    const P: [f64; 23] = [
        1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
        1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
    ];
    P.get(d).copied().unwrap_or_else(|| 10f64.powi(d as i32))
}

/// A number as written (digits, a sign and a point), as the target reads it.
pub(super) fn read_back(written: &[u8]) -> Option<f64> {
    std::str::from_utf8(written).ok()?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f(v: f64, d: u8, m: u8) -> String {
        let mut s = String::new();
        format_number(&mut s, v, d, m);
        s
    }

    /// The rules of `format_number` written the plain way (float
    /// formatting, `log10`, `powi`): the fast writer must agree with it.
    fn reference(v: f64, decimals: u8, max_digits: u8) -> String {
        let a = v.abs();
        if v.fract() == 0.0 && a < 1e15 {
            return format!("{}", v as i64);
        }
        let int_digits = if a < 1.0 {
            0
        } else {
            (a.log10().floor() as i32 + 1).max(1)
        };
        let d = (max_digits as i32 - int_digits).clamp(0, decimals as i32) as usize;
        let scaled = (a * 10f64.powi(d as i32)).round();
        let mut out = String::new();
        if d <= 12 && scaled < 9.0e15 {
            let n = scaled as u64;
            let p = 10u64.pow(d as u32);
            let (int, mut frac) = (n / p, n % p);
            if n != 0 && v < 0.0 {
                out.push('-');
            }
            out.push_str(&format!("{int}"));
            if frac != 0 {
                let mut digits = d;
                while frac % 10 == 0 {
                    frac /= 10;
                    digits -= 1;
                }
                out.push_str(&format!(".{frac:0digits$}"));
            }
            return out;
        }
        let mut s = format!("{:.*}", d, v);
        if s.contains('.') {
            s = s.trim_end_matches('0').trim_end_matches('.').to_string();
        }
        if s.trim_start_matches('-').bytes().all(|b| b == b'0') {
            s = "0".into();
        }
        s
    }

    proptest::proptest! {
        #[test]
        fn fast_writer_keeps_the_rules(
            v in proptest::num::f64::NORMAL | proptest::num::f64::ZERO,
            small in -100_000.0f64..100_000.0,
            pick in proptest::bool::ANY,
            decimals in 0u8..7,
            max_digits in 1u8..12,
        ) {
            let v = if pick { v } else { small };
            proptest::prop_assert_eq!(f(v, decimals, max_digits), reference(v, decimals, max_digits));
        }
    }

    #[test]
    fn numbers_fit_the_target() {
        assert_eq!(f(1.23456789, 4, 8), "1.2346");
        assert_eq!(f(-0.00001, 4, 8), "0");
        assert_eq!(f(12345.678912, 4, 8), "12345.679");
        assert_eq!(f(1e20, 4, 8), "100000000000000000000");
        assert_eq!(f(2.0, 4, 8), "2");
        assert_eq!(f(-2.5, 4, 8), "-2.5");
        assert_eq!(f(-0.05, 4, 8), "-0.05");
        assert_eq!(f(0.00012, 5, 8), "0.00012");
        assert_eq!(f(-1234.56789, 4, 8), "-1234.5679");
        assert_eq!(f(1.99999, 4, 8), "2");
    }
}
