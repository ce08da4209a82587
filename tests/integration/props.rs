//! Property tests: arbitrary input never panics; flattening is idempotent;
//! the number formatter round-trips.

use proptest::prelude::*;

use ngcflat::emit::number_string;
use ngcflat::eval::Settings;

proptest! {
    #[test]
    fn numbers_round_trip(v in proptest::num::f64::NORMAL | proptest::num::f64::SUBNORMAL | proptest::num::f64::ZERO) {
        let s = number_string(v, None);
        prop_assert!(!s.contains(['e', 'E', 'i', 'N']), "{s}");
        prop_assert!(s != "-0");
        let back: f64 = s.parse().unwrap();
        prop_assert_eq!(back, if v == 0.0 { 0.0 } else { v });
    }

    #[test]
    fn fixed_precision_matches_format(v in -1.0e9f64..1.0e9, p in 0u8..8) {
        let s = number_string(v, Some(p));
        let want: f64 = format!("{v:.prec$}", prec = p as usize).parse().unwrap();
        let got: f64 = s.parse().unwrap();
        prop_assert!((got - want).abs() <= 10f64.powi(-(p as i32)) * 1.0001, "{v} {p}: {s} vs {want}");
    }

    #[test]
    fn arbitrary_bytes_never_panic(data in proptest::collection::vec(any::<u8>(), 0..400)) {
        let text = String::from_utf8_lossy(&data);
        let settings = Settings { max_steps: 10_000, max_output_lines: 10_000, ..Settings::default() };
        let _ = ngcflat::flatten_str(&text, &settings);
    }
}
