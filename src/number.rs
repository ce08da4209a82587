//! Numbers as G-code can read them: plain decimal, never an exponent, never
//! `inf`, `NaN` or `-0`.

/// Appends `v` to `out`. Without a precision the shortest text that reads
/// back as exactly `v`; with one, rounded to that many decimals and trailing
/// zeros dropped. Returns false for values that have no G-code form.
pub fn write_number(out: &mut Vec<u8>, v: f64, precision: Option<u8>) -> bool {
    if !v.is_finite() {
        return false;
    }
    match precision {
        None => write_shortest(out, v),
        Some(p) => write_fixed(out, v, p),
    }
    true
}

/// An upper bound of the length `write_number` gives `v`, known without
/// writing it; `None` for values whose text may be long (tiny or huge ones)
/// or that have no G-code form.
#[inline]
pub fn max_len(v: f64, precision: Option<u8>) -> Option<usize> {
    let a = v.abs();
    match precision {
        // At most 17 significant digits, a sign, a point and three zeros
        // after it.
        None if a == 0.0 || (1e-4..1e15).contains(&a) => Some(25),
        // A sign, 16 digits (rounding up to 1e15), a point and the
        // decimals.
        Some(p) if a < 1e15 => Some(18 + p.min(15) as usize),
        _ => None,
    }
}

fn write_shortest(out: &mut Vec<u8>, v: f64) {
    if v == 0.0 {
        out.push(b'0');
        return;
    }
    // Values with at most nine decimals (most of them): the nearest
    // nine-decimal number reads back as `v` exactly when one does, and with
    // its zeros trimmed it is the shortest text. Below 1e6 it is an integer
    // under 2^53, so the product, its rounding and the check are exact
    // enough.
    if v.abs() < 1e6 {
        // Round to an integer by adding and removing 1.5 * 2^52 (inline,
        // no libm call): half-way cases round to even instead of away from
        // zero, but a half-way product never passes the check below, so
        // the result is the same.
        const SHIFT: f64 = 6_755_399_441_055_744.0;
        let s = v * 1e9;
        let r = (s + SHIFT) - SHIFT;
        if r / 1e9 == v {
            write_nine(out, r as i64);
            return;
        }
    }
    write_shortest_ryu(out, v);
}

/// The shortest round-trip text through Ryu, exponent written out.
fn write_shortest_ryu(out: &mut Vec<u8>, v: f64) {
    let mut buf = ryu::Buffer::new();
    let s = buf.format_finite(v).as_bytes();
    // Ryu writes an exponent only outside 1e-5..1e16; the search is made
    // only near and beyond those bounds.
    if (1e-4..1e15).contains(&v.abs()) || !s.contains(&b'e') {
        // Already plain decimal; only a `.0` ending is dropped.
        out.extend_from_slice(s.strip_suffix(b".0").unwrap_or(s));
        return;
    }
    let (neg, s) = match s.first() {
        Some(b'-') => (true, &s[1..]),
        _ => (false, s),
    };
    // Split mantissa and exponent.
    let (mant, exp) = match s.iter().position(|&b| b == b'e' || b == b'E') {
        Some(i) => {
            let e = std::str::from_utf8(&s[i + 1..])
                .ok()
                .and_then(|t| t.parse::<i32>().ok())
                .unwrap_or(0);
            (&s[..i], e)
        }
        None => (s, 0),
    };
    // Digits and the position of the decimal point within them.
    let mut digits: [u8; 32] = [0; 32];
    let mut n = 0;
    let mut point = None;
    for &b in mant {
        if b == b'.' {
            point = Some(n);
        } else {
            digits[n] = b;
            n += 1;
        }
    }
    let mut point = point.unwrap_or(n) as i32 + exp;
    // Trim trailing zeros of the digit string (they carry no value once the
    // point is placed) and leading zeros.
    let mut start = 0;
    while start < n - 1 && digits[start] == b'0' {
        start += 1;
        point -= 1;
    }
    let mut end = n;
    while end > start + 1 && digits[end - 1] == b'0' {
        end -= 1;
    }
    let d = &digits[start..end];
    if neg {
        out.push(b'-');
    }
    if point <= 0 {
        out.extend_from_slice(b"0.");
        out.extend(std::iter::repeat_n(b'0', (-point) as usize));
        out.extend_from_slice(d);
    } else if point as usize >= d.len() {
        out.extend_from_slice(d);
        out.extend(std::iter::repeat_n(b'0', point as usize - d.len()));
    } else {
        out.extend_from_slice(&d[..point as usize]);
        out.push(b'.');
        out.extend_from_slice(&d[point as usize..]);
    }
}

fn write_fixed(out: &mut Vec<u8>, v: f64, p: u8) {
    let p = p.min(15);
    let scale = 10f64.powi(p as i32);
    let scaled = v * scale;
    let frac = (scaled - scaled.trunc()).abs();
    // Fast path only where the product is exact enough to round correctly;
    // near a tie or for large values, round the exact decimal expansion.
    if scaled.abs() >= 1.0e12 || (frac - 0.5).abs() < 1.0e-3 {
        let s = format!("{v:.prec$}", prec = p as usize);
        let s = s.as_bytes();
        let (neg, digits) = match s.first() {
            Some(b'-') => (true, &s[1..]),
            _ => (false, s),
        };
        let digits = match digits.iter().position(|&b| b == b'.') {
            Some(dot) => {
                let frac = trim_zeros(&digits[dot + 1..]);
                if frac.is_empty() {
                    &digits[..dot]
                } else {
                    &digits[..dot + 1 + frac.len()]
                }
            }
            None => digits,
        };
        if digits.iter().all(|&b| b == b'0' || b == b'.') {
            out.push(b'0');
            return;
        }
        if neg {
            out.push(b'-');
        }
        out.extend_from_slice(digits);
        return;
    }
    write_decimal(out, scaled.round() as i64, p as usize);
}

/// Writes `n / 10^p` with trailing zeros dropped.
fn write_decimal(out: &mut Vec<u8>, mut n: i64, p: usize) {
    if n == 0 {
        out.push(b'0');
        return;
    }
    if n < 0 {
        out.push(b'-');
        n = -n;
    }
    let mut ib = itoa::Buffer::new();
    let s = ib.format(n).as_bytes();
    if s.len() <= p {
        out.extend_from_slice(b"0.");
        out.extend(std::iter::repeat_n(b'0', p - s.len()));
        let t = trim_zeros(s);
        out.extend_from_slice(t);
    } else {
        let (int, frac) = s.split_at(s.len() - p);
        out.extend_from_slice(int);
        let t = trim_zeros(frac);
        if !t.is_empty() {
            out.push(b'.');
            out.extend_from_slice(t);
        }
    }
}

/// Writes `n / 10^9` with trailing zeros dropped: `write_decimal` for nine
/// decimals, with the fraction's digits made directly.
fn write_nine(out: &mut Vec<u8>, n: i64) {
    let m = n.unsigned_abs();
    if n < 0 {
        out.push(b'-');
    }
    let int = m / 1_000_000_000;
    let mut frac = (m % 1_000_000_000) as u32;
    let mut ib = itoa::Buffer::new();
    out.extend_from_slice(ib.format(int).as_bytes());
    if frac != 0 {
        let mut digits = 9;
        while frac.is_multiple_of(10) {
            frac /= 10;
            digits -= 1;
        }
        let mut buf = [b'0'; 10];
        buf[0] = b'.';
        let mut i = digits;
        while frac > 0 {
            buf[i] = b'0' + (frac % 10) as u8;
            frac /= 10;
            i -= 1;
        }
        out.extend_from_slice(&buf[..=digits]);
    }
}

fn trim_zeros(s: &[u8]) -> &[u8] {
    let mut e = s.len();
    while e > 0 && s[e - 1] == b'0' {
        e -= 1;
    }
    &s[..e]
}

/// Convenience for tests and messages.
pub fn number_string(v: f64, precision: Option<u8>) -> String {
    let mut b = Vec::new();
    write_number(&mut b, v, precision);
    String::from_utf8(b).expect("ascii")
}

/// Exact powers of ten (every one up to 1e22 is a double).
pub(crate) static POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

static POW10_INT: [u64; 9] = [
    1,
    10,
    100,
    1_000,
    10_000,
    100_000,
    1_000_000,
    10_000_000,
    100_000_000,
];

/// `b` in every byte of a `u64` (eight bytes at a time, first byte lowest).
const fn splat(b: u8) -> u64 {
    0x0101_0101_0101_0101 * b as u64
}

/// The low seven bits of every byte.
const LO7: u64 = splat(0x7f);

/// Number of leading ASCII digits among the 8 bytes of `w` (first byte
/// lowest).
#[inline(always)]
fn leading_digits(w: u64) -> u32 {
    let x = ((w & splat(0xf0)) ^ splat(0x30))
        | ((w & splat(0x0f)).wrapping_add(splat(0x06)) & splat(0xf0));
    // High bit of every byte that is not a digit.
    let non = ((x & LO7).wrapping_add(LO7) | x) & splat(0x80);
    non.trailing_zeros() / 8
}

/// Value of the first `len` (1–8) digit bytes of `w`.
#[inline(always)]
fn digits_value(w: u64, len: u32) -> u64 {
    let d = w.wrapping_sub(splat(b'0')) << (8 * (8 - len));
    let d = (d.wrapping_mul(10).wrapping_add(d >> 8)) & 0x00ff_00ff_00ff_00ff;
    let d = (d.wrapping_mul(100).wrapping_add(d >> 16)) & 0x0000_ffff_0000_ffff;
    (d.wrapping_mul(10_000).wrapping_add(d >> 32)) & 0xffff_ffff
}

/// The eight bytes at `buf[i..]`, zeros (not digits) past the end.
#[inline(always)]
fn load8_padded(buf: &[u8], i: usize) -> u64 {
    let rest = buf.get(i..).unwrap_or(&[]);
    if let Some(b) = rest.first_chunk::<8>() {
        return u64::from_le_bytes(*b);
    }
    let len = buf.len();
    if rest.is_empty() {
        0
    } else if let Some(last) = buf.last_chunk::<8>() {
        // The last eight bytes, shifted down to start at `i` (1 to 7 of
        // them are there): one load, not one per byte.
        u64::from_le_bytes(*last) >> (8 * (8 - (len - i)))
    } else {
        // A buffer shorter than eight bytes, byte by byte (a copy of a
        // variable length would call memcpy).
        rest.iter()
            .enumerate()
            .fold(0, |w, (k, &c)| w | u64::from(c) << (8 * k))
    }
}

/// The eight bytes at `buf[i..]`, which are there.
#[inline(always)]
fn load8(buf: &[u8], i: usize) -> u64 {
    let mut b = [0u8; 8];
    b.copy_from_slice(&buf[i..i + 8]);
    u64::from_le_bytes(b)
}

/// An unsigned decimal `digits[.digits]` as [`digits_at`] reads it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Digits {
    /// All its digits as one integer (below 10^15, so exact as a double).
    pub mant: u64,
    /// Digits before the point.
    pub int: u32,
    /// Digits after the point.
    pub frac: u32,
    /// Whether it has a point.
    pub point: bool,
    /// The offset just after it.
    pub end: usize,
}

impl Digits {
    /// Its value: one correctly rounded division of two exact doubles, so
    /// the correctly rounded value of the decimal, as `str::parse` gives.
    #[inline(always)]
    pub(crate) fn value(self) -> f64 {
        // Through i64: one instruction on x86-64, unlike u64.
        self.mant as i64 as f64 / POW10[self.frac as usize]
    }
}

/// Reads `digits[.digits]` at `buf[i..]` eight bytes at a time, without a
/// branch per digit. `None` for anything this does not decide by itself:
/// 8 or more digits on either side of the point, more than 15 digits in
/// all, no digit. The callers then read the number a byte at a time.
#[inline(always)]
pub(crate) fn digits_at(buf: &[u8], i: usize) -> Option<Digits> {
    if i + 16 <= buf.len() {
        digits_with(buf, i, load8)
    } else {
        digits_with(buf, i, load8_padded)
    }
}

/// [`digits_at`] where 16 bytes follow `i`; `None` where they do not.
#[inline(always)]
pub(crate) fn digits_in(buf: &[u8], i: usize) -> Option<Digits> {
    if i + 16 > buf.len() {
        return None;
    }
    digits_with(buf, i, load8)
}

#[inline(always)]
fn digits_with(buf: &[u8], i: usize, load: impl Fn(&[u8], usize) -> u64) -> Option<Digits> {
    let w = load(buf, i);
    let n1 = leading_digits(w);
    if n1 == 8 {
        return None;
    }
    let int = if n1 == 0 { 0 } else { digits_value(w, n1) };
    let j = i + n1 as usize;
    if buf.get(j) != Some(&b'.') {
        return (n1 > 0).then_some(Digits {
            mant: int,
            int: n1,
            frac: 0,
            point: false,
            end: j,
        });
    }
    let w2 = load(buf, j + 1);
    let n2 = leading_digits(w2);
    if n2 == 8 || n1 + n2 == 0 || n1 + n2 > 15 {
        return None;
    }
    let frac = if n2 == 0 { 0 } else { digits_value(w2, n2) };
    Some(Digits {
        mant: int * POW10_INT[n2 as usize] + frac,
        int: n1,
        frac: n2,
        point: true,
        end: j + 1 + n2 as usize,
    })
}

#[cfg(test)]
mod tests {
    use super::number_string as s;

    /// A padded load is the bytes there, byte by byte, and zeros past the
    /// end, wherever it starts in a buffer of any length.
    #[test]
    fn padded_load_is_the_bytes_then_zeros() {
        let text: Vec<u8> = (1..=24).collect();
        for len in 0..=text.len() {
            let buf = &text[..len];
            for i in 0..=len + 2 {
                let want = (0..8).fold(0u64, |w, k| {
                    w | u64::from(buf.get(i + k).copied().unwrap_or(0)) << (8 * k)
                });
                assert_eq!(super::load8_padded(buf, i), want, "len {len} at {i}");
            }
        }
    }

    #[test]
    fn shortest_without_exponent() {
        let cases: &[(f64, &str)] = &[
            (0.0, "0"),
            (-0.0, "0"),
            (1.0, "1"),
            (-2.5, "-2.5"),
            (0.1, "0.1"),
            (1e-7, "0.0000001"),
            (1.5e17, "150000000000000000"),
            (123456.789, "123456.789"),
            (1.0 / 3.0, "0.3333333333333333"),
            (-14.324700000000007, "-14.324700000000007"),
            (100.0, "100"),
        ];
        for &(v, want) in cases {
            assert_eq!(s(v, None), want, "{v:e}");
        }
    }

    use proptest::prelude::*;

    fn ryu_text(v: f64) -> String {
        let mut b = Vec::new();
        super::write_shortest_ryu(&mut b, v);
        String::from_utf8(b).expect("ascii")
    }

    proptest! {
        /// The nine-decimal path gives the text the Ryu path gives.
        #[test]
        fn short_path_matches_ryu(
            n in -2_000_000_000_000_000i64..2_000_000_000_000_000,
            k in 0u32..12,
            x in -2.0e6f64..2.0e6,
        ) {
            let nice = n as f64 / 10f64.powi(k as i32);
            prop_assert_eq!(s(nice, None), ryu_text(nice));
            prop_assert_eq!(s(x, None), ryu_text(x));
            let small = x * 1e-9;
            prop_assert_eq!(s(small, None), ryu_text(small));
        }
    }

    proptest! {
        /// Nine decimals made directly read as `write_decimal` writes them.
        #[test]
        fn nine_decimals_as_the_general_writer(
            n in prop_oneof![-2_000_000_000_000_000i64..2_000_000_000_000_000, -10_000i64..10_000],
            zeros in 0u32..10,
        ) {
            let n = n.saturating_mul(10i64.pow(zeros)).clamp(-4_000_000_000_000_000_000, 4_000_000_000_000_000_000);
            prop_assume!(n != 0);
            let (mut a, mut b) = (Vec::new(), Vec::new());
            super::write_nine(&mut a, n);
            super::write_decimal(&mut b, n, 9);
            prop_assert_eq!(a, b, "{}", n);
        }
    }

    proptest! {
        /// `max_len` bounds the text of every value it accepts, in every
        /// precision.
        #[test]
        fn max_len_bounds_the_text(
            bits in any::<u64>(),
            mant in -1.0f64..1.0,
            exp in -6i32..17,
            p in proptest::option::of(0u8..20),
        ) {
            let scaled = mant * 10f64.powi(exp);
            for v in [f64::from_bits(bits), scaled, scaled.abs().max(1e-4), 1e15f64.next_down()] {
                if let Some(n) = super::max_len(v, p) {
                    let mut b = Vec::new();
                    prop_assert!(super::write_number(&mut b, v, p));
                    prop_assert!(b.len() <= n, "{:e} {:?}: {}", v, p, String::from_utf8_lossy(&b));
                }
            }
        }
    }

    #[test]
    fn max_len_refuses_long_and_unprintable_values() {
        for v in [1e-5, 1e15, -1e300, f64::NAN, f64::INFINITY] {
            assert_eq!(super::max_len(v, None), None, "{v:e}");
        }
        assert_eq!(super::max_len(1e15, Some(3)), None);
        assert_eq!(super::max_len(1e-300, Some(3)), Some(21));
        assert_eq!(super::max_len(-0.0, None), Some(25));
    }

    #[test]
    fn fixed_precision() {
        assert_eq!(s(1.23456, Some(3)), "1.235");
        assert_eq!(s(1.5, Some(3)), "1.5");
        assert_eq!(s(-0.0001, Some(3)), "0");
        assert_eq!(s(-0.0006, Some(3)), "-0.001");
        assert_eq!(s(2.0, Some(4)), "2");
        assert_eq!(s(0.05, Some(1)), "0.1");
    }

    #[test]
    fn rejects_non_finite() {
        let mut b = Vec::new();
        assert!(!super::write_number(&mut b, f64::NAN, None));
        assert!(!super::write_number(&mut b, f64::INFINITY, Some(3)));
    }
}
