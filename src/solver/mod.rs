//! Solvers: the sparse linear solve, and the integrators built on it.

pub mod generalized_alpha;
pub mod linear;
pub mod statics;

pub use linear::SparseSolver;
