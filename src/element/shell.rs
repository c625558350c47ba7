//! Kirchhoff-Love shell energy of one cubic triangle (MATH.md section 2), with
//! its exact gradient and Hessian for implicit time stepping.
//!
//! The reference facet is flat and straight-edged, so the map from
//! `u = (eta, zeta)` to local Cartesian coordinates `x` is affine and constant:
//! all shape-function derivatives are taken with respect to `x` once, in
//! [`ShellElement::new`]. With `N_k,i = dN_k/dx_i`:
//!
//! - `F_i = sum_k N_k,i e_k` (the columns of the 3x2 deformation gradient),
//!   membrane strain `eps = (F^T F - I)/2`;
//! - `n = F_1 x F_2`, `n_hat = n/|n|`, curvature `kappa_ij = n_hat . r_,ij`
//!   with `r_,ij = sum_k N_k,ij e_k` (reference curvature is zero);
//! - `W = (h/2) eps^T C eps + (h^3/24) kappa^T C kappa` in Voigt form
//!   `[11, 22, 2*12]`, integrated with a Dunavant rule.
//!
//! The tangent is exact: the material part `B^T D B` plus the geometric parts
//! `sum sigma_ij N_k,i N_l,j I3` (membrane) and the Hessian of
//! `n_hat . v` (bending), where `v = sum_V m_V r_,V` gathers the bending
//! moments `m = (h^3/12) C kappa`. Writing `w = (I - n_hat n_hat^T) v / |n|`,
//! `s = n_hat . v`, the Hessian of `n_hat . v` with respect to `n` is
//! `H_n = -(w n_hat^T + n_hat w^T)/|n| - s (I - n_hat n_hat^T)/|n|^2`, and the
//! bilinear map `n = F_1 x F_2` adds `-[w]x` to the `F_1 F_2` block.
//!
//! The curvature gradient
//! `d kappa_ij/de_k = N_k,ij n_hat + N_k,2 (w_ij x F_1) - N_k,1 (w_ij x F_2)`,
//! `w_ij = (I - n_hat n_hat^T) r_,ij/|n|`, is parallel to `n_hat` (both
//! cross products are of tangent vectors), so the bending material part of
//! every 3x3 block is a scalar times `n_hat n_hat^T`; the kernel uses this. Only the upper 3x3 blocks are computed, then mirrored:
//! the tangent is exactly symmetric.

use super::{
    Bending, ElemVec, ElementOptions,
    bending::{Factors, N_CUBIC, Projection, SplitState},
    quadrature::Rule,
    shape::{Interpolation, Shape},
};
use crate::material::Material;
#[cfg(test)]
use nalgebra::Matrix3;
use nalgebra::{Matrix2, SMatrix, SVector, Vector2, Vector3};

/// Largest number of quadrature points of any [`Rule`].
pub const MAX_QP: usize = 12;

/// Weighted membrane resultants `wa h C eps` (Voigt) at each quadrature point.
pub type MembraneResultants = [[f64; 3]; MAX_QP];

/// Per-quadrature-point constants: Cartesian shape-function derivatives and
/// the weight times the area.
#[derive(Clone, Copy, Debug, Default)]
struct QuadPoint {
    /// `dN_k/dx_1`.
    n1: [f64; 9],
    /// `dN_k/dx_2`.
    n2: [f64; 9],
    /// `d2N_k/dx_1^2`.
    n11: [f64; 9],
    /// `d2N_k/dx_2^2`.
    n22: [f64; 9],
    /// `d2N_k/dx_1 dx_2`.
    n12: [f64; 9],
    /// Quadrature weight times the element area.
    wa: f64,
}

/// One flat straight-edged reference triangle with everything about it that
/// does not depend on the deformation precomputed (it is `Copy`, no heap).
#[derive(Clone, Copy, Debug)]
pub struct ShellElement {
    area: f64,
    frame: [Vector2<f64>; 2],
    j2_inv: Matrix2<f64>,
    rule: Rule,
    shape: Shape,
    mass_hat: [[f64; 9]; 9],
    /// The split bending energy's fields ([`Bending::Split`]), or none.
    split: Option<Projection>,
    nq: usize,
    qp: [QuadPoint; MAX_QP],
}

/// Strain energy of one element, split into its membrane and bending parts.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ShellEnergy {
    /// `area * sum_q w_q (h/2) eps^T C eps`.
    pub membrane: f64,
    /// `area * sum_q w_q (h^3/24) kappa^T C kappa`.
    pub bending: f64,
}

impl ShellEnergy {
    /// Membrane plus bending energy.
    pub fn total(&self) -> f64 {
        self.membrane + self.bending
    }
}

/// Plane-stress constants `c = E/(1 - nu^2)` and `nu`.
#[derive(Clone, Copy)]
struct Plane {
    c: f64,
    nu: f64,
}

impl Plane {
    fn new(mat: &Material) -> Self {
        let nu = mat.poisson_ratio;
        Plane {
            c: mat.youngs_modulus / (1.0 - nu * nu),
            nu,
        }
    }
    /// `s * C v` for a Voigt vector `v`.
    #[inline(always)]
    fn apply(&self, s: f64, v: [f64; 3]) -> [f64; 3] {
        let c = s * self.c;
        [
            c * (v[0] + self.nu * v[1]),
            c * (self.nu * v[0] + v[1]),
            c * 0.5 * (1.0 - self.nu) * v[2],
        ]
    }
}

/// Deformation measures at one quadrature point.
#[derive(Clone, Copy, Default)]
struct Kinematics {
    f1: Vector3<f64>,
    f2: Vector3<f64>,
    /// `[r_,11, r_,22, 2 r_,12]`: Voigt-weighted second derivatives.
    rv: [Vector3<f64>; 3],
    n_hat: Vector3<f64>,
    n_len: f64,
    eps: [f64; 3],
    kappa: [f64; 3],
}

#[inline(always)]
fn kinematics(q: &QuadPoint, e: &ElemVec) -> Kinematics {
    let mut f1 = Vector3::zeros();
    let mut f2 = Vector3::zeros();
    let mut r11 = Vector3::zeros();
    let mut r22 = Vector3::zeros();
    let mut r12 = Vector3::zeros();
    for k in 0..9 {
        f1 += e[k] * q.n1[k];
        f2 += e[k] * q.n2[k];
        r11 += e[k] * q.n11[k];
        r22 += e[k] * q.n22[k];
        r12 += e[k] * q.n12[k];
    }
    let n = f1.cross(&f2);
    let n_len = n.norm();
    let n_hat = n / n_len;
    let rv = [r11, r22, r12 * 2.0];
    Kinematics {
        f1,
        f2,
        eps: [
            0.5 * (f1.dot(&f1) - 1.0),
            0.5 * (f2.dot(&f2) - 1.0),
            f1.dot(&f2),
        ],
        kappa: [n_hat.dot(&rv[0]), n_hat.dot(&rv[1]), n_hat.dot(&rv[2])],
        rv,
        n_hat,
        n_len,
    }
}

/// `dX/d eta`, `dX/d zeta` of the reference map `X = sum_k S_k e0_k` from the
/// shape functions' first derivatives `d1` (iso-parametric: the same functions
/// as the field, so the reference state is strain-free).
fn reference_tangents(e0: &[Vector2<f64>; 9], d1: &[[f64; 2]; 9]) -> (Vector2<f64>, Vector2<f64>) {
    let (mut c1, mut c2) = (Vector2::zeros(), Vector2::zeros());
    for k in 0..9 {
        c1 += e0[k] * d1[k][0];
        c2 += e0[k] * d1[k][1];
    }
    (c1, c2)
}

/// `Mhat` of a curved-sided facet: the mean of `s_k s_l` weighted by the
/// reference Jacobian of its map, by the 49-point collapsed Gauss rule
/// (exact to degree 12, the integrand's).
fn curved_mass_hat(shape: &Shape, e0: &[Vector2<f64>; 9]) -> [[f64; 9]; 9] {
    let mut m = [[0.0; 9]; 9];
    let mut total = 0.0;
    for (l, w) in super::shape::collapsed_gauss(7) {
        let (c1, c2) = reference_tangents(e0, &shape.d1(l[1], l[2]));
        let wd = w * c1.perp(&c2);
        total += wd;
        let s = shape.values(l);
        for k in 0..9 {
            for j in 0..9 {
                m[k][j] += wd * s[k] * s[j];
            }
        }
    }
    m.map(|row| row.map(|v| v / total))
}

#[inline(always)]
fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Why a reference triangle makes no element.
#[derive(Clone, Debug, PartialEq)]
pub enum ElementError {
    /// A corner or side vector is NaN or infinite (the corners).
    NonFinite([Vector2<f64>; 3]),
    /// Zero or vanishing area.
    Degenerate {
        /// Twice the signed area.
        twice_area: f64,
        /// Squared length of the longest edge.
        longest_edge_squared: f64,
    },
    /// Corners clockwise.
    Clockwise {
        /// The (negative) signed area.
        signed_area: f64,
    },
    /// The corners' Jacobian has no inverse.
    SingularJacobian,
    /// A curved side makes the reference map fold over at a quadrature point.
    FoldedSide {
        /// The reference Jacobian there.
        jacobian: f64,
        /// The point's area coordinates.
        area_coordinates: [f64; 3],
        /// The chord triangle's Jacobian (twice its area).
        chord_jacobian: f64,
    },
}

impl std::fmt::Display for ElementError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ElementError::NonFinite(x) => write!(f, "triangle has non-finite coordinates {x:?}"),
            ElementError::Degenerate {
                twice_area,
                longest_edge_squared,
            } => write!(
                f,
                "degenerate triangle (2 * area = {twice_area:e}, longest edge^2 = {longest_edge_squared:e})"
            ),
            ElementError::Clockwise { signed_area } => write!(
                f,
                "clockwise triangle (signed area {signed_area:e}); corners must be counter-clockwise"
            ),
            ElementError::SingularJacobian => write!(f, "degenerate triangle (singular Jacobian)"),
            ElementError::FoldedSide {
                jacobian,
                area_coordinates,
                chord_jacobian,
            } => write!(
                f,
                "a curved side folds the facet over itself (reference Jacobian {jacobian:e} \
                 at area coordinates {area_coordinates:?}, chord triangle {chord_jacobian:e})"
            ),
        }
    }
}

impl std::error::Error for ElementError {}

impl ShellElement {
    /// Precomputes the element for the flat reference triangle `x` (crease
    /// pattern coordinates, counter-clockwise) with the default
    /// ([`Interpolation::Specht`]) shape functions.
    ///
    /// Fails ([`ElementError`] naming the reason) for a degenerate or
    /// clockwise triangle.
    pub fn new(x: [Vector2<f64>; 3], rule: Rule) -> Result<Self, ElementError> {
        Self::with_options(
            x,
            ElementOptions {
                rule,
                ..ElementOptions::default()
            },
        )
    }

    /// Like [`ShellElement::new`] with the given shape functions and the
    /// default bending energy.
    pub fn with_interpolation(
        x: [Vector2<f64>; 3],
        rule: Rule,
        interpolation: Interpolation,
    ) -> Result<Self, ElementError> {
        Self::with_options(
            x,
            ElementOptions {
                rule,
                interpolation,
                ..ElementOptions::default()
            },
        )
    }

    /// Like [`ShellElement::new`] with every option given.
    pub fn with_options(
        x: [Vector2<f64>; 3],
        options: ElementOptions,
    ) -> Result<Self, ElementError> {
        let chords = [
            x[1] - x[0],
            x[2] - x[0],
            x[2] - x[1],
            x[0] - x[1],
            x[0] - x[2],
            x[1] - x[2],
        ];
        Self::with_sides(x, chords, options)
    }

    /// A facet whose sides may be curved in the (flat) reference: corners
    /// `x` and the six side vectors in element order `[1->2, 1->3, 2->3,
    /// 2->1, 3->1, 3->2]`, each the reference tangent at its corner along
    /// the side (the chord on a straight side). The map from `u = (eta, zeta)`
    /// to the reference plane is then the element's own cubic, so the metric
    /// `J2`, the weights and the mass come from the quadrature points.
    ///
    /// The curvature needs no correction for the curved map: the extra terms
    /// of the second derivatives are tangent to the surface and drop out of
    /// `n_hat . r_,ij`; the reference curvature stays zero (a flat reference).
    pub fn with_sides(
        x: [Vector2<f64>; 3],
        sides: [Vector2<f64>; 6],
        options: ElementOptions,
    ) -> Result<Self, ElementError> {
        let ElementOptions {
            rule,
            interpolation,
            bending,
        } = options;
        let finite = |p: &Vector2<f64>| p.x.is_finite() && p.y.is_finite();
        if !x.iter().all(finite) || !sides.iter().all(finite) {
            return Err(ElementError::NonFinite(x));
        }
        let a1 = x[1] - x[0];
        let a2 = x[2] - x[0];
        let det = a1.perp(&a2); // 2 * signed area
        let scale = a1
            .norm_squared()
            .max(a2.norm_squared())
            .max((x[2] - x[1]).norm_squared());
        if !scale.is_finite() || !det.is_finite() || scale <= 0.0 || det.abs() <= 1e-12 * scale {
            return Err(ElementError::Degenerate {
                twice_area: det,
                longest_edge_squared: scale,
            });
        }
        if det < 0.0 {
            return Err(ElementError::Clockwise {
                signed_area: 0.5 * det,
            });
        }
        let e1 = a1 / a1.norm();
        let e2 = Vector2::new(-e1.y, e1.x);
        let to_frame = |v: Vector2<f64>| Vector2::new(e1.dot(&v), e2.dot(&v));
        let j2_of = |c1: Vector2<f64>, c2: Vector2<f64>| {
            let (c1, c2) = (to_frame(c1), to_frame(c2));
            Matrix2::new(c1.x, c2.x, c1.y, c2.y)
        };
        let j2_inv = j2_of(a1, a2)
            .try_inverse()
            .ok_or(ElementError::SingularJacobian)?;
        let shape = interpolation.shape(&x);
        // The reference element vector in the plane: corners and side vectors.
        let e0 = [
            x[0], sides[0], sides[1], x[1], sides[2], sides[3], x[2], sides[4], sides[5],
        ];
        let straight = (0..3).all(|i| {
            let chord = x[(i + 1) % 3] - x[i];
            let back = x[(i + 2) % 3] - x[i];
            (sides[2 * i] - chord).norm() <= 1e-14 * scale.sqrt()
                && (sides[2 * i + 1] - back).norm() <= 1e-14 * scale.sqrt()
        });
        let pts = rule.points();
        let mut qp = [QuadPoint::default(); MAX_QP];
        let mut area = 0.0;
        for (q, (l, w)) in qp.iter_mut().zip(pts) {
            let d1 = shape.d1(l[1], l[2]);
            let d2 = shape.d2(l[1], l[2]);
            let (jinv, det_q) = if straight {
                (j2_inv, det)
            } else {
                let (c1, c2) = reference_tangents(&e0, &d1);
                let d = c1.perp(&c2);
                if d.is_nan() || d <= 1e-6 * det {
                    return Err(ElementError::FoldedSide {
                        jacobian: d,
                        area_coordinates: *l,
                        chord_jacobian: det,
                    });
                }
                (
                    j2_of(c1, c2).try_inverse().expect("positive determinant"),
                    d,
                )
            };
            for k in 0..9 {
                // du_a/dx_i = (J2^-1)[a][i].
                let g = |i: usize| d1[k][0] * jinv[(0, i)] + d1[k][1] * jinv[(1, i)];
                q.n1[k] = g(0);
                q.n2[k] = g(1);
                let h = Matrix2::new(d2[k][0], d2[k][2], d2[k][2], d2[k][1]);
                let hx = jinv.transpose() * h * jinv;
                q.n11[k] = hx[(0, 0)];
                q.n22[k] = hx[(1, 1)];
                q.n12[k] = 0.5 * (hx[(0, 1)] + hx[(1, 0)]);
            }
            q.wa = 0.5 * w * det_q;
            area += q.wa;
        }
        let mass_hat = if straight {
            shape.mass_hat()
        } else {
            curved_mass_hat(&shape, &e0)
        };
        // The points in the facet frame (on the chord triangle for a
        // curved-sided facet: the fields need only be linear and independent).
        let split = (bending == Bending::Split).then(|| {
            let at: Vec<Vector2<f64>> = pts
                .iter()
                .map(|(l, _)| to_frame(x[0] * l[0] + x[1] * l[1] + x[2] * l[2]))
                .collect();
            let wa: Vec<f64> = qp[..pts.len()].iter().map(|q| q.wa).collect();
            Projection::new(&at, &wa)
        });
        Ok(ShellElement {
            area: if straight { 0.5 * det } else { area },
            frame: [e1, e2],
            j2_inv,
            rule,
            shape,
            mass_hat,
            split,
            nq: pts.len(),
            qp,
        })
    }

    /// How the element's bending energy is built.
    pub fn bending(&self) -> Bending {
        if self.split.is_some() {
            Bending::Split
        } else {
            Bending::Pointwise
        }
    }

    /// The element's shape functions.
    pub fn shape(&self) -> &Shape {
        &self.shape
    }

    /// `Mhat` of this triangle: its mass is `rho h area Mhat (x) I3`.
    pub fn mass_hat(&self) -> [[f64; 9]; 9] {
        self.mass_hat
    }

    /// Reference area.
    pub fn area(&self) -> f64 {
        self.area
    }

    /// The local Cartesian frame `[e1, e2]` in crease-pattern coordinates:
    /// `e1` along edge 1->2. Strains are expressed in it (the energy is
    /// frame-independent for the isotropic material).
    pub fn frame(&self) -> [Vector2<f64>; 2] {
        self.frame
    }

    /// `J2^-1`, with `J2[i][a] = e_i . dX/du_a` (MATH.md section 2).
    pub fn j2_inv(&self) -> Matrix2<f64> {
        self.j2_inv
    }

    /// The quadrature rule the element was built with.
    pub fn rule(&self) -> Rule {
        self.rule
    }

    /// Strain energy at element vector `e` (uses thickness, E and nu only).
    pub fn energy(&self, mat: &Material, e: &ElemVec) -> ShellEnergy {
        let pl = Plane::new(mat);
        let h = mat.thickness;
        let (hm, hb) = (0.5 * h, h * h * h / 24.0);
        let mut out = ShellEnergy::default();
        let Some(proj) = &self.split else {
            for q in &self.qp[..self.nq] {
                let kin = kinematics(q, e);
                out.membrane += q.wa * hm * dot3(kin.eps, pl.apply(1.0, kin.eps));
                out.bending += q.wa * hb * dot3(kin.kappa, pl.apply(1.0, kin.kappa));
            }
            return out;
        };
        let kins = self.kinematics_at(e);
        for (q, kin) in self.qp[..self.nq].iter().zip(&kins) {
            out.membrane += q.wa * hm * dot3(kin.eps, pl.apply(1.0, kin.eps));
        }
        let mut scratch = None;
        let f = proj.factors_for(pl.nu, &mut scratch);
        out.bending = hb * self.split_state(proj, f, &pl, &kins).energy;
        out
    }

    /// The kinematics at every quadrature point (unused entries default).
    #[inline(always)]
    fn kinematics_at(&self, e: &ElemVec) -> [Kinematics; MAX_QP] {
        let mut out = [Kinematics::default(); MAX_QP];
        for (o, q) in out.iter_mut().zip(&self.qp[..self.nq]) {
            *o = kinematics(q, e);
        }
        out
    }

    /// The split bending energy at the curvatures `kins` ([`super::bending`]).
    #[inline(always)]
    fn split_state(
        &self,
        proj: &Projection,
        f: &Factors,
        pl: &Plane,
        kins: &[Kinematics; MAX_QP],
    ) -> SplitState {
        let kappa: [[f64; 3]; MAX_QP] = std::array::from_fn(|q| kins[q].kappa);
        proj.state(f, &kappa[..self.nq], pl.c)
    }

    /// Keeps what the element's energy needs for `mat` that depends on the
    /// material only (the split bending energy's factors for its Poisson's
    /// ratio), so that evaluations with it need not recompute it. Results
    /// are the same with or without.
    pub fn prepare(&mut self, mat: &Material) {
        if let Some(p) = &mut self.split {
            p.prepare(mat.poisson_ratio);
        }
    }

    /// Energy, internal force f = dU/de (27, index 3*k + c for nodal vector k, component c) and,
    /// if asked, the full tangent d2U/de2 (27x27) INCLUDING geometric terms of membrane and bending.
    ///
    /// `force` and `tangent` are overwritten; the tangent is exactly symmetric.
    /// No allocation. The result is NaN if the deformed surface degenerates
    /// (`F_1 x F_2 = 0`) at a quadrature point.
    pub fn eval(
        &self,
        mat: &Material,
        e: &ElemVec,
        force: &mut SVector<f64, 27>,
        tangent: Option<&mut SMatrix<f64, 27, 27>>,
    ) -> ShellEnergy {
        self.eval_lagged(mat, e, force, tangent, None)
    }

    /// As [`ShellElement::eval`], with the tangent's membrane geometric
    /// stiffness (the membrane resultants times the second derivatives of
    /// the strains) taken from `membrane` (per quadrature point, as
    /// [`ShellElement::membrane_resultants`] gives them at another state)
    /// instead of from `e`. An iteration matrix, not the exact tangent: a
    /// Newton iterate that rotates a facet by a linear update stretches it
    /// by about the square of the angle, and the membrane force of that
    /// stretch, a million times the bending stiffness on thin sheets, would
    /// otherwise dominate the matrix's bending part; at a converged state
    /// the stretch is gone and the lagged resultants (the last converged
    /// state's) are close to the exact ones.
    pub fn eval_lagged(
        &self,
        mat: &Material,
        e: &ElemVec,
        force: &mut SVector<f64, 27>,
        tangent: Option<&mut SMatrix<f64, 27, 27>>,
        membrane: Option<&MembraneResultants>,
    ) -> ShellEnergy {
        match tangent {
            None => self.accumulate(mat, e, force, None, None),
            Some(kt) => {
                let mut blocks = [[ZERO3; 9]; 9];
                let out = self.accumulate(mat, e, force, Some(&mut blocks), membrane);
                // Write the upper blocks and their mirror images; the
                // diagonal blocks are symmetrised.
                for k in 0..9 {
                    for l in k..9 {
                        let b = &blocks[k][l];
                        for i in 0..3 {
                            for j in 0..3 {
                                let v = if k == l {
                                    0.5 * (b[i][j] + b[j][i])
                                } else {
                                    b[i][j]
                                };
                                kt[(3 * k + i, 3 * l + j)] = v;
                                kt[(3 * l + j, 3 * k + i)] = v;
                            }
                        }
                    }
                }
                out
            }
        }
    }

    /// The weighted membrane resultants `wa h C eps` at each quadrature
    /// point of the state `e` (unused points zero).
    pub fn membrane_resultants(&self, mat: &Material, e: &ElemVec) -> MembraneResultants {
        let pl = Plane::new(mat);
        let mut out = [[0.0; 3]; MAX_QP];
        for (o, q) in out.iter_mut().zip(&self.qp[..self.nq]) {
            let kin = kinematics(q, e);
            *o = pl.apply(q.wa * mat.thickness, kin.eps);
        }
        out
    }

    /// Energy and force, plus the upper tangent blocks `(k, l)`, `k <= l`, if asked.
    #[inline(always)]
    fn accumulate(
        &self,
        mat: &Material,
        e: &ElemVec,
        force: &mut SVector<f64, 27>,
        mut blocks: Option<&mut [[M3; 9]; 9]>,
        membrane: Option<&MembraneResultants>,
    ) -> ShellEnergy {
        let pl = Plane::new(mat);
        let h = mat.thickness;
        let (hm, hb) = (h, h * h * h / 12.0);
        force.fill(0.0);
        let mut out = ShellEnergy::default();
        let kins = self.kinematics_at(e);
        let mut scratch = None;
        let factors = self
            .split
            .as_ref()
            .map(|proj| proj.factors_for(pl.nu, &mut scratch));
        let split = self
            .split
            .as_ref()
            .zip(factors)
            .map(|(proj, f)| self.split_state(proj, f, &pl, &kins));
        // The split energy's gradients: of sum_q wa kappa_q (mean_grads[k][V])
        // and of b_m (cubic_grads[m][k]).
        let mut mean_grads = [[Vector3::zeros(); 3]; 9];
        let mut cubic_grads = [[Vector3::zeros(); 9]; N_CUBIC];
        for (iq, q) in self.qp[..self.nq].iter().enumerate() {
            let kin = &kins[iq];
            // Weighted stress resultants and moments (Voigt).
            let nm = pl.apply(q.wa * hm, kin.eps);
            let mb = match &split {
                None => pl.apply(q.wa * hb, kin.kappa),
                Some(sp) => {
                    let mut m = pl.apply(q.wa * hb, sp.mean);
                    let f = factors.expect("a split state has its factors");
                    for (y, w) in sp.y.iter().zip(&f.wc) {
                        for v in 0..3 {
                            m[v] += hb * pl.c * y * w[iq][v];
                        }
                    }
                    m
                }
            };
            out.membrane += 0.5 * dot3(kin.eps, nm);
            out.bending += 0.5 * dot3(kin.kappa, mb);

            // Bending force is the gradient of n_hat . v at fixed moments.
            let v = kin.rv[0] * mb[0] + kin.rv[1] * mb[1] + kin.rv[2] * mb[2];
            let s = kin.n_hat.dot(&v);
            let w = (v - kin.n_hat * s) / kin.n_len;
            let a = kin.f2.cross(&w);
            let c = w.cross(&kin.f1);
            let mut nt = [0.0; 9];
            for k in 0..9 {
                let (n1, n2) = (q.n1[k], q.n2[k]);
                nt[k] = mb[0] * q.n11[k] + mb[1] * q.n22[k] + 2.0 * mb[2] * q.n12[k];
                let fk = kin.f1 * (nm[0] * n1 + nm[2] * n2)
                    + kin.f2 * (nm[2] * n1 + nm[1] * n2)
                    + kin.n_hat * nt[k]
                    + a * n1
                    + c * n2;
                let mut seg = force.fixed_rows_mut::<3>(3 * k);
                seg += fk;
            }

            if let Some(bl) = blocks.as_deref_mut() {
                let stress = Stress {
                    nm: membrane.map_or(nm, |m| m[iq]),
                    nt: &nt,
                    w,
                    s,
                    a,
                    c,
                };
                let material = match &split {
                    None => Material3::Pointwise,
                    Some(_) => Material3::Split {
                        wc_phi: std::array::from_fn(|m| {
                            factors.expect("a split state has its factors").wc[m][iq]
                        }),
                        mean_grads: &mut mean_grads,
                        cubic_grads: &mut cubic_grads,
                    },
                };
                add_tangent_upper(bl, q, kin, &pl, h, &stress, material);
            }
        }
        if let (Some(bl), Some(f), Some(proj)) = (blocks, factors, &self.split) {
            // (h^3/12) (d(A kappa_mean)^T C d(A kappa_mean) / A + a db^T G^-1 db):
            // every block a sum of outer products, three and four; with db
            // over c, a db^T G^-1 db = c |l db|^2.
            let hb = h * h * h / 12.0;
            let s = hb / proj.area();
            let c_mean = mean_grads.map(|g| {
                [
                    (g[0] + g[1] * pl.nu) * (s * pl.c),
                    (g[0] * pl.nu + g[1]) * (s * pl.c),
                    g[2] * (s * pl.c * 0.5 * (1.0 - pl.nu)),
                ]
            });
            let gamma: [[Vector3<f64>; 9]; N_CUBIC] = std::array::from_fn(|t| {
                std::array::from_fn(|k| {
                    (0..N_CUBIC).fold(Vector3::zeros(), |a, m| a + cubic_grads[m][k] * f.l[t][m])
                })
            });
            for k in 0..9 {
                for l in k..9 {
                    let b = &mut bl[k][l];
                    for v in 0..3 {
                        add_outer(b, 1.0, &mean_grads[k][v], &c_mean[l][v]);
                    }
                    for g in &gamma {
                        add_outer(b, hb * pl.c, &g[k], &g[l]);
                    }
                }
            }
        }
        out
    }
}

/// A 3x3 block, row-major.
type M3 = [[f64; 3]; 3];
const ZERO3: M3 = [[0.0; 3]; 3];

#[inline(always)]
fn outer(a: &Vector3<f64>, b: &Vector3<f64>) -> M3 {
    [
        [a.x * b.x, a.x * b.y, a.x * b.z],
        [a.y * b.x, a.y * b.y, a.y * b.z],
        [a.z * b.x, a.z * b.y, a.z * b.z],
    ]
}

/// `y += s x`.
#[inline(always)]
fn axpy(y: &mut M3, s: f64, x: &M3) {
    for i in 0..3 {
        for j in 0..3 {
            y[i][j] += s * x[i][j];
        }
    }
}

/// `y += s a b^T`.
#[inline(always)]
fn add_outer(y: &mut M3, s: f64, a: &Vector3<f64>, b: &Vector3<f64>) {
    for i in 0..3 {
        for j in 0..3 {
            y[i][j] += s * a[i] * b[j];
        }
    }
}

#[inline(always)]
fn transpose(x: &M3) -> M3 {
    [
        [x[0][0], x[1][0], x[2][0]],
        [x[0][1], x[1][1], x[2][1]],
        [x[0][2], x[1][2], x[2][2]],
    ]
}

/// Per-point stress quantities shared by the force and the tangent.
struct Stress<'a> {
    /// Weighted membrane resultants `wa h C eps` (of the iterate, or lagged).
    nm: [f64; 3],
    /// `nt_k = sum_V m_V N_k,V`: the coefficient of `n_hat` in the bending force.
    nt: &'a [f64; 9],
    /// `w = (I - n_hat n_hat^T) v / |n|`, `v = sum_V m_V r_,V`.
    w: Vector3<f64>,
    /// `s = n_hat . v`.
    s: f64,
    /// `F_2 x w`.
    a: Vector3<f64>,
    /// `w x F_1`.
    c: Vector3<f64>,
}

/// How a point adds the bending energy's material tangent: its own
/// `(beta_k . D beta_l) n_hat n_hat^T`, or (split energy) by adding its
/// share of the measures' gradients (the blocks come after the points).
enum Material3<'a> {
    Pointwise,
    Split {
        /// `wa (CA + nu CB) phi_m` at the point.
        wc_phi: [[f64; 3]; N_CUBIC],
        mean_grads: &'a mut [[Vector3<f64>; 3]; 9],
        cubic_grads: &'a mut [[Vector3<f64>; 9]; N_CUBIC],
    },
}

/// Adds one quadrature point's tangent to the blocks `(k, l)`, `k <= l`.
///
/// Per node the derivatives enter through `N_k,1`, `N_k,2` and the Voigt
/// second derivatives `N_k,V`, so every block is a bilinear form in those
/// coefficients with 3x3 matrices fixed at the point. Material and geometric
/// parts of both energies are folded into them first:
/// `block(k,l) = N_k,1 Y1_l + N_k,2 Y2_l + nt_k Yv_l + (beta_k . D beta_l) n_hat n_hat^T`.
#[inline(always)]
fn add_tangent_upper(
    bl: &mut [[M3; 9]; 9],
    q: &QuadPoint,
    kin: &Kinematics,
    pl: &Plane,
    h: f64,
    st: &Stress,
    material: Material3,
) {
    let inv = 1.0 / kin.n_len;
    // d kappa_V / d e_k = beta_kV n_hat with beta_kV = N_k,V + N_k,1 p_V + N_k,2 q_V:
    // the in-plane parts F_2 x w_V and w_V x F_1 (w_V tangent) are normal.
    let t2 = kin.n_hat.cross(&kin.f2) * inv;
    let t1 = kin.f1.cross(&kin.n_hat) * inv;
    let pv = [t2.dot(&kin.rv[0]), t2.dot(&kin.rv[1]), t2.dot(&kin.rv[2])];
    let qv = [t1.dot(&kin.rv[0]), t1.dot(&kin.rv[1]), t1.dot(&kin.rv[2])];
    let sb = q.wa * h * h * h / 12.0;
    let x = point_matrices(q, kin, pl, h, st);
    let mut y1 = [ZERO3; 9];
    let mut y2 = [ZERO3; 9];
    let mut yv = [ZERO3; 9];
    let pointwise = matches!(material, Material3::Pointwise);
    let mut beta = [[0.0; 3]; 9];
    let mut dbeta = [[0.0; 3]; 9];
    for l in 0..9 {
        let (n1, n2, ntl) = (q.n1[l], q.n2[l], st.nt[l]);
        let nv = [q.n11[l], q.n22[l], 2.0 * q.n12[l]];
        beta[l] = [0, 1, 2].map(|v| nv[v] + n1 * pv[v] + n2 * qv[v]);
        if pointwise {
            dbeta[l] = pl.apply(sb, beta[l]);
        }
        let mut m = ZERO3;
        axpy(&mut m, n1, &x.x11);
        axpy(&mut m, n2, &x.x12);
        axpy(&mut m, ntl, &x.g1v);
        y1[l] = m;
        let mut m = ZERO3;
        axpy(&mut m, n1, &x.x21);
        axpy(&mut m, n2, &x.x22);
        axpy(&mut m, ntl, &x.g2v);
        y2[l] = m;
        let mut m = ZERO3;
        axpy(&mut m, n1, &x.gv1);
        axpy(&mut m, n2, &x.gv2);
        yv[l] = m;
    }
    if let Material3::Split {
        wc_phi,
        mean_grads,
        cubic_grads,
    } = material
    {
        for l in 0..9 {
            for v in 0..3 {
                mean_grads[l][v] += kin.n_hat * (q.wa * beta[l][v]);
            }
        }
        for (wp, g) in wc_phi.iter().zip(cubic_grads.iter_mut()) {
            for l in 0..9 {
                g[l] += kin.n_hat * dot3(*wp, beta[l]);
            }
        }
    }
    let nn = outer(&kin.n_hat, &kin.n_hat);
    for k in 0..9 {
        let (n1, n2, ntk) = (q.n1[k], q.n2[k], st.nt[k]);
        for l in k..9 {
            // Bending material part: (beta_k . D beta_l) n_hat n_hat^T.
            let d = if pointwise {
                dot3(beta[k], dbeta[l])
            } else {
                0.0
            };
            let b = &mut bl[k][l];
            for i in 0..3 {
                for j in 0..3 {
                    b[i][j] +=
                        n1 * y1[l][i][j] + n2 * y2[l][i][j] + ntk * yv[l][i][j] + d * nn[i][j];
                }
            }
        }
    }
}

/// The 3x3 matrices of one quadrature point's tangent blocks: the second
/// derivatives with respect to F_1, F_2 (`x11`, `x12`, `x21`, `x22`) and
/// the mixed F-v ones (`g1v`, `g2v` and their transposes).
struct PointMatrices {
    x11: M3,
    x12: M3,
    x21: M3,
    x22: M3,
    g1v: M3,
    g2v: M3,
    gv1: M3,
    gv2: M3,
}

/// [`PointMatrices`]: the Hessian of n_hat . v with respect to F_1, F_2
/// (closed forms of -[F2]x H_n [F2]x, [F2]x H_n [F1]x - [w]x,
/// -[F1]x H_n [F1]x) with the membrane's geometric and material parts.
#[inline(always)]
fn point_matrices(
    q: &QuadPoint,
    kin: &Kinematics,
    pl: &Plane,
    h: f64,
    st: &Stress,
) -> PointMatrices {
    let (f1, f2, nh) = (&kin.f1, &kin.f2, &kin.n_hat);
    let inv = 1.0 / kin.n_len;
    let nm = st.nm;
    let sm = q.wa * h;
    let cm = sm * pl.c;
    let cm_nu = cm * pl.nu;
    let cm_g = cm * 0.5 * (1.0 - pl.nu);
    let b1 = f1.cross(nh);
    let b2 = f2.cross(nh);
    let si = st.s * inv * inv;
    let (a, c, w) = (&st.a, &st.c, &st.w);
    let mut x11 = ZERO3;
    add_outer(&mut x11, -inv, a, &b2);
    add_outer(&mut x11, -inv, &b2, a);
    add_outer(&mut x11, si, f2, f2);
    add_outer(&mut x11, si, &b2, &b2);
    let d11 = nm[0] - si * f2.norm_squared();
    let mut x22 = ZERO3;
    add_outer(&mut x22, inv, c, &b1);
    add_outer(&mut x22, inv, &b1, c);
    add_outer(&mut x22, si, f1, f1);
    add_outer(&mut x22, si, &b1, &b1);
    let d22 = nm[1] - si * f1.norm_squared();
    let mut x12 = ZERO3;
    add_outer(&mut x12, inv, a, &b1);
    add_outer(&mut x12, -inv, &b2, c);
    add_outer(&mut x12, -si, f1, f2);
    add_outer(&mut x12, -si, &b2, &b1);
    let d12 = nm[2] + si * f1.dot(f2);
    // -[w]x
    x12[0][1] += w.z;
    x12[0][2] -= w.y;
    x12[1][0] -= w.z;
    x12[1][2] += w.x;
    x12[2][0] += w.y;
    x12[2][1] -= w.x;
    for i in 0..3 {
        x11[i][i] += d11;
        x22[i][i] += d22;
        x12[i][i] += d12;
    }
    // Membrane material part.
    add_outer(&mut x11, cm, f1, f1);
    add_outer(&mut x11, cm_g, f2, f2);
    add_outer(&mut x22, cm, f2, f2);
    add_outer(&mut x22, cm_g, f1, f1);
    add_outer(&mut x12, cm_nu, f1, f2);
    add_outer(&mut x12, cm_g, f2, f1);
    let x21 = transpose(&x12);
    // Mixed F-v slots: d/dv (d/dF) of n_hat . v, i.e. [F2]x P/|n| and -[F1]x P/|n|.
    let mut g1v = ZERO3;
    add_outer(&mut g1v, -inv, &b2, nh);
    g1v[0][1] -= f2.z * inv;
    g1v[0][2] += f2.y * inv;
    g1v[1][0] += f2.z * inv;
    g1v[1][2] -= f2.x * inv;
    g1v[2][0] -= f2.y * inv;
    g1v[2][1] += f2.x * inv;
    let mut g2v = ZERO3;
    add_outer(&mut g2v, inv, &b1, nh);
    g2v[0][1] += f1.z * inv;
    g2v[0][2] -= f1.y * inv;
    g2v[1][0] -= f1.z * inv;
    g2v[1][2] += f1.x * inv;
    g2v[2][0] += f1.y * inv;
    g2v[2][1] -= f1.x * inv;
    let gv1 = transpose(&g1v);
    let gv2 = transpose(&g2v);
    PointMatrices {
        x11,
        x12,
        x21,
        x22,
        g1v,
        g2v,
        gv1,
        gv2,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::reference_vector;
    use nalgebra::{Matrix3x2, Rotation3, Unit};
    use std::f64::consts::PI;

    /// SplitMix64: a small deterministic generator for the tests.
    struct Rng(u64);
    impl Rng {
        fn next_u64(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^ (z >> 31)
        }
        /// Uniform in [-1, 1).
        fn sym(&mut self) -> f64 {
            (self.next_u64() >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        }
        fn vec3(&mut self) -> Vector3<f64> {
            Vector3::new(self.sym(), self.sym(), self.sym())
        }
        fn rotation(&mut self) -> Rotation3<f64> {
            let axis = loop {
                let v = self.vec3();
                if v.norm() > 0.1 {
                    break v;
                }
            };
            Rotation3::from_axis_angle(&Unit::new_normalize(axis), PI * (1.0 + self.sym()))
        }
    }

    fn v2(x: f64, y: f64) -> Vector2<f64> {
        Vector2::new(x, y)
    }

    /// Right, equilateral and general counter-clockwise triangles.
    fn triangles() -> [[Vector2<f64>; 3]; 3] {
        [
            [v2(0.0, 0.0), v2(1.0, 0.0), v2(0.0, 1.0)],
            [v2(0.0, 0.0), v2(1.0, 0.0), v2(0.5, 0.75f64.sqrt())],
            [v2(0.1, -0.2), v2(1.3, 0.25), v2(0.4, 1.1)],
        ]
    }

    /// The element on `x` with both bending energies (pointwise, split).
    fn both(x: [Vector2<f64>; 3], rule: Rule) -> [ShellElement; 2] {
        [Bending::Pointwise, Bending::Split].map(|bending| {
            let options = ElementOptions {
                rule,
                bending,
                ..ElementOptions::default()
            };
            ShellElement::with_options(x, options).unwrap()
        })
    }

    fn material(h: f64) -> Material {
        Material {
            youngs_modulus: 2.5,
            poisson_ratio: 0.3,
            thickness: h,
            density: 1.0,
        }
    }

    /// Plane-stress `C` (Voigt) for the test material E = 2.5, nu = 0.3.
    fn c_matrix() -> Matrix3<f64> {
        let (e, nu) = (2.5, 0.3);
        Matrix3::new(1.0, nu, 0.0, nu, 1.0, 0.0, 0.0, 0.0, 0.5 * (1.0 - nu)) * (e / (1.0 - nu * nu))
    }

    /// Nodal vector of a field `r(X)` with Jacobian `J(X)` (3x2): positions
    /// `r(X_i)` and gradient DOFs `J(X_i) (X_j - X_i)`.
    fn from_field<F>(x: &[Vector2<f64>; 3], f: F) -> ElemVec
    where
        F: Fn(Vector2<f64>) -> (Vector3<f64>, Matrix3x2<f64>),
    {
        let mut e = [Vector3::zeros(); 9];
        for p in 0..3 {
            let (r, j) = f(x[p]);
            e[3 * p] = r;
            for (m, t) in [(p + 1) % 3, (p + 2) % 3].into_iter().enumerate() {
                e[3 * p + 1 + m] = j * (x[t] - x[p]);
            }
        }
        e
    }

    fn rigid(e: &ElemVec, rot: &Rotation3<f64>, t: Vector3<f64>) -> ElemVec {
        let mut out = [Vector3::zeros(); 9];
        for k in 0..9 {
            out[k] = rot * e[k] + if k % 3 == 0 { t } else { Vector3::zeros() };
        }
        out
    }

    fn total(el: &ShellElement, mat: &Material, e: &ElemVec) -> f64 {
        el.energy(mat, e).total()
    }

    fn force(el: &ShellElement, mat: &Material, e: &ElemVec) -> SVector<f64, 27> {
        let mut f = SVector::zeros();
        el.eval(mat, e, &mut f, None);
        f
    }

    fn perturbed(e: &ElemVec, i: usize, d: f64) -> ElemVec {
        let mut p = *e;
        p[i / 3][i % 3] += d;
        p
    }

    /// A large random deformation: rotation, ~10 % stretch, curvature ~1/L,
    /// then twisted (independently perturbed) gradient DOFs.
    fn random_deformation(x: &[Vector2<f64>; 3], rng: &mut Rng) -> ElemVec {
        let s = Matrix3x2::new(
            1.0 + 0.1 * rng.sym(),
            0.1 * rng.sym(),
            0.1 * rng.sym(),
            1.0 + 0.1 * rng.sym(),
            0.1 * rng.sym(),
            0.1 * rng.sym(),
        );
        let k = [rng.sym(), rng.sym(), rng.sym()];
        let q = [0.1 * rng.sym(), 0.1 * rng.sym()];
        let field = |p: Vector2<f64>| {
            let (x, y) = (p.x, p.y);
            let w = 0.5 * (k[0] * x * x + 2.0 * k[1] * x * y + k[2] * y * y);
            let r = s * p + Vector3::new(q[0] * x * y, q[1] * x * x, w);
            let j = s + Matrix3x2::new(
                q[0] * y,
                q[0] * x,
                2.0 * q[1] * x,
                0.0,
                k[0] * x + k[1] * y,
                k[1] * x + k[2] * y,
            );
            (r, j)
        };
        let mut e = from_field(x, field);
        for k in 0..9 {
            e[k] += rng.vec3() * if k % 3 == 0 { 0.02 } else { 0.08 };
        }
        let rot = rng.rotation();
        rigid(&e, &rot, rng.vec3())
    }

    #[test]
    fn new_rejects_bad_triangles() {
        let bad = [
            ([v2(0.0, 0.0), v2(1.0, 0.0), v2(2.0, 0.0)], "degenerate"),
            ([v2(0.0, 0.0), v2(1.0, 1.0), v2(1.0, 1.0)], "degenerate"),
            ([v2(0.0, 0.0), v2(0.0, 0.0), v2(0.0, 0.0)], "degenerate"),
            ([v2(0.0, 0.0), v2(0.0, 1.0), v2(1.0, 0.0)], "clockwise"),
            (
                [v2(0.0, 0.0), v2(f64::NAN, 1.0), v2(1.0, 0.0)],
                "non-finite",
            ),
        ];
        for rule in [Rule::Dunavant7, Rule::Dunavant12] {
            for (x, why) in bad {
                match ShellElement::new(x, rule) {
                    Err(e) => {
                        let msg = e.to_string();
                        assert!(msg.contains(why), "{msg}")
                    }
                    Ok(_) => panic!("accepted {x:?}"),
                }
            }
        }
        let el = ShellElement::new(triangles()[2], Rule::default()).unwrap();
        assert!((el.area() - 0.5 * (1.2 * 1.3 - 0.45 * 0.3)).abs() < 1e-15);
        assert_eq!(el.rule(), Rule::Dunavant7);
    }

    #[test]
    fn stiffness_rank_at_reference_is_21() {
        let mat = material(0.1);
        for rule in [Rule::Dunavant7, Rule::Dunavant12] {
            for x in triangles() {
                for el in both(x, rule) {
                    let e0 = reference_vector(&x);
                    let mut f = SVector::zeros();
                    let mut k = SMatrix::<f64, 27, 27>::zeros();
                    let en = el.eval(&mat, &e0, &mut f, Some(&mut k));
                    assert!(en.total().abs() < 1e-30 && f.amax() < 1e-15);
                    assert_eq!(k, k.transpose());
                    let ev = k.symmetric_eigenvalues();
                    let max = ev.amax();
                    let rank = ev.iter().filter(|v| v.abs() > 1e-8 * max).count();
                    assert_eq!(rank, 21, "{rule:?} {x:?}: {ev}");
                    // A clear gap: zero modes at round-off, the rest well away.
                    let mut a: Vec<f64> = ev.iter().map(|v| v.abs() / max).collect();
                    a.sort_by(f64::total_cmp);
                    assert!(a[5] < 1e-13 && a[6] > 1e-6, "{a:?}");
                }
            }
        }
    }

    /// Splits a quantity evaluated at thickness 1 and 2 into its membrane
    /// (linear in h) and bending (cubic in h) parts at h = 1.
    fn split<T>(q1: T, q2: T) -> (T, T)
    where
        T: std::ops::Sub<Output = T> + std::ops::Mul<f64, Output = T> + Copy,
    {
        let bending = (q2 - q1 * 2.0) * (1.0 / 6.0);
        (q1 - bending, bending)
    }

    #[test]
    fn force_and_tangent_match_finite_differences() {
        // Membrane energy scales with h and bending with h^3, so evaluating at
        // h = 1 and h = 2 separates the two and each is checked on its own.
        let (m1, m2) = (material(1.0), material(2.0));
        let mut rng = Rng(0x5eed);
        for rule in [Rule::Dunavant12, Rule::Dunavant7] {
            for (i, x) in triangles().into_iter().enumerate() {
                let n = if i == 2 { 5 } else { 1 };
                for trial in 0..n {
                    let e = random_deformation(&x, &mut rng);
                    for el in both(x, rule) {
                        let mut f1 = SVector::zeros();
                        let mut f2 = SVector::zeros();
                        let mut k1 = SMatrix::<f64, 27, 27>::zeros();
                        let mut k2 = SMatrix::<f64, 27, 27>::zeros();
                        let en = el.eval(&m1, &e, &mut f1, Some(&mut k1));
                        el.eval(&m2, &e, &mut f2, Some(&mut k2));
                        let (fm, fb) = split(f1, f2);
                        let (km, kb) = split(k1, k2);
                        assert_eq!(k1, k1.transpose());

                        let en2 = el.energy(&m1, &e);
                        assert!((en.membrane - en2.membrane).abs() <= 1e-14 * en2.membrane);
                        assert!((en.bending - en2.bending).abs() <= 1e-14 * en2.bending);
                        assert!(en.membrane > 0.0 && en.bending > 0.0);
                        let mut f_no_k = SVector::zeros();
                        el.eval(&m1, &e, &mut f_no_k, None);
                        assert_eq!(f1, f_no_k);

                        let d = 1e-6;
                        let mut fm_fd = SVector::<f64, 27>::zeros();
                        let mut fb_fd = SVector::<f64, 27>::zeros();
                        let mut km_fd = SMatrix::<f64, 27, 27>::zeros();
                        let mut kb_fd = SMatrix::<f64, 27, 27>::zeros();
                        for j in 0..27 {
                            let (ep, em) = (perturbed(&e, j, d), perturbed(&e, j, -d));
                            let (up, um) = (el.energy(&m1, &ep), el.energy(&m1, &em));
                            fm_fd[j] = (up.membrane - um.membrane) / (2.0 * d);
                            fb_fd[j] = (up.bending - um.bending) / (2.0 * d);
                            let (fpm, fpb) = split(force(&el, &m1, &ep), force(&el, &m2, &ep));
                            let (fmm, fmb) = split(force(&el, &m1, &em), force(&el, &m2, &em));
                            km_fd.set_column(j, &((fpm - fmm) / (2.0 * d)));
                            kb_fd.set_column(j, &((fpb - fmb) / (2.0 * d)));
                        }
                        let errs = [
                            ("membrane force", (fm_fd - fm).norm() / fm.norm()),
                            ("bending force", (fb_fd - fb).norm() / fb.norm()),
                            ("membrane tangent", (km_fd - km).norm() / km.norm()),
                            ("bending tangent", (kb_fd - kb).norm() / kb.norm()),
                        ];
                        for (what, err) in errs {
                            assert!(
                                err < 1e-6,
                                "{rule:?} {:?} tri {i} trial {trial}: {what} error {err:e}",
                                el.bending()
                            );
                        }
                    }
                }
            }
        }
    }

    /// A facet with one curved side (1-2 bulging out, its end tangents
    /// turned by 0.25 rad): the reference state is strain-free, rigid motions
    /// cost nothing, force and tangent match finite differences of energy and
    /// force, its area and mass are the quadrature's (mass SPD, unit
    /// translation energy rho h area / 2).
    /// The lagged iteration matrix: with the state's own membrane
    /// resultants it is the exact tangent; with other resultants the force
    /// is unchanged and the tangent differs by the membrane geometric
    /// stiffness only, whose 3x3 blocks are multiples of the identity
    /// (sum_q N_k,a N_l,b (n_ab - n'_ab) I) and linear in the resultants.
    #[test]
    fn lagged_membrane_stiffness_changes_only_the_geometric_part() {
        let mat = material(0.05);
        let mut rng = Rng(0x1a99);
        for rule in [Rule::Dunavant12, Rule::Dunavant7] {
            let x = triangles()[2];
            for el in both(x, rule) {
                let e = random_deformation(&x, &mut rng);
                let other = random_deformation(&x, &mut rng);
                let own = el.membrane_resultants(&mat, &e);
                let lag = el.membrane_resultants(&mat, &other);
                let (mut f0, mut f1, mut f2) =
                    (SVector::zeros(), SVector::zeros(), SVector::zeros());
                let mut k0 = SMatrix::<f64, 27, 27>::zeros();
                let mut k1 = k0;
                let mut k2 = k0;
                el.eval(&mat, &e, &mut f0, Some(&mut k0));
                el.eval_lagged(&mat, &e, &mut f1, Some(&mut k1), Some(&own));
                assert_eq!(f0, f1);
                assert_eq!(k0, k1, "{rule:?}: own resultants give the exact tangent");
                el.eval_lagged(&mat, &e, &mut f2, Some(&mut k2), Some(&lag));
                assert_eq!(f0, f2, "the force is the state's own");
                let diff = k2 - k0;
                assert!(
                    diff.norm() > 1e-6 * k0.norm(),
                    "{rule:?}: resultants differ"
                );
                for k in 0..9 {
                    for l in 0..9 {
                        let b = diff.fixed_view::<3, 3>(3 * k, 3 * l);
                        let c = b[(0, 0)];
                        let tol = 1e-12 * k0.norm();
                        for i in 0..3 {
                            for j in 0..3 {
                                let want = if i == j { c } else { 0.0 };
                                assert!((b[(i, j)] - want).abs() < tol, "{rule:?} block ({k},{l})");
                            }
                        }
                    }
                }
                // Linear in the resultants: halfway resultants, halfway matrix.
                let mid: MembraneResultants =
                    std::array::from_fn(|q| std::array::from_fn(|v| 0.5 * (own[q][v] + lag[q][v])));
                let mut km = k0;
                el.eval_lagged(&mat, &e, &mut f2, Some(&mut km), Some(&mid));
                assert!((km - (k0 + k2) * 0.5).norm() < 1e-12 * k0.norm());
            }
        }
    }

    /// Keeping the split energy's factors for the material changes no bit of
    /// the results; kept for another Poisson's ratio, they are not used.
    #[test]
    fn prepared_elements_give_the_same_results() {
        let mut rng = Rng(0xbeef);
        let x = triangles()[2];
        let e = random_deformation(&x, &mut rng);
        let (mat, other) = (
            material(0.1),
            Material {
                poisson_ratio: 0.1,
                ..material(0.1)
            },
        );
        for el in both(x, Rule::default()) {
            let run = |el: &ShellElement| {
                let mut f = SVector::zeros();
                let mut k = SMatrix::<f64, 27, 27>::zeros();
                let en = el.eval(&mat, &e, &mut f, Some(&mut k));
                (en, f, k, el.energy(&mat, &e))
            };
            let plain = run(&el);
            let mut kept = el;
            kept.prepare(&mat);
            assert_eq!(run(&kept), plain, "{:?}", el.bending());
            kept.prepare(&other);
            assert_eq!(run(&kept), plain, "{:?}", el.bending());
        }
    }

    #[test]
    fn curved_sided_facet() {
        let (m1, m2) = (material(1.0), material(2.0));
        let x = triangles()[2];
        let rot2 = |v: Vector2<f64>, a: f64| {
            Vector2::new(a.cos() * v.x - a.sin() * v.y, a.sin() * v.x + a.cos() * v.y)
        };
        let c12 = x[1] - x[0];
        let sides = [
            rot2(c12, -0.25) * 1.02,
            x[2] - x[0],
            x[2] - x[1],
            rot2(-c12, 0.25) * 1.02,
            x[0] - x[2],
            x[1] - x[2],
        ];
        for bending in [Bending::Pointwise, Bending::Split] {
            let options = |bending| ElementOptions {
                bending,
                ..ElementOptions::default()
            };
            let el = ShellElement::with_sides(x, sides, options(bending)).unwrap();
            let straight = ShellElement::new(x, Rule::default()).unwrap();
            assert!(el.area() > straight.area(), "the side bulges out");
            let v3 = |v: Vector2<f64>| Vector3::new(v.x, v.y, 0.0);
            let e0: ElemVec = [
                v3(x[0]),
                v3(sides[0]),
                v3(sides[1]),
                v3(x[1]),
                v3(sides[2]),
                v3(sides[3]),
                v3(x[2]),
                v3(sides[4]),
                v3(sides[5]),
            ];
            let mut rng = Rng(0xc0ffee);
            // A deformation: the reference vector under a smooth map plus noise.
            let mut e = rigid(&e0, &rng.rotation(), rng.vec3());
            for v in e.iter_mut() {
                *v += 0.05 * rng.vec3();
            }
            let unit = total(&el, &m1, &e);
            assert!(unit > 0.0);
            assert!(total(&el, &m1, &e0) < 1e-28, "reference strain energy");
            let moved = rigid(&e0, &rng.rotation(), rng.vec3());
            assert!(total(&el, &m1, &moved) < 1e-12 * unit);
            assert!(force(&el, &m1, &moved).norm() < 1e-10 * force(&el, &m1, &e).norm());
            let (mut f1, mut f2) = (SVector::zeros(), SVector::zeros());
            let (mut k1, mut k2) = (
                SMatrix::<f64, 27, 27>::zeros(),
                SMatrix::<f64, 27, 27>::zeros(),
            );
            el.eval(&m1, &e, &mut f1, Some(&mut k1));
            el.eval(&m2, &e, &mut f2, Some(&mut k2));
            let (fm, fb) = split(f1, f2);
            let (km, kb) = split(k1, k2);
            let d = 1e-6;
            let mut f_fd = [SVector::<f64, 27>::zeros(); 2];
            let mut k_fd = [SMatrix::<f64, 27, 27>::zeros(); 2];
            for j in 0..27 {
                let (ep, em) = (perturbed(&e, j, d), perturbed(&e, j, -d));
                let (up, um) = (el.energy(&m1, &ep), el.energy(&m1, &em));
                f_fd[0][j] = (up.membrane - um.membrane) / (2.0 * d);
                f_fd[1][j] = (up.bending - um.bending) / (2.0 * d);
                let (fpm, fpb) = split(force(&el, &m1, &ep), force(&el, &m2, &ep));
                let (fmm, fmb) = split(force(&el, &m1, &em), force(&el, &m2, &em));
                k_fd[0].set_column(j, &((fpm - fmm) / (2.0 * d)));
                k_fd[1].set_column(j, &((fpb - fmb) / (2.0 * d)));
            }
            for (what, err) in [
                ("membrane force", (f_fd[0] - fm).norm() / fm.norm()),
                ("bending force", (f_fd[1] - fb).norm() / fb.norm()),
                ("membrane tangent", (k_fd[0] - km).norm() / km.norm()),
                ("bending tangent", (k_fd[1] - kb).norm() / kb.norm()),
            ] {
                assert!(err < 1e-6, "{what} error {err:e}");
            }
            let mh = el.mass_hat();
            let m = SMatrix::<f64, 9, 9>::from_fn(|i, j| mh[i][j]);
            assert!((m - m.transpose()).amax() < 1e-15);
            assert!(m.symmetric_eigenvalues().min() > 0.0);
            let trans: f64 = [0, 3, 6]
                .iter()
                .flat_map(|&i| [0, 3, 6].map(|j| mh[i][j]))
                .sum();
            assert!((trans - 1.0).abs() < 1e-12, "{trans}");
        }
    }

    /// `B^T D B` alone, with B from finite differences of the strains: used to
    /// show that the geometric terms are far from negligible in the tests.
    fn material_part(el: &ShellElement, mat: &Material, e: &ElemVec) -> SMatrix<f64, 27, 27> {
        assert_eq!((mat.youngs_modulus, mat.poisson_ratio), (2.5, 0.3));
        let h = mat.thickness;
        let mut k = SMatrix::<f64, 27, 27>::zeros();
        for q in &el.qp[..el.nq] {
            let mut bm = SMatrix::<f64, 3, 27>::zeros();
            let mut bb = SMatrix::<f64, 3, 27>::zeros();
            let d = 1e-7;
            for j in 0..27 {
                let kp = kinematics(q, &perturbed(e, j, d));
                let km = kinematics(q, &perturbed(e, j, -d));
                for v in 0..3 {
                    bm[(v, j)] = (kp.eps[v] - km.eps[v]) / (2.0 * d);
                    bb[(v, j)] = (kp.kappa[v] - km.kappa[v]) / (2.0 * d);
                }
            }
            let c = c_matrix();
            k += bm.transpose() * c * bm * (q.wa * h)
                + bb.transpose() * c * bb * (q.wa * h * h * h / 12.0);
        }
        k
    }

    /// The kernel is the same for both interpolations; the shares were
    /// measured on this state with BCIZ functions (Specht's: 5.6e-2 and 4.5e-2).
    #[test]
    fn geometric_terms_are_significant() {
        let (m1, m2) = (material(1.0), material(2.0));
        let x = triangles()[2];
        let el = ShellElement::with_interpolation(x, Rule::default(), Interpolation::Bciz).unwrap();
        let mut rng = Rng(99);
        let e = random_deformation(&x, &mut rng);
        let mut f = SVector::zeros();
        let mut k1 = SMatrix::<f64, 27, 27>::zeros();
        let mut k2 = SMatrix::<f64, 27, 27>::zeros();
        el.eval(&m1, &e, &mut f, Some(&mut k1));
        el.eval(&m2, &e, &mut f, Some(&mut k2));
        let (km, kb) = split(k1, k2);
        let (kmm, kbm) = split(material_part(&el, &m1, &e), material_part(&el, &m2, &e));
        let gm = (km - kmm).norm() / km.norm();
        let gb = (kb - kbm).norm() / kb.norm();
        assert!(
            gm > 1e-2 && gb > 1e-1,
            "geometric share: membrane {gm:e}, bending {gb:e}"
        );
        // At the reference the tangent is purely material.
        let e0 = reference_vector(&x);
        let mut k0 = SMatrix::<f64, 27, 27>::zeros();
        el.eval(&m1, &e0, &mut f, Some(&mut k0));
        let k0m = material_part(&el, &m1, &e0);
        assert!((k0 - k0m).norm() < 1e-7 * k0.norm());
    }

    #[test]
    fn rigid_motions_give_zero_energy_and_force() {
        let mat = material(0.1);
        for x in triangles() {
            for el in both(x, Rule::default()) {
                let e0 = reference_vector(&x);
                // Unit deformation: strain ~1 and curvature ~1/L.
                let unit = from_field(&x, |p| {
                    let r = Vector3::new(2.0 * p.x, p.y, 0.5 * (p.x * p.x + p.y * p.y));
                    let j = Matrix3x2::new(2.0, 0.0, 0.0, 1.0, p.x, p.y);
                    (r, j)
                });
                let u_unit = total(&el, &mat, &unit);
                let f_unit = force(&el, &mat, &unit).norm();
                let axes = [
                    Vector3::x(),
                    Vector3::y(),
                    Vector3::z(),
                    Vector3::new(1.0, 2.0, -0.5),
                    Vector3::new(-0.3, 0.1, 0.9),
                ];
                for axis in axes {
                    for angle in [0.0, 0.3, 1.7, PI, 4.5, 2.0 * PI - 0.1, 2.0 * PI] {
                        let rot = Rotation3::from_axis_angle(&Unit::new_normalize(axis), angle);
                        let e = rigid(&e0, &rot, Vector3::new(3.0, -1.5, 0.7));
                        let u = total(&el, &mat, &e);
                        let f = force(&el, &mat, &e).norm();
                        assert!(u < 1e-12 * u_unit, "axis {axis} angle {angle}: {u:e}");
                        assert!(f < 1e-12 * f_unit, "axis {axis} angle {angle}: {f:e}");
                    }
                }
            }
        }
    }

    #[test]
    fn constant_curvature_and_twist_patch_test() {
        let h = 1.0;
        let mat = material(h);
        let c = c_matrix();
        let mut rng = Rng(42);
        let curvatures = [
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0], // pure twist
            [1.0, 0.0, -1.0],
            [0.7, -0.4, 0.25],
        ];
        for rule in [Rule::Dunavant7, Rule::Dunavant12] {
            for x in triangles() {
                for el in both(x, rule) {
                    for kk in curvatures {
                        let [k11, k22, k12] = kk.map(|v| 1e-4 * v);
                        let e = from_field(&x, |p| {
                            let w =
                                0.5 * (k11 * p.x * p.x + 2.0 * k12 * p.x * p.y + k22 * p.y * p.y);
                            let r = Vector3::new(p.x, p.y, w);
                            let j = Matrix3x2::new(
                                1.0,
                                0.0,
                                0.0,
                                1.0,
                                k11 * p.x + k12 * p.y,
                                k12 * p.x + k22 * p.y,
                            );
                            (r, j)
                        });
                        let kv = Vector3::new(k11, k22, 2.0 * k12);
                        let want = el.area() * h * h * h / 24.0 * kv.dot(&(c * kv));
                        for e in [e, rigid(&e, &rng.rotation(), rng.vec3())] {
                            let en = el.energy(&mat, &e);
                            let rel = (en.bending - want).abs() / want;
                            assert!(
                                rel < 1e-6,
                                "{rule:?} {x:?} k {kk:?}: {} vs {want} ({rel:e})",
                                en.bending
                            );
                            assert!(en.membrane < 1e-6 * want, "membrane {}", en.membrane);
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn constant_membrane_strain_patch_test() {
        let h = 0.2;
        let mat = material(h);
        let c = c_matrix();
        let mut rng = Rng(3);
        for rule in [Rule::Dunavant7, Rule::Dunavant12] {
            for x in triangles() {
                for el in both(x, rule) {
                    for _ in 0..4 {
                        let a = Matrix3x2::new(
                            1.0 + 0.1 * rng.sym(),
                            0.1 * rng.sym(),
                            0.1 * rng.sym(),
                            1.0 + 0.1 * rng.sym(),
                            0.0,
                            0.0,
                        );
                        let rot = rng.rotation();
                        let a = rot.matrix() * a;
                        let t = rng.vec3();
                        let e = from_field(&x, |p| (a * p + t, a));
                        let g = (a.transpose() * a - nalgebra::Matrix2::identity()) * 0.5;
                        let eps = Vector3::new(g[(0, 0)], g[(1, 1)], 2.0 * g[(0, 1)]);
                        let want = el.area() * h / 2.0 * eps.dot(&(c * eps));
                        let en = el.energy(&mat, &e);
                        assert!(
                            (en.membrane - want).abs() < 1e-12 * want,
                            "{} vs {want}",
                            en.membrane
                        );
                        assert!(en.bending < 1e-12 * want, "bending {}", en.bending);
                    }
                }
            }
        }
    }

    #[test]
    #[ignore = "timing; run with --release --ignored --nocapture"]
    fn eval_timing() {
        let x = triangles()[2];
        let mat = material(0.1);
        let mut rng = Rng(1);
        let e = random_deformation(&x, &mut rng);
        for rule in [Rule::Dunavant12, Rule::Dunavant7] {
            let el = ShellElement::new(x, rule).unwrap();
            let mut f = SVector::zeros();
            let mut k = SMatrix::<f64, 27, 27>::zeros();
            let n = 20_000;
            let mut acc = 0.0;
            // Best of several runs: the machine is shared.
            let (mut with_k, mut without) = (f64::INFINITY, f64::INFINITY);
            for _ in 0..7 {
                let t0 = std::time::Instant::now();
                for _ in 0..n {
                    let ee = std::hint::black_box(&e);
                    acc += el.eval(&mat, ee, &mut f, Some(&mut k)).total();
                    std::hint::black_box(&k);
                }
                with_k = with_k.min(t0.elapsed().as_nanos() as f64 / n as f64);
                let t0 = std::time::Instant::now();
                for _ in 0..n {
                    acc += el
                        .eval(&mat, std::hint::black_box(&e), &mut f, None)
                        .total();
                }
                without = without.min(t0.elapsed().as_nanos() as f64 / n as f64);
            }
            println!(
                "{rule:?}: eval with tangent {with_k:.0} ns, force only {without:.0} ns ({acc:e})"
            );
        }
    }
}
