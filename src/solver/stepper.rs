//! The interface every time integrator implements ([`Stepper`]), and the
//! data a step reads and writes: the dynamic state ([`Dynamics`]), what
//! drives the step ([`Drive`]), the work it did ([`Outcome`]), why it
//! failed ([`StepError`]), and the memory the implicit stepper keeps from
//! step to step ([`StepperMemory`]).
//!
//! The step-size control (`crate::solver::step_control`) is apart from the
//! schemes: it asks an integrator for one step of a given size and decides
//! from the outcome what to do next.

use crate::assembly::{Assembler, Evaluation, State};
use crate::solver::SparseSolver;
use crate::solver::generalized_alpha::JacobianPoint;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::time::Duration;

/// Dynamic state: positions, velocities, accelerations and the algorithmic
/// acceleration (all DOFs).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Dynamics {
    /// Positions.
    pub q: Vec<f64>,
    /// Velocities.
    pub v: Vec<f64>,
    /// Accelerations.
    pub qdd: Vec<f64>,
    /// Algorithmic accelerations.
    pub abar: Vec<f64>,
}

/// What drives one step, evaluated at its end t_{n+1}.
pub struct Drive<'a> {
    /// Rest angle of each crease end.
    pub theta0: &'a [f64],
    /// Applied moment of each crease end.
    pub moment: &'a [f64],
    /// External force, all DOFs.
    pub f_ext: &'a [f64],
    /// Values of the fixed DOFs at t_{n+1}: (scalar index, value).
    pub prescribed: &'a [(usize, f64)],
    /// Unwrapped crease angles at t_n.
    pub theta_prev: &'a [f64],
}

impl<'a> Drive<'a> {
    /// The assembly's view of positions and velocities `d` under this drive.
    pub fn at<'s>(&'s self, d: &'s Dynamics) -> State<'s> {
        State {
            q: &d.q,
            v: &d.v,
            theta0: self.theta0,
            moment: self.moment,
            theta_prev: self.theta_prev,
        }
    }
}

/// What the predictor and the iteration-matrix rules remember from the
/// steps accepted so far (a restored state predicts as the original run).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct NewtonMemory {
    /// How many steps in a row the extrapolated guess has won.
    pub extrapolation_streak: u32,
    /// How many steps in a row the held guess has won.
    pub held_streak: u32,
}

/// Everything the stepper carries from one advance to the next besides the
/// physical state: saved with the model state, so that a restored state
/// continues bit for bit.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StepperMemory {
    /// The internal step size the controller proposes next.
    pub h_next: f64,
    /// The predictor's and the matrix rules' memory.
    pub newton: NewtonMemory,
    /// Where the iteration matrix the solver holds was formed (kept across
    /// advances by modified Newton; None: the next step forms one).
    pub jacobian: Option<JacobianPoint>,
}

/// The work of one step attempt and, where it succeeded, its local error.
#[derive(Clone, Debug, Default)]
pub struct Outcome {
    /// Newton iterations.
    pub iterations: usize,
    /// Numeric factorizations.
    pub factorizations: usize,
    /// Scaled local error estimate (accept when <= 1).
    pub error: f64,
    /// Time spent assembling forces and matrices.
    pub assembly_time: Duration,
    /// Newton steps cut short by a force term (contact's collision check).
    pub limited_steps: usize,
    /// Corrections the line search near contact shortened.
    pub line_search_cuts: usize,
    /// The memory to keep if the step is accepted.
    pub memory: NewtonMemory,
}

/// Why a step attempt failed.
#[derive(Clone, Debug, PartialEq)]
pub enum StepError {
    /// Newton used its whole budget of iterations.
    NotConverged {
        /// The budget.
        iterations: usize,
    },
    /// The correction grew twice in a row.
    Diverged {
        /// The last correction (scaled).
        correction: f64,
        /// Iterations done.
        iterations: usize,
    },
    /// Newton's correction is not finite.
    NonFinite,
    /// Contact admits no part of a Newton correction.
    NoCollisionFreeStep,
    /// An explicit step left non-finite values (beyond its stability limit).
    Unstable,
    /// Forces could not be evaluated (an undefined crease angle, non-finite forces).
    Assembly(Box<crate::assembly::EvalError>),
    /// The sparse solver failed.
    Linear(crate::solver::linear::LinearError),
    /// The advance's CPU limit passed during the iteration: the advance
    /// ends here (not retried with a shorter step).
    OutOfTime,
}

impl From<crate::assembly::EvalError> for StepError {
    fn from(e: crate::assembly::EvalError) -> Self {
        StepError::Assembly(Box::new(e))
    }
}

impl fmt::Display for StepError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StepError::NotConverged { iterations } => {
                write!(f, "Newton did not converge in {iterations} iterations")
            }
            StepError::Diverged {
                correction,
                iterations,
            } => write!(
                f,
                "Newton diverged (correction {correction:.3e} after {iterations} iterations)"
            ),
            StepError::NonFinite => write!(f, "Newton produced non-finite values"),
            StepError::NoCollisionFreeStep => {
                write!(f, "contact: no collision-free Newton step")
            }
            StepError::Unstable => write!(
                f,
                "central differences produced non-finite values (unstable step)"
            ),
            StepError::Assembly(m) => write!(f, "{m}"),
            StepError::Linear(e) => write!(f, "{e}"),
            StepError::OutOfTime => write!(f, "the step's CPU limit passed"),
        }
    }
}

impl std::error::Error for StepError {}

/// A step that failed: why, and the work it took.
#[derive(Clone, Debug)]
pub struct Failure {
    /// What went wrong.
    pub reason: StepError,
    /// Newton iterations, factorizations and assembly time spent on it.
    pub outcome: Outcome,
}

/// How the step-size control chooses the steps of an integrator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StepPolicy {
    /// Steps chosen by the local error estimate (implicit schemes).
    Adaptive,
    /// Equal substeps of each advance, none longer than this (explicit
    /// schemes below their stability limit), all accepted.
    Fixed(f64),
}

/// What the stepper needs of the mechanics: the assembled system and the
/// sparse solver it factors its matrices in.
pub struct Mechanics<'a> {
    /// Forces, matrices and the DOF layout.
    pub asm: &'a Assembler,
    /// The solver of the iteration matrix.
    pub solver: &'a mut SparseSolver,
}

/// One step the controller asks for.
pub struct Attempt<'a> {
    /// Step size, s.
    pub h: f64,
    /// What drives it.
    pub drive: &'a Drive<'a>,
    /// The memory of the steps accepted so far.
    pub memory: NewtonMemory,
    /// The CPU limit past which an iteration gives up
    /// ([`StepError::OutOfTime`]); `None`: no limit.
    pub deadline: Option<crate::cpu_time::ThreadDeadline>,
}

/// A time integration scheme: one step of a given size from a state.
pub trait Stepper {
    /// How its steps are chosen.
    fn policy(&self) -> StepPolicy;

    /// Before the first step of an advance: take up the memory of the
    /// state's history (the implicit scheme re-forms its kept matrix).
    fn begin_advance(
        &mut self,
        asm: &mut Assembler,
        solver: &mut SparseSolver,
        memory: &StepperMemory,
    ) -> Result<(), StepError>;

    /// One step from `cur` into `next` (a buffer of the same size).
    fn step(
        &mut self,
        mech: Mechanics,
        cur: &Dynamics,
        next: &mut Dynamics,
        attempt: &Attempt,
    ) -> Result<Outcome, Failure>;

    /// After the last step of an advance: what to remember besides `h_next`.
    fn end_advance(&self, memory: &mut StepperMemory);

    /// The full evaluation (forces, energies, powers) at the last accepted
    /// state, where the step made one.
    fn evaluation(&self) -> Option<&Evaluation>;

    /// The unwrapped crease angles at the last accepted state.
    fn crease_angles(&self) -> &[f64];

    /// Forget the iteration matrix (the solver was used for something
    /// else, or rebuilt).
    fn invalidate_matrix(&mut self);

    /// Time spent so far in numeric factorizations and in solves by the
    /// linear solver this scheme uses (`shared`: the mechanics' solver).
    fn linear_times(&self, shared: &SparseSolver) -> (Duration, Duration);
}
