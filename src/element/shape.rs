//! Shape functions of the cubic triangle (MATH.md section 1).
//!
//! Two interpolations with the same nine nodal vectors and the same cubic
//! trace on every side (so positions stay C0 and creases still kink):
//!
//! - [`Shape::BCIZ`], the reduced cubic of Bazeley-Cheung-Irons-Zienkiewicz
//!   with bubble coefficient +1/2: it reproduces every quadratic field but
//!   passes the bending patch test only on three-direction meshes;
//! - [`Shape::specht`], Specht's modification (Int. J. Numer. Meth. Eng. 26,
//!   1988): BCIZ plus `sum_i C_ki b L_i` (`b = xi eta zeta`), with the 9x3
//!   coefficients `C` fixed per triangle so that along every side the integral
//!   of the normal slope is the trapezoidal rule of its two corner values.
//!   Neighbours then agree on that integral (the corner gradients are shared),
//!   which is what the constant-curvature patch test needs on any mesh. The
//!   terms `b L_i` vanish with their gradients at the corners and on every
//!   side, so nodal values, sides and quadratic completeness are unchanged.
//!
//! Functions are indexed in element order `[r1, r1_eta, r1_zeta, r2, r2_zeta,
//! r2_xi, r3, r3_xi, r3_eta]`; each scalar `s_k` multiplies the 3x3 identity.
//! Arguments are area coordinates `(xi, eta, zeta)` (sum 1) or, for the
//! derivatives, the independent coordinates `u = (eta, zeta)` with
//! `xi = 1 - eta - zeta`.

use super::ElemVec;
use nalgebra::{Matrix3, Vector2, Vector3};
use serde::{Deserialize, Serialize};
use std::sync::OnceLock;

/// For node `i` (corner area coordinate `i`): the area coordinates the two
/// gradient DOFs point towards, in element order.
const TOWARDS: [[usize; 2]; 3] = [[1, 2], [2, 0], [0, 1]];

/// Values, area-coordinate gradients and Hessians of the nine functions.
type AreaPartials = ([f64; 9], [[f64; 3]; 9], [[[f64; 3]; 3]; 9]);

/// Values, gradients and Hessians of the nine BCIZ shape functions with
/// respect to the three area coordinates treated as independent variables.
///
/// Any polynomial extension off the plane `xi + eta + zeta = 1` gives the same
/// tangential derivatives, so these project to the `(eta, zeta)` derivatives.
fn area_partials(l: [f64; 3]) -> AreaPartials {
    let b = l[0] * l[1] * l[2];
    let db = [l[1] * l[2], l[0] * l[2], l[0] * l[1]];
    let hb = [[0.0, l[2], l[1]], [l[2], 0.0, l[0]], [l[1], l[0], 0.0]];
    let mut v = [0.0; 9];
    let mut g = [[0.0; 3]; 9];
    let mut h = [[[0.0; 3]; 3]; 9];
    for p in 0..3 {
        let (q, r) = ((p + 1) % 3, (p + 2) % 3);
        // Corner function p^3 + 3 p^2 (q + r) + 2 b.
        let k = 3 * p;
        let lp = l[p];
        v[k] = lp * lp * lp + 3.0 * lp * lp * (l[q] + l[r]) + 2.0 * b;
        g[k][p] = 3.0 * lp * lp + 6.0 * lp * (l[q] + l[r]);
        g[k][q] = 3.0 * lp * lp;
        g[k][r] = 3.0 * lp * lp;
        h[k][p][p] = 6.0 * lp + 6.0 * (l[q] + l[r]);
        h[k][p][q] = 6.0 * lp;
        h[k][q][p] = 6.0 * lp;
        h[k][p][r] = 6.0 * lp;
        h[k][r][p] = 6.0 * lp;
        for a in 0..3 {
            g[k][a] += 2.0 * db[a];
            for c in 0..3 {
                h[k][a][c] += 2.0 * hb[a][c];
            }
        }
        // Gradient functions p^2 t + b/2 towards t.
        for (j, &t) in TOWARDS[p].iter().enumerate() {
            let k = 3 * p + 1 + j;
            v[k] = lp * lp * l[t] + 0.5 * b;
            g[k][p] = 2.0 * lp * l[t];
            g[k][t] = lp * lp;
            h[k][p][p] = 2.0 * l[t];
            h[k][p][t] = 2.0 * lp;
            h[k][t][p] = 2.0 * lp;
            for a in 0..3 {
                g[k][a] += 0.5 * db[a];
                for c in 0..3 {
                    h[k][a][c] += 0.5 * hb[a][c];
                }
            }
        }
    }
    (v, g, h)
}

/// Values, area-coordinate gradients and Hessians of the three bubbles.
type BubblePartials = ([f64; 3], [[f64; 3]; 3], [[[f64; 3]; 3]; 3]);

/// Specht's three correction functions `q_i = b L_i` (`b = xi eta zeta`):
/// values, area-coordinate gradients and Hessians.
fn bubble_partials(l: [f64; 3]) -> BubblePartials {
    let b = l[0] * l[1] * l[2];
    let db = [l[1] * l[2], l[0] * l[2], l[0] * l[1]];
    let hb = [[0.0, l[2], l[1]], [l[2], 0.0, l[0]], [l[1], l[0], 0.0]];
    let mut v = [0.0; 3];
    let mut g = [[0.0; 3]; 3];
    let mut h = [[[0.0; 3]; 3]; 3];
    for i in 0..3 {
        v[i] = b * l[i];
        for m in 0..3 {
            g[i][m] = db[m] * l[i] + if m == i { b } else { 0.0 };
            for n in 0..3 {
                h[i][m][n] = hb[m][n] * l[i]
                    + if n == i { db[m] } else { 0.0 }
                    + if m == i { db[n] } else { 0.0 };
            }
        }
    }
    (v, g, h)
}

/// Tangent directions d/d eta and d/d zeta in area-coordinate space.
const DIRS: [[f64; 3]; 2] = [[-1.0, 1.0, 0.0], [-1.0, 0.0, 1.0]];

/// Which cubic a facet uses (both have the same nodal vectors).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Interpolation {
    /// Specht's modified cubic: passes the patch test on any mesh (default).
    #[default]
    Specht,
    /// The plain BCIZ reduced cubic: converges on three-direction meshes only.
    Bciz,
}

impl Interpolation {
    /// The shape functions of the triangle with corners `x`.
    pub fn shape(self, x: &[Vector2<f64>; 3]) -> Shape {
        match self {
            Interpolation::Specht => Shape::specht(x),
            Interpolation::Bciz => Shape::BCIZ,
        }
    }
}

/// The nine shape functions of one triangle: BCIZ plus the correction
/// `sum_i corr[k][i] b L_i` of function `k` (zero for [`Shape::BCIZ`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shape {
    corr: [[f64; 3]; 9],
}

impl Shape {
    /// The BCIZ reduced cubic (the same for every triangle).
    pub const BCIZ: Shape = Shape {
        corr: [[0.0; 3]; 9],
    };

    /// Specht's shape functions for the triangle with corners `x`
    /// (counter-clockwise, not degenerate): along each side (opposite corner
    /// `c`, corners `a`, `b`, outward normal `n`, length `l`)
    /// `int dN_k/dn ds = (l/2) (dN_k/dn(a) + dN_k/dn(b))` for every `k`.
    ///
    /// On side `c` only `q_a`, `q_b` have a normal slope, `-L_a L_b L_i |grad L_c|`,
    /// whose integral is `-l^2/(24 A)`; the BCIZ defect is
    /// `(2l/3)((f_a + f_b)/2 - f_mid)` with `f = dB_k/dn` (Simpson is exact for
    /// its quadratic trace). The 3x3 system `[[0,1,1],[1,0,1],[1,1,0]]` has
    /// the inverse `J/2 - I`.
    pub fn specht(x: &[Vector2<f64>; 3]) -> Shape {
        let two_a = (x[1] - x[0]).perp(&(x[2] - x[0]));
        // grad L_m: the left normal of the opposite side over 2A.
        let grad_l: [Vector2<f64>; 3] = std::array::from_fn(|m| {
            let d = x[(m + 2) % 3] - x[(m + 1) % 3];
            Vector2::new(-d.y, d.x) / two_a
        });
        let mut rhs = [[0.0; 3]; 9]; // rhs[k][c]: the side-c equation scaled by -24A/l^2
        for c in 0..3 {
            let (a, b) = ((c + 1) % 3, (c + 2) % 3);
            let n = -grad_l[c] / grad_l[c].norm();
            let len = (x[b] - x[a]).norm();
            let at = |t: f64| {
                let mut l = [0.0; 3];
                l[a] = 1.0 - t;
                l[b] = t;
                let (_, g, _) = area_partials(l);
                g.map(|gk| (0..3).map(|m| gk[m] * grad_l[m].dot(&n)).sum::<f64>())
            };
            let (fa, fm, fb) = (at(0.0), at(0.5), at(1.0));
            for k in 0..9 {
                let defect = 2.0 * len / 3.0 * (0.5 * (fa[k] + fb[k]) - fm[k]);
                rhs[k][c] = defect * (-12.0 * two_a) / (len * len);
            }
        }
        let mut corr = [[0.0; 3]; 9];
        for k in 0..9 {
            let sum: f64 = rhs[k].iter().sum();
            for i in 0..3 {
                corr[k][i] = 0.5 * sum - rhs[k][i];
            }
        }
        Shape { corr }
    }

    /// Area-coordinate partials of the nine functions.
    fn partials(&self, l: [f64; 3]) -> AreaPartials {
        let (mut v, mut g, mut h) = area_partials(l);
        if *self == Shape::BCIZ {
            return (v, g, h);
        }
        let (qv, qg, qh) = bubble_partials(l);
        for k in 0..9 {
            for i in 0..3 {
                let c = self.corr[k][i];
                v[k] += c * qv[i];
                for m in 0..3 {
                    g[k][m] += c * qg[i][m];
                    for n in 0..3 {
                        h[k][m][n] += c * qh[i][m][n];
                    }
                }
            }
        }
        (v, g, h)
    }

    /// Shape function values `s_1..s_9` at area coordinates `l = (xi, eta, zeta)`.
    pub fn values(&self, l: [f64; 3]) -> [f64; 9] {
        self.partials(l).0
    }

    /// Derivatives `dS_k / d lambda` along the straight path `l + lambda dir`
    /// in area coordinates (`dir` sums to zero), at `l`: the position's
    /// derivative along it is `sum_k e_k dS_k`, the deformation gradient
    /// times the reference vector the path covers per unit `lambda`.
    pub fn d_along(&self, l: [f64; 3], dir: [f64; 3]) -> [f64; 9] {
        let (_, g, _) = self.partials(l);
        g.map(|gk| gk[0] * dir[0] + gk[1] * dir[1] + gk[2] * dir[2])
    }

    /// First derivatives `[dS_k/d eta, dS_k/d zeta]` at `u = (eta, zeta)`, with
    /// `xi = 1 - eta - zeta`.
    pub fn d1(&self, eta: f64, zeta: f64) -> [[f64; 2]; 9] {
        let (_, g, _) = self.partials([1.0 - eta - zeta, eta, zeta]);
        let mut out = [[0.0; 2]; 9];
        for k in 0..9 {
            for a in 0..2 {
                out[k][a] = (0..3).map(|i| DIRS[a][i] * g[k][i]).sum();
            }
        }
        out
    }

    /// Second derivatives `[S_,ee, S_,zz, S_,ez]` (e = eta, z = zeta) at
    /// `u = (eta, zeta)`, with `xi = 1 - eta - zeta`.
    pub fn d2(&self, eta: f64, zeta: f64) -> [[f64; 3]; 9] {
        let (_, _, h) = self.partials([1.0 - eta - zeta, eta, zeta]);
        let proj = |k: usize, a: usize, b: usize| -> f64 {
            let mut s = 0.0;
            for i in 0..3 {
                for j in 0..3 {
                    s += DIRS[a][i] * h[k][i][j] * DIRS[b][j];
                }
            }
            s
        };
        let mut out = [[0.0; 3]; 9];
        for (k, o) in out.iter_mut().enumerate() {
            *o = [proj(k, 0, 0), proj(k, 1, 1), proj(k, 0, 1)];
        }
        out
    }

    /// Position `r = sum_k s_k e_k` at area coordinates `l`.
    pub fn position(&self, e: &ElemVec, l: [f64; 3]) -> Vector3<f64> {
        let s = self.values(l);
        (0..9).fold(Vector3::zeros(), |acc, k| acc + e[k] * s[k])
    }

    /// Surface tangents `[dr/d eta, dr/d zeta]` at `u = (eta, zeta)`.
    pub fn tangents(&self, e: &ElemVec, eta: f64, zeta: f64) -> [Vector3<f64>; 2] {
        let d = self.d1(eta, zeta);
        let mut t = [Vector3::zeros(); 2];
        for k in 0..9 {
            t[0] += e[k] * d[k][0];
            t[1] += e[k] * d[k][1];
        }
        t
    }

    /// `Mhat = mean over the triangle of s_k s_l` (the element mass is
    /// `rho h area Mhat (x) I3`): the BCIZ closed form plus the correction
    /// terms, from exact means of `s_k q_i` and `q_i q_j` (degree 7 and 8).
    pub fn mass_hat(&self) -> [[f64; 9]; 9] {
        let mut m = super::mass::MASS_HAT;
        if *self == Shape::BCIZ {
            return m;
        }
        let (p, q) = bubble_means();
        let c = &self.corr;
        for k in 0..9 {
            for l in 0..9 {
                let mut add = 0.0;
                for i in 0..3 {
                    add += c[l][i] * p[k][i] + c[k][i] * p[l][i];
                    for j in 0..3 {
                        add += c[k][i] * c[l][j] * q[(i, j)];
                    }
                }
                m[k][l] += add;
            }
        }
        m
    }
}

/// Exact means over the triangle of `B_k q_i` and `q_i q_j` (BCIZ functions
/// `B`, bubbles `q`), by the collapsed 5x5 Gauss rule (exact to degree 8).
fn bubble_means() -> &'static ([[f64; 3]; 9], Matrix3<f64>) {
    static MEANS: OnceLock<([[f64; 3]; 9], Matrix3<f64>)> = OnceLock::new();
    MEANS.get_or_init(|| {
        let mut p = [[0.0; 3]; 9];
        let mut q = Matrix3::zeros();
        for (l, w) in collapsed_gauss(5) {
            let (b, _, _) = area_partials(l);
            let (qv, _, _) = bubble_partials(l);
            for i in 0..3 {
                for k in 0..9 {
                    p[k][i] += w * b[k] * qv[i];
                }
                for j in 0..3 {
                    q[(i, j)] += w * qv[i] * qv[j];
                }
            }
        }
        (p, q)
    })
}

/// `n`-point Gauss-Legendre nodes and weights on [0, 1] (Newton on the
/// Legendre polynomial from Chebyshev guesses), exact to degree `2n - 1`.
pub(crate) fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            // P_n(x) and P_n'(x) by the three-term recurrence.
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let k = k as f64;
                (p0, p1) = (p1, ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k);
            }
            let p = if n == 0 { 1.0 } else { p1 };
            let pm = if n == 1 { 1.0 } else { p0 };
            dp = n as f64 * (x * p - pm) / (x * x - 1.0);
            let dx = p / dp;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        out.push((0.5 * (1.0 - x), 0.5 * w));
    }
    out
}

/// An `n x n`-point rule on the triangle exact to degree `2n - 2` (Duffy map
/// of Gauss-Legendre; the map adds one degree in `u`): area coordinates and
/// weights summing to 1.
pub(crate) fn collapsed_gauss(n: usize) -> Vec<([f64; 3], f64)> {
    let g = gauss_legendre(n);
    let mut out = Vec::with_capacity(n * n);
    for &(u, wu) in &g {
        for &(v, wv) in &g {
            let (eta, zeta) = (u, (1.0 - u) * v);
            // d(eta, zeta) = (1 - u) du dv; the triangle's measure is 1/2.
            out.push(([1.0 - eta - zeta, eta, zeta], 2.0 * wu * wv * (1.0 - u)));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// BCIZ and Specht on a few triangles (right, skewed, obtuse, thin).
    fn shapes() -> Vec<Shape> {
        let v = Vector2::new;
        let mut out = vec![Shape::BCIZ];
        for x in [
            [v(0.0, 0.0), v(1.0, 0.0), v(0.0, 1.0)],
            [v(0.1, -0.2), v(1.3, 0.1), v(0.4, 0.9)],
            [v(0.0, 0.0), v(2.0, 0.0), v(1.7, 0.3)],
            [v(0.0, 0.0), v(1.0, 0.0), v(0.5, 0.05)],
        ] {
            out.push(Shape::specht(&x));
        }
        out
    }

    /// Corners in u = (eta, zeta) coordinates.
    const CORNER_U: [[f64; 2]; 3] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];

    /// Nodal functionals in element order applied to a field given by its
    /// value and u-gradient functions: value at a corner, or the derivative
    /// along the edge towards the target node (u_target - u_node) . grad.
    fn nodal<F, G>(f: F, grad: G) -> [f64; 9]
    where
        F: Fn(f64, f64) -> f64,
        G: Fn(f64, f64) -> [f64; 2],
    {
        let mut out = [0.0; 9];
        for p in 0..3 {
            let [ue, uz] = CORNER_U[p];
            out[3 * p] = f(ue, uz);
            let g = grad(ue, uz);
            for (j, &t) in TOWARDS[p].iter().enumerate() {
                let d = [CORNER_U[t][0] - ue, CORNER_U[t][1] - uz];
                out[3 * p + 1 + j] = d[0] * g[0] + d[1] * g[1];
            }
        }
        out
    }

    fn sample_points() -> Vec<[f64; 3]> {
        let mut pts = vec![
            [1.0 / 3.0; 3],
            [0.2, 0.5, 0.3],
            [0.7, 0.1, 0.2],
            [0.05, 0.05, 0.9],
            [0.6, 0.4, 0.0],
            [0.0, 0.25, 0.75],
        ];
        for i in 0..5 {
            for j in 0..(5 - i) {
                let (e, z) = (0.17 * i as f64 + 0.03, 0.19 * j as f64 + 0.02);
                if e + z <= 1.0 {
                    pts.push([1.0 - e - z, e, z]);
                }
            }
        }
        pts
    }

    #[test]
    fn nodal_interpolation_is_identity() {
        for sh in shapes() {
            for k in 0..9 {
                let n = nodal(
                    |e, z| sh.values([1.0 - e - z, e, z])[k],
                    |e, z| sh.d1(e, z)[k],
                );
                for (m, &v) in n.iter().enumerate() {
                    let want = if m == k { 1.0 } else { 0.0 };
                    assert!((v - want).abs() < 1e-13, "functional {m} of s{k}: {v}");
                }
            }
        }
    }

    #[test]
    fn value_functions_sum_to_one() {
        for sh in shapes() {
            for l in sample_points() {
                let s = sh.values(l);
                assert!((s[0] + s[3] + s[6] - 1.0).abs() < 1e-13);
            }
        }
    }

    #[test]
    fn reproduces_linear_and_quadratic_fields() {
        // f = c0 + c1 e + c2 z + c3 e^2 + c4 e z + c5 z^2, several coefficient sets.
        let sets: [[f64; 6]; 4] = [
            [0.3, -1.2, 0.7, 0.0, 0.0, 0.0],
            [1.0, 0.5, -0.25, 2.0, -1.5, 0.75],
            [-0.4, 0.0, 0.0, 0.0, 3.0, 0.0],
            [0.0, 0.0, 0.0, -2.5, 0.0, 1.25],
        ];
        for c in sets {
            let f = |e: f64, z: f64| {
                c[0] + c[1] * e + c[2] * z + c[3] * e * e + c[4] * e * z + c[5] * z * z
            };
            let g = |e: f64, z: f64| {
                [
                    c[1] + 2.0 * c[3] * e + c[4] * z,
                    c[2] + c[4] * e + 2.0 * c[5] * z,
                ]
            };
            let dofs = nodal(f, g);
            for (sh, l) in shapes()
                .into_iter()
                .flat_map(|sh| sample_points().into_iter().map(move |l| (sh, l)))
            {
                let (e, z) = (l[1], l[2]);
                let s = sh.values(l);
                let d = sh.d1(e, z);
                let dd = sh.d2(e, z);
                let val: f64 = (0..9).map(|k| s[k] * dofs[k]).sum();
                let ge: f64 = (0..9).map(|k| d[k][0] * dofs[k]).sum();
                let gz: f64 = (0..9).map(|k| d[k][1] * dofs[k]).sum();
                let hee: f64 = (0..9).map(|k| dd[k][0] * dofs[k]).sum();
                let hzz: f64 = (0..9).map(|k| dd[k][1] * dofs[k]).sum();
                let hez: f64 = (0..9).map(|k| dd[k][2] * dofs[k]).sum();
                assert!((val - f(e, z)).abs() < 1e-13, "value at {l:?}");
                assert!((ge - g(e, z)[0]).abs() < 1e-13);
                assert!((gz - g(e, z)[1]).abs() < 1e-13);
                assert!((hee - 2.0 * c[3]).abs() < 1e-12);
                assert!((hzz - 2.0 * c[5]).abs() < 1e-12);
                assert!((hez - c[4]).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn c0_on_edges() {
        // Edge (node a, node b): the DOFs that may be nonzero on it are the two
        // positions and the two gradients along the edge.
        type Edge = ([usize; 4], fn(f64) -> [f64; 3]);
        let edges: [Edge; 3] = [
            ([0, 1, 3, 5], |t| [1.0 - t, t, 0.0]), // edge 1-2, zeta = 0
            ([3, 4, 6, 8], |t| [0.0, 1.0 - t, t]), // edge 2-3, xi = 0
            ([6, 7, 0, 2], |t| [t, 0.0, 1.0 - t]), // edge 3-1, eta = 0
        ];
        for (sh, (live, at)) in shapes()
            .into_iter()
            .flat_map(|sh| edges.into_iter().map(move |e| (sh, e)))
        {
            let mut some_live = [false; 9];
            for i in 0..=20 {
                let l = at(i as f64 / 20.0);
                let s = sh.values(l);
                for k in 0..9 {
                    if live.contains(&k) {
                        some_live[k] |= s[k].abs() > 1e-3;
                    } else {
                        assert!(s[k].abs() < 1e-15, "s{k} = {} on edge at {l:?}", s[k]);
                    }
                }
            }
            for k in live {
                assert!(some_live[k], "s{k} should live on its edge");
            }
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let h = 1e-5;
        for (sh, l) in shapes()
            .into_iter()
            .flat_map(|sh| sample_points().into_iter().map(move |l| (sh, l)))
        {
            let (e, z) = (l[1], l[2]);
            let v = |e: f64, z: f64| sh.values([1.0 - e - z, e, z]);
            let d1 = |e: f64, z: f64| sh.d1(e, z);
            let d = d1(e, z);
            let dd = sh.d2(e, z);
            for k in 0..9 {
                let fe = (v(e + h, z)[k] - v(e - h, z)[k]) / (2.0 * h);
                let fz = (v(e, z + h)[k] - v(e, z - h)[k]) / (2.0 * h);
                assert!((fe - d[k][0]).abs() < 1e-8);
                assert!((fz - d[k][1]).abs() < 1e-8);
                let fee = (d1(e + h, z)[k][0] - d1(e - h, z)[k][0]) / (2.0 * h);
                let fzz = (d1(e, z + h)[k][1] - d1(e, z - h)[k][1]) / (2.0 * h);
                let fez = (d1(e, z + h)[k][0] - d1(e, z - h)[k][0]) / (2.0 * h);
                let fze = (d1(e + h, z)[k][1] - d1(e - h, z)[k][1]) / (2.0 * h);
                assert!((fee - dd[k][0]).abs() < 1e-8);
                assert!((fzz - dd[k][1]).abs() < 1e-8);
                assert!((fez - dd[k][2]).abs() < 1e-8);
                assert!((fze - dd[k][2]).abs() < 1e-8);
            }
        }
    }

    fn v3(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    #[test]
    fn math_md_test_vectors() {
        // Reference right triangle: r = eta X2 + zeta X3 everywhere.
        let x1 = v3(0.0, 0.0, 0.0);
        let x2 = v3(1.0, 0.0, 0.0);
        let x3 = v3(0.0, 1.0, 0.0);
        let e0: ElemVec = [
            x1,
            x2 - x1,
            x3 - x1,
            x2,
            x3 - x2,
            x1 - x2,
            x3,
            x1 - x3,
            x2 - x3,
        ];
        for l in sample_points() {
            let r = Shape::BCIZ.position(&e0, l);
            assert!((r - (x2 * l[1] + x3 * l[2])).norm() < 1e-14);
        }
        let r = Shape::BCIZ.position(&e0, [1.0 / 3.0; 3]);
        assert!((r - v3(1.0 / 3.0, 1.0 / 3.0, 0.0)).norm() < 1e-15);
        let r = Shape::BCIZ.position(&e0, [0.2, 0.5, 0.3]);
        assert!((r - v3(0.5, 0.3, 0.0)).norm() < 1e-15);

        let e: ElemVec = [
            v3(0.0, 0.0, 0.0),
            v3(1.0, 0.1, 0.2),
            v3(-0.1, 0.9, 0.3),
            v3(1.1, 0.0, 0.1),
            v3(-1.2, 1.0, 0.0),
            v3(-0.9, 0.2, -0.1),
            v3(0.0, 1.0, 0.2),
            v3(0.1, -1.1, -0.3),
            v3(1.0, -0.8, 0.1),
        ];
        let r = Shape::BCIZ.position(&e, [1.0 / 3.0; 3]);
        assert!(
            (r - v3(13.0 / 36.0, 7.0 / 20.0, 1.0 / 9.0)).norm() < 1e-14,
            "{r}"
        );
        let r = Shape::BCIZ.position(&e, [0.2, 0.5, 0.3]);
        assert!((r - v3(0.5451, 0.3225, 0.1159)).norm() < 1e-14, "{r}");
        // MATH.md: (1.111111, 0.066667, 0.077778) and (-0.011111, 1.0, 0.188889);
        // exactly (10/9, 1/15, 7/90) and (-1/90, 1, 17/90).
        let [re, rz] = Shape::BCIZ.tangents(&e, 1.0 / 3.0, 1.0 / 3.0);
        assert!(
            (re - v3(1.111111, 0.066667, 0.077778)).amax() < 5e-7,
            "{re}"
        );
        assert!((rz - v3(-0.011111, 1.0, 0.188889)).amax() < 5e-7, "{rz}");
        assert!(
            (re - v3(10.0 / 9.0, 1.0 / 15.0, 7.0 / 90.0)).norm() < 1e-14,
            "{re}"
        );
        assert!(
            (rz - v3(-1.0 / 90.0, 1.0, 17.0 / 90.0)).norm() < 1e-14,
            "{rz}"
        );
    }

    /// Specht's defining property, checked by quadrature independent of the
    /// construction: along every side, the 5-point Gauss integral of each
    /// function's normal slope equals the trapezoidal rule of its corner
    /// slopes. BCIZ fails it on a general triangle (what breaks its patch test).
    #[test]
    fn specht_normal_slope_integrals_are_trapezoidal() {
        let v = Vector2::new;
        let gauss = gauss_legendre(5);
        for x in [
            [v(0.1, -0.2), v(1.3, 0.1), v(0.4, 0.9)],
            [v(0.0, 0.0), v(2.0, 0.0), v(1.7, 0.3)],
            [v(0.0, 0.0), v(1.0, 0.0), v(0.5, 0.05)],
        ] {
            let two_a = (x[1] - x[0]).perp(&(x[2] - x[0]));
            // Cartesian gradient from u-derivatives: grad = J^-T d/du, J = [X2-X1, X3-X1].
            let jt_inv = nalgebra::Matrix2::from_columns(&[x[1] - x[0], x[2] - x[0]])
                .transpose()
                .try_inverse()
                .unwrap();
            let mut worst = [0.0_f64; 2];
            for (which, sh) in [Shape::specht(&x), Shape::BCIZ].iter().enumerate() {
                for c in 0..3 {
                    let (a, b) = ((c + 1) % 3, (c + 2) % 3);
                    let d = x[b] - x[a];
                    let len = d.norm();
                    let n = Vector2::new(d.y, -d.x) / len; // outward for CCW
                    let slope = |t: f64| -> [f64; 9] {
                        let mut l = [0.0; 3];
                        l[a] = 1.0 - t;
                        l[b] = t;
                        let du = sh.d1(l[1], l[2]);
                        du.map(|g| (jt_inv * Vector2::new(g[0], g[1])).dot(&n))
                    };
                    let (sa, sb) = (slope(0.0), slope(1.0));
                    let mut int = [0.0; 9];
                    for &(t, w) in &gauss {
                        let st = slope(t);
                        for k in 0..9 {
                            int[k] += w * len * st[k];
                        }
                    }
                    for k in 0..9 {
                        let trap = 0.5 * len * (sa[k] + sb[k]);
                        worst[which] = worst[which].max((int[k] - trap).abs());
                    }
                }
            }
            assert!(two_a > 0.0);
            assert!(worst[0] < 1e-12, "Specht defect {:e} on {x:?}", worst[0]);
            assert!(worst[1] > 1e-3, "BCIZ defect {:e} on {x:?}", worst[1]);
        }
    }

    /// Gauss-Legendre against the tabulated 5-point rule and a degree-13
    /// monomial on 7 points; the 7 x 7 triangle rule a degree-12 monomial.
    #[test]
    fn gauss_rules_are_exact() {
        let g = gauss_legendre(5);
        let table = [
            (0.046_910_077_030_668_004, 0.118_463_442_528_094_54),
            (0.230_765_344_947_158_45, 0.239_314_335_249_683_23),
            (0.5, 0.284_444_444_444_444_45),
        ];
        for (k, (x, w)) in table.iter().enumerate() {
            assert!(
                (g[k].0 - x).abs() < 1e-15 && (g[k].1 - w).abs() < 1e-15,
                "{:?}",
                g[k]
            );
        }
        let i: f64 = gauss_legendre(7).iter().map(|(x, w)| w * x.powi(13)).sum();
        assert!((i - 1.0 / 14.0).abs() < 1e-15, "{i}");
        // mean of eta^5 zeta^7 over the triangle = 2 * 5! 7! / 14!
        let t: f64 = collapsed_gauss(7)
            .iter()
            .map(|(l, w)| w * l[1].powi(5) * l[2].powi(7))
            .sum();
        let exact = 2.0 * 120.0 * 5040.0 / 87_178_291_200.0;
        assert!((t - exact).abs() < 1e-14 * exact, "{t} vs {exact}");
    }

    /// The Specht mass matrix: the correction formula equals brute-force
    /// exact integration of `s_k s_l`; symmetric positive definite; value
    /// functions still sum to one (so a rigid translation keeps its kinetic energy).
    #[test]
    fn specht_mass_hat_is_exact_and_positive() {
        let v = Vector2::new;
        let sh = Shape::specht(&[v(0.1, -0.2), v(1.3, 0.1), v(0.4, 0.9)]);
        let m = sh.mass_hat();
        let mut brute = [[0.0; 9]; 9];
        for (l, w) in collapsed_gauss(5) {
            let s = sh.values(l);
            for k in 0..9 {
                for j in 0..9 {
                    brute[k][j] += w * s[k] * s[j];
                }
            }
        }
        let mm = nalgebra::SMatrix::<f64, 9, 9>::from_fn(|i, j| m[i][j]);
        for k in 0..9 {
            for j in 0..9 {
                assert!((m[k][j] - brute[k][j]).abs() < 1e-15, "({k},{j})");
            }
        }
        assert!((mm - mm.transpose()).amax() < 1e-16);
        assert!(mm.symmetric_eigenvalues().min() > 1e-6);
        let mut trans = 0.0;
        for k in [0, 3, 6] {
            for j in [0, 3, 6] {
                trans += m[k][j];
            }
        }
        assert!((trans - 1.0).abs() < 1e-14, "{trans}");
        // It differs from BCIZ's (the correction is not negligible).
        assert!(
            (mm - nalgebra::SMatrix::<f64, 9, 9>::from_fn(|i, j| MASS_BCIZ[i][j])).amax() > 1e-5
        );
    }

    const MASS_BCIZ: [[f64; 9]; 9] = crate::element::mass::MASS_HAT;
}
