//! Explicit central differences (velocity Verlet), the scheme explicit
//! origami simulators use, as the comparison point for generalized-alpha:
//!
//! ```text
//! v_{n+1/2} = v_n + h/2 qdd_n
//! q_{n+1}   = q_n + h v_{n+1/2}
//! M qdd_{n+1} = f_ext(t_{n+1}) - f(q_{n+1}, v_{n+1/2})
//! v_{n+1}   = v_{n+1/2} + h/2 qdd_{n+1}
//! ```
//!
//! Second order, no Newton iteration, the constant mass matrix factored
//! once; stable only for `h < 2 / omega_max`. The highest frequency is
//! estimated once by power iteration at the reference state and the step
//! kept below [`SAFETY`] times the limit. Thin sheets make `omega_max` huge
//! (membrane waves across the smallest element), which is the point of the
//! comparison.

use crate::assembly::{Assembler, EvalError, Evaluation, FIXED, MatrixCoeffs, State};
use crate::solver::stepper::{
    Attempt, Drive, Dynamics, Failure, Mechanics, Outcome, StepError, StepPolicy, Stepper,
    StepperMemory,
};
use crate::solver::{LinearError, SparseSolver};
// Phase times are CPU time, read where phase timing is on (phase_timer).
use crate::solver::phase_timer::PhaseTimer;
use std::time::Duration;

/// Fraction of the estimated stability limit `2 / omega_max` used as step.
pub const SAFETY: f64 = 0.8;

/// The factored mass matrix, the stable step and work vectors.
pub struct CentralDifference {
    mass: SparseSolver,
    /// Largest stable step estimated at the reference state, s.
    pub critical_step: f64,
    eval: Evaluation,
    rhs: Vec<f64>,
    accel_p: Vec<f64>,
    m_accel_p: Vec<f64>,
}

/// Why the explicit stepper could not be set up.
#[derive(Clone, Debug, PartialEq)]
pub enum SetupError {
    /// The mass matrix could not be factored.
    MassMatrix(LinearError),
    /// The stiffness could not be evaluated.
    Assembly(EvalError),
    /// A solve of the power iteration failed.
    PowerIteration(LinearError),
}

impl std::fmt::Display for SetupError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SetupError::MassMatrix(e) => write!(f, "mass matrix: {e}"),
            SetupError::Assembly(m) => write!(f, "{m}"),
            SetupError::PowerIteration(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for SetupError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            SetupError::MassMatrix(e) | SetupError::PowerIteration(e) => Some(e),
            SetupError::Assembly(e) => Some(e),
        }
    }
}

impl CentralDifference {
    /// Factor the mass matrix and estimate `omega_max` at the state `q`
    /// (crease rest angles `theta0`) by power iteration on `M^-1 K`.
    pub fn new(asm: &Assembler, q: &[f64], theta0: &[f64]) -> Result<Self, SetupError> {
        let mut mass = SparseSolver::new(asm.n_free, asm.col_ptr.clone(), asm.row_idx.clone())
            .map_err(SetupError::MassMatrix)?;
        mass.factor(asm.mass_values())
            .map_err(SetupError::MassMatrix)?;
        let n = asm.n_dofs();
        let mut eval = Evaluation::default();
        let mut k = vec![0.0; asm.nnz()];
        let zeros = vec![0.0; n];
        let moment = vec![0.0; asm.creases.len()];
        let theta_prev: Vec<f64> = theta0.to_vec();
        asm.evaluate(
            &State {
                q,
                v: &zeros,
                theta0,
                moment: &moment,
                theta_prev: &theta_prev,
            },
            &mut eval,
            Some((
                &mut k,
                MatrixCoeffs {
                    k: 1.0,
                    m: 0.0,
                    c: 0.0,
                },
            )),
        )
        .map_err(SetupError::Assembly)?;
        let lambda = power_iteration(asm, &k, &mut mass)?;
        let omega = lambda.max(0.0).sqrt();
        // Rayleigh damping alpha M + beta K shrinks the limit to
        // (sqrt(1 + zeta^2) - zeta) 2 / omega with zeta = (alpha/omega + beta omega)/2.
        let p = asm.physics;
        let zeta = 0.5 * (p.alpha / omega.max(f64::MIN_POSITIVE) + p.beta * omega);
        let limit = (zeta * zeta + 1.0).sqrt() - zeta;
        let critical_step = if omega > 0.0 {
            2.0 * limit / omega
        } else {
            f64::INFINITY
        };
        Ok(CentralDifference {
            mass,
            critical_step,
            eval,
            rhs: vec![0.0; asm.n_free],
            accel_p: vec![0.0; n],
            m_accel_p: vec![0.0; n],
        })
    }

    /// The step to use: the safety fraction of the stability limit.
    pub fn stable_step(&self) -> f64 {
        SAFETY * self.critical_step
    }

    /// Advance `s` by one step of size `h` in place. Prescribed DOFs move to
    /// their values at the end of the step. Returns the time spent
    /// evaluating forces.
    pub fn step_in_place(
        &mut self,
        asm: &Assembler,
        s: &mut Dynamics,
        h: f64,
        drive: &Drive,
    ) -> Result<Duration, StepError> {
        let n = asm.n_dofs();
        for i in 0..n {
            s.v[i] += 0.5 * h * s.qdd[i];
            s.q[i] += h * s.v[i];
        }
        // Prescribed DOFs: the half-step velocity that reaches the value, and
        // the acceleration consistent with it (zero for fixed supports).
        self.accel_p.fill(0.0);
        // Fixed supports have zero acceleration: only moving prescribed DOFs
        // couple into the free ones through the mass matrix.
        let mut coupled = false;
        for &(i, x) in drive.prescribed {
            let v_start = s.v[i] - 0.5 * h * s.qdd[i];
            let q_start = s.q[i] - h * s.v[i];
            let v_half = (x - q_start) / h;
            let a = 2.0 * (v_half - v_start) / h;
            s.q[i] = x;
            s.v[i] = v_half;
            self.accel_p[i] = a;
            coupled |= a != 0.0;
        }
        let t0 = PhaseTimer::start();
        asm.evaluate(&drive.at(s), &mut self.eval, None)
            .map_err(StepError::from)?;
        let assembly_time = t0.elapsed();
        if coupled {
            asm.mass_mul(&self.accel_p, &mut self.m_accel_p);
        }
        for i in 0..n {
            let fi = asm.free[i];
            if fi != FIXED {
                let mut r = drive.f_ext[i] - self.eval.force[i];
                if coupled {
                    r -= self.m_accel_p[i];
                }
                self.rhs[fi] = r;
            }
        }
        self.mass
            .solve_in_place(&mut self.rhs)
            .map_err(StepError::Linear)?;
        for i in 0..n {
            let fi = asm.free[i];
            s.qdd[i] = if fi != FIXED {
                self.rhs[fi]
            } else {
                self.accel_p[i]
            };
            s.v[i] += 0.5 * h * s.qdd[i];
        }
        s.abar.copy_from_slice(&s.qdd);
        if s.q.iter().chain(&s.v).any(|x| !x.is_finite()) {
            return Err(StepError::Unstable);
        }
        Ok(assembly_time)
    }
}

impl Stepper for CentralDifference {
    fn policy(&self) -> StepPolicy {
        StepPolicy::Fixed(self.stable_step())
    }

    fn begin_advance(
        &mut self,
        _: &mut Assembler,
        _: &mut SparseSolver,
        _: &StepperMemory,
    ) -> Result<(), StepError> {
        Ok(())
    }

    fn step(
        &mut self,
        mech: Mechanics,
        cur: &Dynamics,
        next: &mut Dynamics,
        attempt: &Attempt,
    ) -> Result<Outcome, Failure> {
        next.clone_from(cur);
        match self.step_in_place(mech.asm, next, attempt.h, attempt.drive) {
            Ok(assembly_time) => Ok(Outcome {
                assembly_time,
                memory: attempt.memory,
                ..Outcome::default()
            }),
            Err(reason) => Err(Failure {
                reason,
                outcome: Outcome::default(),
            }),
        }
    }

    fn end_advance(&self, _: &mut StepperMemory) {}

    fn evaluation(&self) -> Option<&Evaluation> {
        Some(&self.eval)
    }

    fn crease_angles(&self) -> &[f64] {
        &self.eval.theta
    }

    fn invalidate_matrix(&mut self) {}

    fn linear_times(&self, _: &SparseSolver) -> (Duration, Duration) {
        let s = self.mass.stats();
        (s.factor_time, s.solve_time)
    }
}

/// Largest eigenvalue of `M^-1 K` on the free DOFs (`k`: matrix values in
/// the assembler's pattern, `mass`: factored), by power iteration: the norm
/// ratio `|M^-1 K x| / |x|` tends to it from below, so it is raised by 5 %.
fn power_iteration(asm: &Assembler, k: &[f64], mass: &mut SparseSolver) -> Result<f64, SetupError> {
    let nf = asm.n_free;
    if nf == 0 {
        return Ok(0.0);
    }
    // A deterministic, rough start vector excites the highest modes.
    let mut x: Vec<f64> = (0..nf)
        .map(|i| (i as f64 * 0.754_877_666_2).fract() - 0.5 + if i % 2 == 0 { 0.3 } else { -0.3 })
        .collect();
    let mut y = vec![0.0; nf];
    let mut lambda = 0.0;
    for _ in 0..300 {
        y.fill(0.0);
        for (j, &xj) in x.iter().enumerate() {
            for p in asm.col_ptr[j]..asm.col_ptr[j + 1] {
                y[asm.row_idx[p]] += k[p] * xj;
            }
        }
        mass.solve_in_place(&mut y)
            .map_err(SetupError::PowerIteration)?;
        let ny = y.iter().map(|a| a * a).sum::<f64>().sqrt();
        let nx = x.iter().map(|a| a * a).sum::<f64>().sqrt();
        let new = ny / nx;
        std::mem::swap(&mut x, &mut y);
        let scale = 1.0 / ny.max(f64::MIN_POSITIVE);
        x.iter_mut().for_each(|a| *a *= scale);
        let done = (new - lambda).abs() <= 1e-6 * new;
        lambda = new;
        if done {
            break;
        }
    }
    Ok(1.05 * lambda)
}
