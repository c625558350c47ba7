//! The cubic triangular iso-ANCF shell element (MATH.md sections 1-3).
//!
//! Each facet is a reduced-cubic (BCIZ) triangle whose 27 DOFs are nine
//! nodal vectors: at every corner the position and the two position
//! gradients along the sides meeting there. Its strain energy is Kirchhoff-Love
//! with Green-Lagrange membrane strain and the exact normal-projected
//! curvature change against a flat reference, so it is valid for large
//! rotations and displacements; the mass matrix is constant.
//!
//! - [`shape`]: the nine shape functions and their derivatives,
//! - [`quadrature`]: Dunavant rules ([`Rule`]),
//! - [`shell`]: [`ShellElement`], energy, internal force and exact tangent,
//! - [`bending`]: the split bending energy ([`Bending::Split`]),
//! - [`mass`]: the closed-form mass matrix [`MASS_HAT`].
// Numerical kernels index several parallel per-node arrays with one loop index.
#![allow(clippy::needless_range_loop)]

pub mod bending;
pub mod mass;
pub mod quadrature;
pub mod shape;
pub mod shell;

use nalgebra::{Vector2, Vector3};

/// Local element vector: 9 nodal vectors in MATH.md order
/// `[r1, r1_eta, r1_zeta, r2, r2_zeta, r2_xi, r3, r3_xi, r3_eta]`.
pub type ElemVec = [Vector3<f64>; 9];

pub use mass::{MASS_HAT, element_mass};
pub use quadrature::Rule;
pub use shape::{Interpolation, Shape};

/// How every facet is discretized: quadrature rule, shape functions and
/// bending energy.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct ElementOptions {
    /// Quadrature of the strain energy.
    pub rule: Rule,
    /// Shape functions (Specht by default).
    pub interpolation: Interpolation,
    /// How the curvature enters the bending energy.
    pub bending: Bending,
}

impl From<Interpolation> for ElementOptions {
    /// The displacement element of these shape functions (pointwise
    /// bending energy) with the default rule: what the benchmarks compare.
    fn from(interpolation: Interpolation) -> Self {
        ElementOptions {
            rule: Rule::default(),
            interpolation,
            bending: Bending::Pointwise,
        }
    }
}

/// How the bending energy is built from the curvature at the quadrature
/// points (the membrane energy is the same for both).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Bending {
    /// `(h^3/24) kappa^T C kappa` at every point: the displacement element.
    #[default]
    Pointwise,
    /// The facet's mean curvature carries its full energy; the curvature's
    /// variation about it counts through its projection on the curvatures of
    /// cubic deflections, with the weight [`bending::HIGHER_ORDER_WEIGHT`]
    /// ([`bending`]).
    Split,
}
pub use shell::{ElementError, MembraneResultants, ShellElement, ShellEnergy};

/// The element vector `e0` of a flat straight-edged reference triangle in the
/// plane `z = 0`: positions `X_i` and, at node `i`, the gradient DOF towards
/// node `j` equal to `X_j - X_i`.
pub fn reference_vector(x: &[Vector2<f64>; 3]) -> ElemVec {
    let p = x.map(|v| Vector3::new(v.x, v.y, 0.0));
    [
        p[0],
        p[1] - p[0],
        p[2] - p[0],
        p[1],
        p[2] - p[1],
        p[0] - p[1],
        p[2],
        p[0] - p[2],
        p[1] - p[2],
    ]
}
