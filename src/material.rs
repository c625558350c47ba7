//! Sheet material: the data the shell element needs from a scene, kept
//! below the element layer so that the element and the assembly do not
//! depend on [`crate::scene`] (which re-exports it as `scene::Material`).

use serde::{Deserialize, Serialize};

/// Sheet material, SI units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Young's modulus E in Pa.
    pub youngs_modulus: f64,
    /// Poisson's ratio nu, in (-1, 0.5).
    pub poisson_ratio: f64,
    /// Sheet thickness h in m.
    pub thickness: f64,
    /// Mass density rho in kg/m^3.
    pub density: f64,
}

impl Default for Material {
    /// Paper-like sheet: E = 3 GPa, nu = 0.3, h = 0.1 mm, rho = 800 kg/m^3.
    fn default() -> Self {
        Material {
            youngs_modulus: 3.0e9,
            poisson_ratio: 0.3,
            thickness: 1.0e-4,
            density: 800.0,
        }
    }
}

impl Material {
    /// Bending stiffness D = E h^3 / (12 (1 - nu^2)) in N m.
    pub fn bending_stiffness(&self) -> f64 {
        let Material {
            youngs_modulus: e,
            poisson_ratio: nu,
            thickness: h,
            ..
        } = *self;
        e * h * h * h / (12.0 * (1.0 - nu * nu))
    }
}
