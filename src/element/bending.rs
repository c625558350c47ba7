//! The split bending energy of [`super::Bending::Split`]: the facet's mean
//! curvature carries its full energy, the curvature's variation about it
//! counts only through its energy-orthogonal projection on the curvature
//! fields of cubic deflections, with the weight [`HIGHER_ORDER_WEIGHT`].
//!
//! With `kappa_q` the curvature (Voigt) at quadrature point `q`, `A` the
//! area, `kappa_mean = sum_q wa_q kappa_q / A`, and `phi_m` the curvatures of
//! the cubic deflections `x^3/6, x^2 y/2, x y^2/2, y^3/6` (in the facet frame,
//! centred on the points' centroid so that they have no mean and are
//! orthogonal to constants), `b_m = sum_q wa_q phi_mq^T C kappa_q` and
//! `G_mn = sum_q wa_q phi_mq^T C phi_nq`:
//!
//! `U_b = (h^3/24) (A kappa_mean^T C kappa_mean + a b^T G^-1 b)`,
//!
//! the mean curvature's energy plus `a` times the energy of the variation's
//! C-orthogonal projection on the cubic deflections' curvatures. It is a
//! function of the `kappa_q`, which rigid motions leave unchanged, so the
//! energy is exact under large rotations; a constant curvature has no
//! variation, so the patch test holds; the force is the pointwise energy's
//! with the moments `(h^3/12) (wa_q C kappa_mean + sum_m y_m wa_q C phi_mq)`,
//! `y = a G^-1 b`. `G = E/(1-nu^2) (GA + nu GB)` is factored at each
//! evaluation (4 x 4), so the material may change between evaluations.
//!
//! Why (docs/model.md, "Bending on coarse meshes"): the displacement
//! element's higher-order stiffness (the energy of the curvature's variation)
//! is what makes coarse meshes too stiff (the clamped plate 18-25 % at 4 x 4
//! cells); Bergan's free formulation and the ANDES elements of Felippa and
//! Militello keep the mean curvature's energy, which the patch test fixes,
//! and scale the rest.

use super::shell::MAX_QP;
use nalgebra::Vector2;

/// The weight of the projected curvature variation's energy.
pub const HIGHER_ORDER_WEIGHT: f64 = 0.5;

/// Number of cubic deflections the variation is projected on.
pub const N_CUBIC: usize = 4;

/// A Voigt vector and 3-vector kernels.
type V3 = [f64; 3];

#[inline(always)]
fn dot3(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The cubic deflections' curvatures at a facet's points, weighted, split
/// into the parts of `C / (E/(1-nu^2)) = CA + nu CB`.
#[derive(Clone, Copy, Debug)]
pub struct Projection {
    /// `wa_q CA phi_m(q)`.
    wa_ca: [[V3; MAX_QP]; N_CUBIC],
    /// `wa_q CB phi_m(q)`.
    wa_cb: [[V3; MAX_QP]; N_CUBIC],
    /// `sum_q wa_q phi_m^T CA phi_n`.
    ga: [[f64; N_CUBIC]; N_CUBIC],
    /// `sum_q wa_q phi_m^T CB phi_n`.
    gb: [[f64; N_CUBIC]; N_CUBIC],
    /// `wa_q`.
    wa: [f64; MAX_QP],
    /// `sum_q wa_q`.
    area: f64,
}

/// The split energy at one state, for the force and the tangent.
#[derive(Clone, Copy, Debug)]
pub struct SplitState {
    /// `kappa_mean`.
    pub mean: V3,
    /// `a G^-1 b`.
    pub y: [f64; N_CUBIC],
    /// `sqrt(a) L^-1` with `G = L L^T`: `a G^-1 = l^T l`.
    pub l: [[f64; N_CUBIC]; N_CUBIC],
    /// `A kappa_mean^T C kappa_mean + a b^T G^-1 b` (the energy over `h^3/24`).
    pub energy: f64,
}

impl Projection {
    /// The fields at points `x` (facet frame) with weights `wa` (weight
    /// times area).
    pub fn new(x: &[Vector2<f64>], wa: &[f64]) -> Projection {
        let area: f64 = wa.iter().sum();
        let centre = x
            .iter()
            .zip(wa)
            .fold(Vector2::zeros(), |s, (p, w)| s + p * *w)
            / area;
        // Scaled by the facet size so that G is of order one.
        let size = area.sqrt();
        let mut wa_ca = [[[0.0; 3]; MAX_QP]; N_CUBIC];
        let mut wa_cb = wa_ca;
        let mut phi = [[[0.0; 3]; MAX_QP]; N_CUBIC];
        for (q, p) in x.iter().enumerate() {
            let r = (p - centre) / size;
            let fields = [
                [r.x, 0.0, 0.0],
                [r.y, 0.0, 2.0 * r.x],
                [0.0, r.x, 2.0 * r.y],
                [0.0, r.y, 0.0],
            ];
            for (m, f) in fields.into_iter().enumerate() {
                phi[m][q] = f;
                wa_ca[m][q] = [wa[q] * f[0], wa[q] * f[1], 0.5 * wa[q] * f[2]];
                wa_cb[m][q] = [wa[q] * f[1], wa[q] * f[0], -0.5 * wa[q] * f[2]];
            }
        }
        let gram = |w: &[[V3; MAX_QP]; N_CUBIC]| {
            std::array::from_fn(|m| {
                std::array::from_fn(|n| (0..x.len()).map(|q| dot3(w[m][q], phi[n][q])).sum())
            })
        };
        Projection {
            ga: gram(&wa_ca),
            gb: gram(&wa_cb),
            wa_ca,
            wa_cb,
            wa: std::array::from_fn(|q| wa.get(q).copied().unwrap_or(0.0)),
            area,
        }
    }

    /// `wa_q C phi_m(q)` for the material `c = E/(1-nu^2)`, `nu`.
    #[inline(always)]
    pub fn wc_phi(&self, m: usize, q: usize, c: f64, nu: f64) -> V3 {
        let (a, b) = (self.wa_ca[m][q], self.wa_cb[m][q]);
        [
            c * (a[0] + nu * b[0]),
            c * (a[1] + nu * b[1]),
            c * (a[2] + nu * b[2]),
        ]
    }

    /// The state at the curvatures `kappa[..nq]` (Voigt, one per point) for
    /// the material `c = E/(1-nu^2)`, `nu`.
    #[inline(always)]
    pub fn state(&self, kappa: &[V3], c: f64, nu: f64) -> SplitState {
        let mut mean = [0.0; 3];
        let mut b = [0.0; N_CUBIC];
        for (q, k) in kappa.iter().enumerate() {
            for v in 0..3 {
                mean[v] += self.wa[q] * k[v];
            }
            for m in 0..N_CUBIC {
                b[m] += c * (dot3(self.wa_ca[m][q], *k) + nu * dot3(self.wa_cb[m][q], *k));
            }
        }
        let mean = mean.map(|m| m / self.area);
        // G = L L^T (Cholesky), then l = sqrt(a) L^-1.
        let mut g = [[0.0; N_CUBIC]; N_CUBIC];
        for m in 0..N_CUBIC {
            for n in 0..N_CUBIC {
                g[m][n] = c * (self.ga[m][n] + nu * self.gb[m][n]);
            }
        }
        let mut low = [[0.0; N_CUBIC]; N_CUBIC];
        for i in 0..N_CUBIC {
            for j in 0..=i {
                let s = g[i][j] - (0..j).map(|k| low[i][k] * low[j][k]).sum::<f64>();
                low[i][j] = if i == j { s.sqrt() } else { s / low[j][j] };
            }
        }
        let mut l = [[0.0; N_CUBIC]; N_CUBIC];
        let ra = HIGHER_ORDER_WEIGHT.sqrt();
        for col in 0..N_CUBIC {
            // Forward substitution of L x = e_col.
            for i in col..N_CUBIC {
                let rhs = if i == col { 1.0 } else { 0.0 };
                let s = rhs - (col..i).map(|k| low[i][k] * l[k][col]).sum::<f64>();
                l[i][col] = s / low[i][i];
            }
        }
        let l = l.map(|row| row.map(|v| ra * v));
        // gamma = l b, y = l^T gamma = a G^-1 b.
        let gamma: [f64; N_CUBIC] =
            std::array::from_fn(|t| (0..N_CUBIC).map(|m| l[t][m] * b[m]).sum());
        let y = std::array::from_fn(|m| (0..N_CUBIC).map(|t| l[t][m] * gamma[t]).sum());
        let cm = [
            c * (mean[0] + nu * mean[1]),
            c * (nu * mean[0] + mean[1]),
            c * 0.5 * (1.0 - nu) * mean[2],
        ];
        SplitState {
            mean,
            y,
            l,
            energy: self.area * dot3(mean, cm) + gamma.iter().map(|g| g * g).sum::<f64>(),
        }
    }

    /// `sum_q wa_q`.
    pub fn area(&self) -> f64 {
        self.area
    }
}
