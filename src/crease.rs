//! Crease fold-angle kernel: the angle between two facets at one crease end
//! node, its exact first and second derivatives, and the rotational spring on
//! it (MATH.md section 5).
//!
//! # Geometry
//!
//! At a crease end node, `t` is the crease tangent (pointing from this node
//! along the crease), `a` a position gradient pointing into facet I and `b`
//! one pointing into facet II. Facet I lies to the **right** of `t` and facet
//! II to the **left**, seen from the side the counter-clockwise facet normal
//! points to (flat sheet in z = 0 seen from +z: `t = +x`, `a = -y`, `b = +y`).
//!
//! ```text
//! m = a x t,   n = b x t
//! theta = atan2(|t| (n . a), m . n)   wrapped to [0, 2 pi)
//! ```
//!
//! `theta` is the counter-clockwise angle about `t` from the part of `a`
//! normal to `t` to the part of `b` normal to `t`: it is `pi` when flat and
//! does not depend on the components of `a`, `b` along `t` nor on the lengths
//! of `a`, `b`, `t`. The FOLD fold angle is `phi = theta - pi`, positive for a
//! valley fold (both facets lifted towards their counter-clockwise normal) and
//! negative for a mountain fold. `atan2` is used instead of the paper's
//! `arccos` because it keeps the sign (mountain vs. valley) and full precision
//! at the flat state, where `arccos` and its `1/sin(theta)` derivatives fail.
//!
//! # Derivatives
//!
//! With `g_a = d theta/d a` etc. (these are exact, see MATH.md section 5):
//!
//! ```text
//! g_a = + |t| m / |m|^2
//! g_b = - |t| n / |n|^2
//! g_t = - (alpha g_a + beta g_b),   alpha = a.t / |t|^2,  beta = b.t / |t|^2
//! ```
//!
//! The Hessian blocks follow by differentiating these once more, with
//! `P_m = I - 2 m m^T / |m|^2` (the derivative of `m / |m|^2` times `|m|^2`)
//! and `[v]x` the cross-product matrix (`[v]x w = v x w`):
//!
//! ```text
//! H_aa = - |t| / |m|^2 P_m [t]x          H_bb = + |t| / |n|^2 P_n [t]x
//! H_at = m t^T / (|t| |m|^2) + |t| / |m|^2 P_m [a]x
//! H_bt = - ( n t^T / (|t| |n|^2) + |t| / |n|^2 P_n [b]x )
//! H_ab = 0
//! H_tt = - ( g_a grad(alpha)^T + alpha H_at + g_b grad(beta)^T + beta H_bt ),
//!        grad(alpha) = a / |t|^2 - 2 (a.t) t / |t|^4  (likewise beta)
//! ```
//!
//! These equal MATH.md's symmetric forms; the diagonal blocks are symmetrised
//! numerically so that the assembled 9x9 Hessian is exactly symmetric.
//!
//! # Degenerate input
//!
//! Nothing here panics or returns NaN/inf. If `t = 0`, or `a` or `b` is
//! parallel to `t` to within rounding (`|m| <= eps |a| |t|`, likewise `n`), or
//! any input is not finite, the derivatives are all zero; `theta` is still
//! `atan2` of the (finite) numbers and is exactly `pi` when both arguments are
//! zero or not finite. Callers should treat `|m|` or `|n|` near zero as a
//! failed configuration rather than rely on these fallback values.
//!
//! # Example
//!
//! ```
//! use nalgebra::Vector3;
//! use origami_fmu::crease::{theta, unwrap};
//! use std::f64::consts::PI;
//! // Valley fold by 2 * 0.3 rad: both facets of a flat sheet lifted towards +z.
//! let (c, s) = (0.3f64.cos(), 0.3f64.sin());
//! let t = Vector3::new(1.0, 0.0, 0.0);
//! let a = Vector3::new(0.0, -c, s); // facet I, right of t
//! let b = Vector3::new(0.0, c, s); // facet II, left of t
//! let phi = theta(&a, &b, &t) - PI;
//! assert!((phi - 0.6).abs() < 1e-14);
//! // Tracking through 0 = 2 pi: 0.01 after 6.27 is really 2 pi + 0.01.
//! assert!((unwrap(0.01, 6.27) - (2.0 * PI + 0.01)).abs() < 1e-14);
//! ```

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};
use std::f64::consts::{PI, TAU};

/// The two `atan2` arguments `(y, x)` and the cross products `m`, `n`.
struct Raw {
    y: f64,
    x: f64,
    m: Vector3<f64>,
    n: Vector3<f64>,
    t_norm: f64,
}

fn raw(a: &Vector3<f64>, b: &Vector3<f64>, t: &Vector3<f64>) -> Raw {
    let m = a.cross(t);
    let n = b.cross(t);
    let t_norm = t.norm();
    Raw {
        y: t_norm * n.dot(a),
        x: m.dot(&n),
        m,
        n,
        t_norm,
    }
}

/// `atan2(y, x)` wrapped to `[0, 2 pi)`; exactly `pi` if both are zero or
/// either is not finite.
fn wrapped_atan2(y: f64, x: f64) -> f64 {
    if !(y.is_finite() && x.is_finite()) || (y == 0.0 && x == 0.0) {
        return PI;
    }
    let mut th = y.atan2(x);
    if th < 0.0 {
        th += TAU;
    }
    // -tiny + 2 pi rounds to 2 pi, which lies on the branch of 0.
    if th >= TAU { 0.0 } else { th }
}

/// The crease angle `theta = atan2(|t| (n . a), m . n)` in `[0, 2 pi)` with
/// `m = a x t`, `n = b x t`: `pi` when flat, `pi + phi` for a FOLD fold angle
/// `phi` (valley positive). `a` points into facet I (right of `t`), `b` into
/// facet II (left of `t`). Exactly `pi` for degenerate input (see the module
/// docs); never NaN.
pub fn theta(a: &Vector3<f64>, b: &Vector3<f64>, t: &Vector3<f64>) -> f64 {
    let r = raw(a, b, t);
    wrapped_atan2(r.y, r.x)
}

/// [`theta`] with its exact derivatives with respect to `(a, b, t)`.
#[derive(Clone, Debug, PartialEq)]
pub struct AngleDerivatives {
    /// The angle, identical to [`theta`] (in `[0, 2 pi)`, not unwrapped).
    pub theta: f64,
    /// `[d theta/d a, d theta/d b, d theta/d t]`; all zero for degenerate input.
    pub grad: [Vector3<f64>; 3],
    /// If requested, the Hessian as 3x3 blocks: `hess[i][j]` is
    /// `d^2 theta / (d x_i d x_j^T)` with `x = (a, b, t)`; exactly symmetric
    /// (`hess[j][i] == hess[i][j]^T`). All zero for degenerate input.
    pub hess: Option<[[Matrix3<f64>; 3]; 3]>,
}

impl AngleDerivatives {
    /// The gradient as one 9-vector ordered `(a, b, t)`.
    pub fn grad9(&self) -> SVector<f64, 9> {
        let mut g = SVector::<f64, 9>::zeros();
        for (i, gi) in self.grad.iter().enumerate() {
            g.fixed_rows_mut::<3>(3 * i).copy_from(gi);
        }
        g
    }

    /// The Hessian as one 9x9 matrix ordered `(a, b, t)`, if it was computed.
    pub fn hess9(&self) -> Option<SMatrix<f64, 9, 9>> {
        self.hess.as_ref().map(|h| {
            let mut out = SMatrix::<f64, 9, 9>::zeros();
            for (i, row) in h.iter().enumerate() {
                for (j, blk) in row.iter().enumerate() {
                    out.fixed_view_mut::<3, 3>(3 * i, 3 * j).copy_from(blk);
                }
            }
            out
        })
    }
}

fn symmetrised(h: &Matrix3<f64>) -> Matrix3<f64> {
    (h + h.transpose()) * 0.5
}

/// [`theta`] with its exact gradient with respect to `(a, b, t)` and, if
/// `hessian`, the exact 9x9 Hessian (formulas in the module docs). For
/// degenerate input (`t = 0`, `a` or `b` parallel to `t`, non-finite values)
/// the derivatives are zero and `theta` is as [`theta`] returns it.
pub fn theta_derivatives(
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    t: &Vector3<f64>,
    hessian: bool,
) -> AngleDerivatives {
    let r = raw(a, b, t);
    let th = wrapped_atan2(r.y, r.x);
    let zero = || AngleDerivatives {
        theta: th,
        grad: [Vector3::zeros(); 3],
        hess: hessian.then(|| [[Matrix3::zeros(); 3]; 3]),
    };

    let tt = t.norm_squared();
    let mm = r.m.norm_squared();
    let nn = r.n.norm_squared();
    let eps2 = f64::EPSILON * f64::EPSILON;
    let finite = a
        .iter()
        .chain(b.iter())
        .chain(t.iter())
        .all(|v| v.is_finite());
    // NaN from overflowing products slips past these comparisons but is
    // caught by the finiteness check on the results below.
    if !finite
        || tt <= 0.0
        || mm <= eps2 * a.norm_squared() * tt
        || nn <= eps2 * b.norm_squared() * tt
    {
        return zero();
    }

    let (m, n, tn) = (&r.m, &r.n, r.t_norm);
    let ga = m * (tn / mm);
    let gb = n * (-tn / nn);
    let alpha = a.dot(t) / tt;
    let beta = b.dot(t) / tt;
    let gt = -(ga * alpha + gb * beta);

    let hess = hessian.then(|| {
        let id = Matrix3::<f64>::identity();
        let pm = id - m * m.transpose() * (2.0 / mm);
        let pn = id - n * n.transpose() * (2.0 / nn);
        let tx = t.cross_matrix();
        let haa = symmetrised(&(pm * tx * (-tn / mm)));
        let hbb = symmetrised(&(pn * tx * (tn / nn)));
        let hat = m * t.transpose() / (tn * mm) + pm * a.cross_matrix() * (tn / mm);
        let hbt = -(n * t.transpose() / (tn * nn) + pn * b.cross_matrix() * (tn / nn));
        let dalpha = a / tt - t * (2.0 * a.dot(t) / (tt * tt));
        let dbeta = b / tt - t * (2.0 * b.dot(t) / (tt * tt));
        let htt = symmetrised(
            &(-(ga * dalpha.transpose() + hat * alpha + gb * dbeta.transpose() + hbt * beta)),
        );
        let z = Matrix3::zeros();
        [
            [haa, z, hat],
            [z, hbb, hbt],
            [hat.transpose(), hbt.transpose(), htt],
        ]
    });

    let out = AngleDerivatives {
        theta: th,
        grad: [ga, gb, gt],
        hess,
    };
    let all_finite = out.grad.iter().all(|g| g.iter().all(|v| v.is_finite()))
        && out.hess.as_ref().is_none_or(|h| {
            h.iter()
                .flatten()
                .all(|blk| blk.iter().all(|v| v.is_finite()))
        });
    if all_finite { out } else { zero() }
}

/// Bring a raw angle (e.g. from [`theta`], in `[0, 2 pi)`) onto the branch
/// `raw + 2 pi k` nearest to `previous`, so that an angle tracked in time
/// passes through `0 = 2 pi` without a jump. Returns `raw` unchanged if either
/// argument is not finite.
pub fn unwrap(raw: f64, previous: f64) -> f64 {
    if !(raw.is_finite() && previous.is_finite()) {
        return raw;
    }
    let k = ((previous - raw) / TAU).round();
    raw + k * TAU
}

/// Rotational spring `U = k (theta - theta0)^2 / 2` on a crease angle.
///
/// `theta` is the (unwrapped) current angle, `d` the derivatives from
/// [`theta_derivatives`] at the same configuration. Overwrites `force` with
/// `dU/d(a, b, t) = k (theta - theta0) grad` (ordered `a, b, t`) and, if
/// given, `tangent` with `k grad grad^T + k (theta - theta0) H` (the second
/// term is left out if `d.hess` is `None`). Returns `U`. A viscous moment
/// `c * theta_dot` is the caller's business (its force is `c theta_dot grad`).
pub fn spring(
    k: f64,
    theta: f64,
    theta0: f64,
    d: &AngleDerivatives,
    force: &mut SVector<f64, 9>,
    tangent: Option<&mut SMatrix<f64, 9, 9>>,
) -> f64 {
    let dth = theta - theta0;
    let g = d.grad9();
    *force = g * (k * dth);
    if let Some(kt) = tangent {
        *kt = g * g.transpose() * k;
        if let Some(h) = d.hess9() {
            *kt += h * (k * dth);
        }
    }
    0.5 * k * dth * dth
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic random numbers for the tests.
    struct Rng(crate::rng::XorShift);
    impl Rng {
        fn new(seed: u64) -> Self {
            Rng(crate::rng::XorShift(seed))
        }
        fn range(&mut self, lo: f64, hi: f64) -> f64 {
            self.0.range(lo, hi)
        }
        fn unit(&mut self) -> Vector3<f64> {
            loop {
                let v = Vector3::new(
                    self.range(-1.0, 1.0),
                    self.range(-1.0, 1.0),
                    self.range(-1.0, 1.0),
                );
                let l = v.norm();
                if l > 0.2 && l < 1.0 {
                    return v / l;
                }
            }
        }
    }

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    /// Rotation of `x` about the unit axis `k` by `ang` (Rodrigues).
    fn rotate(x: &Vector3<f64>, k: &Vector3<f64>, ang: f64) -> Vector3<f64> {
        x * ang.cos() + k.cross(x) * ang.sin() + k * (k.dot(x) * (1.0 - ang.cos()))
    }

    /// A random configuration with prescribed angle `target`: random `t` of
    /// length in [0.5, 2], `a` normal part random, `b` normal part that rotated
    /// by `target` about `t`, then random lengths and components along `t`.
    fn config(rng: &mut Rng, target: f64) -> [Vector3<f64>; 3] {
        let that = rng.unit();
        let t = that * rng.range(0.5, 2.0);
        let r = rng.unit();
        let u = (r - that * that.dot(&r)).normalize();
        let w = rotate(&u, &that, target);
        let a = u * rng.range(0.3, 3.0) + t * rng.range(-1.5, 1.5);
        let b = w * rng.range(0.3, 3.0) + t * rng.range(-1.5, 1.5);
        [a, b, t]
    }

    fn pack(x: &[Vector3<f64>; 3]) -> SVector<f64, 9> {
        let mut s = SVector::<f64, 9>::zeros();
        for (i, xi) in x.iter().enumerate() {
            s.fixed_rows_mut::<3>(3 * i).copy_from(xi);
        }
        s
    }

    fn unpack(s: &SVector<f64, 9>) -> [Vector3<f64>; 3] {
        [
            s.fixed_rows::<3>(0).into_owned(),
            s.fixed_rows::<3>(3).into_owned(),
            s.fixed_rows::<3>(6).into_owned(),
        ]
    }

    fn theta9(s: &SVector<f64, 9>) -> f64 {
        let x = unpack(s);
        theta(&x[0], &x[1], &x[2])
    }

    /// The test configurations: generic, near flat, strongly folded both ways.
    fn targets() -> Vec<f64> {
        let mut ts = vec![
            PI,
            PI + 1e-3,
            PI - 1e-3,
            PI + 1e-4,
            PI - 3e-4,
            PI + 1e-7,
            0.05,
            TAU - 0.05,
            0.08,
            TAU - 0.07,
        ];
        let mut rng = Rng::new(0x1234_5678_9ABC_DEF1);
        for _ in 0..30 {
            ts.push(rng.range(0.05, TAU - 0.05));
        }
        ts
    }

    fn max_abs<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> f64 {
        m.iter().fold(0.0f64, |acc, x| acc.max(x.abs()))
    }

    /// The valley/mountain sign convention of the brief, checked by hand:
    /// t = +x, a = (0, -cos al, sin al), b = (0, cos al, sin al) is a valley
    /// fold lifting both facets towards +z, and must give phi = +2 al.
    #[test]
    fn crease_valley_positive_mountain_negative() {
        let t = v(1.0, 0.0, 0.0);
        for &al in &[
            1e-6,
            0.01,
            0.1,
            0.3,
            0.7,
            PI / 4.0,
            1.0,
            1.3,
            PI / 2.0 - 1e-3,
        ] {
            let (c, s) = (al.cos(), al.sin());
            // Valley: facets rise towards +z (their counter-clockwise normal).
            let phi = theta(&v(0.0, -c, s), &v(0.0, c, s), &t) - PI;
            assert!((phi - 2.0 * al).abs() < 1e-13, "valley al={al}: phi={phi}");
            // Mountain: facets drop towards -z.
            let phi = theta(&v(0.0, -c, -s), &v(0.0, c, -s), &t) - PI;
            assert!(
                (phi + 2.0 * al).abs() < 1e-13,
                "mountain al={al}: phi={phi}"
            );
            // Only facet I lifted: fold angle al, still valley.
            let phi = theta(&v(0.0, -c, s), &v(0.0, 1.0, 0.0), &t) - PI;
            assert!((phi - al).abs() < 1e-13, "one-sided al={al}: phi={phi}");
        }
    }

    /// Flat sheets in z = 0 give exactly pi, whatever the in-plane directions
    /// and lengths, as long as a is right of t and b left of it.
    #[test]
    fn crease_flat_is_exactly_pi() {
        let cases = [
            (v(0.0, -1.0, 0.0), v(0.0, 1.0, 0.0), v(1.0, 0.0, 0.0)),
            (v(0.3, -1.0, 0.0), v(-0.2, 1.5, 0.0), v(2.0, 0.0, 0.0)),
            (v(-0.7, -0.1, 0.0), v(0.9, 2.0, 0.0), v(0.5, 0.0, 0.0)),
            (v(1.0, 0.0, 0.0), v(-1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)),
            (v(0.6, -0.8, 0.0), v(-0.6, 0.8, 0.0), v(0.8, 0.6, 0.0)),
        ];
        for (a, b, t) in cases {
            assert_eq!(theta(&a, &b, &t), PI, "a={a:?} b={b:?} t={t:?}");
            let d = theta_derivatives(&a, &b, &t, true);
            assert_eq!(d.theta, PI);
        }
    }

    /// Folds beyond 90 degrees and close to +-180 degrees (facets nearly
    /// folded onto each other), through the valley/mountain parametrisation.
    #[test]
    fn crease_large_folds() {
        let t = v(1.0, 0.0, 0.0);
        for &phi in &[
            1.7,
            2.5,
            3.0,
            PI - 1e-2,
            PI - 1e-4,
            PI - 1e-8,
            -1.7,
            -2.5,
            -(PI - 1e-2),
            -(PI - 1e-4),
            -(PI - 1e-8),
        ] {
            let al: f64 = phi / 2.0;
            let (c, s) = (al.cos(), al.sin());
            let th = theta(&v(0.0, -c, s), &v(0.0, c, s), &t);
            assert!((0.0..TAU).contains(&th));
            assert!((th - PI - phi).abs() < 1e-12, "phi={phi}: theta={th}");
        }
        // +-179 degrees in general position, also via the derivatives routine.
        let mut rng = Rng::new(77);
        for &deg in &[179.0f64, -179.0, 179.9, -179.9, 120.0, -135.0] {
            let phi = deg.to_radians();
            for _ in 0..5 {
                let x = config(&mut rng, PI + phi);
                let th = theta(&x[0], &x[1], &x[2]);
                assert!((th - PI - phi).abs() < 1e-12, "deg={deg}: theta={th}");
                assert_eq!(theta_derivatives(&x[0], &x[1], &x[2], true).theta, th);
            }
        }
    }

    /// theta is the counter-clockwise angle about t from a's normal part to
    /// b's normal part: `config` builds exactly that, so theta must match.
    #[test]
    fn crease_angle_is_ccw_angle_about_t() {
        let mut rng = Rng::new(5);
        for target in targets() {
            for _ in 0..5 {
                let x = config(&mut rng, target);
                let th = theta(&x[0], &x[1], &x[2]);
                assert!((th - target).abs() < 1e-11, "target={target}: {th}");
            }
        }
    }

    /// Invariance under positive scaling of each of a, b, t, under a rigid
    /// rotation of all three, and under adding multiples of t to a or b.
    #[test]
    fn crease_invariances() {
        let mut rng = Rng::new(99);
        for target in targets() {
            let [a, b, t] = config(&mut rng, target);
            let th = theta(&a, &b, &t);
            let close = |x: f64, what: &str| {
                assert!(
                    (x - th).abs() < 1e-12,
                    "{what}: {x} vs {th} (target {target})"
                );
            };
            for &s in &[1e-3, 0.37, 2.5, 1e3] {
                close(theta(&(a * s), &b, &t), "scale a");
                close(theta(&a, &(b * s), &t), "scale b");
                close(theta(&a, &b, &(t * s)), "scale t");
            }
            let axis = rng.unit();
            let ang = rng.range(-PI, PI);
            let (ra, rb, rt) = (
                rotate(&a, &axis, ang),
                rotate(&b, &axis, ang),
                rotate(&t, &axis, ang),
            );
            close(theta(&ra, &rb, &rt), "rotation");
            for &l in &[-2.0, -0.3, 0.8, 5.0] {
                close(theta(&(a + t * l), &b, &t), "a along t");
                close(theta(&a, &(b + t * l), &t), "b along t");
            }
            // Reversing t (or swapping the facets) mirrors the angle.
            let mirrored = theta(&a, &b, &(-t));
            assert!(
                (mirrored - (TAU - th)).abs() < 1e-12,
                "mirror: {mirrored} vs {th}"
            );
        }
    }

    /// Gradient against central differences of theta, relative error < 1e-6
    /// of the largest entry, at generic, near-flat and strongly folded states
    /// with non-orthogonal a, b, t and |t| != 1.
    #[test]
    fn crease_gradient_matches_finite_differences() {
        let mut rng = Rng::new(2024);
        for target in targets() {
            for _ in 0..3 {
                let x = config(&mut rng, target);
                let d = theta_derivatives(&x[0], &x[1], &x[2], false);
                assert!(d.hess.is_none());
                let g = d.grad9();
                let s0 = pack(&x);
                let h = 1e-6;
                let mut fd = SVector::<f64, 9>::zeros();
                for i in 0..9 {
                    let (mut sp, mut sm) = (s0, s0);
                    sp[i] += h;
                    sm[i] -= h;
                    let (tp, tm) = (unwrap(theta9(&sp), d.theta), unwrap(theta9(&sm), d.theta));
                    fd[i] = (tp - tm) / (2.0 * h);
                }
                let err = max_abs(&(fd - g)) / max_abs(&g);
                assert!(err < 1e-6, "target={target}: rel err {err}\n{g}\n{fd}");
            }
        }
    }

    /// Hessian against central differences of the gradient, same tolerance,
    /// and exactly symmetric.
    #[test]
    fn crease_hessian_matches_finite_differences() {
        let mut rng = Rng::new(31337);
        for target in targets() {
            for _ in 0..3 {
                let x = config(&mut rng, target);
                let d = theta_derivatives(&x[0], &x[1], &x[2], true);
                let hm = d.hess9().unwrap();
                assert_eq!(hm, hm.transpose(), "Hessian not exactly symmetric");
                let s0 = pack(&x);
                let h = 1e-6;
                let mut fd = SMatrix::<f64, 9, 9>::zeros();
                for j in 0..9 {
                    let (mut sp, mut sm) = (s0, s0);
                    sp[j] += h;
                    sm[j] -= h;
                    let (xp, xm) = (unpack(&sp), unpack(&sm));
                    let gp = theta_derivatives(&xp[0], &xp[1], &xp[2], false).grad9();
                    let gm = theta_derivatives(&xm[0], &xm[1], &xm[2], false).grad9();
                    fd.set_column(j, &((gp - gm) / (2.0 * h)));
                }
                let err = max_abs(&(fd - hm)) / max_abs(&hm);
                assert!(err < 1e-6, "target={target}: rel err {err}\n{hm}\n{fd}");
            }
        }
    }

    /// The blocks equal MATH.md section 5's closed forms, written with
    /// `u (.) v = u v^T + v u^T` (checked to 1e-12 relative).
    #[test]
    fn crease_hessian_equals_math_md_forms() {
        let sym = |u: &Vector3<f64>, w: &Vector3<f64>| u * w.transpose() + w * u.transpose();
        let mut rng = Rng::new(17);
        for target in targets() {
            let [a, b, t] = config(&mut rng, target);
            let d = theta_derivatives(&a, &b, &t, true);
            let h = d.hess.unwrap();
            let (m, n, tn) = (a.cross(&t), b.cross(&t), t.norm());
            let (m2, n2) = (m.norm_squared(), n.norm_squared());
            let haa = sym(&m, &t.cross(&m)) * (-tn / (m2 * m2));
            let hbb = sym(&n, &t.cross(&n)) * (tn / (n2 * n2));
            let hat = m * t.transpose() / (m2 * tn) + sym(&m, &a.cross(&m)) * (tn / (m2 * m2));
            let hbt = -(n * t.transpose() / (n2 * tn) + sym(&n, &b.cross(&n)) * (tn / (n2 * n2)));
            let scale = max_abs(&d.hess9().unwrap());
            for (mine, theirs) in [
                (h[0][0], haa),
                (h[1][1], hbb),
                (h[0][2], hat),
                (h[1][2], hbt),
            ] {
                assert!(
                    max_abs(&(mine - theirs)) < 1e-12 * scale,
                    "{mine}\n{theirs}"
                );
            }
            assert_eq!(h[0][1], Matrix3::zeros());
            assert!((d.grad[0] - m * (tn / m2)).norm() < 1e-14 * d.grad[0].norm());
            assert!((d.grad[1] + n * (tn / n2)).norm() < 1e-14 * d.grad[1].norm());
        }
    }

    /// The gradient obeys the invariances exactly: orthogonal to t in each
    /// block, and sum of x_i cross g_i = 0 (rotation invariance).
    #[test]
    fn crease_gradient_invariance_identities() {
        let mut rng = Rng::new(8);
        for target in targets() {
            let x = config(&mut rng, target);
            let d = theta_derivatives(&x[0], &x[1], &x[2], false);
            let scale = d.grad.iter().map(|g| g.norm()).fold(0.0, f64::max) * x[2].norm();
            for g in &d.grad {
                assert!(g.dot(&x[2]).abs() < 1e-12 * scale);
            }
            let rot: Vector3<f64> = (0..3).map(|i| x[i].cross(&d.grad[i])).sum();
            let scale: f64 = (0..3).map(|i| x[i].norm() * d.grad[i].norm()).sum();
            assert!(rot.norm() < 1e-12 * scale, "{rot}");
        }
    }

    /// Degenerate input gives finite output and zero derivatives, never NaN.
    #[test]
    fn crease_degenerate_input_is_finite() {
        let t = v(1.0, 0.0, 0.0);
        let a = v(0.0, -1.0, 0.2);
        let b = v(0.3, 1.0, 0.4);
        let nan = v(f64::NAN, 0.0, 0.0);
        let inf = v(0.0, f64::INFINITY, 0.0);
        let cases = [
            (a, b, Vector3::zeros()),
            (v(2.0, 0.0, 0.0), b, t),
            (a, v(-3.0, 0.0, 0.0), t),
            (v(2.0, 0.0, 0.0), v(-1.0, 0.0, 0.0), t),
            (Vector3::zeros(), b, t),
            (a, Vector3::zeros(), t),
            (Vector3::zeros(), Vector3::zeros(), Vector3::zeros()),
            (v(1.0, 1e-300, 0.0), b, t),
            (v(1.0, 1e-17, 0.0), b, t),
            (nan, b, t),
            (a, inf, t),
            (a, b, nan),
            // Overflowing products.
            (v(0.0, -1e200, 1e200), b, v(1e200, 0.0, 0.0)),
            (
                v(0.0, -1e160, 1e160),
                v(0.0, 1e160, 1e150),
                v(1e160, 0.0, 0.0),
            ),
        ];
        for (a, b, t) in cases {
            let th = theta(&a, &b, &t);
            assert!(th.is_finite() && (0.0..TAU).contains(&th), "{th}");
            let d = theta_derivatives(&a, &b, &t, true);
            assert_eq!(d.theta, th);
            assert!(
                d.grad.iter().all(|g| *g == Vector3::zeros()),
                "{a:?} {b:?} {t:?}"
            );
            assert!(d.hess9().unwrap() == SMatrix::<f64, 9, 9>::zeros());
            let mut f = SVector::<f64, 9>::zeros();
            let mut kt = SMatrix::<f64, 9, 9>::zeros();
            let u = spring(2.0, th, 1.0, &d, &mut f, Some(&mut kt));
            assert!(u.is_finite() && f.iter().all(|x| x.is_finite()));
            assert!(kt.iter().all(|x| x.is_finite()));
        }
        // Exactly degenerate (both atan2 arguments zero): theta is pi.
        assert_eq!(theta(&a, &b, &Vector3::zeros()), PI);
        assert_eq!(theta(&v(2.0, 0.0, 0.0), &b, &t), PI);
        assert_eq!(theta(&v(f64::NAN, 0.0, 0.0), &b, &t), PI);
    }

    /// Wrapping lands in [0, 2 pi) even for angles a hair below 0.
    #[test]
    fn crease_theta_range() {
        let t = v(1.0, 0.0, 0.0);
        for &e in &[1e-300, 1e-20, 1e-17, 1e-15, 1e-10] {
            // Facets folded completely onto each other, b slightly past a.
            for s in [-1.0, 1.0] {
                let a = v(0.0, 1.0, 0.0);
                let b = v(0.0, 1.0, s * e);
                let th = theta(&a, &b, &t);
                assert!((0.0..TAU).contains(&th), "{th}");
                assert!(th.min(TAU - th) < 1e-9, "{th}");
            }
        }
    }

    /// unwrap puts a value on the branch nearest the previous one.
    #[test]
    fn crease_unwrap_basic() {
        let c = |x: f64, y: f64| assert!((x - y).abs() < 1e-13, "{x} vs {y}");
        c(unwrap(0.01, 6.27), TAU + 0.01);
        c(unwrap(6.27, 0.01), 6.27 - TAU);
        c(unwrap(1.0, 1.2), 1.0);
        c(unwrap(3.0, 3.0 + 5.0 * TAU), 3.0 + 5.0 * TAU);
        c(unwrap(6.2, -3.0 * TAU + 0.1), 6.2 - 4.0 * TAU);
        assert_eq!(unwrap(1.5, f64::NAN), 1.5);
    }

    /// A crease folded continuously from theta = 0.6 down through 0 = 2 pi to
    /// -0.9 and back up to 0.4 is tracked without jumps by unwrapping each
    /// raw theta against the previous tracked value.
    #[test]
    fn crease_unwrap_tracks_through_zero() {
        let mut rng = Rng::new(4242);
        let that = rng.unit();
        let t = that * 1.3;
        let r = rng.unit();
        let u = (r - that * that.dot(&r)).normalize();
        let a = u * 0.8 + t * 0.2;
        let steps = 400;
        let path = |k: usize| {
            let s = k as f64 / steps as f64;
            // Down from 0.6 to -0.9 for s in [0, 0.5], back up to 0.4.
            if s <= 0.5 {
                0.6 - 3.0 * s
            } else {
                -0.9 + 2.6 * (s - 0.5)
            }
        };
        let mut tracked = theta(&a, &(rotate(&u, &that, path(0)) * 1.1), &t);
        let mut wrapped_seen = false;
        for k in 1..=steps {
            let want = path(k);
            let b = rotate(&u, &that, want) * 1.1 - t * 0.4;
            let raw = theta(&a, &b, &t);
            assert!((0.0..TAU).contains(&raw));
            wrapped_seen |= raw > PI;
            let next = unwrap(raw, tracked);
            assert!(
                (next - tracked).abs() < 0.02,
                "jump at step {k}: {tracked} -> {next}"
            );
            assert!((next - want).abs() < 1e-12, "step {k}: {next} vs {want}");
            tracked = next;
        }
        assert!(wrapped_seen, "the raw angle never wrapped");
        assert!((tracked - 0.4).abs() < 1e-12);
    }

    /// Spring force against central differences of the energy, tangent
    /// against central differences of the force.
    #[test]
    fn crease_spring_matches_finite_differences() {
        let mut rng = Rng::new(555);
        let k = 3.7;
        for target in targets() {
            let x = config(&mut rng, target);
            // theta0 on either side, including across the 0 = 2 pi branch.
            let theta0 = target + rng.range(-1.0, 1.0);
            let s0 = pack(&x);
            let energy_force = |s: &SVector<f64, 9>, tangent: Option<&mut SMatrix<f64, 9, 9>>| {
                let y = unpack(s);
                let d = theta_derivatives(&y[0], &y[1], &y[2], tangent.is_some());
                let th = unwrap(d.theta, target);
                let mut f = SVector::<f64, 9>::zeros();
                let u = spring(k, th, theta0, &d, &mut f, tangent);
                (u, f)
            };
            let mut kt = SMatrix::<f64, 9, 9>::zeros();
            let (u0, f0) = energy_force(&s0, Some(&mut kt));
            let th0 = unwrap(theta9(&s0), target);
            assert!((u0 - 0.5 * k * (th0 - theta0).powi(2)).abs() < 1e-12 * (1.0 + u0));
            assert_eq!(kt, kt.transpose());
            let h = 1e-6;
            let mut fd_f = SVector::<f64, 9>::zeros();
            let mut fd_k = SMatrix::<f64, 9, 9>::zeros();
            for j in 0..9 {
                let (mut sp, mut sm) = (s0, s0);
                sp[j] += h;
                sm[j] -= h;
                let (up, fp) = energy_force(&sp, None);
                let (um, fm) = energy_force(&sm, None);
                fd_f[j] = (up - um) / (2.0 * h);
                fd_k.set_column(j, &((fp - fm) / (2.0 * h)));
            }
            let ef = max_abs(&(fd_f - f0)) / max_abs(&f0);
            let ek = max_abs(&(fd_k - kt)) / max_abs(&kt);
            assert!(ef < 1e-6, "force: target={target}: {ef}");
            assert!(ek < 1e-6, "tangent: target={target}: {ek}");
        }
        // Without a Hessian the tangent is the Gauss-Newton part k g g^T.
        let x = config(&mut rng, 2.0);
        let d = theta_derivatives(&x[0], &x[1], &x[2], false);
        let (mut f, mut kt) = (SVector::<f64, 9>::zeros(), SMatrix::<f64, 9, 9>::zeros());
        spring(k, d.theta, 1.0, &d, &mut f, Some(&mut kt));
        let g = d.grad9();
        assert_eq!(kt, g * g.transpose() * k);
        assert_eq!(f, g * (k * (d.theta - 1.0)));
    }
}
