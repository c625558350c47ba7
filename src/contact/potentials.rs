//! The scalar laws under self-contact and the obstacles: the log barrier in
//! the gap and its derivatives, the stiffness a fast approach asks for, and
//! smoothed Coulomb friction (its slip factor, its matrix, the fraction of
//! a correction that would carry a slide through rest), with the tangent
//! basis at a normal.

use super::scalar::Real;
use nalgebra::{Matrix3, Vector2, Vector3};

/// The kinetic energy `m v_n^2 / 2` of a pair's approach is stopped at
/// `b(s) = PAIR_SPEED_DIVISOR s_hat^2 / 2`: at about 4 % of the barrier
/// width (see [`ContactTerm::pair_stiffness`]).
pub(crate) const PAIR_SPEED_DIVISOR: f64 = 6.0;

/// The fraction of a correction `du` of a pair's tangential velocity `u`
/// at which it comes closest to rest, where the correction would carry it
/// through sticking to sliding the other way (`slide` its velocity at the
/// step start, `eps` the stick velocity); None where it would not (see
/// [`ContactTerm::friction_fraction`]).
pub(crate) fn reversal_fraction(
    u: Vector2<f64>,
    du: Vector2<f64>,
    slide: Vector2<f64>,
    eps: f64,
) -> Option<f64> {
    let end = u + du;
    // A pair that slid at the step start only where it slides that
    // way and is carried past rest to slide back (an iterate
    // sliding the other way, such as the held predictor's, is on
    // its way back); one that stuck, wherever it is carried past.
    let start = if slide.norm() > eps { slide } else { u };
    if u.norm() <= eps || end.norm() <= eps || u.dot(&start) <= 0.0 || end.dot(&start) >= 0.0 {
        return None;
    }
    let stop = -u.dot(&du) / du.norm_squared();
    (stop > 0.0).then_some(stop)
}

/// Smoothed Coulomb friction's `f1(y) / y` and its derivative over `y`
/// at tangential speed `y` (`f1` rises as `2y/eps - (y/eps)^2` up to the
/// stick velocity `eps`, then is 1).
pub(crate) fn slip_factor(y: f64, eps: f64) -> (f64, f64) {
    if y < eps {
        (
            2.0 / eps - y / (eps * eps),
            if y > 0.0 { -1.0 / (eps * eps * y) } else { 0.0 },
        )
    } else {
        (1.0 / y, -1.0 / (y * y * y))
    }
}

/// `scale T [phi I + (phi'/y) u u^T] T^T`: friction's derivative in the
/// relative velocity times `scale` (`c mu lambda`), `T` the tangent
/// `basis`, `u` the tangential velocity in it, `(phi, dphi_y)` from
/// [`slip_factor`].
pub(crate) fn friction_matrix(
    scale: f64,
    basis: &[Vector3<f64>; 2],
    u: Vector2<f64>,
    (phi, dphi_y): (f64, f64),
) -> Matrix3<f64> {
    let t = nalgebra::Matrix3x2::from_columns(basis);
    let inner = nalgebra::Matrix2::identity() * phi + dphi_y * u * u.transpose();
    scale * t * inner * t.transpose()
}

/// The barrier stiffness a pair of sample mass `mass` approaching at
/// `approach` (m/s) takes: `kappa`, or enough to stop it at
/// `b(s) = PAIR_SPEED_DIVISOR s_hat^2 / 2` (see
/// [`ContactTerm::pair_stiffness`]).
pub(crate) fn speed_stiffness(kappa: f64, mass: f64, approach: f64, s_hat: f64) -> f64 {
    kappa.max(mass * approach * approach / (PAIR_SPEED_DIVISOR * s_hat.powi(2)))
}

/// Barrier `b(s)` and its first two derivatives in `s`.
pub(crate) fn barrier<T: Real>(s: T, s_hat: f64) -> T {
    let u = s - s_hat;
    -(u * u) * (s / s_hat).ln()
}

/// `b'(s)` (negative inside the width).
pub(crate) fn db(s: f64, s_hat: f64) -> f64 {
    let u = s - s_hat;
    -2.0 * u * (s / s_hat).ln() - u * u / s
}

/// `b''(s)`.
pub(crate) fn ddb(s: f64, s_hat: f64) -> f64 {
    let u = s - s_hat;
    -2.0 * (s / s_hat).ln() - 4.0 * u / s + u * u / (s * s)
}

/// An orthonormal basis of the plane normal to `n` (unit).
pub(crate) fn tangent_basis(n: &Vector3<f64>) -> [Vector3<f64>; 2] {
    let a = if n.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let t0 = n.cross(&a).normalize();
    [t0, n.cross(&t0)]
}
