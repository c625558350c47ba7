//! Solvers: the sparse linear solve, and the integrators built on it.

pub mod linear;

pub use linear::SparseSolver;
