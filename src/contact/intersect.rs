//! Exact triangle-triangle and segment-triangle intersection of closed sets in `f64`,
//! built only on orientation predicates made exact by a floating-point filter with an
//! expansion-arithmetic fallback (Shewchuk 1997); exact barring overflow and underflow.
//! Convention: touching counts as intersecting; zero-area triangles never intersect.

use nalgebra::Vector3;
use std::cmp::Ordering;

/// Error-free sum: a + b = x + y exactly (Knuth's two-sum).
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let x = a + b;
    let bv = x - a;
    let av = x - bv;
    (x, (a - av) + (b - bv))
}

/// Error-free product: a b = x + y exactly (with a fused multiply-add).
fn two_product(a: f64, b: f64) -> (f64, f64) {
    let x = a * b;
    (x, a.mul_add(b, -x))
}

/// A nonoverlapping expansion (components by increasing magnitude, zeros dropped)
/// that terms are added to exactly; its sign is that of its largest component.
struct Expansion<const CAP: usize> {
    e: [f64; CAP],
    len: usize,
}

impl<const CAP: usize> Expansion<CAP> {
    fn new() -> Self {
        Expansion {
            e: [0.0; CAP],
            len: 0,
        }
    }

    /// Adds one double exactly (Shewchuk's Grow-Expansion with zero elimination).
    fn add(&mut self, b: f64) {
        let mut q = b;
        let mut n = 0;
        for i in 0..self.len {
            let (s, h) = two_sum(q, self.e[i]);
            q = s;
            if h != 0.0 {
                self.e[n] = h;
                n += 1;
            }
        }
        if q != 0.0 {
            self.e[n] = q;
            n += 1;
        }
        self.len = n;
    }

    /// Adds `sign * x * y * z` exactly (four doubles).
    fn add_product3(&mut self, sign: f64, x: f64, y: f64, z: f64) {
        let (p, e) = two_product(x, y);
        let (p1, e1) = two_product(p, z);
        let (p2, e2) = two_product(e, z);
        for c in [e2, p2, e1, p1] {
            self.add(sign * c);
        }
    }

    /// Adds `sign * x * y` exactly (two doubles).
    fn add_product2(&mut self, sign: f64, x: f64, y: f64) {
        let (p, e) = two_product(x, y);
        self.add(sign * e);
        self.add(sign * p);
    }

    /// The sign; `Equal` (degenerate) for values that are not numbers,
    /// which arise only from non-finite coordinates.
    fn sign(&self) -> Ordering {
        match self.len {
            0 => Ordering::Equal,
            n => self.e[n - 1].partial_cmp(&0.0).unwrap_or(Ordering::Equal),
        }
    }
}

/// Sign of det[a - d; b - d; c - d] = (a - d) . ((b - d) x (c - d)), exactly:
/// `Greater` when `d` is below the plane of `a b c` seen counterclockwise from above.
pub fn orient3d(
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    c: &Vector3<f64>,
    d: &Vector3<f64>,
) -> Ordering {
    let (ad, bd, cd) = (a - d, b - d, c - d);
    let bdxcdy = bd.x * cd.y;
    let cdxbdy = cd.x * bd.y;
    let cdxady = cd.x * ad.y;
    let adxcdy = ad.x * cd.y;
    let adxbdy = ad.x * bd.y;
    let bdxady = bd.x * ad.y;
    let det = ad.z * (bdxcdy - cdxbdy) + bd.z * (cdxady - adxcdy) + cd.z * (adxbdy - bdxady);
    let permanent = (bdxcdy.abs() + cdxbdy.abs()) * ad.z.abs()
        + (cdxady.abs() + adxcdy.abs()) * bd.z.abs()
        + (adxbdy.abs() + bdxady.abs()) * cd.z.abs();
    // Shewchuk's bound is (7 + 56 eps) eps ~ 7.8e-16; a little more is safe.
    if det.abs() > 1e-15 * permanent {
        return det.partial_cmp(&0.0).unwrap_or(Ordering::Equal);
    }
    orient3d_exact(a, b, c, d)
}

/// The exact sign of orient3d: det[a-d; b-d; c-d] = |abc| - |abd| + |acd| - |bcd|
/// with |pqr| = p . (q x r), each a sum of six exact triple products.
fn orient3d_exact(
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    c: &Vector3<f64>,
    d: &Vector3<f64>,
) -> Ordering {
    let mut e = Expansion::<100>::new();
    let mut det3 = |sign: f64, p: &Vector3<f64>, q: &Vector3<f64>, r: &Vector3<f64>| {
        e.add_product3(sign, p.x, q.y, r.z);
        e.add_product3(-sign, p.x, q.z, r.y);
        e.add_product3(sign, p.y, q.z, r.x);
        e.add_product3(-sign, p.y, q.x, r.z);
        e.add_product3(sign, p.z, q.x, r.y);
        e.add_product3(-sign, p.z, q.y, r.x);
    };
    det3(1.0, a, b, c);
    det3(-1.0, a, b, d);
    det3(1.0, a, c, d);
    det3(-1.0, b, c, d);
    e.sign()
}

/// A point projected to 2D.
type P2 = [f64; 2];

/// Sign of det[a - c; b - c], exactly: `Greater` when a, b, c turn counterclockwise.
fn orient2d(a: P2, b: P2, c: P2) -> Ordering {
    let left = (a[0] - c[0]) * (b[1] - c[1]);
    let right = (a[1] - c[1]) * (b[0] - c[0]);
    let det = left - right;
    if det.abs() > 1e-15 * (left.abs() + right.abs()) {
        return det.partial_cmp(&0.0).unwrap_or(Ordering::Equal);
    }
    // det2(a, b) - det2(a, c) + det2(b, c) with det2(p, q) = p0 q1 - p1 q0.
    let mut e = Expansion::<16>::new();
    for (s, p, q) in [(1.0, a, b), (-1.0, a, c), (1.0, b, c)] {
        e.add_product2(s, p[0], q[1]);
        e.add_product2(-s, p[1], q[0]);
    }
    e.sign()
}

/// True when the signs contain both a `Greater` and a `Less`.
fn mixed(o: &[Ordering]) -> bool {
    o.contains(&Ordering::Greater) && o.contains(&Ordering::Less)
}

/// Drops the coordinate along which the triangle's normal is largest (a projection
/// that keeps the triangle non-degenerate), or `None` for a zero-area triangle.
fn projection(t: &[Vector3<f64>; 3]) -> Option<impl Fn(&Vector3<f64>) -> P2> {
    let n = (t[1] - t[0]).cross(&(t[2] - t[0])).abs();
    let k = n.imax();
    if n[k] == 0.0 {
        return None;
    }
    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
    Some(move |p: &Vector3<f64>| [p[i], p[j]])
}

/// Closed 2D segments `p q` and `r s` share a point.
fn segments_intersect_2d(p: P2, q: P2, r: P2, s: P2) -> bool {
    let (d1, d2) = (orient2d(r, s, p), orient2d(r, s, q));
    let (d3, d4) = (orient2d(p, q, r), orient2d(p, q, s));
    let strict = |x: Ordering, y: Ordering| x != Ordering::Equal && y != Ordering::Equal && x != y;
    if strict(d1, d2) && strict(d3, d4) {
        return true;
    }
    // Collinear touching: a point on the other segment's bounding box.
    let within =
        |a: P2, b: P2, x: P2| (0..2).all(|k| a[k].min(b[k]) <= x[k] && x[k] <= a[k].max(b[k]));
    (d1 == Ordering::Equal && within(r, s, p))
        || (d2 == Ordering::Equal && within(r, s, q))
        || (d3 == Ordering::Equal && within(p, q, r))
        || (d4 == Ordering::Equal && within(p, q, s))
}

/// The closed 2D triangle `t` (either orientation) contains `x`.
fn in_triangle_2d(x: P2, t: [P2; 3]) -> bool {
    !mixed(&[
        orient2d(t[0], t[1], x),
        orient2d(t[1], t[2], x),
        orient2d(t[2], t[0], x),
    ])
}

/// Segment `p q`, in the plane of the triangle, against it in the projection.
fn coplanar_segment_triangle(p: &Vector3<f64>, q: &Vector3<f64>, t: &[Vector3<f64>; 3]) -> bool {
    let Some(proj) = projection(t) else {
        return false;
    };
    let (p, q) = (proj(p), proj(q));
    let t2 = [proj(&t[0]), proj(&t[1]), proj(&t[2])];
    in_triangle_2d(p, t2)
        || in_triangle_2d(q, t2)
        || (0..3).any(|i| segments_intersect_2d(p, q, t2[i], t2[(i + 1) % 3]))
}

/// Whether the closed segment `p q` and the closed triangle `t` share a point
/// (exact; coplanar configurations included).
pub fn segment_triangle_intersect(
    p: &Vector3<f64>,
    q: &Vector3<f64>,
    t: &[Vector3<f64>; 3],
) -> bool {
    let (op, oq) = (
        orient3d(&t[0], &t[1], &t[2], p),
        orient3d(&t[0], &t[1], &t[2], q),
    );
    if op == Ordering::Equal && oq == Ordering::Equal {
        return coplanar_segment_triangle(p, q, t);
    }
    if op == oq {
        return false; // strictly on one side
    }
    // The segment meets the plane in one point: inside the triangle iff the line
    // p q does not pass strictly outside any of its edges.
    !mixed(&[
        orient3d(p, q, &t[0], &t[1]),
        orient3d(p, q, &t[1], &t[2]),
        orient3d(p, q, &t[2], &t[0]),
    ])
}

/// Whether closed triangles `a` and `b` share a point (exact). Their intersection,
/// when not empty, always contains a point of an edge of one of them, so six
/// segment-triangle tests decide it; pairs sharing vertices are the caller's business.
pub fn triangles_intersect(a: [Vector3<f64>; 3], b: [Vector3<f64>; 3]) -> bool {
    if projection(&a).is_none() || projection(&b).is_none() {
        return false;
    }
    // Quick rejection: one triangle strictly on one side of the other's plane.
    let side = |t: &[Vector3<f64>; 3], u: &[Vector3<f64>; 3]| {
        let o = u.map(|p| orient3d(&t[0], &t[1], &t[2], &p));
        o[0] != Ordering::Equal && o[0] == o[1] && o[1] == o[2]
    };
    if side(&a, &b) || side(&b, &a) {
        return false;
    }
    (0..3).any(|i| segment_triangle_intersect(&a[i], &a[(i + 1) % 3], &b))
        || (0..3).any(|i| segment_triangle_intersect(&b[i], &b[(i + 1) % 3], &a))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::XorShift;

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    const T: [Vector3<f64>; 3] = [
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(0.0, 1.0, 0.0),
    ];

    #[test]
    fn orient3d_exact_agrees_with_integer_determinants() {
        let mut rng = XorShift(5);
        for _ in 0..2000 {
            // Small integers: the plain determinant is exact.
            let mut r = || {
                v(
                    rng.below(21) as f64 - 10.0,
                    rng.below(21) as f64 - 10.0,
                    rng.below(21) as f64 - 10.0,
                )
            };
            let (a, b, c, d) = (r(), r(), r(), r());
            let det = (a - d).dot(&(b - d).cross(&(c - d)));
            let want = det.partial_cmp(&0.0).unwrap();
            assert_eq!(orient3d_exact(&a, &b, &c, &d), want);
            assert_eq!(orient3d(&a, &b, &c, &d), want);
            let p = |x: &Vector3<f64>| [x.x, x.y];
            let det2 = (a.x - c.x) * (b.y - c.y) - (a.y - c.y) * (b.x - c.x);
            assert_eq!(
                orient2d(p(&a), p(&b), p(&c)),
                det2.partial_cmp(&0.0).unwrap()
            );
        }
    }

    #[test]
    fn orient3d_is_exact_on_coplanar_dyadic_points() {
        // Points on x + y + z = 1 with dyadic coordinates are exactly coplanar;
        // nudging one by an ulp off the plane gives a consistent nonzero sign.
        let mut rng = XorShift(11);
        let mut naive_wrong = 0;
        for _ in 0..2000 {
            let mut r = || {
                // x on a 2^-20 grid in [-3, 3], y on a 2^-22 grid: z = 1 - x - y is exact.
                let x = (rng.below(1 << 21) as f64 - 1048576.0) / 1048576.0 * 3.0;
                let y = (rng.below(1 << 21) as f64 - 1048576.0) / 4194304.0;
                v(x, y, 1.0 - x - y)
            };
            let (a, b, c, d) = (r(), r(), r(), r());
            assert_eq!(d.x + d.y + d.z, 1.0);
            assert_eq!(orient3d(&a, &b, &c, &d), Ordering::Equal);
            let det = (a - d).dot(&(b - d).cross(&(c - d)));
            if det != 0.0 {
                naive_wrong += 1;
            }
            let up = v(d.x, d.y, d.z + d.z.abs().max(1e-300) * f64::EPSILON);
            let o = orient3d(&a, &b, &c, &up);
            if o != Ordering::Equal {
                // Same side as a big step the same way.
                let far = v(d.x, d.y, d.z + 1.0);
                assert_eq!(o, orient3d(&a, &b, &c, &far));
            }
        }
        assert!(naive_wrong > 0, "the test should hit rounded determinants");
    }

    #[test]
    fn named_configurations() {
        let tri = |p: [(f64, f64, f64); 3]| p.map(|(x, y, z)| v(x, y, z));
        let cases: [(&str, [Vector3<f64>; 3], bool); 12] = [
            (
                "piercing",
                tri([(0.2, 0.2, -1.0), (0.3, 0.2, 1.0), (0.2, 0.4, 1.0)]),
                true,
            ),
            (
                "separated above",
                tri([(0.0, 0.0, 0.1), (1.0, 0.0, 0.2), (0.0, 1.0, 0.3)]),
                false,
            ),
            (
                "separated beside",
                tri([(2.0, 0.0, -1.0), (3.0, 0.0, 1.0), (2.0, 1.0, 0.0)]),
                false,
            ),
            (
                "coplanar overlap",
                tri([(0.5, 0.5, 0.0), (-0.5, 0.2, 0.0), (0.2, -0.5, 0.0)]),
                true,
            ),
            (
                "coplanar inside",
                tri([(0.1, 0.1, 0.0), (0.3, 0.1, 0.0), (0.1, 0.3, 0.0)]),
                true,
            ),
            (
                "coplanar disjoint",
                tri([(0.6, 0.6, 0.0), (1.5, 0.6, 0.0), (0.6, 1.5, 0.0)]),
                false,
            ),
            (
                "coplanar edge touch",
                tri([(0.5, 0.5, 0.0), (1.0, 1.0, 0.0), (0.0, 2.0, 0.0)]),
                true,
            ),
            // An edge of b through the interior of a; b's vertices all outside a.
            (
                "edge piercing",
                tri([(0.3, 0.3, -1.0), (0.3, 0.3, 1.0), (5.0, 5.0, 0.0)]),
                true,
            ),
            // a's edge through b (b vertical, crossing the hypotenuse region).
            (
                "crossing wall",
                tri([(0.5, -1.0, -1.0), (0.5, 2.0, -1.0), (0.5, 0.5, 1.0)]),
                true,
            ),
            (
                "near miss over edge",
                tri([
                    (0.5 + 1e-12, 0.5 + 1e-12, -1.0),
                    (0.5 + 1e-12, 0.5 + 1e-12, 1.0),
                    (3.0, 3.0, 0.0),
                ]),
                false,
            ),
            (
                "exact touch of hypotenuse",
                tri([(0.5, 0.5, -1.0), (0.5, 0.5, 1.0), (3.0, 3.0, 0.0)]),
                true,
            ),
            (
                "vertex on face",
                tri([(0.25, 0.25, 0.0), (0.3, 0.2, 1.0), (0.2, 0.4, 1.0)]),
                true,
            ),
        ];
        for (name, b, want) in cases {
            assert_eq!(triangles_intersect(T, b), want, "{name}");
            assert_eq!(triangles_intersect(b, T), want, "{name} swapped");
            let rev = [b[2], b[1], b[0]];
            assert_eq!(triangles_intersect(rev, T), want, "{name} reversed");
        }
        // Near miss just above the plane.
        let b = tri([(0.2, 0.2, 1e-300), (0.3, 0.2, 1.0), (0.2, 0.4, 1.0)]);
        assert!(!triangles_intersect(T, b));
        // Segments.
        assert!(segment_triangle_intersect(
            &v(0.2, 0.2, 1.0),
            &v(0.2, 0.2, -1.0),
            &T
        ));
        assert!(!segment_triangle_intersect(
            &v(0.6, 0.6, 1.0),
            &v(0.6, 0.6, -1.0),
            &T
        ));
        assert!(!segment_triangle_intersect(
            &v(0.2, 0.2, 1.0),
            &v(0.2, 0.2, 1e-300),
            &T
        ));
        assert!(segment_triangle_intersect(
            &v(0.2, 0.2, 1.0),
            &v(0.2, 0.2, 0.0),
            &T
        ));
        assert!(segment_triangle_intersect(
            &v(-1.0, 0.5, 0.0),
            &v(2.0, 0.5, 0.0),
            &T
        ));
        assert!(!segment_triangle_intersect(
            &v(-1.0, 1.5, 0.0),
            &v(2.0, 1.5, 0.0),
            &T
        ));
        assert!(segment_triangle_intersect(
            &v(-1.0, 0.0, 0.0),
            &v(2.0, 0.0, 0.0),
            &T
        ));
        // Degenerate triangle: never.
        assert!(!triangles_intersect(T, [v(0.2, 0.2, 0.0); 3]));
    }

    /// A floating-point reference for segment-triangle: plane crossing parameter and
    /// barycentrics; `None` when any is within `tol` of a decision boundary.
    fn reference_segment(
        p: &Vector3<f64>,
        q: &Vector3<f64>,
        t: &[Vector3<f64>; 3],
        tol: f64,
    ) -> Option<bool> {
        let n = (t[1] - t[0]).cross(&(t[2] - t[0])).normalize();
        let (dp, dq) = ((p - t[0]).dot(&n), (q - t[0]).dot(&n));
        if dp.abs() < tol || dq.abs() < tol {
            return None;
        }
        if dp * dq > 0.0 {
            return Some(false);
        }
        let x = p + (q - p) * (dp / (dp - dq));
        let area = (t[1] - t[0]).cross(&(t[2] - t[0])).dot(&n);
        let w: Vec<f64> = (0..3)
            .map(|i| (t[(i + 1) % 3] - x).cross(&(t[(i + 2) % 3] - x)).dot(&n) / area)
            .collect();
        if w.iter().any(|wi| wi.abs() < tol) {
            return None;
        }
        Some(w.iter().all(|&wi| wi > 0.0))
    }

    #[test]
    fn random_pairs_agree_with_a_float_reference() {
        let mut rng = XorShift(0x7717);
        let (mut yes, mut no) = (0, 0);
        for _ in 0..5000 {
            let mut r = || {
                v(
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                )
            };
            let a = [r(), r(), r()];
            let b = [r(), r(), r()];
            let (mut undecided, mut want) = (false, false);
            for (s, t) in [(&a, &b), (&b, &a)] {
                for i in 0..3 {
                    match reference_segment(&s[i], &s[(i + 1) % 3], t, 1e-9) {
                        None => undecided = true,
                        Some(hit) => want |= hit,
                    }
                }
            }
            if undecided {
                continue; // too close to call in floats
            }
            assert_eq!(triangles_intersect(a, b), want, "{a:?} {b:?}");
            if want { yes += 1 } else { no += 1 }
        }
        assert!(yes > 200 && no > 200, "yes {yes} no {no}");
    }

    #[test]
    fn random_coplanar_pairs_agree_with_a_float_reference() {
        // Dyadic points on the exact plane z = x: coplanar for the predicates.
        let mut rng = XorShift(0xc0de);
        let (mut yes, mut no) = (0, 0);
        for _ in 0..3000 {
            let mut r = || {
                let x = (rng.range(-1.0, 1.0) * 65536.0).round() / 65536.0;
                let y = (rng.range(-1.0, 1.0) * 65536.0).round() / 65536.0;
                v(x, y, x)
            };
            let a = [r(), r(), r()];
            let b = [r(), r(), r()];
            // Reference in the (x, y) plane with floats and margins: an edge crossing
            // or a vertex strictly inside.
            let p = |x: &Vector3<f64>| [x.x, x.y];
            let o =
                |a: P2, b: P2, c: P2| (a[0] - c[0]) * (b[1] - c[1]) - (a[1] - c[1]) * (b[0] - c[0]);
            let tol = 1e-9;
            let mut close = false;
            let mut hit = false;
            for (s, t) in [(&a, &b), (&b, &a)] {
                for i in 0..3 {
                    let (s0, s1) = (p(&s[i]), p(&s[(i + 1) % 3]));
                    let os: Vec<f64> = (0..3)
                        .map(|j| o(p(&t[j]), p(&t[(j + 1) % 3]), s0))
                        .collect();
                    close |= os.iter().any(|x| x.abs() < tol);
                    hit |= os.iter().all(|&x| x > 0.0) || os.iter().all(|&x| x < 0.0);
                    for j in 0..3 {
                        let (t0, t1) = (p(&t[j]), p(&t[(j + 1) % 3]));
                        let d = [o(t0, t1, s0), o(t0, t1, s1), o(s0, s1, t0), o(s0, s1, t1)];
                        close |= d.iter().any(|x| x.abs() < tol);
                        hit |= d[0] * d[1] < 0.0 && d[2] * d[3] < 0.0;
                    }
                }
            }
            if close {
                continue;
            }
            assert_eq!(triangles_intersect(a, b), hit, "{a:?} {b:?}");
            if hit { yes += 1 } else { no += 1 }
        }
        assert!(yes > 100 && no > 100, "yes {yes} no {no}");
    }
}
