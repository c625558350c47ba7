//! Continuous collision detection for primitives thickened by `xi`: conservative
//! advancement (as additive CCD, Li, Kaufman, Jiang 2021, "Codimensional IPC",
//! Alg. 1) with a bound on the rate of *normal approach* instead of the whole
//! relative motion.
//!
//! The bound: split each primitive's motion into its mean translation and the
//! rest (deformation, rotation). Under the translations alone the two primitives'
//! Minkowski difference is a convex set moving on a line, so its distance to the
//! origin is convex in time: it never falls below its tangent, whose slope is the
//! approach of the translations along the current normal. The rest moves any point
//! of either primitive by at most its largest vertex deviation. So from fraction
//! `t` on, `d(t + r) >= d(t) + r (n . (u_a - u_b)) - r (e_a + e_b)`. A pair sliding
//! at a tiny gap approaches at the rate its primitives deform and rotate, not at
//! the rate it slides (additive CCD admits a fraction `gap / |relative motion|`).
//! Conventions: positions `x` at the step start, displacements `dx` over the whole
//! step, so a vertex is at `x + t dx` at fraction `t`; results are fractions of the step.

use super::distance::{edge_edge_closest, point_triangle_closest};
use nalgebra::Vector3;

/// The minimum-separation factor s: the advancement stops once the gap `d - xi`
/// falls below `s (d0 - xi)`.
pub const MIN_SEPARATION: f64 = 0.1;

/// Iteration cap: past it the current (safe) `t` is returned.
pub const MAX_ITERATIONS: usize = 10_000;

/// Time-of-impact fraction for point `x[0]` against triangle `x[1..4]`: `Some(t)`,
/// `t` in [0, t_max], a conservative fraction at which the distance is still at
/// least `xi + s (d0 - xi)`; `None` when the motion up to `t_max` stays clear of `xi`.
pub fn point_triangle_toi(
    x: [Vector3<f64>; 4],
    dx: [Vector3<f64>; 4],
    xi: f64,
    t_max: f64,
) -> Option<f64> {
    advance(x, dx, 1, xi, t_max, |y| {
        let b = point_triangle_closest(&y[0], &y[1], &y[2], &y[3]);
        (y[0], y[1] * b[0] + y[2] * b[1] + y[3] * b[2])
    })
}

/// Time-of-impact fraction for edge `x[0] x[1]` against edge `x[2] x[3]`, as
/// [`point_triangle_toi`].
pub fn edge_edge_toi(
    x: [Vector3<f64>; 4],
    dx: [Vector3<f64>; 4],
    xi: f64,
    t_max: f64,
) -> Option<f64> {
    advance(x, dx, 2, xi, t_max, |y| {
        let (s, t) = edge_edge_closest(&y[0], &y[1], &y[2], &y[3]);
        (y[0] + (y[1] - y[0]) * s, y[2] + (y[3] - y[2]) * t)
    })
}

/// Conservative advancement on a four-vertex stencil whose first `split`
/// vertices form one primitive; `closest` gives the closest points of the
/// two primitives (first, second) at positions `y`.
fn advance(
    x: [Vector3<f64>; 4],
    dx: [Vector3<f64>; 4],
    split: usize,
    xi: f64,
    t_max: f64,
    closest: impl Fn(&[Vector3<f64>; 4]) -> (Vector3<f64>, Vector3<f64>),
) -> Option<f64> {
    // Each primitive's mean translation and its vertices' largest deviation
    // from it.
    let mean = |r: &[Vector3<f64>]| r.iter().sum::<Vector3<f64>>() / r.len() as f64;
    let (ua, ub) = (mean(&dx[..split]), mean(&dx[split..]));
    let dev =
        |r: &[Vector3<f64>], u: &Vector3<f64>| r.iter().map(|v| (v - u).norm()).fold(0.0, f64::max);
    let spread = dev(&dx[..split], &ua) + dev(&dx[split..], &ub);
    let du = ua - ub;
    let at = |t: f64| -> [Vector3<f64>; 4] { std::array::from_fn(|k| x[k] + dx[k] * t) };
    // Distance and the rate bound at fraction t.
    let probe = |t: f64| {
        let (a, b) = closest(&at(t));
        let r = a - b;
        let d = r.norm();
        let approach = if d > 0.0 {
            -(r.dot(&du)) / d
        } else {
            du.norm()
        };
        (d, spread + approach.max(0.0))
    };
    advance_by(probe, xi, t_max)
}

/// Conservative advancement of a distance along a motion: `probe(t)`
/// gives the distance at fraction `t` and a bound on its rate of decrease
/// from there on (`d(t + r) >= d(t) - r rate`). As [`point_triangle_toi`]:
/// `Some(t)` safe with the gap above `s (d0 - xi)`, or `None` when the
/// motion up to `t_max` stays clear of `xi`.
pub(crate) fn advance_by(probe: impl Fn(f64) -> (f64, f64), xi: f64, t_max: f64) -> Option<f64> {
    let s = MIN_SEPARATION;
    let (d0, mut rate) = probe(0.0);
    if d0 <= xi {
        return Some(0.0);
    }
    let target = s * (d0 - xi);
    let mut t = 0.0;
    let mut gap = d0 - xi;
    for it in 0..MAX_ITERATIONS {
        if rate <= 0.0 {
            return None;
        }
        // The first step spends (1 - s) of the gap, later ones 0.9 of theirs.
        let t_l = if it == 0 { 1.0 - s } else { 0.9 } * gap / rate;
        if t + t_l > t_max {
            // Safe up to t + t_l, past t_max.
            return None;
        }
        let (d, r) = probe(t + t_l);
        // The first step keeps s of the gap by the bound (a rounding below
        // the target there is no reason to stop).
        if d <= xi || (it > 0 && d - xi < target) {
            return Some(t);
        }
        t += t_l;
        gap = d - xi;
        rate = r;
    }
    Some(t.min(t_max))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::distance::{V3, edge_edge_distance_sq, point_triangle_distance_sq};
    use crate::rng::XorShift;

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    fn pt_dist(x: [Vector3<f64>; 4]) -> f64 {
        let v = x.map(V3::<f64>::from);
        point_triangle_distance_sq(&v[0], &v[1], &v[2], &v[3]).sqrt()
    }

    fn ee_dist(x: [Vector3<f64>; 4]) -> f64 {
        let v = x.map(V3::<f64>::from);
        edge_edge_distance_sq(&v[0], &v[1], &v[2], &v[3]).sqrt()
    }

    fn at(x: &[Vector3<f64>; 4], dx: &[Vector3<f64>; 4], t: f64) -> [Vector3<f64>; 4] {
        std::array::from_fn(|k| x[k] + dx[k] * t)
    }

    const TRI: [Vector3<f64>; 3] = [
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(0.0, 1.0, 0.0),
    ];

    #[test]
    fn point_through_triangle_is_caught_before_crossing() {
        let xi = 1e-3;
        let z = Vector3::zeros();
        // From z = 1 to z = -1 in one step (crossing at t = 0.5), and a fast one
        // (to z = -1000: crossing at t ~ 1e-3) that a discrete check would tunnel through.
        for depth in [-1.0, -1000.0] {
            let x = [v(0.2, 0.2, 1.0), TRI[0], TRI[1], TRI[2]];
            let dx = [v(0.0, 0.0, depth - 1.0), z, z, z];
            let cross = 1.0 / (1.0 - depth);
            let t = point_triangle_toi(x, dx, xi, 1.0).expect("caught");
            assert!(t < cross, "t {t} at or past the crossing {cross}");
            let d = pt_dist(at(&x, &dx, t));
            assert!(d >= xi, "distance {d} below xi at t {t}");
            // Not absurdly early: the gap target is 0.1 (d0 - xi).
            assert!(
                d < xi + 0.2 * (1.0 - xi),
                "d {d} at t {t}: too conservative"
            );
            // The same with the triangle moving instead (the mean is removed).
            let dx2 = [z, -dx[0], -dx[0], -dx[0]];
            let t2 = point_triangle_toi(x, dx2, xi, 1.0).expect("caught");
            assert!(t2 < cross && pt_dist(at(&x, &dx2, t2)) >= xi);
            // A step limit before the impact: clear.
            assert_eq!(point_triangle_toi(x, dx, xi, 0.5 * cross), None);
        }
    }

    #[test]
    fn parallel_sliding_stays_clear_and_contact_at_start_is_zero() {
        let z = Vector3::zeros();
        let x = [v(0.2, 0.2, 0.01), TRI[0], TRI[1], TRI[2]];
        let dx = [v(5.0, 3.0, 0.0), z, z, z];
        assert_eq!(point_triangle_toi(x, dx, 1e-3, 1.0), None);
        // Within xi at the start.
        assert_eq!(point_triangle_toi(x, dx, 0.02, 1.0), Some(0.0));
        // Edges sliding along each other at a constant gap.
        let e = [
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.5, -1.0, 0.05),
            v(0.5, 1.0, 0.05),
        ];
        let de = [z, z, v(3.0, 0.0, 0.0), v(3.0, 0.0, 0.0)];
        assert_eq!(edge_edge_toi(e, de, 1e-2, 1.0), None);
        // Not moving at all.
        assert_eq!(edge_edge_toi(e, [z; 4], 1e-2, 1.0), None);
    }

    /// A pair sliding at a gap of 1e-13 of the thickness over a panel that
    /// turns a little: additive CCD, bounded by the whole relative motion,
    /// admitted 1e-6 of such a step per iteration and gave up at its
    /// iteration cap; the bound on the normal approach admits all of it,
    /// or stops where the turn brings the surfaces together.
    #[test]
    fn sliding_at_a_tiny_gap_is_not_held_up() {
        let xi = 5e-4;
        let z = Vector3::zeros();
        let x = [v(0.2, 0.2, xi + 1e-13), TRI[0], TRI[1], TRI[2]];
        // The point slides 0.3 along the triangle, which rises as a whole.
        let up = v(0.0, 0.0, 1e-9);
        let dx = [v(0.3, 0.1, 1e-9), up, up, up];
        assert_eq!(point_triangle_toi(x, dx, xi, 1.0), None);
        // The triangle turns about its edge 1-2 by 1e-6 rad, its vertex 0
        // coming up 1.4e-6: the gap closes over about 1e-7 of the step.
        let dx = [v(0.3, 0.1, 0.0), v(0.0, 0.0, 1.4e-6), z, z];
        let t = point_triangle_toi(x, dx, xi, 1.0).expect("the turn closes the gap");
        assert!(t > 3e-8 && t < 1.3e-7, "t {t}");
        let d = pt_dist(at(&x, &dx, t));
        assert!(d >= xi, "d {d} below the thickness");
        // Edges sliding along each other at a tiny gap.
        let e = [
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.5, -1.0, xi + 1e-13),
            v(0.5, 1.0, xi + 1e-13),
        ];
        let de = [z, z, v(0.2, 0.3, 0.0), v(0.2, 0.3, 0.0)];
        assert_eq!(edge_edge_toi(e, de, xi, 1.0), None);
    }

    /// Small gaps and motions mostly along the surfaces, with some
    /// deformation: never closer than the thickness on the way.
    #[test]
    fn grazing_motions_are_safe() {
        let mut rng = XorShift(0x9a7e);
        let mut hits = 0;
        for k in 0..400 {
            let xi = 1e-3;
            let gap = 10f64.powf(-rng.range(3.0, 12.0));
            let t: [Vector3<f64>; 3] = [
                v(rng.range(-0.1, 0.1), rng.range(-0.1, 0.1), 0.0),
                v(1.0 + rng.range(-0.1, 0.1), rng.range(-0.1, 0.1), 0.0),
                v(rng.range(-0.1, 0.1), 1.0 + rng.range(-0.1, 0.1), 0.0),
            ];
            let p = v(rng.range(0.1, 0.4), rng.range(0.1, 0.4), xi + gap);
            let slide = v(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), 0.0);
            let bend = 10f64.powf(-rng.range(2.0, 8.0));
            let mut r = || {
                v(
                    rng.range(-bend, bend),
                    rng.range(-bend, bend),
                    rng.range(-bend, bend),
                )
            };
            let dx = [slide + r(), r(), r(), r()];
            let x = [p, t[0], t[1], t[2]];
            let toi = point_triangle_toi(x, dx, xi, 1.0);
            let end = toi.unwrap_or(1.0);
            hits += usize::from(toi.is_some());
            for i in 0..=400 {
                let d = pt_dist(at(&x, &dx, end * i as f64 / 400.0));
                assert!(d >= xi, "case {k}: d - xi = {:.3e} before {end}", d - xi);
            }
        }
        assert!(hits > 50, "hits {hits}");
    }

    #[test]
    fn edge_edge_crossing_is_caught() {
        let z = Vector3::zeros();
        let xi = 1e-4;
        let e = [
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.5, -1.0, 0.5),
            v(0.5, 1.0, 0.5),
        ];
        for speed in [1.0, 200.0] {
            let de = [z, z, v(0.0, 0.0, -speed), v(0.0, 0.0, -speed)];
            let cross = 0.5 / speed;
            let t = edge_edge_toi(e, de, xi, 1.0).expect("caught");
            assert!(t < cross, "t {t} past the crossing {cross}");
            assert!(ee_dist(at(&e, &de, t)) >= xi);
        }
    }

    #[test]
    fn random_motions_are_safe() {
        let mut rng = XorShift(0xacc0);
        let mut r3 = |r: f64| v(rng.range(-r, r), rng.range(-r, r), rng.range(-r, r));
        let (mut hits, mut misses) = (0, 0);
        for k in 0..600 {
            let x: [Vector3<f64>; 4] = std::array::from_fn(|_| r3(1.0));
            let dx: [Vector3<f64>; 4] = std::array::from_fn(|_| r3(2.0));
            let xi = [0.0, 1e-3, 0.05][k % 3];
            let edge = k % 2 == 1;
            let dist = if edge { ee_dist } else { pt_dist };
            let toi = if edge {
                edge_edge_toi(x, dx, xi, 1.0)
            } else {
                point_triangle_toi(x, dx, xi, 1.0)
            };
            let d0 = dist(x);
            match toi {
                Some(t) => {
                    assert!((0.0..=1.0).contains(&t));
                    if d0 > xi {
                        hits += 1;
                        // Safe at t, and over the whole way from 0 to t.
                        for i in 0..=200 {
                            let d = dist(at(&x, &dx, t * i as f64 / 200.0));
                            assert!(d >= xi, "case {k}: d {d} < xi {xi} before t {t}");
                        }
                    } else {
                        assert_eq!(t, 0.0);
                    }
                }
                None => {
                    misses += 1;
                    for i in 0..=2000 {
                        let d = dist(at(&x, &dx, i as f64 / 2000.0));
                        assert!(d > xi, "case {k}: None, but d {d} < xi {xi}");
                    }
                }
            }
        }
        assert!(hits > 50 && misses > 50, "hits {hits} misses {misses}");
    }
}
