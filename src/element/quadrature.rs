//! Symmetric Dunavant quadrature on the triangle (MATH.md section 2).
//!
//! The 1- and 3-point rules leave spurious zero-energy modes in the cubic
//! shell, so only the 7-point (degree 5) and 12-point (degree 6) rules are
//! offered. Points are area coordinates `(xi, eta, zeta)`; weights sum to 1
//! and are multiplied by the triangle area.
//!
//! The 7-point rule is the default: its errors equal the 12-point rule's
//! to two digits on every mesh family studied, at 0.6x the cost; on coarse
//! meshes the mesh error dominates and it is no further from the converged
//! sheet (docs/validation.md, `cargo bench --bench element_families` and
//! `cargo bench --bench quadrature_fidelity`).

use serde::{Deserialize, Serialize};

/// A quadrature rule for the shell energy.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Rule {
    /// 7 points, exact for polynomials of degree 5: the default.
    #[default]
    Dunavant7,
    /// 12 points, exact for polynomials of degree 6.
    Dunavant12,
}

impl Rule {
    /// The points `(area coordinates, weight)`, weights summing to 1.
    pub fn points(&self) -> &'static [([f64; 3], f64)] {
        match self {
            Rule::Dunavant7 => &DUNAVANT7,
            Rule::Dunavant12 => &DUNAVANT12,
        }
    }
}

// Dunavant 7: a = (6 - sqrt 15)/21, b = (6 + sqrt 15)/21,
// weights 9/40, (155 - sqrt 15)/1200, (155 + sqrt 15)/1200, rounded to f64.
const D7_A: f64 = 0.101_286_507_323_456_34;
const D7_A1: f64 = 0.797_426_985_353_087_3;
const D7_WA: f64 = 0.125_939_180_544_827_14;
const D7_B: f64 = 0.470_142_064_105_115_1;
const D7_B1: f64 = 0.059_715_871_789_769_82;
const D7_WB: f64 = 0.132_394_152_788_506_2;

static DUNAVANT7: [([f64; 3], f64); 7] = [
    ([1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0], 9.0 / 40.0),
    ([D7_A1, D7_A, D7_A], D7_WA),
    ([D7_A, D7_A1, D7_A], D7_WA),
    ([D7_A, D7_A, D7_A1], D7_WA),
    ([D7_B1, D7_B, D7_B], D7_WB),
    ([D7_B, D7_B1, D7_B], D7_WB),
    ([D7_B, D7_B, D7_B1], D7_WB),
];

// Dunavant 12: the degree-6 moment equations re-solved in 40-digit arithmetic
// from Dunavant's 15-digit table, rounded to f64.
const D12_A: f64 = 0.063_089_014_491_502_23;
const D12_A1: f64 = 0.873_821_971_016_995_5;
const D12_WA: f64 = 0.050_844_906_370_206_82;
const D12_B: f64 = 0.249_286_745_170_910_43;
const D12_B1: f64 = 0.501_426_509_658_179_1;
const D12_WB: f64 = 0.116_786_275_726_379_37;
const D12_C: f64 = 0.310_352_451_033_784_4;
const D12_D: f64 = 0.053_145_049_844_816_945;
const D12_CD: f64 = 0.636_502_499_121_398_7;
const D12_WC: f64 = 0.082_851_075_618_373_57;

static DUNAVANT12: [([f64; 3], f64); 12] = [
    ([D12_A1, D12_A, D12_A], D12_WA),
    ([D12_A, D12_A1, D12_A], D12_WA),
    ([D12_A, D12_A, D12_A1], D12_WA),
    ([D12_B1, D12_B, D12_B], D12_WB),
    ([D12_B, D12_B1, D12_B], D12_WB),
    ([D12_B, D12_B, D12_B1], D12_WB),
    ([D12_CD, D12_C, D12_D], D12_WC),
    ([D12_CD, D12_D, D12_C], D12_WC),
    ([D12_C, D12_CD, D12_D], D12_WC),
    ([D12_D, D12_CD, D12_C], D12_WC),
    ([D12_C, D12_D, D12_CD], D12_WC),
    ([D12_D, D12_C, D12_CD], D12_WC),
];

#[cfg(test)]
mod tests {
    use super::*;

    fn factorial(n: u32) -> f64 {
        (1..=n).map(f64::from).product()
    }

    /// Mean of eta^a zeta^b over the triangle: 2 a! b! / (a + b + 2)!.
    fn exact_mean(a: u32, b: u32) -> f64 {
        2.0 * factorial(a) * factorial(b) / factorial(a + b + 2)
    }

    fn quad_mean(rule: Rule, a: i32, b: i32) -> f64 {
        rule.points()
            .iter()
            .map(|(l, w)| w * l[1].powi(a) * l[2].powi(b))
            .sum()
    }

    #[test]
    fn weights_sum_to_one_and_points_are_area_coordinates() {
        for rule in [Rule::Dunavant7, Rule::Dunavant12] {
            let s: f64 = rule.points().iter().map(|p| p.1).sum();
            assert!((s - 1.0).abs() < 1e-15, "{rule:?}: {s}");
            for (l, w) in rule.points() {
                assert!((l[0] + l[1] + l[2] - 1.0).abs() < 1e-15);
                assert!(l.iter().all(|&x| x > 0.0) && *w > 0.0);
            }
        }
        assert_eq!(Rule::default(), Rule::Dunavant7);
        assert_eq!(Rule::Dunavant7.points().len(), 7);
        assert_eq!(Rule::Dunavant12.points().len(), 12);
    }

    #[test]
    fn exact_up_to_degree() {
        for (rule, deg) in [(Rule::Dunavant7, 5), (Rule::Dunavant12, 6)] {
            for a in 0..=deg {
                for b in 0..=(deg - a) {
                    let q = quad_mean(rule, a as i32, b as i32);
                    let x = exact_mean(a, b);
                    assert!(
                        (q - x).abs() < 1e-15,
                        "{rule:?} eta^{a} zeta^{b}: {q} vs {x}"
                    );
                }
            }
            // One degree higher is not exact for every monomial.
            let worst = (0..=deg + 1)
                .map(|a| {
                    let b = deg + 1 - a;
                    (quad_mean(rule, a as i32, b as i32) - exact_mean(a, b)).abs()
                })
                .fold(0.0, f64::max);
            assert!(
                worst > 1e-7,
                "{rule:?} unexpectedly exact at degree {}",
                deg + 1
            );
        }
    }
}
