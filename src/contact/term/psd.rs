//! Projection of a pair Hessian to positive semi-definite, in the
//! translation-free frame of the stencil points its type involves.

use nalgebra::SMatrix;

/// A pair Hessian with its negative eigenvalues set to zero. The pair
/// energy depends only on the differences of the stencil points its
/// formula involves (`points`: 2, 3 or 4), so its Hessian lives in their
/// translation-free motions: the eigensolve runs there (3x3, 6x6 or 9x9 in
/// place of a 12x12, the same result).
pub(super) fn project_psd(h: &SMatrix<f64, 12, 12>, points: &[usize]) -> SMatrix<f64, 12, 12> {
    match points.len() {
        2 => project_psd_in(h, &translation_free_frame::<3>(points)),
        3 => project_psd_in(h, &translation_free_frame::<6>(points)),
        _ => project_psd_in(h, &translation_free_frame::<9>(&[0, 1, 2, 3])),
    }
}

/// `h` projected to positive semi-definite, given an orthonormal basis `q`
/// of a subspace that holds its range.
fn project_psd_in<const N: usize>(
    h: &SMatrix<f64, 12, 12>,
    q: &SMatrix<f64, 12, N>,
) -> SMatrix<f64, 12, 12>
where
    nalgebra::Const<N>: nalgebra::DimSub<nalgebra::U1>,
    nalgebra::DefaultAllocator:
        nalgebra::allocator::Allocator<nalgebra::DimDiff<nalgebra::Const<N>, nalgebra::U1>>,
{
    let eig = (q.transpose() * h * q).symmetric_eigen();
    if eig.eigenvalues.iter().all(|&l| l >= 0.0) {
        return *h;
    }
    let v = q * eig.eigenvectors;
    let mut vl = v;
    for (mut col, l) in vl.column_iter_mut().zip(eig.eigenvalues.iter()) {
        col *= l.max(0.0);
    }
    vl * v.transpose()
}

/// An orthonormal basis (12 x N, N = 3 (points - 1)) of the motions of the
/// stencil's `points` that leave their centroid in place (the other points
/// fixed): the Helmert contrasts `(1, -1) / sqrt 2`, `(1, 1, -2) / sqrt 6`,
/// `(1, 1, 1, -3) / sqrt 12` over the points, each per coordinate.
fn translation_free_frame<const N: usize>(points: &[usize]) -> SMatrix<f64, 12, N> {
    debug_assert_eq!(N, 3 * (points.len() - 1));
    let mut q = SMatrix::<f64, 12, N>::zeros();
    for j in 1..points.len() {
        let norm = ((j * (j + 1)) as f64).sqrt();
        for (k, &pt) in points[..=j].iter().enumerate() {
            let c = if k < j { 1.0 } else { -(j as f64) } / norm;
            for d in 0..3 {
                q[(3 * pt + d, 3 * (j - 1) + d)] = c;
            }
        }
    }
    q
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::XorShift;
    use nalgebra::SVector;

    /// The projection in the translation-free frame of the points a pair
    /// Hessian involves equals the full 12x12 eigen-projection, and the
    /// frames are orthonormal and orthogonal to the translations.
    #[test]
    fn projection_in_the_translation_free_frame_equals_the_full_one() {
        fn check<const N: usize>(points: &[usize], rng: &mut XorShift) {
            let q = translation_free_frame::<N>(points);
            assert!((q.transpose() * q - SMatrix::<f64, N, N>::identity()).norm() < 1e-14);
            for d in 0..3 {
                let t = SVector::<f64, 12>::from_fn(|i, _| if i % 3 == d { 1.0 } else { 0.0 });
                assert!((q.transpose() * t).norm() < 1e-14);
            }
            for _ in 0..100 {
                let m = SMatrix::<f64, N, N>::from_fn(|_, _| rng.range(-1.0, 1.0));
                let h = q * (m + m.transpose()) * q.transpose();
                let eig = h.symmetric_eigen();
                let l = eig.eigenvalues.map(|l| l.max(0.0));
                let full = eig.eigenvectors
                    * SMatrix::<f64, 12, 12>::from_diagonal(&l)
                    * eig.eigenvectors.transpose();
                let got = project_psd(&h, points);
                let e = (got - full).norm();
                assert!(e < 1e-12 * h.norm(), "{points:?}: {e}");
                assert!(got.symmetric_eigen().eigenvalues.min() > -1e-12 * h.norm());
            }
        }
        let mut rng = XorShift(40);
        for points in [[0, 2].as_slice(), &[1, 3], &[3, 0]] {
            check::<3>(points, &mut rng);
        }
        for points in [[0, 1, 2].as_slice(), &[0, 3, 1], &[2, 0, 1]] {
            check::<6>(points, &mut rng);
        }
        check::<9>(&[0, 1, 2, 3], &mut rng);
    }
}
