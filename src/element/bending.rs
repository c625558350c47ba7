//! The split bending energy of [`super::Bending::Split`]: the facet's mean
//! curvature carries its full energy, the curvature's variation about it
//! counts only through its energy-orthogonal projection on the curvature
//! fields of cubic deflections, with the weight [`HIGHER_ORDER_WEIGHT`].
//!
//! With `kappa_q` the curvature (Voigt) at quadrature point `q` and `Phi_m`
//! seven fields on the facet: the three constants and the curvatures of the
//! cubic deflections `x^3/6, x^2 y/2, x y^2/2, y^3/6` (centred, in the facet
//! frame), `b_m = sum_q wa_q Phi_mq^T C kappa_q`, `G = sum_q wa_q Phi^T C Phi
//! = L L^T` and `gamma = L^-1 b` (the curvature field's C-orthonormal
//! coordinates on the seven fields, the constants first):
//!
//! `U_b = (h^3/24) (gamma_1^2 + gamma_2^2 + gamma_3^2 + a sum_{t>3} gamma_t^2)`,
//!
//! `A kappa_mean^T C kappa_mean` plus `a` times the energy of the projected
//! variation. It is a function of the `kappa_q`, which are exact under
//! rigid motions, so the energy is too; a constant curvature has no
//! variation, so the patch test holds; the force is the pointwise one's with
//! the moments `(h^3/12) wa_q C sum_m y_m Phi_mq`, `y = L^-T (w gamma)`.
//!
//! Why (docs/model.md, "Bending on coarse meshes"): the displacement
//! element's higher-order stiffness is what makes coarse meshes too stiff
//! (the clamped plate 18-25 % at 4 x 4 cells); Bergan's free formulation and
//! the ANDES elements of Felippa and Militello keep the mean curvature's
//! energy, which the patch test fixes, and scale the rest.

use super::shell::MAX_QP;
use nalgebra::{Matrix3, SMatrix, Vector2};

/// The weight of the projected curvature variation's energy.
pub const HIGHER_ORDER_WEIGHT: f64 = 0.5;

/// Fields the curvature is projected on: constants and cubic deflections'.
pub const N_FIELDS: usize = 7;

/// `C / (E/(1-nu^2)) = CA + nu CB` (Voigt, engineering twist).
const CA: [f64; 3] = [1.0, 1.0, 0.5];

/// The seven fields at a facet's quadrature points and their Gram matrices
/// under `CA` and `CB` (so `G = c (GA + nu GB)` for any material).
#[derive(Clone, Copy, Debug)]
pub struct Projection {
    /// `phi[m][q]`: field `m` at point `q` (Voigt).
    pub phi: [[[f64; 3]; MAX_QP]; N_FIELDS],
    ga: SMatrix<f64, N_FIELDS, N_FIELDS>,
    gb: SMatrix<f64, N_FIELDS, N_FIELDS>,
}

/// `CA v` and `CB v` for a Voigt vector.
#[inline(always)]
fn ca(v: [f64; 3]) -> [f64; 3] {
    [CA[0] * v[0], CA[1] * v[1], CA[2] * v[2]]
}
#[inline(always)]
fn cb(v: [f64; 3]) -> [f64; 3] {
    [v[1], v[0], -0.5 * v[2]]
}
#[inline(always)]
fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
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
        // Scaled by the facet size so the Gram matrices are of order one.
        let size = area.sqrt();
        let mut phi = [[[0.0; 3]; MAX_QP]; N_FIELDS];
        for (q, p) in x.iter().enumerate() {
            let r = (p - centre) / size;
            let fields = [
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                [r.x, 0.0, 0.0],
                [r.y, 0.0, 2.0 * r.x],
                [0.0, r.x, 2.0 * r.y],
                [0.0, r.y, 0.0],
            ];
            for (m, f) in fields.into_iter().enumerate() {
                phi[m][q] = f;
            }
        }
        let gram = |c: fn([f64; 3]) -> [f64; 3]| {
            SMatrix::<f64, N_FIELDS, N_FIELDS>::from_fn(|m, n| {
                (0..x.len())
                    .map(|q| wa[q] * dot3(phi[m][q], c(phi[n][q])))
                    .sum()
            })
        };
        Projection {
            phi,
            ga: gram(ca),
            gb: gram(cb),
        }
    }

    /// The lower Cholesky factor's inverse `L^-1` of `G = c (GA + nu GB)`.
    #[inline(always)]
    pub fn l_inv(&self, c: f64, nu: f64) -> SMatrix<f64, N_FIELDS, N_FIELDS> {
        let g = (self.ga + self.gb * nu) * c;
        let l = g
            .cholesky()
            .expect("the fields are independent and C is positive definite")
            .unpack();
        l.try_inverse().expect("a Cholesky factor is invertible")
    }

    /// `wa_q C phi_m(q)` for every field and point: the weights of `b_m`.
    #[inline(always)]
    pub fn weighted(&self, c: f64, nu: f64, wa: &[f64]) -> [[[f64; 3]; MAX_QP]; N_FIELDS] {
        let cm = Matrix3::new(1.0, nu, 0.0, nu, 1.0, 0.0, 0.0, 0.0, 0.5 * (1.0 - nu)) * c;
        let mut out = [[[0.0; 3]; MAX_QP]; N_FIELDS];
        for m in 0..N_FIELDS {
            for (q, &w) in wa.iter().enumerate() {
                let v = cm * nalgebra::Vector3::from(self.phi[m][q]) * w;
                out[m][q] = [v.x, v.y, v.z];
            }
        }
        out
    }
}

/// The energy weights of the C-orthonormal coordinates: the constants in
/// full, the cubic deflections' curvatures with [`HIGHER_ORDER_WEIGHT`].
pub const WEIGHTS: [f64; N_FIELDS] = [
    1.0,
    1.0,
    1.0,
    HIGHER_ORDER_WEIGHT,
    HIGHER_ORDER_WEIGHT,
    HIGHER_ORDER_WEIGHT,
    HIGHER_ORDER_WEIGHT,
];
