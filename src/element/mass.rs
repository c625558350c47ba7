//! Closed-form consistent mass matrix (MATH.md section 3).
//!
//! The shape functions depend on area coordinates only, so for every
//! straight-edged triangle `M = rho h area Mhat (x) I3` with the same rational
//! `Mhat = mean over the triangle of s_i s_j`. It is constant: factor it once.
//!
//! MATH.md prints row 8 with its last two entries swapped (19, 31), which makes
//! the matrix unsymmetric; exact integration gives (31, 19), used here.

use super::shape::Shape;
use crate::material::Material;
use nalgebra::SMatrix;

/// `10080 * Mhat`, exact integers (element order as in [`super::ElemVec`]).
const MASS_HAT_10080: [[f64; 9]; 9] = [
    [1936., 208., 208., 712., 76., 136., 712., 136., 76.],
    [208., 31., 19., 136., 13., 25., 76., 13., 11.],
    [208., 19., 31., 76., 11., 13., 136., 25., 13.],
    [712., 136., 76., 1936., 208., 208., 712., 76., 136.],
    [76., 13., 11., 208., 31., 19., 136., 13., 25.],
    [136., 25., 13., 208., 19., 31., 76., 11., 13.],
    [712., 76., 136., 712., 136., 76., 1936., 208., 208.],
    [136., 13., 25., 76., 13., 11., 208., 31., 19.],
    [76., 11., 13., 136., 25., 13., 208., 19., 31.],
];

const fn divide(m: [[f64; 9]; 9], d: f64) -> [[f64; 9]; 9] {
    let mut out = [[0.0; 9]; 9];
    let mut i = 0;
    while i < 9 {
        let mut j = 0;
        while j < 9 {
            out[i][j] = m[i][j] / d;
            j += 1;
        }
        i += 1;
    }
    out
}

/// Dimensionless mass matrix `Mhat` (mean of `s_i s_j` over the triangle):
/// the element mass is `rho * h * area * Mhat (x) I3`.
pub const MASS_HAT: [[f64; 9]; 9] = divide(MASS_HAT_10080, 10080.0);

/// The 27x27 element mass matrix `rho h area Mhat (x) I3` (index `3 k + c`)
/// of a triangle with shape functions `shape`.
pub fn element_mass(mat: &Material, area: f64, shape: &Shape) -> SMatrix<f64, 27, 27> {
    let s = mat.density * mat.thickness * area;
    let mass_hat = shape.mass_hat();
    let mut m = SMatrix::<f64, 27, 27>::zeros();
    for k in 0..9 {
        for l in 0..9 {
            for c in 0..3 {
                m[(3 * k + c, 3 * l + c)] = s * mass_hat[k][l];
            }
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::quadrature::Rule;
    use nalgebra::{SMatrix, SVector};

    fn mhat() -> SMatrix<f64, 9, 9> {
        SMatrix::<f64, 9, 9>::from_fn(|i, j| MASS_HAT[i][j])
    }

    #[test]
    fn symmetric_positive_definite() {
        let m = mhat();
        assert_eq!(m, m.transpose());
        let ev = m.symmetric_eigenvalues();
        assert!(ev.min() > 1e-6, "eigenvalues {ev}");
        let m27 = element_mass(&sheet(0.5, 3.0), 2.0, &Shape::BCIZ);
        assert_eq!(m27, m27.transpose());
        assert!(m27.cholesky().is_some());
    }

    /// A sheet of thickness `h` and density `rho` (the mass ignores E and nu).
    fn sheet(h: f64, rho: f64) -> Material {
        Material {
            youngs_modulus: 1.0,
            poisson_ratio: 0.3,
            thickness: h,
            density: rho,
        }
    }

    #[test]
    fn unit_right_triangle_diagonal() {
        let m = element_mass(&sheet(0.25, 4.0), 0.5, &Shape::BCIZ);
        for k in 0..9 {
            let want = if k % 3 == 0 { 0.0960317 } else { 0.0015377 };
            for c in 0..3 {
                assert!((m[(3 * k + c, 3 * k + c)] - want).abs() < 5e-8);
            }
        }
    }

    #[test]
    fn rigid_translation_kinetic_energy() {
        let mat = Material {
            youngs_modulus: 1.0,
            poisson_ratio: 0.3,
            thickness: 0.1,
            density: 7.0,
        };
        let area = 1.7;
        let m = element_mass(&mat, area, &Shape::BCIZ);
        // Unit velocity along a direction d: positions move with d, gradients are fixed.
        for d in [[1.0, 0.0, 0.0], [0.0, 0.6, 0.8]] {
            let mut v = SVector::<f64, 27>::zeros();
            for node in 0..3 {
                for c in 0..3 {
                    v[9 * node + c] = d[c];
                }
            }
            let t = 0.5 * v.dot(&(m * v));
            let want = 0.5 * mat.density * mat.thickness * area;
            assert!((t - want).abs() < 1e-14 * want, "{t} vs {want}");
        }
    }

    fn integrated(rule: Rule) -> SMatrix<f64, 9, 9> {
        let mut m = SMatrix::<f64, 9, 9>::zeros();
        for (l, w) in rule.points() {
            let s = Shape::BCIZ.values(*l);
            for i in 0..9 {
                for j in 0..9 {
                    m[(i, j)] += w * s[i] * s[j];
                }
            }
        }
        m
    }

    #[test]
    fn dunavant12_reproduces_and_dunavant7_does_not() {
        let err12 = (integrated(Rule::Dunavant12) - mhat()).amax();
        assert!(err12 < 1e-15, "12-point error {err12}");
        // The 7-point rule misses degree 6: largest entry error 6.8e-4 (= 1/1470).
        let err7 = (integrated(Rule::Dunavant7) - mhat()).amax();
        assert!((err7 - 1.0 / 1470.0).abs() < 1e-9, "7-point error {err7}");
    }
}
