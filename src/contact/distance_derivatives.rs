//! Closed-form gradients and Hessians of the squared distances of
//! [`distance`](super::distance), per closest-feature type, with respect to
//! the 12 coordinates of a pair's stencil (point `k` holds coordinates
//! `3k..3k+3`, in the order of the `f64` functions' arguments).
//!
//! Every formula depends on the points only through two or three difference
//! vectors (`p - q`; `e0 - p, e1 - p`; `p - t0, t1 - t0, t2 - t0`), so each is
//! differentiated in those few variables by the chain rule through the cross
//! and triple products, then scattered to the stencil (each difference is +1
//! on one point and -1 on another). The results come as [`Dual2`] values
//! (the value-gradient-Hessian container), built here without dual
//! arithmetic. `Dual2` evaluation of the generic formulas is the reference
//! the tests hold these to.

use super::distance::{EdgeEdgeType, PointTriangleType};
use super::scalar::Dual2;
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

/// A difference vector of the stencil: point `.0` minus point `.1`.
type Diff = (usize, usize);

/// Value, gradient and Hessian in the difference vectors, scattered to the
/// 12 stencil coordinates: `x_diff[k] = x[d.0] - x[d.1]`, so the gradient
/// is `J^T g` and the Hessian `J^T H J` with `J` of +-identity blocks.
fn scatter<const N: usize>(f: &Dual2<N>, diffs: &[Diff]) -> Dual2<12> {
    debug_assert_eq!(3 * diffs.len(), N);
    let terms = |k: usize| [(diffs[k].0, 1.0), (diffs[k].1, -1.0)];
    let mut g = SVector::<f64, 12>::zeros();
    let mut h = SMatrix::<f64, 12, 12>::zeros();
    for i in 0..diffs.len() {
        let gi = f.g.fixed_rows::<3>(3 * i);
        for (a, sa) in terms(i) {
            g.fixed_rows_mut::<3>(3 * a).axpy(sa, &gi, 1.0);
            for j in 0..diffs.len() {
                let hij = f.h.fixed_view::<3, 3>(3 * i, 3 * j);
                for (b, sb) in terms(j) {
                    let mut block = h.fixed_view_mut::<3, 3>(3 * a, 3 * b);
                    block += hij * (sa * sb);
                }
            }
        }
    }
    Dual2 { v: f.v, g, h }
}

/// |r|^2 in `r`.
fn norm_sq(r: &Vector3<f64>) -> Dual2<3> {
    Dual2 {
        v: r.norm_squared(),
        g: 2.0 * r,
        h: 2.0 * Matrix3::identity(),
    }
}

/// |u x v|^2 in `(u, v)`: with c = u x v, dc = -[v]x du + [u]x dv, so
/// g = 2 J^T c and H = 2 J^T J + 2 (c . d2c), whose `uv` block is -[c]x.
fn cross_norm_sq(u: &Vector3<f64>, v: &Vector3<f64>) -> Dual2<6> {
    let c = u.cross(v);
    let mut jac = SMatrix::<f64, 3, 6>::zeros();
    jac.fixed_columns_mut::<3>(0)
        .copy_from(&(-v.cross_matrix()));
    jac.fixed_columns_mut::<3>(3).copy_from(&u.cross_matrix());
    let mut h = 2.0 * jac.transpose() * jac;
    let cx = c.cross_matrix();
    let mut uv = h.fixed_view_mut::<3, 3>(0, 3);
    uv -= 2.0 * cx;
    let mut vu = h.fixed_view_mut::<3, 3>(3, 0);
    vu += 2.0 * cx;
    Dual2 {
        v: c.norm_squared(),
        g: 2.0 * jac.transpose() * c,
        h,
    }
}

/// The triple product r . (a x b) in `(r, a, b)`: gradient
/// `(a x b, b x r, r x a)`, Hessian blocks `ra = -[b]x`, `rb = [a]x`, `ab = -[r]x`.
fn triple(r: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> Dual2<9> {
    let mut g = SVector::<f64, 9>::zeros();
    g.fixed_rows_mut::<3>(0).copy_from(&a.cross(b));
    g.fixed_rows_mut::<3>(3).copy_from(&b.cross(r));
    g.fixed_rows_mut::<3>(6).copy_from(&r.cross(a));
    let mut h = SMatrix::<f64, 9, 9>::zeros();
    for (i, j, m) in [
        (0, 1, -b.cross_matrix()),
        (0, 2, a.cross_matrix()),
        (1, 2, -r.cross_matrix()),
    ] {
        h.fixed_view_mut::<3, 3>(3 * i, 3 * j).copy_from(&m);
        h.fixed_view_mut::<3, 3>(3 * j, 3 * i)
            .copy_from(&m.transpose());
    }
    Dual2 {
        v: r.dot(&a.cross(b)),
        g,
        h,
    }
}

/// n / b: from n = q b, g_q = (g_n - q g_b) / b and
/// H_q = (H_n - q H_b - g_q g_b^T - g_b g_q^T) / b.
fn quotient<const N: usize>(n: &Dual2<N>, b: &Dual2<N>) -> Dual2<N> {
    let q = n.v / b.v;
    let g = (n.g - b.g * q) / b.v;
    let mut h = n.h - b.h * q;
    h.ger(-1.0, &g, &b.g, 1.0);
    h.ger(-1.0, &b.g, &g, 1.0);
    Dual2 {
        v: q,
        g,
        h: h / b.v,
    }
}

/// |p - q|^2 for stencil points `p`, `q`.
fn point_point(x: &[Vector3<f64>; 4], p: usize, q: usize) -> Dual2<12> {
    scatter(&norm_sq(&(x[p] - x[q])), &[(p, q)])
}

/// Point `p` to the line through `e0`, `e1`: |u x v|^2 / |v - u|^2 in
/// u = e0 - p, v = e1 - p.
fn point_line(x: &[Vector3<f64>; 4], p: usize, e0: usize, e1: usize) -> Dual2<12> {
    let (u, v) = (x[e0] - x[p], x[e1] - x[p]);
    let w = v - u;
    let mut len = Dual2::<6>::cst(w.norm_squared());
    len.g.fixed_rows_mut::<3>(0).copy_from(&(-2.0 * w));
    len.g.fixed_rows_mut::<3>(3).copy_from(&(2.0 * w));
    let i = Matrix3::identity() * 2.0;
    for (a, b, s) in [(0, 0, 1.0), (0, 3, -1.0), (3, 0, -1.0), (3, 3, 1.0)] {
        len.h.fixed_view_mut::<3, 3>(a, b).copy_from(&(i * s));
    }
    scatter(&quotient(&cross_norm_sq(&u, &v), &len), &[(e0, p), (e1, p)])
}

/// (r . (a x b))^2 / |a x b|^2 in `(r, a, b)`: the point-plane and line-line
/// formula alike.
fn triple_sq_over_cross_sq(r: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> Dual2<9> {
    let t = triple(r, a, b);
    let mut num = Dual2 {
        v: t.v * t.v,
        g: t.g * (2.0 * t.v),
        h: t.h * (2.0 * t.v),
    };
    num.h.ger(2.0, &t.g, &t.g, 1.0);
    let c = cross_norm_sq(a, b);
    let mut den = Dual2::<9>::cst(c.v);
    den.g.fixed_rows_mut::<6>(3).copy_from(&c.g);
    den.h.fixed_view_mut::<6, 6>(3, 3).copy_from(&c.h);
    quotient(&num, &den)
}

/// Squared distance of point `x[0]` and triangle `x[1] x[2] x[3]` by the
/// formula of type `ty`, with its gradient and Hessian.
pub fn point_triangle_sq_derivatives(ty: PointTriangleType, x: &[Vector3<f64>; 4]) -> Dual2<12> {
    match ty {
        PointTriangleType::Vertex(i) => point_point(x, 0, 1 + i as usize),
        PointTriangleType::Edge(i) => point_line(x, 0, 1 + i as usize, 1 + (i as usize + 1) % 3),
        PointTriangleType::Face => scatter(
            &triple_sq_over_cross_sq(&(x[0] - x[1]), &(x[2] - x[1]), &(x[3] - x[1])),
            &[(0, 1), (2, 1), (3, 1)],
        ),
    }
}

/// Squared distance of segments `x[0] x[1]` and `x[2] x[3]` by the formula
/// of type `ty`, with its gradient and Hessian.
pub fn edge_edge_sq_derivatives(ty: EdgeEdgeType, x: &[Vector3<f64>; 4]) -> Dual2<12> {
    match ty {
        EdgeEdgeType::Points(i, j) => point_point(x, i as usize, 2 + j as usize),
        EdgeEdgeType::PointAEdgeB(i) => point_line(x, i as usize, 2, 3),
        EdgeEdgeType::EdgeAPointB(j) => point_line(x, 2 + j as usize, 0, 1),
        EdgeEdgeType::LineLine => scatter(
            &triple_sq_over_cross_sq(&(x[2] - x[0]), &(x[1] - x[0]), &(x[3] - x[2])),
            &[(2, 0), (1, 0), (3, 2)],
        ),
    }
}

/// The stencil points the formula of point-triangle type `ty` depends on:
/// its derivatives vanish on the other points' coordinates (and, being a
/// function of differences, on translations).
pub fn point_triangle_points(ty: PointTriangleType) -> &'static [usize] {
    match ty {
        PointTriangleType::Vertex(0) => &[0, 1],
        PointTriangleType::Vertex(1) => &[0, 2],
        PointTriangleType::Vertex(_) => &[0, 3],
        PointTriangleType::Edge(0) => &[0, 1, 2],
        PointTriangleType::Edge(1) => &[0, 2, 3],
        PointTriangleType::Edge(_) => &[0, 3, 1],
        PointTriangleType::Face => &[0, 1, 2, 3],
    }
}

/// The stencil points the formula of edge-edge type `ty` depends on (the
/// mollifier depends on all four).
pub fn edge_edge_points(ty: EdgeEdgeType) -> &'static [usize] {
    match ty {
        EdgeEdgeType::Points(0, 0) => &[0, 2],
        EdgeEdgeType::Points(0, _) => &[0, 3],
        EdgeEdgeType::Points(_, 0) => &[1, 2],
        EdgeEdgeType::Points(_, _) => &[1, 3],
        EdgeEdgeType::PointAEdgeB(0) => &[0, 2, 3],
        EdgeEdgeType::PointAEdgeB(_) => &[1, 2, 3],
        EdgeEdgeType::EdgeAPointB(0) => &[2, 0, 1],
        EdgeEdgeType::EdgeAPointB(_) => &[3, 0, 1],
        EdgeEdgeType::LineLine => &[0, 1, 2, 3],
    }
}

/// IPC's edge-edge mollifier (see
/// [`edge_edge_mollifier`](super::distance::edge_edge_mollifier)) with its
/// gradient and Hessian: m(c) = 2 c / eps_x - c^2 / eps_x^2 of
/// c = |(a1 - a0) x (b1 - b0)|^2 below eps_x; `None` above, where it is the
/// constant 1.
pub fn edge_edge_mollifier_derivatives(x: &[Vector3<f64>; 4], eps_x: f64) -> Option<Dual2<12>> {
    let c = cross_norm_sq(&(x[1] - x[0]), &(x[3] - x[2]));
    if c.v >= eps_x {
        return None;
    }
    let s = c.v / eps_x;
    let c = scatter(&c, &[(1, 0), (3, 2)]);
    let (dm, ddm) = ((2.0 - 2.0 * s) / eps_x, -2.0 / (eps_x * eps_x));
    let mut h = c.h * dm;
    h.ger(ddm, &c.g, &c.g, 1.0);
    Some(Dual2 {
        v: s * (2.0 - s),
        g: c.g * dm,
        h,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::distance::{
        V3, edge_edge_mollifier, edge_edge_sq_of_type, edge_edge_type, point_triangle_sq_of_type,
        point_triangle_type,
    };
    use crate::rng::XorShift;

    fn rand_point(rng: &mut XorShift, r: f64) -> Vector3<f64> {
        Vector3::new(rng.range(-r, r), rng.range(-r, r), rng.range(-r, r))
    }

    fn rand_stencil(rng: &mut XorShift) -> [Vector3<f64>; 4] {
        std::array::from_fn(|_| rand_point(rng, 1.0))
    }

    /// Closed form against `Dual2` evaluation of the generic formula: value,
    /// gradient and Hessian to `1e-10` of their norms.
    fn assert_matches(got: &Dual2<12>, want: &Dual2<12>, what: &str) {
        let tol = 1e-10;
        assert!(
            (got.v - want.v).abs() <= tol * want.v.abs().max(1e-300),
            "{what}: value {} vs {}",
            got.v,
            want.v
        );
        let eg = (got.g - want.g).norm();
        assert!(eg <= tol * want.g.norm(), "{what}: gradient off by {eg:e}");
        let eh = (got.h - want.h).norm();
        assert!(eh <= tol * want.h.norm(), "{what}: Hessian off by {eh:e}");
    }

    /// The gradient against central differences of the `f64` formula `f`,
    /// the Hessian against central differences of the closed-form gradient
    /// `grad`, to `1e-6` of their norms.
    fn assert_matches_differences(
        got: &Dual2<12>,
        x: &[Vector3<f64>; 4],
        f: impl Fn(&[Vector3<f64>; 4]) -> f64,
        grad: impl Fn(&[Vector3<f64>; 4]) -> SVector<f64, 12>,
    ) {
        let h = 1e-6;
        let at = |k: usize, dx: f64| {
            let mut y = *x;
            y[k / 3][k % 3] += dx;
            y
        };
        let (sg, sh) = (got.g.norm().max(1e-3), got.h.norm().max(1e-3));
        for k in 0..12 {
            let g = (f(&at(k, h)) - f(&at(k, -h))) / (2.0 * h);
            assert!(
                (got.g[k] - g).abs() < 1e-6 * sg,
                "g[{k}] {} vs {g}",
                got.g[k]
            );
            let hk = (grad(&at(k, h)) - grad(&at(k, -h))) / (2.0 * h);
            let e = (got.h.column(k) - hk).norm();
            assert!(e < 1e-6 * sh, "H column {k} off by {e:e}");
        }
    }

    /// The derivatives vanish on the coordinates of points outside
    /// `points` and along translations.
    fn assert_supported_on(got: &Dual2<12>, points: &[usize]) {
        for k in (0..4).filter(|k| !points.contains(k)) {
            assert_eq!(got.g.fixed_rows::<3>(3 * k).norm(), 0.0);
            assert_eq!(got.h.fixed_rows::<3>(3 * k).norm(), 0.0);
        }
        for d in 0..3 {
            let t = SVector::<f64, 12>::from_fn(|i, _| if i % 3 == d { 1.0 } else { 0.0 });
            assert!(got.g.dot(&t).abs() <= 1e-12 * got.g.norm());
            assert!((got.h * t).norm() <= 1e-12 * got.h.norm());
        }
    }

    fn pt_of_type(ty: PointTriangleType, x: &[Vector3<f64>; 4]) -> f64 {
        let v = x.map(V3::from);
        point_triangle_sq_of_type(ty, &v[0], &v[1], &v[2], &v[3])
    }

    fn ee_of_type(ty: EdgeEdgeType, x: &[Vector3<f64>; 4]) -> f64 {
        let v = x.map(V3::from);
        edge_edge_sq_of_type(ty, &v[0], &v[1], &v[2], &v[3])
    }

    #[test]
    fn point_triangle_closed_forms_match_dual2_and_differences_on_every_type() {
        let mut rng = XorShift(0x5eed_0040);
        let mut seen = std::collections::HashMap::new();
        for k in 0..600 {
            let mut x = rand_stencil(&mut rng);
            x[0] *= 1.5;
            let ty = point_triangle_type(&x[0], &x[1], &x[2], &x[3]);
            let got = point_triangle_sq_derivatives(ty, &x);
            let s = V3::<Dual2<12>>::stencil(&x);
            let want = point_triangle_sq_of_type(ty, &s[0], &s[1], &s[2], &s[3]);
            assert_matches(&got, &want, &format!("{ty:?}"));
            assert_supported_on(&got, point_triangle_points(ty));
            *seen.entry(ty).or_insert(0) += 1;
            if k % 20 == 0 {
                assert_matches_differences(
                    &got,
                    &x,
                    |y| pt_of_type(ty, y),
                    |y| point_triangle_sq_derivatives(ty, y).g,
                );
            }
        }
        assert_eq!(seen.len(), 7, "all seven types: {seen:?}");
    }

    #[test]
    fn edge_edge_closed_forms_match_dual2_and_differences_on_every_type() {
        let mut rng = XorShift(0x5eed_4004);
        let mut seen = std::collections::HashMap::new();
        for k in 0..600 {
            let x = rand_stencil(&mut rng);
            let ty = edge_edge_type(&x[0], &x[1], &x[2], &x[3]);
            let got = edge_edge_sq_derivatives(ty, &x);
            let s = V3::<Dual2<12>>::stencil(&x);
            let want = edge_edge_sq_of_type(ty, &s[0], &s[1], &s[2], &s[3]);
            assert_matches(&got, &want, &format!("{ty:?}"));
            assert_supported_on(&got, edge_edge_points(ty));
            *seen.entry(ty).or_insert(0) += 1;
            if k % 20 == 0 {
                assert_matches_differences(
                    &got,
                    &x,
                    |y| ee_of_type(ty, y),
                    |y| edge_edge_sq_derivatives(ty, y).g,
                );
            }
        }
        assert_eq!(seen.len(), 9, "all nine types: {seen:?}");
    }

    #[test]
    fn mollifier_closed_form_matches_dual2_and_differences() {
        let mut rng = XorShift(0x0040_4040);
        for k in 0..200 {
            let x = rand_stencil(&mut rng);
            let c = (x[1] - x[0]).cross(&(x[3] - x[2])).norm_squared();
            // Active (threshold above c) in three of four cases, constant else.
            let eps = if k % 4 == 3 {
                0.5 * c
            } else {
                c * rng.range(1.05, 4.0)
            };
            let got = edge_edge_mollifier_derivatives(&x, eps);
            let s = V3::<Dual2<12>>::stencil(&x);
            let want = edge_edge_mollifier(&s[0], &s[1], &s[2], &s[3], eps);
            let Some(got) = got else {
                assert_eq!(k % 4, 3, "active below the threshold");
                assert_eq!(want, Dual2::cst(1.0));
                continue;
            };
            assert_ne!(k % 4, 3, "constant above the threshold");
            assert_matches(&got, &want, "mollifier");
            if k % 10 == 0 {
                assert_matches_differences(
                    &got,
                    &x,
                    |y| {
                        let v = y.map(V3::from);
                        edge_edge_mollifier(&v[0], &v[1], &v[2], &v[3], eps)
                    },
                    |y| edge_edge_mollifier_derivatives(y, eps).expect("active").g,
                );
            }
        }
    }
}
