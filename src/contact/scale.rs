//! The sheet's scales both barrier terms take: mean facet side, default stiffness, lumped masses.

use super::settings::ContactSettings;
use crate::element::ShellElement;
use crate::mesh::Mesh;

/// What a sheet and the contact settings give self-contact and the
/// obstacles alike.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SheetScale {
    /// Mean facet side `l` (m).
    pub(crate) side: f64,
    /// Default barrier stiffness `kappa` (N/m): the settings', else
    /// `E h xi / l` (membrane stiffness times the contact thickness over
    /// the mean facet side).
    pub(crate) kappa: f64,
    /// Lumped mass of a contact sample (kg): a mean facet's over the
    /// `n^2` sub-triangles of its sampling.
    pub(crate) sample_mass: f64,
    /// Lumped mass of a facet's corner (kg): a third of a mean facet's.
    pub(crate) corner_mass: f64,
}

impl SheetScale {
    /// The scales of `mesh` (facets `elements`) sampled at `n` subdivisions
    /// a side, with `settings`; `areal_mass` is density times thickness
    /// (kg/m^2), `membrane` the membrane stiffness E h (N/m).
    pub(crate) fn new(
        mesh: &Mesh,
        elements: &[ShellElement],
        n: usize,
        settings: &ContactSettings,
        areal_mass: f64,
        membrane: f64,
    ) -> SheetScale {
        let nf = mesh.triangles().len().max(1);
        let area: f64 = elements.iter().map(|e| e.area()).sum::<f64>() / nf as f64;
        let side = mesh.edge_ids().map(|e| mesh.edge_length(e)).sum::<f64>()
            / mesh.edges().len().max(1) as f64;
        let n = n as f64;
        // The barrier must absorb impacts: kappa s_hat^2 is its energy scale.
        // D / l^2 (bending) leaves 1e-11 J against the 1e-6 J of a 4 cm
        // paper panel falling 5 mm; E h xi / l stops it within the width.
        let kappa = settings
            .stiffness
            .unwrap_or(membrane * settings.thickness / side);
        SheetScale {
            side,
            kappa,
            sample_mass: areal_mass * area / (n * n),
            corner_mass: areal_mass * area / 3.0,
        }
    }
}
