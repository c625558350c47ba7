//! Shape functions of the cubic triangle (MATH.md section 1): the reduced
//! cubic of Bazeley-Cheung-Irons-Zienkiewicz with bubble coefficient +1/2,
//! which reproduces every quadratic field.
//!
//! Functions are indexed in element order `[r1, r1_eta, r1_zeta, r2, r2_zeta,
//! r2_xi, r3, r3_xi, r3_eta]`; each scalar `s_k` multiplies the 3x3 identity.
//! Arguments are area coordinates `(xi, eta, zeta)` (sum 1) or, for the
//! derivatives, the independent coordinates `u = (eta, zeta)` with
//! `xi = 1 - eta - zeta`.

use super::ElemVec;
use nalgebra::Vector3;

/// For node `i` (corner area coordinate `i`): the area coordinates the two
/// gradient DOFs point towards, in element order.
const TOWARDS: [[usize; 2]; 3] = [[1, 2], [2, 0], [0, 1]];

/// Values, area-coordinate gradients and Hessians of the nine functions.
type AreaPartials = ([f64; 9], [[f64; 3]; 9], [[[f64; 3]; 3]; 9]);

/// Values, gradients and Hessians of all nine shape functions with respect to
/// the three area coordinates treated as independent variables.
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

/// Tangent directions d/d eta and d/d zeta in area-coordinate space.
const DIRS: [[f64; 3]; 2] = [[-1.0, 1.0, 0.0], [-1.0, 0.0, 1.0]];

/// Shape function values `s_1..s_9` at area coordinates `l = (xi, eta, zeta)`.
pub fn values(l: [f64; 3]) -> [f64; 9] {
    area_partials(l).0
}

/// First derivatives `[dS_k/d eta, dS_k/d zeta]` at `u = (eta, zeta)`, with
/// `xi = 1 - eta - zeta`.
pub fn d1(eta: f64, zeta: f64) -> [[f64; 2]; 9] {
    let (_, g, _) = area_partials([1.0 - eta - zeta, eta, zeta]);
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
pub fn d2(eta: f64, zeta: f64) -> [[f64; 3]; 9] {
    let (_, _, h) = area_partials([1.0 - eta - zeta, eta, zeta]);
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
pub fn position(e: &ElemVec, l: [f64; 3]) -> Vector3<f64> {
    let s = values(l);
    (0..9).fold(Vector3::zeros(), |acc, k| acc + e[k] * s[k])
}

/// Surface tangents `[dr/d eta, dr/d zeta]` at `u = (eta, zeta)`.
pub fn tangents(e: &ElemVec, eta: f64, zeta: f64) -> [Vector3<f64>; 2] {
    let d = d1(eta, zeta);
    let mut t = [Vector3::zeros(); 2];
    for k in 0..9 {
        t[0] += e[k] * d[k][0];
        t[1] += e[k] * d[k][1];
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

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
        for k in 0..9 {
            let n = nodal(|e, z| values([1.0 - e - z, e, z])[k], |e, z| d1(e, z)[k]);
            for (m, &v) in n.iter().enumerate() {
                let want = if m == k { 1.0 } else { 0.0 };
                assert!((v - want).abs() < 1e-14, "functional {m} of s{k}: {v}");
            }
        }
    }

    #[test]
    fn value_functions_sum_to_one() {
        for l in sample_points() {
            let s = values(l);
            assert!((s[0] + s[3] + s[6] - 1.0).abs() < 1e-14);
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
            for l in sample_points() {
                let (e, z) = (l[1], l[2]);
                let s = values(l);
                let d = d1(e, z);
                let dd = d2(e, z);
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
        for (live, at) in edges {
            let mut some_live = [false; 9];
            for i in 0..=20 {
                let l = at(i as f64 / 20.0);
                let s = values(l);
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
        for l in sample_points() {
            let (e, z) = (l[1], l[2]);
            let v = |e: f64, z: f64| values([1.0 - e - z, e, z]);
            let d = d1(e, z);
            let dd = d2(e, z);
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
            let r = position(&e0, l);
            assert!((r - (x2 * l[1] + x3 * l[2])).norm() < 1e-14);
        }
        let r = position(&e0, [1.0 / 3.0; 3]);
        assert!((r - v3(1.0 / 3.0, 1.0 / 3.0, 0.0)).norm() < 1e-15);
        let r = position(&e0, [0.2, 0.5, 0.3]);
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
        let r = position(&e, [1.0 / 3.0; 3]);
        assert!(
            (r - v3(13.0 / 36.0, 7.0 / 20.0, 1.0 / 9.0)).norm() < 1e-14,
            "{r}"
        );
        let r = position(&e, [0.2, 0.5, 0.3]);
        assert!((r - v3(0.5451, 0.3225, 0.1159)).norm() < 1e-14, "{r}");
        // MATH.md: (1.111111, 0.066667, 0.077778) and (-0.011111, 1.0, 0.188889);
        // exactly (10/9, 1/15, 7/90) and (-1/90, 1, 17/90).
        let [re, rz] = tangents(&e, 1.0 / 3.0, 1.0 / 3.0);
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
}
