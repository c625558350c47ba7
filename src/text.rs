//! Numbers in messages: short and exact. Rust prints `1e-200` with `{}`
//! as 200 digits; [`num`] keeps moderate numbers plain and writes the
//! others in scientific form, always with the fewest digits that read back
//! to the same value.

/// `x` as `0.25`, `1234.5`, `1e-200`, `2.5e9`, `NaN` or `inf`.
pub fn num(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-3..1e4).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::num;

    #[test]
    fn short_and_exact() {
        assert_eq!(num(1e-200), "1e-200");
        assert_eq!(num(0.25), "0.25");
        assert_eq!(num(-1234.5), "-1234.5");
        assert_eq!(num(2.5e9), "2.5e9");
        assert_eq!(num(1e300), "1e300");
        assert_eq!(num(0.0), "0");
        assert_eq!(num(f64::NAN), "NaN");
        assert_eq!(num(f64::NEG_INFINITY), "-inf");
        for x in [0.1 + 0.2, 1.0 / 3.0, 6.02214076e23, -5e-324] {
            assert_eq!(num(x).parse::<f64>().unwrap().to_bits(), x.to_bits());
        }
    }
}
