//! Solvers: the sparse linear solve, and the time integrators built on it
//! behind one interface ([`stepper::Stepper`]), with the step-size
//! control apart from them ([`step_control`]) and their numerical
//! constants in one struct ([`IntegrationParameters`]).

pub mod broyden;
pub mod central_difference;
pub mod generalized_alpha;
pub mod linear;
pub mod ordering;
mod parameters;
pub mod phase_timer;
pub mod statics;
pub mod step_control;
pub mod stepper;

pub use generalized_alpha::NewtonMode;
pub use linear::{FactorKind, LinearError, LowRank, Ordering, SolverStats, SparseSolver};
pub use parameters::{IntegrationParameters, Rule};
pub use phase_timer::set_phase_timing;
