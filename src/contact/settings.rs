//! The contact settings (the scene's `ancf:contact` keys), which self-contact
//! and the obstacles both read, and why a term refuses them.

/// Contact settings (scene keys under `ancf:contact`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ContactSettings {
    /// Distance kept between surfaces (m): the sheet thickness by default.
    pub thickness: f64,
    /// Barrier width `s_hat` as a fraction of the thickness: pairs act
    /// below a gap of `thickness * width`.
    pub width: f64,
    /// Barrier stiffness `kappa` (N/m); `None`: `E h xi / l` (membrane
    /// stiffness times contact thickness over the mean facet side).
    pub stiffness: Option<f64>,
    /// Coulomb friction coefficient.
    pub friction: f64,
    /// Tangential speed (m/s) below which friction sticks (smoothed).
    pub stick_velocity: f64,
    /// Damping ratio of the normal dashpot.
    pub damping_ratio: f64,
    /// Subdivisions of each facet side for the contact samples.
    pub subdivisions: usize,
}

impl Default for ContactSettings {
    fn default() -> Self {
        ContactSettings {
            thickness: 0.0,
            width: 0.1,
            stiffness: None,
            friction: 0.3,
            stick_velocity: 1e-4,
            damping_ratio: 1.0,
            subdivisions: 3,
        }
    }
}

impl ContactSettings {
    /// How far (m) self-contact's samples on a cut's lips stand back from
    /// the drawn line: the lips start apart by the thickness and twice the
    /// barrier's width, out of the barrier's reach.
    pub fn kerf(&self) -> f64 {
        0.5 * self.thickness * (1.0 + 2.0 * self.width)
    }

    /// Whether a contact term can be made with these settings: a positive
    /// thickness.
    pub(crate) fn check(&self) -> Result<(), SettingsError> {
        if self.thickness.is_nan() || self.thickness <= 0.0 {
            return Err(SettingsError::Thickness(self.thickness));
        }
        Ok(())
    }
}

/// Why [`ContactTerm::new`](super::ContactTerm::new) refused its settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SettingsError {
    /// The thickness (given) is not positive.
    Thickness(f64),
}

impl std::fmt::Display for SettingsError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SettingsError::Thickness(_) => write!(f, "contact needs a positive thickness"),
        }
    }
}

impl std::error::Error for SettingsError {}
