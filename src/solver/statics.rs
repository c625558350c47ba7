//! Static equilibrium `f_int(q) = lambda f_ext + extra(q)` followed from
//! `lambda = 0` to 1 by Newton's method with adaptive load stepping and a
//! line search. Used for the benchmarks with known static answers.
//!
//! Each increment starts from the last converged state moved along the
//! secant of the previous increment, then iterates Newton steps with the
//! analytic tangent, each scaled by a line search on the energy slope
//! (Crisfield). An increment that does not converge is retried with half the
//! size; easy increments let the size grow back to `1 / load_steps`.

use crate::assembly::{Assembler, EvalError, Evaluation, FIXED, MatrixCoeffs, State};
use crate::solver::{LinearError, SparseSolver};

/// A load that depends on the configuration (e.g. an end moment acting on
/// a rotation angle): adds `-dV/dq` scaled by `lambda` to `force` and, if
/// given, the matching `d2V/dq2` to the matrix values.
pub trait Load {
    /// Add `lambda * (-dV/dq)` to `force_ext` and `lambda * d2V/dq2` to `matrix`.
    fn apply(
        &self,
        asm: &Assembler,
        q: &[f64],
        lambda: f64,
        force_ext: &mut [f64],
        matrix: Option<&mut [f64]>,
    );
}

/// Safety factor of the round-off floor of the residual (see
/// `Newton::round_off_floor`): the floors met on the case A strip were 0.3
/// to 1.7 times `EPSILON * norm(|K| |q|)`.
const ROUND_OFF_FACTOR: f64 = 10.0;

/// Settings of the static solve.
#[derive(Clone, Copy, Debug)]
pub struct StaticSettings {
    /// The largest load increment is `1 / load_steps` (the first one too).
    pub load_steps: usize,
    /// Maximum Newton iterations per increment before it is cut.
    pub max_iterations: usize,
    /// Converged when the residual norm is below `tolerance` times the
    /// external force norm, or at its round-off floor (below ten times
    /// `EPSILON * norm(|K| |q|)`, which scales with the stiffness and the
    /// size, so fine and thin meshes converge at any tolerance), or when the
    /// work of a Newton correction is below 1e-16 of the increment's first.
    pub tolerance: f64,
    /// Give up when an increment would have to be smaller than this.
    pub min_increment: f64,
}

impl Default for StaticSettings {
    fn default() -> Self {
        StaticSettings {
            load_steps: 10,
            max_iterations: 50,
            tolerance: 1e-9,
            min_increment: 1e-6,
        }
    }
}

/// What a static solve did.
#[derive(Clone, Debug, Default)]
pub struct StaticReport {
    /// Load factor reached by each accepted increment.
    pub lambdas: Vec<f64>,
    /// Newton iterations of each accepted increment.
    pub iterations: Vec<usize>,
    /// Final relative residual norm of each accepted increment.
    pub residuals: Vec<f64>,
    /// Increments that failed and were retried at half the size.
    pub cuts: usize,
    /// Newton iterations spent in those failed increments.
    pub wasted_iterations: usize,
}

impl StaticReport {
    /// All Newton iterations, failed increments included.
    pub fn total_iterations(&self) -> usize {
        self.iterations.iter().sum::<usize>() + self.wasted_iterations
    }
}

/// Why a static solve failed or was refused.
#[derive(Clone, Debug, PartialEq)]
pub enum StaticsError {
    /// `q` does not have one value per DOF.
    StateSize {
        /// Values given.
        values: usize,
        /// DOFs of the model.
        dofs: usize,
    },
    /// `theta0` does not have one rest angle per crease end.
    RestAngleCount {
        /// Angles given.
        angles: usize,
        /// Crease ends of the model.
        crease_ends: usize,
    },
    /// `load_steps` or `max_iterations` is zero.
    ZeroBudget,
    /// `tolerance` or `min_increment` is not positive and finite (or
    /// `min_increment` above 1).
    BadTolerance,
    /// The stops do not increase within (0, 1].
    BadStops,
    /// `q` has non-finite values.
    NonFiniteState,
    /// The sparse solver could not be set up.
    Linear(LinearError),
    /// Forces could not be evaluated.
    Assembly(EvalError),
    /// The load (or the residual) is not finite.
    NonFiniteLoad,
    /// An increment failed and a smaller one would be below `min_increment`.
    IncrementFailed {
        /// The last converged load factor.
        lambda: f64,
        /// The increment that failed.
        increment: f64,
        /// What Newton did ("did not converge", ...).
        reason: &'static str,
        /// Relative residual at the end.
        residual: f64,
        /// Iterations spent.
        iterations: usize,
        /// The smallest increment tried.
        min_increment: f64,
    },
}

impl std::fmt::Display for StaticsError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StaticsError::StateSize { values, dofs } => {
                write!(f, "static solve: q has {values} values, the model {dofs}")
            }
            StaticsError::RestAngleCount {
                angles,
                crease_ends,
            } => write!(
                f,
                "static solve: {angles} rest angles for {crease_ends} crease ends"
            ),
            StaticsError::ZeroBudget => write!(
                f,
                "static solve: load_steps and max_iterations must be positive"
            ),
            StaticsError::BadTolerance => write!(
                f,
                "static solve: tolerance and min_increment must be positive and finite"
            ),
            StaticsError::BadStops => write!(f, "static solve: stops must increase within (0, 1]"),
            StaticsError::NonFiniteState => write!(f, "static solve: q has non-finite values"),
            StaticsError::Linear(e) => write!(f, "{e}"),
            StaticsError::Assembly(m) => write!(f, "{m}"),
            StaticsError::NonFiniteLoad => write!(f, "the load is not finite"),
            StaticsError::IncrementFailed {
                lambda,
                increment,
                reason,
                residual,
                iterations,
                min_increment,
            } => write!(
                f,
                "static solve failed at load factor {lambda:.6}: an increment of {increment:.3e} {reason} \
                 (relative residual {residual:.3e} after {iterations} iterations) and increments below {min_increment:.1e} are not tried"
            ),
        }
    }
}

impl std::error::Error for StaticsError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            StaticsError::Linear(e) => Some(e),
            StaticsError::Assembly(e) => Some(e),
            _ => None,
        }
    }
}

/// Solve for equilibrium starting from `q` (updated in place). Fixed DOFs
/// keep their values in `q`. `theta0` are the crease rest angles; crease
/// angles are unwrapped from the flat state (pi) at the start.
pub fn solve(
    asm: &Assembler,
    q: &mut [f64],
    theta0: &[f64],
    load: &dyn Load,
    settings: StaticSettings,
) -> Result<StaticReport, StaticsError> {
    solve_path(asm, q, theta0, load, settings, &[], |_, _, _| {})
}

/// Like [`solve`], with increments that land exactly on each load factor in
/// `stops` (increasing, within (0, 1]), where `at_stop(lambda, q, report)`
/// sees the converged state. So one load path yields several load levels.
pub fn solve_path(
    asm: &Assembler,
    q: &mut [f64],
    theta0: &[f64],
    load: &dyn Load,
    settings: StaticSettings,
    stops: &[f64],
    mut at_stop: impl FnMut(f64, &[f64], &StaticReport),
) -> Result<StaticReport, StaticsError> {
    check_inputs(asm, q, theta0, &settings, stops)?;
    let mut newton = Newton::new(asm, theta0, load)?;
    let mut report = StaticReport::default();
    let max_step = 1.0 / settings.load_steps as f64;
    // Unwrapped crease angles of the start, measured from the flat state.
    let flat = vec![std::f64::consts::PI; asm.creases.len()];
    newton.residual(q, 0.0, &flat, false)?;
    let mut theta_prev = newton.ev.theta.clone();

    let mut lambda = 0.0;
    let mut step = max_step;
    // Secant of the last accepted increment (free DOFs), per unit load.
    let mut rate: Option<Vec<f64>> = None;
    let mut q_start = q.to_vec();
    let mut next_stop = 0;
    while lambda < 1.0 {
        let target = stops.get(next_stop).copied().unwrap_or(1.0);
        // Land on the target rather than leave a sliver of rounding.
        let lambda_new = if target - lambda <= step * (1.0 + 1e-9) {
            target
        } else {
            lambda + step
        };
        let dl = lambda_new - lambda;
        if let Some(r) = &rate {
            for i in 0..q.len() {
                if asm.free[i] != FIXED {
                    q[i] = q_start[i] + dl * r[i];
                }
            }
        }
        match newton.iterate(q, lambda_new, &theta_prev, &settings) {
            Ok((its, res)) => {
                rate = Some(q.iter().zip(&q_start).map(|(a, b)| (a - b) / dl).collect());
                q_start.copy_from_slice(q);
                theta_prev.clone_from(&newton.ev.theta);
                lambda = lambda_new;
                report.lambdas.push(lambda);
                report.iterations.push(its);
                report.residuals.push(res);
                if its <= settings.max_iterations / 2 {
                    step = (2.0 * step).min(max_step);
                }
                if lambda == target && next_stop < stops.len() {
                    next_stop += 1;
                    at_stop(lambda, q, &report);
                }
            }
            Err(fail) => {
                q.copy_from_slice(&q_start);
                report.cuts += 1;
                report.wasted_iterations += fail.iterations;
                step = 0.5 * dl;
                if step < settings.min_increment {
                    return Err(StaticsError::IncrementFailed {
                        lambda,
                        increment: dl,
                        reason: fail.reason,
                        residual: fail.residual,
                        iterations: fail.iterations,
                        min_increment: settings.min_increment,
                    });
                }
            }
        }
    }
    Ok(report)
}

/// Reject inputs that would make the solve index out of range or loop.
fn check_inputs(
    asm: &Assembler,
    q: &[f64],
    theta0: &[f64],
    settings: &StaticSettings,
    stops: &[f64],
) -> Result<(), StaticsError> {
    if q.len() != asm.n_dofs() {
        return Err(StaticsError::StateSize {
            values: q.len(),
            dofs: asm.n_dofs(),
        });
    }
    if theta0.len() != asm.creases.len() {
        return Err(StaticsError::RestAngleCount {
            angles: theta0.len(),
            crease_ends: asm.creases.len(),
        });
    }
    if settings.load_steps == 0 || settings.max_iterations == 0 {
        return Err(StaticsError::ZeroBudget);
    }
    let tolerance_ok = settings.tolerance > 0.0 && settings.tolerance.is_finite();
    let increment_ok = settings.min_increment > 0.0 && settings.min_increment <= 1.0;
    if !(tolerance_ok && increment_ok) {
        return Err(StaticsError::BadTolerance);
    }
    if stops.iter().any(|s| !(*s > 0.0 && *s <= 1.0)) || stops.windows(2).any(|w| w[1] <= w[0]) {
        return Err(StaticsError::BadStops);
    }
    if q.iter().any(|x| !x.is_finite()) {
        return Err(StaticsError::NonFiniteState);
    }
    Ok(())
}

/// Why one increment failed.
struct Failure {
    reason: &'static str,
    iterations: usize,
    residual: f64,
}

/// Buffers of the Newton iteration at one load factor.
struct Newton<'a> {
    asm: &'a Assembler,
    theta0: &'a [f64],
    load: &'a dyn Load,
    solver: SparseSolver,
    zeros: Vec<f64>,
    moment: Vec<f64>,
    ev: Evaluation,
    mat: Vec<f64>,
    fext: Vec<f64>,
    rhs: Vec<f64>,
    q0: Vec<f64>,
    /// DOF index of each free unknown.
    dof_of_free: Vec<usize>,
}

impl<'a> Newton<'a> {
    fn new(
        asm: &'a Assembler,
        theta0: &'a [f64],
        load: &'a dyn Load,
    ) -> Result<Self, StaticsError> {
        let n = asm.n_dofs();
        Ok(Newton {
            asm,
            theta0,
            load,
            solver: SparseSolver::new(asm.n_free, asm.col_ptr.clone(), asm.row_idx.clone())
                .map_err(StaticsError::Linear)?,
            zeros: vec![0.0; n],
            moment: vec![0.0; asm.creases.len()],
            ev: Evaluation::default(),
            mat: vec![0.0; asm.nnz()],
            fext: vec![0.0; n],
            rhs: vec![0.0; asm.n_free],
            q0: vec![0.0; n],
            dof_of_free: (0..n).filter(|&i| asm.free[i] != FIXED).collect(),
        })
    }

    /// Evaluate forces (and the tangent if asked) at `q`; return the free
    /// residual norm and leave `f_int` in `ev.force`, `f_ext` in `fext`.
    fn residual(
        &mut self,
        q: &[f64],
        lambda: f64,
        theta_prev: &[f64],
        tangent: bool,
    ) -> Result<f64, StaticsError> {
        let st = State {
            q,
            v: &self.zeros,
            theta0: self.theta0,
            moment: &self.moment,
            theta_prev,
        };
        self.fext.iter_mut().for_each(|x| *x = 0.0);
        if tangent {
            let co = MatrixCoeffs {
                k: 1.0,
                m: 0.0,
                c: 0.0,
            };
            self.asm
                .evaluate(&st, &mut self.ev, Some((&mut self.mat, co)))
                .map_err(StaticsError::Assembly)?;
            self.load
                .apply(self.asm, q, lambda, &mut self.fext, Some(&mut self.mat));
        } else {
            self.asm
                .evaluate(&st, &mut self.ev, None)
                .map_err(StaticsError::Assembly)?;
            self.load.apply(self.asm, q, lambda, &mut self.fext, None);
        }
        let r2: f64 = (0..q.len())
            .filter(|&i| self.asm.free[i] != FIXED)
            .map(|i| (self.ev.force[i] - self.fext[i]).powi(2))
            .sum();
        if !r2.is_finite() || self.fext.iter().any(|x| !x.is_finite()) {
            return Err(StaticsError::NonFiniteLoad);
        }
        Ok(r2.sqrt())
    }

    /// What round-off leaves in the free residual at `q`: the internal forces
    /// sum terms as large as `|K| |q|` (positions and gradients times
    /// stiffness), each carrying a relative error of a few `f64::EPSILON`, so
    /// a residual below `ROUND_OFF_FACTOR * EPSILON * norm(|K| |q|)` is as
    /// converged as it can be (the tangent in `mat` belongs to `q`).
    fn round_off_floor(&self, q: &[f64]) -> f64 {
        let (col_ptr, row_idx) = (&self.asm.col_ptr, &self.asm.row_idx);
        let mut s = vec![0.0; self.asm.n_free];
        for (col, &dof) in self.dof_of_free.iter().enumerate() {
            let x = q[dof].abs();
            for p in col_ptr[col]..col_ptr[col + 1] {
                s[row_idx[p]] += self.mat[p].abs() * x;
            }
        }
        ROUND_OFF_FACTOR * f64::EPSILON * s.iter().map(|x| x * x).sum::<f64>().sqrt()
    }

    /// Energy slope `dq . (f_ext - f_int)` at `q0 + alpha dq` (`dq` in
    /// `rhs`); `None` where the configuration cannot be evaluated.
    fn slope(&mut self, q: &mut [f64], alpha: f64, lambda: f64, theta_prev: &[f64]) -> Option<f64> {
        let free = &self.asm.free;
        for i in 0..q.len() {
            if free[i] != FIXED {
                q[i] = self.q0[i] + alpha * self.rhs[free[i]];
            }
        }
        self.residual(q, lambda, theta_prev, false).ok()?;
        let s: f64 = (0..q.len())
            .filter(|&i| free[i] != FIXED)
            .map(|i| self.rhs[free[i]] * (self.fext[i] - self.ev.force[i]))
            .sum();
        s.is_finite().then_some(s)
    }

    /// Newton iterations at load factor `lambda` from `q`; on success the
    /// iterations and the final relative residual, with `ev.theta` the
    /// unwrapped crease angles of the converged `q`.
    fn iterate(
        &mut self,
        q: &mut [f64],
        lambda: f64,
        theta_prev: &[f64],
        settings: &StaticSettings,
    ) -> Result<(usize, f64), Failure> {
        let n = q.len();
        let mut first_work = 0.0;
        let mut rel = f64::NAN;
        let fail = |reason, iterations, residual| Failure {
            reason,
            iterations,
            residual,
        };
        for it in 1..=settings.max_iterations {
            let rnorm = self
                .residual(q, lambda, theta_prev, true)
                .map_err(|_| fail("reached a configuration that cannot be evaluated", it, rel))?;
            let fref = self.fext.iter().map(|x| x * x).sum::<f64>().sqrt();
            rel = rnorm / fref.max(1e-300);
            if rnorm <= settings.tolerance * fref || rnorm <= self.round_off_floor(q) {
                return Ok((it, rel));
            }
            for i in 0..n {
                let fi = self.asm.free[i];
                if fi != FIXED {
                    self.rhs[fi] = self.fext[i] - self.ev.force[i];
                }
            }
            let b = self.rhs.clone();
            self.solver
                .factor(&self.mat)
                .and_then(|_| self.solver.solve_in_place(&mut self.rhs))
                .map_err(|_| fail("met a singular tangent", it, rel))?;
            // Energy criterion (Bathe): the work of the correction against the
            // residual, relative to the first one of this increment. It stays
            // meaningful where the force residual hits its round-off floor
            // (thin sheets: membrane stiffness >> load).
            let work = self
                .rhs
                .iter()
                .zip(&b)
                .map(|(x, y)| x * y)
                .sum::<f64>()
                .abs();
            if it == 1 {
                first_work = work;
            } else if work <= 1e-16 * first_work {
                return Ok((it, rel));
            }
            // Line search on the energy slope along the step (Crisfield):
            // s(alpha) = dq . R(q + alpha dq) should vanish; accept the full
            // step when |s(1)| <= 0.8 |s(0)|, else take secant steps.
            self.q0.copy_from_slice(q);
            let s0: f64 = self.rhs.iter().zip(&b).map(|(x, y)| x * y).sum();
            let (mut a_lo, mut s_lo, mut alpha) = (0.0, s0, 1.0);
            for _ in 0..8 {
                match self.slope(q, alpha, lambda, theta_prev) {
                    Some(s) if s.abs() <= 0.8 * s0.abs() => break,
                    Some(s) => {
                        let next = if (s_lo - s).abs() > 0.0 {
                            alpha - s * (alpha - a_lo) / (s - s_lo)
                        } else {
                            0.5 * alpha
                        };
                        a_lo = alpha;
                        s_lo = s;
                        alpha = next.clamp(0.05, 4.0);
                    }
                    None => alpha *= 0.25,
                }
            }
            if self.slope(q, alpha, lambda, theta_prev).is_none() {
                return Err(fail("left the valid configurations", it, rel));
            }
        }
        Err(fail("did not converge", settings.max_iterations, rel))
    }
}
