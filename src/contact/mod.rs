//! Self-contact of the sheet: the sampled contact surface, the broad phase,
//! the barrier and friction force term, and the geometric kernels under them
//! (distances with exact derivatives, continuous collision detection,
//! triangle-triangle intersection); and contact with rigid obstacles
//! (their shapes, and their force term in the same barrier). The two force
//! terms share what they lag from the step start (`lagged`), the pair
//! stiffnesses they keep and list in a saved state (`memory`), and the
//! sheet's scales their barrier is set from (`scale`).

pub mod broad;
pub mod ccd;
pub mod check;
pub mod distance;
pub mod distance_derivatives;
pub mod intersect;
mod lagged;
mod memory;
pub mod obstacles;
pub mod potentials;
pub mod scalar;
mod scale;
mod settings;
pub mod shapes;
pub mod surface;
pub mod term;

pub use obstacles::{ObstacleError, ObstacleTerm};
pub use settings::{ContactSettings, SettingsError};
pub use shapes::{Obstacle, Shape, ShapeError};
pub use term::{ContactReport, ContactTerm};
