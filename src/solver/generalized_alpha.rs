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

use crate::assembly::{Assembler, Evaluation, FIXED, MatrixCoeffs, State};
pub use crate::scene::NewtonMode;
use crate::solver::SparseSolver;
use crate::solver::broyden::Broyden;
use std::time::{Duration, Instant};

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
}

/// Dynamic state: positions, velocities, accelerations and the algorithmic
/// acceleration (all DOFs).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Dynamics {
    /// Positions.
    pub q: Vec<f64>,
    /// Velocities.
    pub v: Vec<f64>,
    /// Accelerations.
    pub qdd: Vec<f64>,
    /// Algorithmic accelerations.
    pub abar: Vec<f64>,
    /// How many steps in a row the extrapolated predictor guess has won
    /// (part of the state, so a restored state predicts as the original run).
    #[serde(default)]
    pub extrapolation_streak: u32,
    /// How many steps in a row the held guess has won (likewise).
    #[serde(default)]
    pub held_streak: u32,
    /// Whether the kept matrix's second correction grew the last time it
    /// was tried (likewise part of the state).
    #[serde(default)]
    pub kept_second_grew: bool,
    /// Steps since then that formed their matrix at the second iterate
    /// without trying the kept one.
    #[serde(default)]
    pub early_forms: u32,
}

/// After this many steps in a row won by one predictor guess, the other is
/// skipped (one force evaluation less per step) ...
const SKIP_LOSER_AFTER: u32 = 4;
/// ... except on every this-many-th step of the streak, where both compete again.
const RECHECK_EVERY: u32 = 8;

/// Where the kept matrix's second correction grew in the last step that
/// tried it (a folding sheet: the first correction turns the facets, and
/// a matrix formed before the turn maps bending onto membrane stretch), the
/// next steps form their matrix at the second iterate at once, saving the
/// correction that would be dropped (a force evaluation and a solve); every
/// this-many-th step tries the kept matrix again, to see whether the sheet
/// has slowed down. Measured (throughput bench, 8x8 cells at tolerance
/// 1e-3): 3.63 -> 3.11 Newton iterations per step, the same
/// factorizations, 1.18 -> 1.09 CPU s per simulated s; recheck every 2nd
/// step 3.22, every 8th 3.10; without a recheck a matrix is formed at
/// every step for good (0.95 per step against 0.75).
const EARLY_FORMS_BEFORE_RECHECK: u32 = 4;

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

/// The work of one step and, where it succeeded, its local error.
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
}

/// Reusable work vectors, and which iteration matrix the solver holds.
#[derive(Default)]
pub struct Workspace {
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
}

/// Everything the iteration matrix is a function of: the iterate, the
/// drive and the step size. Saved with the model state, so that a restored
/// state re-forms the very matrix the original run held and continues bit
/// for bit while modified Newton keeps the matrix across communication
/// points.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct JacobianPoint {
    /// Step size.
    pub h: f64,
    /// Positions of the iterate.
    pub q: Vec<f64>,
    /// Velocities of the iterate.
    pub v: Vec<f64>,
    /// Rest angles of the crease ends.
    pub theta0: Vec<f64>,
    /// Applied crease moments.
    pub moment: Vec<f64>,
    /// Unwrapped crease angles at the step start.
    pub theta_prev: Vec<f64>,
    /// Positions and velocities at the step start: what terms lag from
    /// (contact's friction), so a restore forms the same matrix.
    #[serde(default)]
    pub q_start: Vec<f64>,
    /// Velocities at the step start.
    #[serde(default)]
    pub v_start: Vec<f64>,
    /// Whether the matrix is the exact tangent (see `EXACT_AFTER_RATE`)
    /// rather than the one with the membrane stiffness lagged.
    #[serde(default)]
    pub exact: bool,
}

impl Workspace {
    /// The full evaluation (forces, energies, powers) at the last accepted
    /// state, where the step made one: only when a force term reports
    /// powers ([`Assembler::reports_power`]); outputs evaluate otherwise.
    pub fn evaluation(&self) -> Option<&Evaluation> {
        self.evaluated.then_some(&self.eval)
    }

    /// The unwrapped crease angles at the last accepted state.
    pub fn crease_angles(&self) -> &[f64] {
        &self.eval.theta
    }

    /// Forget the iteration matrix: the next step forms a fresh one (after
    /// the solver was used for something else, e.g. the mass matrix).
    pub fn invalidate_jacobian(&mut self) {
        self.jacobian = None;
    }

    /// Where the iteration matrix the solver holds was formed.
    pub fn jacobian(&self) -> Option<&JacobianPoint> {
        self.jacobian.as_ref()
    }
}

/// The weights of K, C and M in the iteration matrix for step `h` (the
/// lagged membrane stiffness where the assembler lags it).
fn matrix_coeffs(co: Coefficients, h: f64) -> MatrixCoeffs {
    let bh2 = co.beta * h * h;
    MatrixCoeffs {
        k: 1.0,
        c: co.gamma / (co.beta * h),
        m: (1.0 - co.am) / ((1.0 - co.af) * bh2),
        exact: false,
    }
}

/// Factor the iteration matrix formed at `q` (its sparse values in
/// `matrix`) with the dense low-rank part the force terms add to it.
fn factor_iteration_matrix(
    asm: &Assembler,
    solver: &mut SparseSolver,
    matrix: &[f64],
    q: &[f64],
    co: MatrixCoeffs,
) -> Result<(), String> {
    solver.factor(matrix)?;
    if let Some(lr) = asm.matrix_low_rank(q, co) {
        solver.set_low_rank(lr)?;
    }
    Ok(())
}

/// Make the solver hold the iteration matrix formed at `point` (None: no
/// matrix, the next step forms one). Nothing to do when it already does;
/// otherwise the matrix is assembled at `point` and factored, which gives
/// bit for bit the factorization the saved run held.
pub fn restore_jacobian(
    asm: &mut Assembler,
    solver: &mut SparseSolver,
    co: Coefficients,
    point: Option<&JacobianPoint>,
    ws: &mut Workspace,
) -> Result<(), String> {
    if ws.jacobian.as_ref() == point {
        return Ok(());
    }
    ws.jacobian = None;
    let Some(p) = point else {
        return Ok(());
    };
    ws.matrix.resize(asm.nnz(), 0.0);
    if !p.q_start.is_empty() {
        // The lagged data the matrix was formed with (the next step lags
        // again from its own start).
        asm.lag(&p.q_start, &p.v_start);
    }
    let st = State {
        q: &p.q,
        v: &p.v,
        theta0: &p.theta0,
        moment: &p.moment,
        theta_prev: &p.theta_prev,
    };
    let mut scratch = Evaluation::default();
    let coeffs = MatrixCoeffs {
        exact: p.exact,
        ..matrix_coeffs(co, p.h)
    };
    asm.evaluate(&st, &mut scratch, Some((&mut ws.matrix[..], coeffs)))?;
    factor_iteration_matrix(asm, solver, &ws.matrix, &p.q, coeffs)?;
    ws.jacobian = Some(p.clone());
    Ok(())
}

/// Modified Newton forms a new iteration matrix when the contraction rate
/// of the iteration exceeds this.
const MAX_RATE: f64 = 0.25;

/// Within this factor of Newton's tolerance a slow contraction of the kept
/// matrix does not at once form the matrix anew...
const NEAR_FACTOR: f64 = 10.0;

/// ...for up to this many iterations in a row (rigid Miura fold, factorizations
/// over 2 s without this rule -> with it: 4x4 205 -> 157, 10x10 184 -> 154,
/// 16x16 174 -> 167).
const NEAR_CHANCES: u32 = 3;

/// A matrix formed at the iterate whose first correction is more than this
/// times the correction before it (Newton's global phase, not its local
/// one) has shown that the membrane's geometric stiffness taken from the
/// step start is not good enough in this step: its later matrices are the
/// exact tangent. A folding sheet's fresh matrices contract at 0.01-0.2
/// and seldom meet it (rigid_fold bench, Miura 4x4..16x16: factorizations
/// 154/142/145/127 -> 150/143/143/126; throughput bench: the same
/// counts); the BoxPleatPyramid's snaps, where they contract at 0.3-1, do
/// (its second from flat: 1766 -> 1654 factorizations, 5938 -> 5626
/// Newton iterations, 4 % less CPU side by side).
const EXACT_AFTER_RATE: f64 = 0.5;

/// Newton gives up a step early (where it may be retried shorter, see
/// [`Settings::may_shorten`]) when a matrix formed at the iterate, from
/// the third iteration on, corrects by more than this times each of the
/// last two corrections applied: even Newton's own tangent sends the
/// iterate away, and the rest of the 20-iteration budget is mostly spent
/// in vain. Traced over the BoxPleatPyramid's first 0.5 s (its snaps): 34
/// of the 41 attempts that failed (about 10 factorizations each) showed
/// such a growth, 16 of them by the 7th iteration; 4 of the 568 attempts
/// that converged did too, and are now retried shorter. Smaller growths
/// happen in converging zig-zags between two gradient slots
/// (`newton_converges_on_a_moderate_hinge_step`: 5.2e-4, 2.9e-4, 1.2e-3,
/// then converged), and a large one can still converge (a quarter-period
/// step of a hinge swinging 1 rad takes all 20 iterations), hence no
/// early give-up where the step cannot be shortened. The pyramid's second
/// from flat: 1654 -> 1459 factorizations, 5626 -> 5245 Newton
/// iterations, 603 (63) -> 607 (67) steps, 321.6 -> 246.4 CPU s on the
/// idle machine. Variants, one run each: growth over the last correction
/// alone at 3x, 1449 factorizations, but it gives up the hinge's
/// zig-zags; at 5x 1471; at 2x 1620. The Miura folds never meet it
/// (rigid_fold and throughput benches: the same counts).
const DIVERGED_FRESH_RATE: f64 = 3.0;

/// Sufficient-decrease constant of Newton's line search near contact.
const ARMIJO: f64 = 0.1;

/// Most halvings of one correction in the line search.
const LINE_SEARCH_HALVINGS: usize = 8;

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

/// Settings of the Newton iteration and error estimate.
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
    /// Whether a failed attempt will be retried with a shorter step: only
    /// then does Newton give up early on an iteration that diverges
    /// (`DIVERGED_FRESH_RATE`) rather than spend its whole budget.
    pub may_shorten: bool,
}

/// Newton's velocity error against friction's stick velocity: a position
/// correction `d` left over moves the velocity by `gamma / (beta h) d`,
/// and regularized friction reads velocities below `stick_velocity` as
/// stick, so an iteration error near it lets a sticking contact creep.
const STICK_FRACTION: f64 = 1.0;

/// [`Settings::stick_bound`] of a scene whose contact has friction: scaled
/// corrections (positions over the sheet size `length`) stay below this
/// times the step, i.e. the velocity left to the iteration below
/// `STICK_FRACTION` of `stick_velocity`. Measured (tests/contact.rs, a
/// panel held by mu = 0.8 on a 30 degree incline, 0.3 s, creep allowed
/// 2.2e-4 m): at tolerance 1e-2 (Newton 1e-5) it crept 1.4e-3 m without
/// this bound, 9.5e-5 m with it. With Newton at 1e-6 the fraction was
/// varied: creep 1.4e-5 m at 0.1 and 1, 1.7e-5 m at 10, 1.5e-3 m at 100.
pub fn stick_bound(co: Coefficients, stick_velocity: f64, length: f64) -> f64 {
    STICK_FRACTION * stick_velocity * co.beta / (co.gamma * length)
}

/// A step that failed: why, and the work it took.
#[derive(Clone, Debug)]
pub struct Failure {
    /// What went wrong (Newton did not converge, an invalid state).
    pub reason: String,
    /// Newton iterations, factorizations and assembly time spent on it.
    pub outcome: Outcome,
}

/// Take one step of size `h` from `cur`. Fails with a reason (and the work
/// spent) when Newton does not converge or the state becomes invalid;
/// `cur` is untouched.
#[allow(clippy::too_many_arguments)]
pub fn step(
    asm: &Assembler,
    solver: &mut SparseSolver,
    co: Coefficients,
    cur: &Dynamics,
    h: f64,
    drive: &Drive,
    scales: &Scales,
    settings: Settings,
    ws: &mut Workspace,
) -> Result<(Dynamics, Outcome), Failure> {
    let mut out = Outcome::default();
    match step_inner(
        asm, solver, co, cur, h, drive, scales, settings, ws, &mut out,
    ) {
        Ok(next) => Ok((next, out)),
        Err(reason) => Err(Failure {
            reason,
            outcome: out,
        }),
    }
}

#[allow(clippy::too_many_arguments)]
fn step_inner(
    asm: &Assembler,
    solver: &mut SparseSolver,
    co: Coefficients,
    cur: &Dynamics,
    h: f64,
    drive: &Drive,
    scales: &Scales,
    settings: Settings,
    ws: &mut Workspace,
    out: &mut Outcome,
) -> Result<Dynamics, String> {
    let Scales {
        newton: scales,
        error: error_scales,
    } = scales;
    let n = asm.n_dofs();
    let Coefficients { am, beta, .. } = co;
    let bh2 = beta * h * h;
    let newton_tolerance = settings.newton_tolerance.min(settings.stick_bound * h);
    // Predictor: of two guesses, the one with the smaller residual. Held
    // positions (q_{n+1} = q_n) suit a folding sheet: extrapolating its
    // motion starts Newton from stretched rotating gradients and from the
    // unresolved membrane vibration in qdd_n, and meets many more
    // indefinite iteration matrices (8x8 Miura-ori folding 1 s at
    // tolerance 1e-3: 9.1 s of CPU with 4 LDLT against 19.1 s with 122 from
    // constant acceleration). Constant acceleration suits fast rigid
    // motion (a spin at 100 rad/s: 1212 Newton iterations against 3203
    // held). Choosing costs one force evaluation per step.
    ws.matrix.resize(asm.nnz(), 0.0);
    ws.rhs.resize(asm.n_free, 0.0);
    ws.mqdd.resize(n, 0.0);
    ws.dq.resize(n, 0.0);
    let mut next = cur.clone();
    let mut alt = std::mem::take(&mut ws.guess);
    alt.clone_from(cur);
    for i in 0..n {
        alt.abar[i] = (cur.qdd[i] - am * cur.abar[i]) / (1.0 - am);
        alt.q[i] = cur.q[i] + h * cur.v[i] + h * h * (0.5 - beta) * cur.abar[i] + bh2 * alt.abar[i];
    }
    // Where extrapolation keeps winning (small steps: its error falls as
    // h^3, the held guess's as h) the held guess is skipped, and re-tried
    // every RECHECK_EVERY steps of the streak or when extrapolation fails.
    // Where the held guess keeps winning (a folding sheet, whose stiff
    // modes ring in qdd_n) extrapolation is skipped alike.
    let streak = cur.extrapolation_streak;
    let skip_held = streak >= SKIP_LOSER_AFTER && streak % RECHECK_EVERY != 0;
    let held = cur.held_streak;
    let skip_extrapolated = held >= SKIP_LOSER_AFTER && held % RECHECK_EVERY != 0;
    // The size of a guess's residual (infinite where it cannot be evaluated).
    let evaluate = |k: usize, guess: &mut Dynamics, ws: &mut Workspace, out: &mut Outcome| {
        for &(i, x) in drive.prescribed {
            guess.q[i] = x;
        }
        // A guess the surfaces cannot reach without touching is no guess.
        if k == 1 {
            for i in 0..n {
                ws.dq[i] = guess.q[i] - cur.q[i];
            }
            if asm.max_step_fraction(&cur.q, &ws.dq) < 1.0 {
                return f64::INFINITY;
            }
        }
        update_rates(guess, cur, co, h);
        let t0 = Instant::now();
        let ok = residual(asm, drive, guess, ws, None).is_ok();
        out.assembly_time += t0.elapsed();
        if !ok {
            return f64::INFINITY;
        }
        if k == 0 {
            ws.first_rhs.clone_from(&ws.rhs);
        }
        // Work-like norm: force times the DOF's scale.
        (0..n)
            .filter(|&i| asm.free[i] != FIXED)
            .map(|i| (ws.rhs[asm.free[i]] * scales[i]).powi(2))
            .sum()
    };
    let mut size = [f64::INFINITY; 2];
    if skip_held {
        size[1] = evaluate(1, &mut alt, ws, out);
        if !size[1].is_finite() {
            size[0] = evaluate(0, &mut next, ws, out);
        }
    } else {
        size[0] = evaluate(0, &mut next, ws, out);
        if !(skip_extrapolated && size[0].is_finite()) {
            size[1] = evaluate(1, &mut alt, ws, out);
        }
    }
    // The winner's residual is Newton's first one (the same evaluation, so
    // the same numbers) unless the first iteration forms a matrix.
    let winner = if size[1] < size[0] {
        std::mem::swap(&mut next, &mut alt);
        1
    } else {
        if size[0].is_finite() {
            std::mem::swap(&mut ws.rhs, &mut ws.first_rhs);
        }
        0
    };
    next.extrapolation_streak = if winner == 1 { streak + 1 } else { 0 };
    next.held_streak = if winner == 0 { held + 1 } else { 0 };
    let have_rhs = size[winner].is_finite();
    ws.guess = alt;
    let mut coeffs = matrix_coeffs(co, h);
    let modified = settings.newton == NewtonMode::Modified;
    // Full Newton forms the matrix at every iterate (set in the loop);
    // modified Newton keeps one formed for a step size close to h.
    let mut refresh = match &ws.jacobian {
        Some(jp) => !(0.8..=1.25).contains(&(h / jp.h)),
        None => true,
    };
    let mut last_norm = f64::INFINITY;
    // The correction applied before the last one.
    let mut norm_before_last = f64::INFINITY;
    let mut last_rate = 0.0;
    // Slow contractions in a row let through within NEAR_FACTOR.
    let mut near_chances_used = 0u32;
    // Near contact Newton searches along each correction d: the residual
    // is the gradient of the step's incremental potential Phi (up to the
    // dashpots), and the iteration matrix is positive definite (barrier
    // Hessians projected), so d descends Phi. A correction is halved (up to
    // LINE_SEARCH_HALVINGS times) until the slope g . d at its end meets the
    // trapezoidal Armijo condition Phi(a) - Phi(0) ~ a (s0 + s(a)) / 2 <=
    // c1 a s0, i.e. s(a) <= (1 - 2 c1) |s0|. A residual-norm search is no
    // use here: a projected Newton direction need not lower |g|, and the
    // iteration then cycles against the barrier.
    let line_search = asm.limits_steps();
    // Secant updates where modified Newton keeps a matrix (not near
    // contact, whose line search needs plain Newton directions).
    let secant = modified && !line_search;
    let weights = ws.secant.reset(asm.n_free);
    for (&fi, &sc) in asm.free.iter().zip(scales) {
        if fi != FIXED {
            weights[fi] = 1.0 / (sc * sc);
        }
    }
    // Slope g . d at the iterate a correction started from (negative).
    let mut slope0 = 0.0;
    // Whether a barrier acted where the last correction started.
    let mut barrier_before = true;
    let mut applied = 0.0;
    for it in 0..settings.max_newton {
        refresh |= !modified;
        if it == 1
            && modified
            && cur.kept_second_grew
            && cur.early_forms < EARLY_FORMS_BEFORE_RECHECK
        {
            if !refresh {
                next.early_forms = cur.early_forms + 1;
            }
            refresh = true;
        }
        update_rates(&mut next, cur, co, h);
        if line_search && it > 0 && slope0 < 0.0 {
            let t0 = Instant::now();
            residual(asm, drive, &next, ws, None)?;
            let mut tries = 0;
            // Away from the barrier the plain Newton step stands.
            while (barrier_before || ws.eval.barrier_pairs > 0)
                && slope_along(asm, &ws.rhs, &ws.dq) > (1.0 - 2.0 * ARMIJO) * -slope0
                && tries < LINE_SEARCH_HALVINGS
            {
                applied *= 0.5;
                for i in 0..n {
                    next.q[i] -= applied * ws.dq[i];
                }
                update_rates(&mut next, cur, co, h);
                residual(asm, drive, &next, ws, None)?;
                tries += 1;
            }
            if tries > 0 {
                out.line_search_cuts += 1;
            }
            if refresh {
                residual(asm, drive, &next, ws, Some(coeffs))?;
            }
            out.assembly_time += t0.elapsed();
        } else if !(it == 0 && have_rhs && !refresh) {
            let t0 = Instant::now();
            residual(asm, drive, &next, ws, refresh.then_some(coeffs))?;
            out.assembly_time += t0.elapsed();
        }
        if line_search {
            ws.rhs_prev.clone_from(&ws.rhs);
            // (The first iterate's evaluation may be the other guess's.)
            barrier_before = ws.eval.barrier_pairs > 0;
        }
        // Whether the matrix was formed at this iterate (else it is stale:
        // formed at an earlier iterate or step).
        let stale = !refresh;
        if refresh {
            // Record where the matrix is formed (buffers reused).
            let mut jp = ws.jacobian.take().unwrap_or_default();
            factor_iteration_matrix(asm, solver, &ws.matrix, &next.q, coeffs)?;
            jp.h = h;
            jp.q.clone_from(&next.q);
            jp.v.clone_from(&next.v);
            jp.theta0.clear();
            jp.theta0.extend_from_slice(drive.theta0);
            jp.moment.clear();
            jp.moment.extend_from_slice(drive.moment);
            jp.theta_prev.clear();
            jp.theta_prev.extend_from_slice(drive.theta_prev);
            jp.q_start.clone_from(&cur.q);
            jp.v_start.clone_from(&cur.v);
            jp.exact = coeffs.exact;
            ws.jacobian = Some(jp);
            out.factorizations += 1;
            refresh = false;
            ws.secant.clear();
        }
        solver.solve_in_place(&mut ws.rhs)?;
        out.iterations = it + 1;
        let scaled_norm = |x: &[f64]| {
            let mut norm: f64 = 0.0;
            for (&fi, &scale) in asm.free.iter().zip(scales) {
                if fi != FIXED {
                    norm = norm.max(x[fi].abs() / scale);
                }
            }
            norm
        };
        // The plain correction's size against the last correction applied:
        // the contraction rate of the iteration (modified Newton converges
        // linearly: the remaining error is about rate / (1 - rate) times
        // the last correction).
        let plain = scaled_norm(&ws.rhs);
        let rate = plain / last_norm;
        // The correction applied: the plain one through the secant updates.
        let norm = if secant && stale {
            ws.secant.correct(&mut ws.rhs);
            scaled_norm(&ws.rhs)
        } else {
            plain
        };
        if !norm.is_finite() {
            return Err("Newton produced non-finite values".into());
        }
        if settings.may_shorten
            && !stale
            && it >= 2
            && norm > DIVERGED_FRESH_RATE * last_norm.max(norm_before_last)
        {
            return Err(format!(
                "Newton diverged (the matrix formed at iteration {} corrects by {norm:.3e}, more than {DIVERGED_FRESH_RATE} times each of the two corrections before)",
                it + 1
            ));
        }
        if !stale && it >= 1 && rate > EXACT_AFTER_RATE {
            coeffs.exact = true;
        }
        if it == 1 && stale {
            next.kept_second_grew = rate > 1.0;
            next.early_forms = 0;
        }
        if modified && stale && rate > 1.0 && it + 1 < settings.max_newton {
            // A matrix formed elsewhere sends the iterate away: drop this
            // correction and form the matrix here.
            refresh = true;
            slope0 = 0.0;
            ws.secant.clear();
            continue;
        }
        for i in 0..n {
            let fi = asm.free[i];
            ws.dq[i] = if fi != FIXED { ws.rhs[fi] } else { 0.0 };
        }
        if line_search {
            slope0 = slope_along(asm, &ws.rhs_prev, &ws.dq);
        }
        // Force terms may admit only part of the step (contact: the largest
        // collision-free fraction); the iteration then goes on from there.
        let fraction = asm.max_step_fraction(&next.q, &ws.dq);
        if fraction <= 0.0 {
            return Err("contact: no collision-free Newton step".into());
        }
        if fraction < 1.0 {
            // The matrix did not see the contact that stopped the step.
            out.limited_steps += 1;
            refresh |= stale;
        }
        for i in 0..n {
            next.q[i] += fraction * ws.dq[i];
        }
        applied = fraction;
        if secant {
            ws.secant.applied(&ws.rhs, fraction == 1.0);
        }
        let remaining = if fraction < 1.0 {
            f64::INFINITY
        } else if modified && stale {
            if rate < 1.0 {
                norm * (rate / (1.0 - rate)).max(1.0)
            } else {
                f64::INFINITY
            }
        } else {
            norm
        };
        // A fresh matrix that stops contracting this close to the tolerance
        // has reached the round-off floor of an ill-conditioned (thin,
        // membrane-stiff) system: as converged as it gets.
        let floor = !stale && it >= 2 && rate > 0.5 && norm <= 100.0 * newton_tolerance;
        if remaining <= newton_tolerance || floor {
            // Final consistent update. The converged state is evaluated in
            // full only where a term's powers are integrated over the step
            // (contact's friction work); otherwise only its crease angles
            // (the next step's unwrapping reference) are needed here, and
            // outputs evaluate forces and energies where they are read.
            update_rates(&mut next, cur, co, h);
            let t0 = Instant::now();
            ws.evaluated = asm.reports_power();
            if ws.evaluated {
                asm.evaluate(&drive.at(&next), &mut ws.eval, None)?;
            } else {
                asm.crease_angles(&next.q, drive.theta_prev, &mut ws.eval.theta)?;
            }
            out.assembly_time += t0.elapsed();
            out.error = local_error(&next, cur, asm, h, beta, error_scales, settings.tolerance);
            return Ok(next);
        }
        // Diverging: the correction grew twice in a row (one growth alone
        // happens in a converging zig-zag between slots).
        if it >= 3 && rate > 2.0 && last_rate > 2.0 {
            return Err(format!(
                "Newton diverged (correction {norm:.3e} after {} iterations)",
                it + 1
            ));
        }
        // Slow contraction: the iterate has moved far from where the matrix
        // was formed; form it anew at the next iterate. Within NEAR_FACTOR
        // of the tolerance the rate of two tiny corrections says little
        // (they are no longer a geometric sequence: 4x4 Miura folding,
        // a rate of 0.68 read there, where the error fell 6-fold), so slow
        // contractions there get up to NEAR_CHANCES more iterations first;
        // a diverging iterate refreshes as soon as it leaves the band.
        let slow = rate > MAX_RATE;
        let near = norm <= NEAR_FACTOR * newton_tolerance;
        let let_through = slow && near && near_chances_used < NEAR_CHANCES;
        if modified && stale && slow && !let_through && it + 1 < settings.max_newton {
            refresh = true;
        }
        near_chances_used = if let_through {
            near_chances_used + 1
        } else {
            0
        };
        last_rate = rate;
        norm_before_last = last_norm;
        last_norm = norm;
    }
    Err(format!(
        "Newton did not converge in {} iterations",
        settings.max_newton
    ))
}

/// Evaluate at `d` and write the negated residual of the equation of
/// motion, f_ext - M qdd - f, into `ws.rhs` (free DOFs); with `matrix`,
/// also the iteration matrix into `ws.matrix`.
fn residual(
    asm: &Assembler,
    drive: &Drive,
    d: &Dynamics,
    ws: &mut Workspace,
    matrix: Option<MatrixCoeffs>,
) -> Result<(), String> {
    asm.evaluate(
        &drive.at(d),
        &mut ws.eval,
        matrix.map(|co| (&mut ws.matrix[..], co)),
    )?;
    asm.mass_mul(&d.qdd, &mut ws.mqdd);
    for i in 0..d.q.len() {
        let fi = asm.free[i];
        if fi != FIXED {
            ws.rhs[fi] = -(ws.mqdd[i] + ws.eval.force[i] - drive.f_ext[i]);
        }
    }
    Ok(())
}

/// Slope `g . dq` of the incremental potential along the correction `dq`
/// (all DOFs), where `rhs = -g` on the free DOFs.
fn slope_along(asm: &Assembler, rhs: &[f64], dq: &[f64]) -> f64 {
    asm.free
        .iter()
        .zip(dq)
        .filter(|&(&fi, _)| fi != FIXED)
        .map(|(&fi, &d)| -rhs[fi] * d)
        .sum()
}

/// Local error estimate h^2 |beta - 1/6| (qdd_{n+1} - qdd_n) (at least
/// h^2/24 of it), RMS over the free DOFs, scaled by tolerance and DOF size.
fn local_error(
    next: &Dynamics,
    cur: &Dynamics,
    asm: &Assembler,
    h: f64,
    beta: f64,
    scales: &[f64],
    tolerance: f64,
) -> f64 {
    let c = h * h * (beta - 1.0 / 6.0).abs().max(1.0 / 24.0);
    let mut sum = 0.0;
    let mut cnt = 0usize;
    for (i, &fi) in asm.free.iter().enumerate() {
        if fi != FIXED {
            let e = c * (next.qdd[i] - cur.qdd[i]) / (tolerance * scales[i]);
            sum += e * e;
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
