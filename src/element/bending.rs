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
//! `y = a G^-1 b`. `G = E/(1-nu^2) (GA + nu GB)`: its factors for the
//! sheet's Poisson's ratio are kept ([`Projection::prepare`]); at another
//! ratio they are computed at the evaluation (4 x 4).
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
    /// The factors kept for one Poisson's ratio ([`Projection::prepare`]).
    kept: Option<Factors>,
}

/// What the split energy needs for one Poisson ratio `nu`: the weights
/// `wc_mq = wa_q (CA + nu CB) phi_m(q)` and `l = sqrt(a) L^-1` with
/// `GA + nu GB = L L^T` (so `a (GA + nu GB)^-1 = l^T l`).
#[derive(Clone, Copy, Debug)]
pub struct Factors {
    nu: f64,
    /// `wc[m][q]`.
    pub wc: [[V3; MAX_QP]; N_CUBIC],
    /// `l[t][m]`.
    pub l: [[f64; N_CUBIC]; N_CUBIC],
}

/// The split energy at one state, for the force and the tangent; with
/// `c = E/(1-nu^2)`, `b_m = c sum_q wc_mq . kappa_q` and `a G^-1 = l^T l / c`.
#[derive(Clone, Copy, Debug)]
pub struct SplitState {
    /// `kappa_mean`.
    pub mean: V3,
    /// `a G^-1 b / c`: the moments at point `q` are
    /// `(h^3/12) (wa_q C kappa_mean + c sum_m y_m wc_mq)`.
    pub y: [f64; N_CUBIC],
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
            kept: None,
        }
    }

    /// The factors for Poisson's ratio `nu`.
    pub fn factors(&self, nu: f64) -> Factors {
        let mut wc = [[[0.0; 3]; MAX_QP]; N_CUBIC];
        for m in 0..N_CUBIC {
            for q in 0..MAX_QP {
                let (a, b) = (self.wa_ca[m][q], self.wa_cb[m][q]);
                wc[m][q] = [a[0] + nu * b[0], a[1] + nu * b[1], a[2] + nu * b[2]];
            }
        }
        // GA + nu GB = L L^T (Cholesky), then l = sqrt(a) L^-1.
        let mut low = [[0.0; N_CUBIC]; N_CUBIC];
        for i in 0..N_CUBIC {
            for j in 0..=i {
                let g = self.ga[i][j] + nu * self.gb[i][j];
                let s = g - (0..j).map(|k| low[i][k] * low[j][k]).sum::<f64>();
                low[i][j] = if i == j { s.sqrt() } else { s / low[j][j] };
            }
        }
        let mut l = [[0.0; N_CUBIC]; N_CUBIC];
        for col in 0..N_CUBIC {
            // Forward substitution of L x = e_col.
            for i in col..N_CUBIC {
                let rhs = if i == col { 1.0 } else { 0.0 };
                let s = rhs - (col..i).map(|k| low[i][k] * l[k][col]).sum::<f64>();
                l[i][col] = s / low[i][i];
            }
        }
        let ra = HIGHER_ORDER_WEIGHT.sqrt();
        Factors {
            nu,
            wc,
            l: l.map(|row| row.map(|v| ra * v)),
        }
    }

    /// Keeps the factors for `nu`, so that evaluations at that Poisson's
    /// ratio need not recompute them.
    pub fn prepare(&mut self, nu: f64) {
        self.kept = Some(self.factors(nu));
    }

    /// The factors for `nu`: the kept ones if they are for it, else
    /// computed into `scratch`.
    #[inline(always)]
    pub fn factors_for<'a>(&'a self, nu: f64, scratch: &'a mut Option<Factors>) -> &'a Factors {
        match &self.kept {
            Some(f) if f.nu == nu => f,
            _ => scratch.insert(self.factors(nu)),
        }
    }

    /// The state at the curvatures `kappa[..nq]` (Voigt, one per point),
    /// with the factors `f` of the material's Poisson's ratio and
    /// `c = E/(1-nu^2)`.
    #[inline(always)]
    pub fn state(&self, f: &Factors, kappa: &[V3], c: f64) -> SplitState {
        let mut mean = [0.0; 3];
        let mut b = [0.0; N_CUBIC];
        for (q, k) in kappa.iter().enumerate() {
            for v in 0..3 {
                mean[v] += self.wa[q] * k[v];
            }
            for m in 0..N_CUBIC {
                b[m] += dot3(f.wc[m][q], *k);
            }
        }
        let mean = mean.map(|m| m / self.area);
        // With b over c: gamma = l b (the energy's c gamma^2), y = l^T gamma.
        let gamma: [f64; N_CUBIC] =
            std::array::from_fn(|t| (0..N_CUBIC).map(|m| f.l[t][m] * b[m]).sum());
        let y = std::array::from_fn(|m| (0..N_CUBIC).map(|t| f.l[t][m] * gamma[t]).sum());
        let nu = f.nu;
        let cm = [
            c * (mean[0] + nu * mean[1]),
            c * (nu * mean[0] + mean[1]),
            c * 0.5 * (1.0 - nu) * mean[2],
        ];
        SplitState {
            mean,
            y,
            energy: self.area * dot3(mean, cm) + c * gamma.iter().map(|g| g * g).sum::<f64>(),
        }
    }

    /// `sum_q wa_q`.
    pub fn area(&self) -> f64 {
        self.area
    }
}
