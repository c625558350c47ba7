//! Squared distances between contact primitives (point-triangle, edge-edge) as in
//! IPC (Li et al. 2020): the closest-feature type is chosen on the `f64` values, then
//! that type's smooth formula runs in any [`Real`] (duals give exact derivatives).
//! Conventions: generic points are [`V3<T>`]; `f64`-only functions take `Vector3<f64>`;
//! triangle edge `i` runs from vertex `i` to vertex `(i + 1) % 3`; segment
//! parameters are `s` on `a0 -> a1`, `t` on `b0 -> b1`, both in [0, 1].

use super::scalar::Real;
use nalgebra::Vector3;
use std::ops::{Add, Neg, Sub};

/// A point or vector in 3D over a generic scalar: the small vector algebra that the
/// distance formulas need (`+`, `-`, dot, cross, scale).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V3<T>(pub [T; 3]);

impl<T: Real> V3<T> {
    /// From three components.
    pub fn new(x: T, y: T, z: T) -> Self {
        V3([x, y, z])
    }
    /// A constant point (zero derivatives).
    pub fn cst(p: &Vector3<f64>) -> Self {
        V3([T::cst(p.x), T::cst(p.y), T::cst(p.z)])
    }
    /// A point whose components are variables `first`, `first + 1`, `first + 2`.
    pub fn vars(p: &Vector3<f64>, first: usize) -> Self {
        V3([
            T::var(p.x, first),
            T::var(p.y, first + 1),
            T::var(p.z, first + 2),
        ])
    }
    /// The points of a stencil as variables: point `k` holds variables `3k..3k+3`
    /// (for `Dual2<{3 * M}>`, the derivatives with respect to all coordinates).
    pub fn stencil<const M: usize>(points: &[Vector3<f64>; M]) -> [Self; M] {
        std::array::from_fn(|k| V3::vars(&points[k], 3 * k))
    }
    /// The values, without derivatives.
    pub fn val(&self) -> Vector3<f64> {
        Vector3::new(self.0[0].val(), self.0[1].val(), self.0[2].val())
    }
    /// Dot product.
    pub fn dot(&self, o: &Self) -> T {
        self.0[0] * o.0[0] + self.0[1] * o.0[1] + self.0[2] * o.0[2]
    }
    /// Cross product.
    pub fn cross(&self, o: &Self) -> Self {
        let (a, b) = (&self.0, &o.0);
        V3([
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ])
    }
    /// Squared length.
    pub fn norm_sq(&self) -> T {
        self.dot(self)
    }
    /// Scaled by a scalar of the same type.
    pub fn scale(&self, s: T) -> Self {
        V3([self.0[0] * s, self.0[1] * s, self.0[2] * s])
    }
}

impl<T: Real> Add for V3<T> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        V3([self.0[0] + o.0[0], self.0[1] + o.0[1], self.0[2] + o.0[2]])
    }
}
impl<T: Real> Sub for V3<T> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        V3([self.0[0] - o.0[0], self.0[1] - o.0[1], self.0[2] - o.0[2]])
    }
}
impl<T: Real> Neg for V3<T> {
    type Output = Self;
    fn neg(self) -> Self {
        V3([-self.0[0], -self.0[1], -self.0[2]])
    }
}
impl From<Vector3<f64>> for V3<f64> {
    fn from(p: Vector3<f64>) -> Self {
        V3([p.x, p.y, p.z])
    }
}

/// Which feature pair of a point-triangle pair is closest (IPC's `PointTriangleDistanceType`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PointTriangleType {
    /// The point to triangle vertex `i` (0, 1 or 2).
    Vertex(u8),
    /// The point to the line of edge `i` (vertex `i` to `(i + 1) % 3`).
    Edge(u8),
    /// The point to the plane of the triangle (projection inside).
    Face,
}

/// Which feature pair of two segments is closest (IPC's `EdgeEdgeDistanceType`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EdgeEdgeType {
    /// Vertex `a_i` to vertex `b_j`.
    Points(u8, u8),
    /// Vertex `a_i` to the line of edge b.
    PointAEdgeB(u8),
    /// Vertex `b_j` to the line of edge a.
    EdgeAPointB(u8),
    /// The two lines (closest points inside both segments, not near parallel).
    LineLine,
}

/// |p - q|^2.
pub fn point_point_sq<T: Real>(p: &V3<T>, q: &V3<T>) -> T {
    (*p - *q).norm_sq()
}

/// Squared distance from `p` to the infinite line through `e0`, `e1`:
/// |(e0 - p) x (e1 - p)|^2 / |e1 - e0|^2.
pub fn point_line_sq<T: Real>(p: &V3<T>, e0: &V3<T>, e1: &V3<T>) -> T {
    let c = (*e0 - *p).cross(&(*e1 - *p));
    c.norm_sq() / (*e1 - *e0).norm_sq()
}

/// Squared distance from `p` to the plane through `t0`, `t1`, `t2`:
/// ((p - t0) . n)^2 / |n|^2 with n = (t1 - t0) x (t2 - t0).
pub fn point_plane_sq<T: Real>(p: &V3<T>, t0: &V3<T>, t1: &V3<T>, t2: &V3<T>) -> T {
    let n = (*t1 - *t0).cross(&(*t2 - *t0));
    (*p - *t0).dot(&n).sq() / n.norm_sq()
}

/// Squared distance between the infinite lines through `a0 a1` and `b0 b1`:
/// ((b0 - a0) . n)^2 / |n|^2 with n = (a1 - a0) x (b1 - b0) (not parallel).
pub fn line_line_sq<T: Real>(a0: &V3<T>, a1: &V3<T>, b0: &V3<T>, b1: &V3<T>) -> T {
    let n = (*a1 - *a0).cross(&(*b1 - *b0));
    (*b0 - *a0).dot(&n).sq() / n.norm_sq()
}

/// Closest point parameter of `p` on segment `a b`, clamped to [0, 1]
/// (0 for a zero-length segment).
fn segment_param(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let e = b - a;
    let l = e.norm_squared();
    if l <= 0.0 {
        return 0.0;
    }
    ((p - a).dot(&e) / l).clamp(0.0, 1.0)
}

/// Barycentric coordinates `[w0, w1, w2]` (summing to 1) of the point of triangle
/// `t0 t1 t2` closest to `p`: for friction bases and reports.
pub fn point_triangle_closest(
    p: &Vector3<f64>,
    t0: &Vector3<f64>,
    t1: &Vector3<f64>,
    t2: &Vector3<f64>,
) -> [f64; 3] {
    point_triangle_closest_typed(p, t0, t1, t2).0
}

/// The closest point's barycentrics and the feature type it lies on.
fn point_triangle_closest_typed(
    p: &Vector3<f64>,
    t0: &Vector3<f64>,
    t1: &Vector3<f64>,
    t2: &Vector3<f64>,
) -> ([f64; 3], PointTriangleType) {
    let (e1, e2, r) = (t1 - t0, t2 - t0, p - t0);
    let n = e1.cross(&e2);
    let nn = n.norm_squared();
    if nn > 0.0 {
        // Barycentrics of the projection onto the plane (Cramer with the normal).
        let b1 = r.cross(&e2).dot(&n) / nn;
        let b2 = e1.cross(&r).dot(&n) / nn;
        if b1 > 0.0 && b2 > 0.0 && b1 + b2 < 1.0 {
            return ([1.0 - b1 - b2, b1, b2], PointTriangleType::Face);
        }
    }
    // Outside (or a degenerate triangle): the minimum lies on the boundary.
    let t = [t0, t1, t2];
    let mut best: Option<(f64, [f64; 3], PointTriangleType)> = None;
    for i in 0..3 {
        let j = (i + 1) % 3;
        let s = segment_param(p, t[i], t[j]);
        let q = t[i] + (t[j] - t[i]) * s;
        let d = (p - q).norm_squared();
        let mut w = [0.0; 3];
        w[i] = 1.0 - s;
        w[j] = s;
        let ty = if s <= 0.0 {
            PointTriangleType::Vertex(i as u8)
        } else if s >= 1.0 {
            PointTriangleType::Vertex(j as u8)
        } else {
            PointTriangleType::Edge(i as u8)
        };
        if best.is_none_or(|b| d < b.0) {
            best = Some((d, w, ty));
        }
    }
    let (_, w, ty) = best.expect("three edges");
    (w, ty)
}

/// The closest-feature type of point `p` and triangle `t0 t1 t2` (exact closest
/// point in `f64`, then which feature it lies on).
pub fn point_triangle_type(
    p: &Vector3<f64>,
    t0: &Vector3<f64>,
    t1: &Vector3<f64>,
    t2: &Vector3<f64>,
) -> PointTriangleType {
    point_triangle_closest_typed(p, t0, t1, t2).1
}

/// The squared distance of a point-triangle pair by the formula of a given type
/// (to classify once and evaluate in several scalars).
pub fn point_triangle_sq_of_type<T: Real>(
    ty: PointTriangleType,
    p: &V3<T>,
    t0: &V3<T>,
    t1: &V3<T>,
    t2: &V3<T>,
) -> T {
    let t = [t0, t1, t2];
    match ty {
        PointTriangleType::Vertex(i) => point_point_sq(p, t[i as usize]),
        PointTriangleType::Edge(i) => point_line_sq(p, t[i as usize], t[(i as usize + 1) % 3]),
        PointTriangleType::Face => point_plane_sq(p, t0, t1, t2),
    }
}

/// Squared distance between point `p` and triangle `t0 t1 t2`, smooth within each
/// closest-feature type (IPC's `point_triangle_distance`).
pub fn point_triangle_distance_sq<T: Real>(p: &V3<T>, t0: &V3<T>, t1: &V3<T>, t2: &V3<T>) -> T {
    let ty = point_triangle_type(&p.val(), &t0.val(), &t1.val(), &t2.val());
    point_triangle_sq_of_type(ty, p, t0, t1, t2)
}

/// Relative threshold on sin^2 of the angle between two edges below which the
/// line-line formula is not used (IPC's parallel threshold).
const PARALLEL_SIN_SQ: f64 = 1e-20;

/// Closest parameters `(s, t)` on segments `a0 a1` and `b0 b1` with the feature type.
fn edge_edge_closest_typed(
    a0: &Vector3<f64>,
    a1: &Vector3<f64>,
    b0: &Vector3<f64>,
    b1: &Vector3<f64>,
) -> (f64, f64, EdgeEdgeType) {
    let (u, v, w) = (a1 - a0, b1 - b0, a0 - b0);
    let (a, b, c, d, e) = (
        u.norm_squared(),
        u.dot(&v),
        v.norm_squared(),
        u.dot(&w),
        v.dot(&w),
    );
    let ty = |s: f64, t: f64| {
        let side = |x: f64| {
            if x <= 0.0 {
                Some(0u8)
            } else if x >= 1.0 {
                Some(1u8)
            } else {
                None
            }
        };
        match (side(s), side(t)) {
            (Some(i), Some(j)) => EdgeEdgeType::Points(i, j),
            (Some(i), None) => EdgeEdgeType::PointAEdgeB(i),
            (None, Some(j)) => EdgeEdgeType::EdgeAPointB(j),
            (None, None) => EdgeEdgeType::LineLine,
        }
    };
    let n = u.cross(&v);
    let cross = n.norm_squared();
    if a > 0.0 && c > 0.0 && cross >= PARALLEL_SIN_SQ * a * c {
        // Interior stationary point of |w + s u - t v|^2, from cross products:
        // `a c - b^2` and `b e - c d` cancel to round-off for nearly
        // collinear segments and would put it anywhere.
        let r = b0 - a0;
        let s = r.cross(&v).dot(&n) / cross;
        let t = r.cross(&u).dot(&n) / cross;
        if s > 0.0 && s < 1.0 && t > 0.0 && t < 1.0 {
            return (s, t, EdgeEdgeType::LineLine);
        }
    }
    // Otherwise the minimum of the convex quadratic is on the boundary of the unit
    // square: the best of the four sides, each an exact clamped 1D minimum.
    let clamp = |x: f64, l: f64| {
        if l > 0.0 {
            (x / l).clamp(0.0, 1.0)
        } else {
            0.0
        }
    };
    let candidates = [
        (0.0, clamp(e, c)),
        (1.0, clamp(e + b, c)),
        (clamp(-d, a), 0.0),
        (clamp(b - d, a), 1.0),
    ];
    let mut best = (f64::INFINITY, 0.0, 0.0);
    for (s, t) in candidates {
        let dist = (w + u * s - v * t).norm_squared();
        if dist < best.0 {
            best = (dist, s, t);
        }
    }
    (best.1, best.2, ty(best.1, best.2))
}

/// Parameters `(s, t)` of the closest points `a0 + s (a1 - a0)` and
/// `b0 + t (b1 - b0)` of two segments: for friction bases and reports.
pub fn edge_edge_closest(
    a0: &Vector3<f64>,
    a1: &Vector3<f64>,
    b0: &Vector3<f64>,
    b1: &Vector3<f64>,
) -> (f64, f64) {
    let (s, t, _) = edge_edge_closest_typed(a0, a1, b0, b1);
    (s, t)
}

/// The closest-feature type of segments `a0 a1` and `b0 b1`; nearly parallel
/// pairs get a point-edge or point-point type, never `LineLine`.
pub fn edge_edge_type(
    a0: &Vector3<f64>,
    a1: &Vector3<f64>,
    b0: &Vector3<f64>,
    b1: &Vector3<f64>,
) -> EdgeEdgeType {
    edge_edge_closest_typed(a0, a1, b0, b1).2
}

/// The squared distance of an edge-edge pair by the formula of a given type.
pub fn edge_edge_sq_of_type<T: Real>(
    ty: EdgeEdgeType,
    a0: &V3<T>,
    a1: &V3<T>,
    b0: &V3<T>,
    b1: &V3<T>,
) -> T {
    let (a, b) = ([a0, a1], [b0, b1]);
    match ty {
        EdgeEdgeType::Points(i, j) => point_point_sq(a[i as usize], b[j as usize]),
        EdgeEdgeType::PointAEdgeB(i) => point_line_sq(a[i as usize], b0, b1),
        EdgeEdgeType::EdgeAPointB(j) => point_line_sq(b[j as usize], a0, a1),
        EdgeEdgeType::LineLine => line_line_sq(a0, a1, b0, b1),
    }
}

/// Squared distance between segments `a0 a1` and `b0 b1`, smooth within each
/// closest-feature type (IPC's `edge_edge_distance`).
pub fn edge_edge_distance_sq<T: Real>(a0: &V3<T>, a1: &V3<T>, b0: &V3<T>, b1: &V3<T>) -> T {
    let ty = edge_edge_type(&a0.val(), &a1.val(), &b0.val(), &b1.val());
    edge_edge_sq_of_type(ty, a0, a1, b0, b1)
}

/// Whether the first `k` points and the rest of a stencil are at least `d`
/// apart along a coordinate axis: then the distance between their convex
/// hulls (the point, segment or triangle) is at least `d`, which a pair
/// filter learns without the closest-feature search.
pub fn axis_apart(x: &[Vector3<f64>; 4], k: usize, d: f64) -> bool {
    // The spans of coordinate values, written out for the two stencils (a
    // pair filter's innermost test, for every candidate every iteration).
    let span = |v: &[f64]| {
        v.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &y| {
                (lo.min(y), hi.max(y))
            })
    };
    (0..3).any(|c| {
        let v = [x[0][c], x[1][c], x[2][c], x[3][c]];
        let ((alo, ahi), (blo, bhi)) = match k {
            1 => (span(&v[..1]), span(&v[1..])),
            2 => (span(&v[..2]), span(&v[2..])),
            _ => (span(&v[..k]), span(&v[k..])),
        };
        blo - ahi >= d || alo - bhi >= d
    })
}

/// IPC's mollifier for nearly parallel edges: with c = |(a1 - a0) x (b1 - b0)|^2,
/// m = 2 c / eps_x - c^2 / eps_x^2 for c < eps_x, else 1 (C1 at c = eps_x).
pub fn edge_edge_mollifier<T: Real>(
    a0: &V3<T>,
    a1: &V3<T>,
    b0: &V3<T>,
    b1: &V3<T>,
    eps_x: f64,
) -> T {
    let c = (*a1 - *a0).cross(&(*b1 - *b0)).norm_sq();
    if c.val() < eps_x {
        let x = c / eps_x;
        x * (-x + 2.0)
    } else {
        T::cst(1.0)
    }
}

/// The mollifier threshold eps_x = 1e-3 |a1 - a0|^2 |b1 - b0|^2 from the rest positions.
pub fn mollifier_threshold(
    a0: &Vector3<f64>,
    a1: &Vector3<f64>,
    b0: &Vector3<f64>,
    b1: &Vector3<f64>,
) -> f64 {
    1e-3 * (a1 - a0).norm_squared() * (b1 - b0).norm_squared()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::scalar::Dual2;
    use crate::rng::XorShift;

    fn rand_point(rng: &mut XorShift, r: f64) -> Vector3<f64> {
        Vector3::new(rng.range(-r, r), rng.range(-r, r), rng.range(-r, r))
    }

    fn f(p: &Vector3<f64>) -> V3<f64> {
        V3::from(*p)
    }

    /// Brute force: the minimum over a dense barycentric grid (and the edges, finer).
    fn brute_pt(p: &Vector3<f64>, t: [Vector3<f64>; 3]) -> f64 {
        let n = 300;
        let mut best = f64::INFINITY;
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                let q = t[0] * (1.0 - u - v) + t[1] * u + t[2] * v;
                best = best.min((p - q).norm_squared());
            }
        }
        for k in 0..3 {
            best = best.min(brute_segment_point(p, &t[k], &t[(k + 1) % 3]));
        }
        best
    }

    fn brute_segment_point(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
        let n = 20000;
        (0..=n)
            .map(|i| (p - (a + (b - a) * (i as f64 / n as f64))).norm_squared())
            .fold(f64::INFINITY, f64::min)
    }

    fn brute_ee(a0: &Vector3<f64>, a1: &Vector3<f64>, b0: &Vector3<f64>, b1: &Vector3<f64>) -> f64 {
        let n = 600;
        let mut best = f64::INFINITY;
        for i in 0..=n {
            let p = a0 + (a1 - a0) * (i as f64 / n as f64);
            for j in 0..=n {
                let q = b0 + (b1 - b0) * (j as f64 / n as f64);
                best = best.min((p - q).norm_squared());
            }
        }
        best
    }

    #[test]
    fn point_triangle_matches_brute_force_on_all_types() {
        let mut rng = XorShift(0x1234_5678_9abc);
        let mut seen = std::collections::HashSet::new();
        for _ in 0..400 {
            let t = [
                rand_point(&mut rng, 1.0),
                rand_point(&mut rng, 1.0),
                rand_point(&mut rng, 1.0),
            ];
            let p = rand_point(&mut rng, 1.5);
            let d = point_triangle_distance_sq(&f(&p), &f(&t[0]), &f(&t[1]), &f(&t[2]));
            let ty = point_triangle_type(&p, &t[0], &t[1], &t[2]);
            seen.insert(ty);
            let b = brute_pt(&p, t);
            // The grid only overestimates; its error is O(h) in distance.
            assert!(d <= b + 1e-12, "{ty:?}: {d} > brute {b}");
            assert!(b.sqrt() - d.sqrt() < 2e-2, "{ty:?}: {d} vs brute {b}");
            // The closest point reproduces the distance.
            let w = point_triangle_closest(&p, &t[0], &t[1], &t[2]);
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            assert!(w.iter().all(|&x| x >= -1e-12));
            let q = t[0] * w[0] + t[1] * w[1] + t[2] * w[2];
            assert!(((p - q).norm_squared() - d).abs() < 1e-10 * (1.0 + d));
        }
        assert_eq!(seen.len(), 7, "all seven types were hit: {seen:?}");
    }

    #[test]
    fn point_triangle_exact_cases() {
        let t = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
        ];
        let cases = [
            (Vector3::new(0.2, 0.2, 0.5), PointTriangleType::Face, 0.25),
            (
                Vector3::new(0.5, -1.0, 1.0),
                PointTriangleType::Edge(0),
                2.0,
            ),
            (Vector3::new(1.0, 1.0, 0.0), PointTriangleType::Edge(1), 0.5),
            (
                Vector3::new(-2.0, 0.5, 0.0),
                PointTriangleType::Edge(2),
                4.0,
            ),
            (
                Vector3::new(-1.0, -1.0, 1.0),
                PointTriangleType::Vertex(0),
                3.0,
            ),
            (
                Vector3::new(3.0, 0.0, 0.0),
                PointTriangleType::Vertex(1),
                4.0,
            ),
            (
                Vector3::new(-0.5, 2.0, 0.0),
                PointTriangleType::Vertex(2),
                1.25,
            ),
        ];
        for (p, ty, d) in cases {
            assert_eq!(point_triangle_type(&p, &t[0], &t[1], &t[2]), ty, "{p:?}");
            let got = point_triangle_distance_sq(&f(&p), &f(&t[0]), &f(&t[1]), &f(&t[2]));
            assert!((got - d).abs() < 1e-14, "{p:?}: {got} vs {d}");
        }
    }

    #[test]
    fn edge_edge_matches_brute_force_on_all_types() {
        let mut rng = XorShift(0xfeed_beef);
        let mut seen = std::collections::HashSet::new();
        for k in 0..300 {
            let a0 = rand_point(&mut rng, 1.0);
            let a1 = rand_point(&mut rng, 1.0);
            let mut b0 = rand_point(&mut rng, 1.0);
            let mut b1 = rand_point(&mut rng, 1.0);
            if k % 10 == 0 {
                // Exactly parallel (shifted copies): must avoid the line-line formula.
                let off = rand_point(&mut rng, 0.5);
                let sc = rng.range(0.3, 1.5);
                b0 = a0 + off;
                b1 = a0 + off + (a1 - a0) * sc;
            }
            let d = edge_edge_distance_sq(&f(&a0), &f(&a1), &f(&b0), &f(&b1));
            let ty = edge_edge_type(&a0, &a1, &b0, &b1);
            if k % 10 == 0 {
                assert_ne!(ty, EdgeEdgeType::LineLine);
            }
            seen.insert(ty);
            let b = brute_ee(&a0, &a1, &b0, &b1);
            assert!(d <= b + 1e-12, "{ty:?}: {d} > brute {b}");
            assert!(b.sqrt() - d.sqrt() < 1e-2, "{ty:?}: {d} vs brute {b}");
            let (s, t) = edge_edge_closest(&a0, &a1, &b0, &b1);
            assert!((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t));
            let gap = (a0 + (a1 - a0) * s) - (b0 + (b1 - b0) * t);
            assert!((gap.norm_squared() - d).abs() < 1e-10 * (1.0 + d));
        }
        assert_eq!(seen.len(), 9, "all nine types were hit: {seen:?}");
    }

    #[test]
    fn edge_edge_exact_cases() {
        let v = |x, y, z| Vector3::new(x, y, z);
        // Crossing lines 1 apart.
        let (a0, a1) = (v(-1.0, 0.0, 0.0), v(1.0, 0.0, 0.0));
        let (b0, b1) = (v(0.0, -1.0, 1.0), v(0.0, 1.0, 1.0));
        assert_eq!(edge_edge_type(&a0, &a1, &b0, &b1), EdgeEdgeType::LineLine);
        assert_eq!(edge_edge_closest(&a0, &a1, &b0, &b1), (0.5, 0.5));
        // T configuration: b0 above the middle of a.
        let (b0, b1) = (v(0.0, 0.0, 2.0), v(0.0, 0.0, 5.0));
        assert_eq!(
            edge_edge_type(&a0, &a1, &b0, &b1),
            EdgeEdgeType::EdgeAPointB(0)
        );
        let d = edge_edge_distance_sq(&f(&a0), &f(&a1), &f(&b0), &f(&b1));
        assert!((d - 4.0).abs() < 1e-14);
        // Collinear, disjoint: end to end.
        let (b0, b1) = (v(4.0, 0.0, 0.0), v(2.0, 0.0, 0.0));
        assert_eq!(
            edge_edge_type(&a0, &a1, &b0, &b1),
            EdgeEdgeType::Points(1, 1)
        );
        // Parallel overlapping at distance 0.5.
        let (b0, b1) = (v(0.0, 0.5, 0.0), v(3.0, 0.5, 0.0));
        let ty = edge_edge_type(&a0, &a1, &b0, &b1);
        assert!(matches!(
            ty,
            EdgeEdgeType::PointAEdgeB(_) | EdgeEdgeType::EdgeAPointB(_)
        ));
        let d = edge_edge_distance_sq(&f(&a0), &f(&a1), &f(&b0), &f(&b1));
        assert!((d - 0.25).abs() < 1e-14);
    }

    /// Segments nearly on one line (sin^2 of their angle 1e-17..1e-12, above
    /// the parallel threshold) and apart along it, their lines crossing in
    /// the gap, are as far apart as their nearest ends: the closest points of
    /// the lines lie just beyond both, and a stationary point from `a c - b^2`
    /// (round-off there) put some inside. The first case is two fine edges
    /// of a real pattern (flat-folder's seamless 4x4) whose distance was so
    /// taken as the lines' 1.8e-12 m instead of 2.6e-3 m.
    #[test]
    fn nearly_collinear_segments_apart_along_their_line() {
        let v = |x, y, z| Vector3::new(x, y, z);
        let point_segment = |p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>| {
            (a + (b - a) * segment_param(p, a, b) - p).norm_squared()
        };
        let exact = |a0: &Vector3<f64>, a1: &Vector3<f64>, b0: &Vector3<f64>, b1: &Vector3<f64>| {
            [
                point_segment(a0, b0, b1),
                point_segment(a1, b0, b1),
                point_segment(b0, a0, a1),
                point_segment(b1, a0, a1),
            ]
            .into_iter()
            .fold(f64::INFINITY, f64::min)
        };
        let mut cases = vec![(
            v(
                0.02728951141700892,
                0.08642895956204996,
                -0.0014689321601994271,
            ),
            v(
                0.026437068098735212,
                0.08404123420992422,
                -0.0008125644318228395,
            ),
            v(
                0.023879738181304604,
                0.07687805818296709,
                0.0011565389088699072,
            ),
            v(
                0.025584624786126154,
                0.08165350886225509,
                -0.00015619667987808492,
            ),
        )];
        let mut rng = XorShift(0x5eed_ca11);
        for k in 0..4000 {
            let a0 = rand_point(&mut rng, 0.1);
            let dir = rand_point(&mut rng, 1.0).normalize();
            let side = dir.cross(&rand_point(&mut rng, 1.0)).normalize();
            let len = rng.range(1e-3, 2e-2);
            let tilt = 10f64.powf(-rng.range(6.0, 8.5));
            // The lines cross at `x`, in the gap between the segments'
            // near ends (where a line-line stationary point is just beyond
            // both segments).
            let a1 = a0 + dir * len;
            let half_gap = rng.range(1e-5, 5e-3);
            let x = a1 + dir * half_gap;
            let turned = (dir + side * tilt).normalize();
            let b1 = x + turned * half_gap;
            let b0 = b1 + turned * rng.range(1e-3, 2e-2);
            cases.push(if k % 2 == 0 {
                (a0, a1, b0, b1)
            } else {
                (b1, b0, a1, a0)
            });
        }
        for (a0, a1, b0, b1) in cases {
            let want = exact(&a0, &a1, &b0, &b1);
            let got = edge_edge_distance_sq(&f(&a0), &f(&a1), &f(&b0), &f(&b1));
            let ty = edge_edge_type(&a0, &a1, &b0, &b1);
            assert!(
                (got - want).abs() <= 1e-9 * want,
                "{ty:?}: {got:e} against {want:e}"
            );
        }
    }

    /// Gradient and Hessian of `Dual2` against central differences of the f64 version.
    fn check_derivatives(
        x: [Vector3<f64>; 4],
        fd: impl Fn(&[Vector3<f64>; 4]) -> f64,
        dual: impl Fn(&[V3<Dual2<12>>; 4]) -> Dual2<12>,
    ) {
        let d = dual(&V3::stencil(&x));
        assert!((d.v - fd(&x)).abs() <= 1e-14 * (1.0 + d.v.abs()));
        let h = 1e-4;
        let shifted = |k: usize, dx: f64| {
            let mut y = x;
            y[k / 3][k % 3] += dx;
            y
        };
        let scale_g = d.g.norm().max(1e-3);
        let scale_h = d.h.norm().max(1e-3);
        for k in 0..12 {
            let g = (fd(&shifted(k, h)) - fd(&shifted(k, -h))) / (2.0 * h);
            assert!(
                (d.g[k] - g).abs() < 1e-6 * scale_g,
                "g[{k}] {} vs fd {g}",
                d.g[k]
            );
            for l in 0..12 {
                let e = |a: f64, b: f64| fd(&shifted2(&x, k, a, l, b));
                let hkl = (e(h, h) - e(h, -h) - e(-h, h) + e(-h, -h)) / (4.0 * h * h);
                assert!(
                    (d.h[(k, l)] - hkl).abs() < 1e-6 * scale_h,
                    "H[{k},{l}] {} vs fd {hkl}",
                    d.h[(k, l)]
                );
            }
        }
    }

    fn shifted2(x: &[Vector3<f64>; 4], k: usize, a: f64, l: usize, b: f64) -> [Vector3<f64>; 4] {
        let mut y = *x;
        y[k / 3][k % 3] += a;
        y[l / 3][l % 3] += b;
        y
    }

    fn pt_f64(x: &[Vector3<f64>; 4]) -> f64 {
        point_triangle_distance_sq(&f(&x[0]), &f(&x[1]), &f(&x[2]), &f(&x[3]))
    }

    fn ee_f64(x: &[Vector3<f64>; 4]) -> f64 {
        edge_edge_distance_sq(&f(&x[0]), &f(&x[1]), &f(&x[2]), &f(&x[3]))
    }

    #[test]
    fn dual2_derivatives_of_point_triangle_match_finite_differences() {
        let mut rng = XorShift(77);
        let mut seen = std::collections::HashSet::new();
        let mut tested = 0;
        while tested < 60 {
            let x = [
                rand_point(&mut rng, 1.5),
                rand_point(&mut rng, 1.0),
                rand_point(&mut rng, 1.0),
                rand_point(&mut rng, 1.0),
            ];
            // Away from type boundaries: the type is the same in a box around x.
            let ty = point_triangle_type(&x[0], &x[1], &x[2], &x[3]);
            let stable = (0..200).all(|_| {
                let mut y = x;
                for p in y.iter_mut() {
                    *p += rand_point(&mut rng, 3e-3);
                }
                point_triangle_type(&y[0], &y[1], &y[2], &y[3]) == ty
            });
            if !stable || pt_f64(&x) < 1e-2 {
                continue;
            }
            seen.insert(ty);
            tested += 1;
            check_derivatives(x, pt_f64, |v| {
                point_triangle_distance_sq(&v[0], &v[1], &v[2], &v[3])
            });
        }
        assert!(seen.len() >= 3, "{seen:?}");
    }

    #[test]
    fn dual2_derivatives_of_edge_edge_and_mollifier_match_finite_differences() {
        let mut rng = XorShift(99);
        let mut seen = std::collections::HashSet::new();
        let mut tested = 0;
        while tested < 60 {
            let x = [
                rand_point(&mut rng, 1.0),
                rand_point(&mut rng, 1.0),
                rand_point(&mut rng, 1.0),
                rand_point(&mut rng, 1.0),
            ];
            let ty = edge_edge_type(&x[0], &x[1], &x[2], &x[3]);
            let stable = (0..200).all(|_| {
                let mut y = x;
                for p in y.iter_mut() {
                    *p += rand_point(&mut rng, 3e-3);
                }
                edge_edge_type(&y[0], &y[1], &y[2], &y[3]) == ty
            });
            if !stable || ee_f64(&x) < 1e-2 {
                continue;
            }
            seen.insert(ty);
            tested += 1;
            check_derivatives(x, ee_f64, |v| {
                edge_edge_distance_sq(&v[0], &v[1], &v[2], &v[3])
            });
            // The mollifier in its active branch (threshold above c) and its product.
            let c = (x[1] - x[0]).cross(&(x[3] - x[2])).norm_squared();
            let eps = 2.0 * c + 1e-3;
            let mol = |x: &[Vector3<f64>; 4]| {
                edge_edge_mollifier(&f(&x[0]), &f(&x[1]), &f(&x[2]), &f(&x[3]), eps) * ee_f64(x)
            };
            check_derivatives(x, mol, |v| {
                edge_edge_mollifier(&v[0], &v[1], &v[2], &v[3], eps)
                    * edge_edge_distance_sq(&v[0], &v[1], &v[2], &v[3])
            });
        }
        assert!(seen.len() >= 3, "{seen:?}");
    }

    /// The written-out spans decide as the plain splits of the stencil do,
    /// for every split and on ties.
    #[test]
    fn axis_apart_is_the_split_stencils_test() {
        let plain = |x: &[Vector3<f64>; 4], k: usize, d: f64| {
            let (a, b) = x.split_at(k);
            (0..3).any(|c| {
                let lo = |s: &[Vector3<f64>]| s.iter().map(|p| p[c]).fold(f64::INFINITY, f64::min);
                let hi =
                    |s: &[Vector3<f64>]| s.iter().map(|p| p[c]).fold(f64::NEG_INFINITY, f64::max);
                lo(b) - hi(a) >= d || lo(a) - hi(b) >= d
            })
        };
        let mut rng = XorShift(0x5b1d);
        for case in 0..5000 {
            // Coordinates on a coarse grid: ties between the spans are common.
            let mut grid = || (rng.below(5) as f64 - 2.0) * 0.25;
            let x: [Vector3<f64>; 4] =
                std::array::from_fn(|_| Vector3::new(grid(), grid(), grid()));
            let d = [0.0, 0.25, 0.5, 1.0][case % 4];
            for k in 0..=4 {
                assert_eq!(
                    axis_apart(&x, k, d),
                    plain(&x, k, d),
                    "case {case}, split {k}"
                );
            }
        }
    }

    #[test]
    fn axis_apart_is_a_lower_bound_on_the_distance() {
        let mut rng = XorShift(0xa515);
        let (mut apart, mut near) = (0, 0);
        for _ in 0..2000 {
            let x: [Vector3<f64>; 4] = std::array::from_fn(|_| rand_point(&mut rng, 1.0));
            let d = rng.range(0.0, 1.0);
            let pt = point_triangle_distance_sq(&f(&x[0]), &f(&x[1]), &f(&x[2]), &f(&x[3]));
            let ee = edge_edge_distance_sq(&f(&x[0]), &f(&x[1]), &f(&x[2]), &f(&x[3]));
            for (k, dist_sq) in [(1, pt), (2, ee)] {
                if axis_apart(&x, k, d) {
                    assert!(
                        dist_sq.sqrt() >= d * (1.0 - 1e-12),
                        "{k}: {dist_sq} < {d}^2"
                    );
                    apart += 1;
                } else if dist_sq.sqrt() < d {
                    near += 1;
                }
            }
        }
        assert!(apart > 200 && near > 200, "{apart} apart, {near} near");
    }

    #[test]
    fn mollifier_values() {
        let v = |x, y, z| V3::<f64>::new(x, y, z);
        let (a0, a1) = (v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0));
        // Perpendicular unit edges: c = 1.
        let (b0, b1) = (v(0.0, 0.0, 1.0), v(0.0, 1.0, 1.0));
        assert_eq!(edge_edge_mollifier(&a0, &a1, &b0, &b1, 0.5), 1.0);
        assert!((edge_edge_mollifier(&a0, &a1, &b0, &b1, 2.0) - 0.75).abs() < 1e-15);
        assert!((edge_edge_mollifier(&a0, &a1, &b0, &b1, 1.0) - 1.0).abs() < 1e-15);
        // Parallel: zero.
        let (b0, b1) = (v(0.0, 0.0, 1.0), v(2.0, 0.0, 1.0));
        assert_eq!(edge_edge_mollifier(&a0, &a1, &b0, &b1, 0.5), 0.0);
        let t = mollifier_threshold(&a0.val(), &a1.val(), &b0.val(), &b1.val());
        assert!((t - 4e-3).abs() < 1e-18);
    }
}
