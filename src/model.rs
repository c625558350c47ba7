//! The plain Rust `Model` API: one origami scene, its state, and a stepper.
//! The FMU, the CLI and the tests all drive the model through this API.
//!
//! Variables are flat, numbered tables (parameters, inputs, outputs) so that
//! the FMI layer only maps value references onto indices.
//!
//! Life cycle: [`Model::new`] validates and builds the scene;
//! [`Model::set_parameter`] may change parameters until
//! [`Model::initialize`]; then [`Model::set_input`] and [`Model::advance`]
//! alternate. Inputs are ramped linearly over each step from the value in
//! force at its start to the value last set (never held, never jumped).

use serde::{Deserialize, Serialize};
use std::fmt;

/// One scalar variable of the model, as the FMU and CSV files name it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VariableSpec {
    /// Structured name, e.g. `vertex[3].x`, `crease[7].angle`, `fold`.
    pub name: String,
    /// SI unit symbol ("" for dimensionless).
    pub unit: String,
    /// One line for a user.
    pub description: String,
    /// Start value.
    pub start: f64,
}

/// Errors of the model API; each names what is wrong.
#[derive(Clone, Debug, PartialEq)]
#[allow(missing_docs)] // variant fields are named for what they hold
pub enum Error {
    /// The scene cannot be turned into a model.
    Scene(String),
    /// A variable index is out of range.
    NoSuchVariable { kind: &'static str, index: usize },
    /// A non-finite or out-of-range value for a variable; nothing changed.
    BadValue { name: String, value: f64, reason: String },
    /// A call that is not allowed in the current phase.
    Phase(String),
    /// The stepper could not complete; the state is as it was before.
    StepFailed { time: f64, reason: String },
    /// A saved state does not fit this model.
    State(String),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Scene(m) => write!(f, "invalid scene: {m}"),
            Error::NoSuchVariable { kind, index } => write!(f, "no {kind} with index {index}"),
            Error::BadValue { name, value, reason } => {
                write!(f, "{name} = {value}: {reason}; value not applied")
            }
            Error::Phase(m) => write!(f, "{m}"),
            Error::StepFailed { time, reason } => {
                write!(f, "step from t = {time} failed: {reason}; state rolled back")
            }
            Error::State(m) => write!(f, "bad saved state: {m}"),
        }
    }
}

impl std::error::Error for Error {}

/// What one [`Model::advance`] did.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StepReport {
    /// Internal steps taken.
    pub steps: usize,
    /// Internal steps rejected (Newton failure or error too large) and retried.
    pub rejected: usize,
    /// Newton iterations in total.
    pub newton_iterations: usize,
    /// Sparse numeric factorizations in total.
    pub factorizations: usize,
    /// Smallest internal step used, s.
    pub min_step: f64,
}
