//! Self-contact of the sheet: the sampled contact surface, the broad phase,
//! the barrier and friction force term, and the geometric kernels under them
//! (distances with exact derivatives, continuous collision detection,
//! triangle-triangle intersection).

pub mod broad;
pub mod ccd;
pub mod check;
pub mod distance;
pub mod intersect;
pub mod scalar;
pub mod surface;
pub mod term;

pub use term::{ContactReport, ContactSettings, ContactTerm, SettingsError};
