//! Solvers: the sparse linear solve, and the integrators built on it.

pub mod broyden;
pub mod central_difference;
pub mod generalized_alpha;
pub mod linear;
pub mod ordering;
pub mod statics;

pub use linear::{FactorKind, LowRank, Ordering, SolverStats, SparseSolver};
