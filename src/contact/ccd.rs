//! Additive continuous collision detection (ACCD; Li, Kaufman, Jiang 2021,
//! "Codimensional IPC", Alg. 1) for primitives thickened by `xi`.
//! Conventions: positions `x` at the step start, displacements `dx` over the whole
//! step, so a vertex is at `x + t dx` at fraction `t`; results are fractions of the step.

use super::distance::{V3, edge_edge_distance_sq, point_triangle_distance_sq};
use nalgebra::Vector3;

/// The minimum-separation factor s: ACCD stops once the gap `d - xi` falls below
/// `s (d0 - xi)`.
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
    accd(x, dx, 1, xi, t_max, |y| {
        let v = y.map(V3::<f64>::from);
        point_triangle_distance_sq(&v[0], &v[1], &v[2], &v[3])
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
    accd(x, dx, 2, xi, t_max, |y| {
        let v = y.map(V3::<f64>::from);
        edge_edge_distance_sq(&v[0], &v[1], &v[2], &v[3])
    })
}

/// ACCD on a four-vertex stencil whose first `split` vertices form one primitive.
fn accd(
    x: [Vector3<f64>; 4],
    dx: [Vector3<f64>; 4],
    split: usize,
    xi: f64,
    t_max: f64,
    dist_sq: impl Fn([Vector3<f64>; 4]) -> f64,
) -> Option<f64> {
    let s = MIN_SEPARATION;
    let xi_sq = xi * xi;
    let mut d_sq = dist_sq(x);
    if d_sq <= xi_sq {
        return Some(0.0);
    }
    // The distance is translation invariant: remove the mean displacement, then
    // lp bounds the rate at which the distance can shrink.
    let mean = dx.iter().sum::<Vector3<f64>>() / 4.0;
    let p = dx.map(|d| d - mean);
    let norm = |r: &[Vector3<f64>]| r.iter().map(|v| v.norm()).fold(0.0, f64::max);
    let lp = norm(&p[..split]) + norm(&p[split..]);
    if lp <= 0.0 {
        return None;
    }
    // Gap d - xi, evaluated as (d^2 - xi^2) / (d + xi).
    let gap = |d_sq: f64| (d_sq - xi_sq) / (d_sq.sqrt() + xi);
    let target = s * gap(d_sq);
    let at = |t: f64| std::array::from_fn(|k| x[k] + p[k] * t);
    let mut t = 0.0;
    let mut t_l = (1.0 - s) * gap(d_sq) / lp;
    if t_l > t_max {
        // The first step is safe and already passes t_max (as the loop
        // would find, one distance later).
        return None;
    }
    for it in 0..MAX_ITERATIONS {
        d_sq = dist_sq(at(t + t_l));
        // The first step is safe by construction (it spends (1 - s) of the gap).
        if it > 0 && (d_sq <= xi_sq || gap(d_sq) < target) {
            return Some(t);
        }
        t += t_l;
        if t > t_max {
            return None;
        }
        t_l = 0.9 * gap(d_sq) / lp;
    }
    Some(t.min(t_max))
}

#[cfg(test)]
mod tests {
    use super::*;
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
