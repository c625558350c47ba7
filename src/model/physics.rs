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
/// [`AUTO_DAMPING_RATIO`] on the folding mode ([`folding_frequency`]). Every
/// deformation mode then decays at the same rate alpha / 2, so a fold
/// settles within a few of its periods.
fn auto_alpha(sc: &Scene, k_per_length: f64) -> f64 {
    2.0 * AUTO_DAMPING_RATIO * folding_omega(sc, k_per_length)
}

/// The folding mode's angular frequency (rad/s) of the scene's sheet: what
/// the default damping is tuned to, and a yardstick for a servo's time
/// constant (a servo n times faster than the sheet folds: 1 / (n omega)).
pub fn folding_frequency(sc: &Scene) -> f64 {
    folding_omega(sc, physics(sc).crease_k_per_length)
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

/// The actuators' time constant (s): the scene's servo, or 0, the ideal
/// actuator (the input is the rest angle or moment at once). There is no
/// automatic value: a servo is part of the plant the user chooses.
pub fn actuator_time_constant(sc: &Scene) -> f64 {
    sc.actuator_time_constant.unwrap_or(0.0)
}
