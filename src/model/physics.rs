//! Physics defaults: the material, crease stiffness and damping a scene
//! asks for, with the automatic damping a scene without `ancf:damping` gets.

use crate::assembly::Physics;
use crate::scene::{CreaseStiffness, Scene};

/// Damping ratio of the automatic damping on a mean facet's folding mode.
pub const AUTO_DAMPING_RATIO: f64 = 0.2;

/// The physics a scene asks for: material, crease stiffness per unit
/// length, damping (the automatic damping when the scene sets none).
pub fn physics(sc: &Scene) -> Physics {
    let material = sc.material;
    let k_pl = match sc.crease {
        CreaseStiffness::LengthScale(l) => material.bending_stiffness() / l,
        CreaseStiffness::PerLength(k) => k,
    };
    let (alpha, beta, crease) = if sc.auto_damping {
        (auto_alpha(sc, k_pl), 0.0, sc.damping.crease)
    } else {
        (sc.damping.alpha, sc.damping.beta, sc.damping.crease)
    };
    Physics {
        material,
        crease_k_per_length: k_pl,
        crease_c_per_length: crease,
        alpha,
        beta,
    }
}

/// Default damping: mass-proportional damping of the deformation rate
/// (rigid motion undamped, see [`crate::rigid`]) with damping ratio
/// [`AUTO_DAMPING_RATIO`] on the folding mode (`folding_omega`). Every
/// deformation mode then decays at the same rate alpha / 2, so a fold
/// settles within a few of its periods.
fn auto_alpha(sc: &Scene, k_per_length: f64) -> f64 {
    2.0 * AUTO_DAMPING_RATIO * folding_omega(sc, k_per_length)
}

/// The folding mode's angular frequency (rad/s): a panel of the mean facet
/// size w hinged on its crease, omega = sqrt(3 k / (rho h w^3)) per unit
/// crease length.
fn folding_omega(sc: &Scene, k_per_length: f64) -> f64 {
    let mesh = &sc.mesh;
    let nt = mesh.triangles().len().max(1);
    let mean_area: f64 = mesh.facet_ids().map(|t| mesh.area(t)).sum::<f64>() / nt as f64;
    let w = (2.0 * mean_area).sqrt();
    let m = &sc.material;
    (3.0 * k_per_length / (m.density * m.thickness * w.powi(3))).sqrt()
}

/// The automatic actuator's natural frequency over the folding mode's.
pub const AUTO_ACTUATOR_BANDWIDTH: f64 = 4.0;

/// The actuators' time constant (s): the scene's, or automatic: the
/// natural frequency [`AUTO_ACTUATOR_BANDWIDTH`] times the folding mode's
/// (`folding_omega`), fast against the sheet's folding and slow against
/// its facets' bending, so a held or stepped input folds the sheet without
/// ringing the facets. 0 where the folding frequency is not positive (no
/// crease stiffness).
pub fn actuator_time_constant(sc: &Scene) -> f64 {
    if let Some(t) = sc.actuator_time_constant {
        return t;
    }
    let omega = folding_omega(sc, physics(sc).crease_k_per_length);
    if omega > 0.0 && omega.is_finite() {
        1.0 / (AUTO_ACTUATOR_BANDWIDTH * omega)
    } else {
        0.0
    }
}
