//! Generalized-alpha (Chung & Hulbert 1993) in the form of Arnold & Brüls
//! (2007): the equation of motion holds exactly at t_{n+1},
//!
//! ```text
//! M qdd_{n+1} + f(q_{n+1}, v_{n+1}) = f_ext(t_{n+1})
//! (1 - am) abar_{n+1} + am abar_n = (1 - af) qdd_{n+1} + af qdd_n
//! q_{n+1} = q_n + h v_n + h^2 (1/2 - beta) abar_n + h^2 beta abar_{n+1}
//! v_{n+1} = v_n + h (1 - gamma) abar_n + h gamma abar_{n+1}
//! ```
//!
//! with am = (2 rho - 1)/(rho + 1), af = rho/(rho + 1), gamma = 1/2 + af - am,
//! beta = (1 + af - am)^2 / 4: second order, unconditionally stable,
//! rho_inf = 1 is the trapezoidal rule. Newton on q_{n+1} with the matrix
//! `K + gamma/(beta h) C + (1 - am)/((1 - af) beta h^2) M`. Prescribed DOFs
//! follow the same update with q_{n+1} given, so their inertia couples in.
//!
//! A step, in the phases of Chrono's HHT stepper: the predictor's guess
//! (`predictor`), the Newton iteration (`newton`: evaluate, form and factor
//! the iteration matrix where its rules ask (`matrix`), solve, screen the
//! correction, apply it, check convergence), then the local error estimate
//! (`local_error`). Accepting or rejecting the step is the step control's
//! (`crate::solver::step_control`).

mod matrix;
mod newton;
mod predictor;

pub use crate::scene::NewtonMode;
pub use matrix::JacobianPoint;

use crate::assembly::{Assembler, Evaluation, FIXED, MatrixCoeffs};
use crate::solver::broyden::Broyden;
use crate::solver::stepper::{
    Attempt, Dynamics, Failure, Mechanics, Outcome, StepError, StepPolicy, Stepper, StepperMemory,
};
use crate::solver::{IntegrationParameters, SparseSolver};
use std::time::Duration;

/// The four coefficients of the scheme.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coefficients {
    /// alpha_m.
    pub am: f64,
    /// alpha_f.
    pub af: f64,
    /// Newmark beta.
    pub beta: f64,
    /// Newmark gamma.
    pub gamma: f64,
}

impl Coefficients {
    /// Coefficients for spectral radius `rho_inf` in [0, 1].
    pub fn new(rho_inf: f64) -> Self {
        let r = rho_inf.clamp(0.0, 1.0);
        let am = (2.0 * r - 1.0) / (r + 1.0);
        let af = r / (r + 1.0);
        let gamma = 0.5 + af - am;
        let beta = 0.25 * (1.0 + af - am).powi(2);
        Coefficients {
            am,
            af,
            beta,
            gamma,
        }
    }

    /// The weights of K, C and M in the iteration matrix for step `h`.
    fn matrix(self, h: f64) -> MatrixCoeffs {
        let bh2 = self.beta * h * h;
        MatrixCoeffs {
            k: 1.0,
            c: self.gamma / (self.beta * h),
            m: (1.0 - self.am) / ((1.0 - self.af) * bh2),
        }
    }
}

/// Characteristic sizes of the scalar DOFs (all DOFs): what Newton's
/// corrections and residuals are measured against, and what the local error
/// estimate is ([`crate::assembly::Assembler::scales`],
/// [`crate::assembly::error_scales`]).
#[derive(Clone, Debug, Default)]
pub struct Scales {
    /// For Newton's corrections and residuals.
    pub newton: Vec<f64>,
    /// For the local error of a step.
    pub error: Vec<f64>,
}

/// The scene's settings of the Newton iteration and error estimate.
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    /// Relative tolerance for the local error.
    pub tolerance: f64,
    /// Newton stops when every scaled correction is below this.
    pub newton_tolerance: f64,
    /// And below this times the step (1/s; infinite without friction):
    /// see [`stick_bound`].
    pub stick_bound: f64,
    /// Maximum Newton iterations.
    pub max_newton: usize,
    /// Full or modified Newton.
    pub newton: NewtonMode,
    /// Filter the local error estimate through the iteration matrix
    /// ([`filter_error`]).
    pub error_filter: bool,
}

/// [`Settings::stick_bound`] of a scene whose contact has friction: scaled
/// corrections (positions over the sheet size `length`) stay below this
/// times the step, i.e. the velocity a correction `d` left over carries,
/// `gamma / (beta h) d`, below `stick_fraction` of `stick_velocity`
/// (regularized friction reads slower velocities as stick, so an
/// iteration error near it lets a sticking contact creep).
pub fn stick_bound(
    co: Coefficients,
    params: &IntegrationParameters,
    stick_velocity: f64,
    length: f64,
) -> f64 {
    params.stick_fraction * stick_velocity * co.beta / (co.gamma * length)
}

/// Reusable work vectors, and which iteration matrix the solver holds.
#[derive(Default)]
struct Workspace {
    eval: Evaluation,
    /// Whether `eval` is the full evaluation at the last accepted state
    /// (else only its crease angles are).
    evaluated: bool,
    matrix: Vec<f64>,
    rhs: Vec<f64>,
    mqdd: Vec<f64>,
    /// A Newton correction over all DOFs (zero on fixed ones).
    dq: Vec<f64>,
    /// The predictor's second guess (buffers reused across steps).
    guess: Dynamics,
    /// The residual of the predictor's first guess (kept for Newton's
    /// first iteration when that guess wins).
    first_rhs: Vec<f64>,
    /// The residual at the iterate a correction started from (line search).
    rhs_prev: Vec<f64>,
    /// Where the factorization in the solver was formed (None: no usable
    /// factorization).
    jacobian: Option<JacobianPoint>,
    /// Secant updates of the kept matrix within a step.
    secant: Broyden,
    /// The filtered error estimate on the free DOFs.
    filtered: Vec<f64>,
}

/// The implicit stepper: generalized-alpha with Newton's iteration.
pub struct GeneralizedAlpha {
    coeffs: Coefficients,
    settings: Settings,
    params: IntegrationParameters,
    scales: Scales,
    ws: Workspace,
}

impl GeneralizedAlpha {
    /// The stepper of spectral radius `rho_inf`.
    pub fn new(
        rho_inf: f64,
        settings: Settings,
        params: IntegrationParameters,
        scales: Scales,
    ) -> Self {
        GeneralizedAlpha {
            coeffs: Coefficients::new(rho_inf),
            settings,
            params,
            scales,
            ws: Workspace::default(),
        }
    }

    /// The scheme's coefficients.
    pub fn coefficients(&self) -> Coefficients {
        self.coeffs
    }

    /// Where the iteration matrix the solver holds was formed.
    pub fn jacobian(&self) -> Option<&JacobianPoint> {
        self.ws.jacobian.as_ref()
    }
}

impl Stepper for GeneralizedAlpha {
    fn policy(&self) -> StepPolicy {
        StepPolicy::Adaptive
    }

    /// The iteration matrix of the state's history (a restored state
    /// re-forms the one it was saved with), so that modified Newton keeps
    /// it across communication points.
    fn begin_advance(
        &mut self,
        asm: &mut Assembler,
        solver: &mut SparseSolver,
        memory: &StepperMemory,
    ) -> Result<(), StepError> {
        matrix::restore(
            asm,
            solver,
            self.coeffs,
            memory.jacobian.as_ref(),
            &mut self.ws,
        )
    }

    fn step(
        &mut self,
        mech: Mechanics,
        cur: &Dynamics,
        next: &mut Dynamics,
        attempt: &Attempt,
    ) -> Result<Outcome, Failure> {
        let mut out = Outcome {
            memory: attempt.memory,
            ..Outcome::default()
        };
        match self.step_inner(mech, cur, next, attempt, &mut out) {
            Ok(()) => Ok(out),
            Err(reason) => Err(Failure {
                reason,
                outcome: out,
            }),
        }
    }

    fn end_advance(&self, memory: &mut StepperMemory) {
        memory.jacobian = self.ws.jacobian.clone();
    }

    /// The full evaluation (forces, energies, powers) at the last accepted
    /// state, where the step made one: only when a force term's powers may
    /// be nonzero in the step ([`Assembler::dissipates_this_step`]);
    /// outputs evaluate otherwise.
    fn evaluation(&self) -> Option<&Evaluation> {
        self.ws.evaluated.then_some(&self.ws.eval)
    }

    fn crease_angles(&self) -> &[f64] {
        &self.ws.eval.theta
    }

    fn invalidate_matrix(&mut self) {
        self.ws.jacobian = None;
    }

    fn linear_times(&self, shared: &SparseSolver) -> (Duration, Duration) {
        let s = shared.stats();
        (s.factor_time, s.solve_time)
    }
}

impl GeneralizedAlpha {
    /// One step: predict, iterate, estimate the error.
    fn step_inner(
        &mut self,
        mech: Mechanics,
        cur: &Dynamics,
        next: &mut Dynamics,
        attempt: &Attempt,
        out: &mut Outcome,
    ) -> Result<(), StepError> {
        let Mechanics { asm, solver } = mech;
        let ws = &mut self.ws;
        let n = asm.n_dofs();
        ws.matrix.resize(asm.nnz(), 0.0);
        ws.rhs.resize(asm.n_free, 0.0);
        ws.mqdd.resize(n, 0.0);
        ws.dq.resize(n, 0.0);
        let ctx = StepContext {
            asm,
            co: self.coeffs,
            h: attempt.h,
            drive: attempt.drive,
            cur,
            scales: &self.scales,
            params: &self.params,
            settings: &self.settings,
            deadline: attempt.deadline,
        };
        let have_rhs = predictor::predict(&ctx, next, ws, out);
        newton::iterate(&ctx, solver, have_rhs, next, ws, out)?;
        let c = error_constant(attempt.h, self.coeffs.beta);
        for (i, e) in ws.dq.iter_mut().enumerate() {
            *e = match asm.free[i] {
                FIXED => 0.0,
                _ => c * (next.qdd[i] - cur.qdd[i]),
            };
        }
        if self.settings.error_filter {
            filter_error(asm, solver, self.coeffs, ws);
        }
        out.error = error_norm(asm, &ws.dq, &self.scales.error, self.settings.tolerance);
        Ok(())
    }
}

/// What every phase of one step reads.
struct StepContext<'a> {
    asm: &'a Assembler,
    co: Coefficients,
    h: f64,
    drive: &'a crate::solver::stepper::Drive<'a>,
    cur: &'a Dynamics,
    scales: &'a Scales,
    params: &'a IntegrationParameters,
    settings: &'a Settings,
    /// The attempt's CPU deadline ([`Attempt::deadline`]).
    deadline: Option<crate::cpu_time::ThreadDeadline>,
}

impl StepContext<'_> {
    /// Algorithmic acceleration, velocity and acceleration of `next` from
    /// its positions (the scheme's update formulas, solved for q_{n+1}).
    fn update_rates(&self, next: &mut Dynamics) {
        update_rates(next, self.cur, self.co, self.h);
    }

    /// Evaluate at `d` and write the negated residual of the equation of
    /// motion, f_ext - M qdd - f, into `ws.rhs` (free DOFs); with `matrix`,
    /// also the iteration matrix into `ws.matrix`.
    fn residual(
        &self,
        d: &Dynamics,
        ws: &mut Workspace,
        matrix: Option<MatrixCoeffs>,
    ) -> Result<(), StepError> {
        let asm = self.asm;
        asm.evaluate(
            &self.drive.at(d),
            &mut ws.eval,
            matrix.map(|co| (&mut ws.matrix[..], co)),
        )
        .map_err(StepError::from)?;
        asm.mass_mul(&d.qdd, &mut ws.mqdd);
        for i in 0..d.q.len() {
            let fi = asm.free[i];
            if fi != FIXED {
                ws.rhs[fi] = -(ws.mqdd[i] + ws.eval.force[i] - self.drive.f_ext[i]);
            }
        }
        Ok(())
    }
}

/// The local error estimate's factor: h^2 |beta - 1/6| (at least h^2/24)
/// times the change of the acceleration over the step.
fn error_constant(h: f64, beta: f64) -> f64 {
    h * h * (beta - 1.0 / 6.0).abs().max(1.0 / 24.0)
}

/// Filter the raw estimate `ws.dq` (all DOFs) in place through the
/// factored iteration matrix S = K + c_c C + c_m M: `S^-1 c_m M e`. A mode
/// of frequency w keeps 1 / (1 + w^2 / c_m) of its estimate: resolved
/// modes (w^2 << c_m, about 1 / (beta h^2)) all of it, stiff ones the
/// displacement their acceleration change stands for. Left raw where the
/// solver holds no factorization or the solve fails.
fn filter_error(asm: &Assembler, solver: &mut SparseSolver, co: Coefficients, ws: &mut Workspace) {
    let Some(h_matrix) = ws.jacobian.as_ref().map(|jp| jp.h) else {
        return;
    };
    let cm = co.matrix(h_matrix).m;
    asm.mass_mul(&ws.dq, &mut ws.mqdd);
    ws.filtered.resize(asm.n_free, 0.0);
    for (i, &fi) in asm.free.iter().enumerate() {
        if fi != FIXED {
            ws.filtered[fi] = cm * ws.mqdd[i];
        }
    }
    if solver.solve_in_place(&mut ws.filtered).is_err() {
        return;
    }
    for (i, &fi) in asm.free.iter().enumerate() {
        if fi != FIXED {
            ws.dq[i] = ws.filtered[fi];
        }
    }
}

/// RMS over the free DOFs of the error estimate `e`, scaled by tolerance
/// and DOF size.
fn error_norm(asm: &Assembler, e: &[f64], scales: &[f64], tolerance: f64) -> f64 {
    let mut sum = 0.0;
    let mut cnt = 0usize;
    for (i, &fi) in asm.free.iter().enumerate() {
        if fi != FIXED {
            let x = e[i] / (tolerance * scales[i]);
            sum += x * x;
            cnt += 1;
        }
    }
    if cnt > 0 {
        (sum / cnt as f64).sqrt()
    } else {
        0.0
    }
}

/// Algorithmic acceleration, velocity and acceleration of `next` from its
/// positions (the scheme's update formulas, solved for q_{n+1}).
fn update_rates(next: &mut Dynamics, cur: &Dynamics, co: Coefficients, h: f64) {
    let Coefficients {
        am,
        af,
        beta,
        gamma,
    } = co;
    let bh2 = beta * h * h;
    for i in 0..next.q.len() {
        next.abar[i] =
            (next.q[i] - cur.q[i] - h * cur.v[i] - h * h * (0.5 - beta) * cur.abar[i]) / bh2;
        next.v[i] = cur.v[i] + h * (1.0 - gamma) * cur.abar[i] + h * gamma * next.abar[i];
        next.qdd[i] = ((1.0 - am) * next.abar[i] + am * cur.abar[i] - af * cur.qdd[i]) / (1.0 - af);
    }
}
