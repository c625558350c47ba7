//! Newton's iteration on q_{n+1}, one iteration in five phases: evaluate
//! the residual (with a line search near contact), form and factor the
//! iteration matrix where the rules ask for it, solve for the correction
//! and screen it, apply it (as far as contact admits), check convergence.
//!
//! Full Newton forms the matrix at every iterate. Modified Newton keeps a
//! matrix across iterations and steps and forms it anew where it serves
//! badly: a correction that grows, a contraction slower than
//! [`IntegrationParameters::max_rate`], a step size far from the one it was
//! formed for. Its matrix takes the membrane's geometric stiffness from the
//! step start.
//!
//! Near contact Newton searches along each correction d: the residual is
//! the gradient of the step's incremental potential Phi (up to the
//! dashpots), and the iteration matrix is positive definite (barrier
//! Hessians projected), so d descends Phi. A correction is halved until
//! the slope g . d at its end meets the trapezoidal Armijo condition
//! Phi(a) - Phi(0) ~ a (s0 + s(a)) / 2 <= c1 a s0, i.e. s(a) <= (1 - 2 c1)
//! |s0|. A residual-norm search is no use here: a projected Newton
//! direction need not lower |g|, and the iteration then cycles against the
//! barrier.

use super::{StepContext, Workspace, matrix};
use crate::assembly::{Assembler, FIXED, MatrixCoeffs};
use crate::solver::SparseSolver;
use crate::solver::stepper::{Dynamics, Outcome, StepError};
use crate::solver::{IntegrationParameters, NewtonMode};
// Phase times are CPU time, read where phase timing is on (phase_timer).
use crate::solver::phase_timer::PhaseTimer;

/// One step's iteration: its settings and what it remembers from one
/// iteration to the next.
struct Newton {
    /// Modified (else full) Newton.
    modified: bool,
    /// A force term limits the step (contact in touch): line search.
    line_search: bool,
    /// Secant updates of a kept matrix.
    secant: bool,
    /// Every scaled correction below this: converged.
    tolerance: f64,
    /// The iteration matrix's weights.
    coeffs: MatrixCoeffs,
    /// Form the matrix at the next iterate.
    refresh: bool,
    /// The last correction applied (scaled).
    last_norm: f64,
    /// The correction applied before the last one.
    norm_before_last: f64,
    /// The contraction rate of the last iteration.
    last_rate: f64,
    /// Slow contractions in a row let through near the tolerance.
    near_chances_used: u32,
    /// Slope g . d at the iterate a correction started from (negative).
    slope0: f64,
    /// Whether a barrier acted where the last correction started.
    barrier_before: bool,
    /// The fraction of the last correction applied.
    applied: f64,
}

/// What the screen makes of a correction.
enum Screen {
    /// Apply it.
    Apply,
    /// Drop it and form the matrix here.
    Drop,
}

/// Iterate from the predicted `next` (whose residual is in `ws.rhs` when
/// `have_rhs`) to convergence; `next` is then the step's end state.
pub(super) fn iterate(
    ctx: &StepContext,
    solver: &mut SparseSolver,
    have_rhs: bool,
    next: &mut Dynamics,
    ws: &mut Workspace,
    out: &mut Outcome,
) -> Result<(), StepError> {
    let max_newton = ctx.settings.max_newton;
    let mut nw = Newton::start(ctx, ws);
    for it in 0..max_newton {
        if ctx.deadline.is_some_and(|d| d.passed()) {
            return Err(StepError::OutOfTime);
        }
        nw.choose_matrix();
        ctx.update_rates(next);
        nw.evaluate(ctx, it, have_rhs, next, ws, out)?;
        // Whether the matrix was formed at this iterate (else it is stale:
        // formed at an earlier iterate or step).
        let stale = !nw.refresh;
        if nw.refresh {
            nw.form(ctx, solver, next, ws, out)?;
        }
        solver
            .solve_in_place(&mut ws.rhs)
            .map_err(StepError::Linear)?;
        out.iterations = it + 1;
        let (rate, norm) = nw.measure(ctx.asm, &ctx.scales.newton, stale, ws);
        if let Screen::Drop = nw.screen(ctx, it, stale, rate, norm, ws)? {
            continue;
        }
        let fraction = nw.apply(ctx.asm, stale, next, ws, out)?;
        if nw.converged(ctx.params, it, stale, rate, norm, fraction) {
            return finish(ctx, next, ws, out);
        }
        nw.prepare_next(ctx, it, stale, rate, norm)?;
    }
    Err(StepError::NotConverged {
        iterations: max_newton,
    })
}

impl Newton {
    /// The iteration's settings, and the secant history reset.
    fn start(ctx: &StepContext, ws: &mut Workspace) -> Newton {
        let (asm, p, settings) = (ctx.asm, ctx.params, ctx.settings);
        let modified = settings.newton == NewtonMode::Modified;
        let line_search = asm.limits_steps();
        // Secant updates where modified Newton keeps a matrix (not near
        // contact, whose line search needs plain Newton directions).
        let secant = modified && !line_search && p.secant_updates;
        let weights = ws.secant.reset(asm.n_free);
        for (&fi, &sc) in asm.free.iter().zip(&ctx.scales.newton) {
            if fi != FIXED {
                weights[fi] = 1.0 / (sc * sc);
            }
        }
        // Modified Newton keeps a matrix formed for a step size close to h.
        let r = p.kept_matrix_ratio;
        let refresh = match &ws.jacobian {
            Some(jp) => !(1.0 / r..=r).contains(&(ctx.h / jp.h)),
            None => true,
        };
        Newton {
            modified,
            line_search,
            secant,
            tolerance: settings.newton_tolerance.min(settings.stick_bound * ctx.h),
            coeffs: ctx.co.matrix(ctx.h),
            refresh,
            last_norm: f64::INFINITY,
            norm_before_last: f64::INFINITY,
            last_rate: 0.0,
            near_chances_used: 0,
            slope0: 0.0,
            barrier_before: true,
            applied: 0.0,
        }
    }

    /// Full Newton forms the matrix at every iterate.
    fn choose_matrix(&mut self) {
        self.refresh |= !self.modified;
    }

    /// The residual at the iterate (and the matrix where it is to be
    /// formed); near contact the last correction is first shortened until
    /// the incremental potential's slope meets the Armijo condition.
    fn evaluate(
        &mut self,
        ctx: &StepContext,
        it: usize,
        have_rhs: bool,
        next: &mut Dynamics,
        ws: &mut Workspace,
        out: &mut Outcome,
    ) -> Result<(), StepError> {
        let matrix = self.refresh.then_some(self.coeffs);
        if self.line_search && it > 0 && self.slope0 < 0.0 {
            let t0 = PhaseTimer::start();
            // With the matrix where it is to be formed: most corrections
            // stand, and their end is where it is formed.
            ctx.residual(next, ws, matrix)?;
            let p = ctx.params;
            let mut tries = 0;
            // Away from the barrier the plain Newton step stands.
            while (self.barrier_before || ws.eval.barrier_pairs > 0)
                && slope_along(ctx.asm, &ws.rhs, &ws.dq) > (1.0 - 2.0 * p.armijo) * -self.slope0
                && tries < p.line_search_halvings
            {
                self.applied *= 0.5;
                for (q, d) in next.q.iter_mut().zip(&ws.dq) {
                    *q -= self.applied * d;
                }
                ctx.update_rates(next);
                ctx.residual(next, ws, None)?;
                tries += 1;
            }
            if tries > 0 {
                out.line_search_cuts += 1;
                if self.refresh {
                    ctx.residual(next, ws, matrix)?;
                }
            }
            out.assembly_time += t0.elapsed();
        } else if !(it == 0 && have_rhs && !self.refresh) {
            let t0 = PhaseTimer::start();
            ctx.residual(next, ws, matrix)?;
            out.assembly_time += t0.elapsed();
        }
        if self.line_search {
            ws.rhs_prev.clone_from(&ws.rhs);
            // (The first iterate's evaluation may be the other guess's.)
            self.barrier_before = ws.eval.barrier_pairs > 0;
        }
        Ok(())
    }

    /// Factor the matrix formed at this iterate and record where.
    fn form(
        &mut self,
        ctx: &StepContext,
        solver: &mut SparseSolver,
        next: &Dynamics,
        ws: &mut Workspace,
        out: &mut Outcome,
    ) -> Result<(), StepError> {
        let jp = ws.jacobian.take();
        matrix::factor(ctx.asm, solver, &ws.matrix, &next.q, self.coeffs)?;
        matrix::record(ctx.asm, ws, jp, ctx.h, next, ctx.cur, ctx.drive);
        out.factorizations += 1;
        self.refresh = false;
        ws.secant.clear();
        Ok(())
    }

    /// The solved correction's contraction rate against the last correction
    /// applied (modified Newton converges linearly: the remaining error is
    /// about rate / (1 - rate) times the last correction), and the size of
    /// the correction to apply (the plain one through the secant updates).
    fn measure(
        &self,
        asm: &Assembler,
        scales: &[f64],
        stale: bool,
        ws: &mut Workspace,
    ) -> (f64, f64) {
        let scaled_norm = |x: &[f64]| {
            let mut norm: f64 = 0.0;
            for (&fi, &scale) in asm.free.iter().zip(scales) {
                if fi != FIXED {
                    norm = norm.max(x[fi].abs() / scale);
                }
            }
            norm
        };
        let plain = scaled_norm(&ws.rhs);
        let rate = plain / self.last_norm;
        let norm = if self.secant && stale {
            ws.secant.correct(&mut ws.rhs);
            scaled_norm(&ws.rhs)
        } else {
            plain
        };
        (rate, norm)
    }

    /// Refuse a non-finite correction; drop a growing correction of a kept
    /// matrix and form one here.
    fn screen(
        &mut self,
        ctx: &StepContext,
        it: usize,
        stale: bool,
        rate: f64,
        norm: f64,
        ws: &mut Workspace,
    ) -> Result<Screen, StepError> {
        if !norm.is_finite() {
            return Err(StepError::NonFinite);
        }
        if self.modified && stale && rate > 1.0 && it + 1 < ctx.settings.max_newton {
            // A matrix formed elsewhere sends the iterate away: drop this
            // correction and form the matrix here.
            self.refresh = true;
            self.slope0 = 0.0;
            ws.secant.clear();
            return Ok(Screen::Drop);
        }
        Ok(Screen::Apply)
    }

    /// Apply the correction as far as the force terms admit (contact: the
    /// largest collision-free fraction); returns that fraction.
    fn apply(
        &mut self,
        asm: &Assembler,
        stale: bool,
        next: &mut Dynamics,
        ws: &mut Workspace,
        out: &mut Outcome,
    ) -> Result<f64, StepError> {
        for (i, &fi) in asm.free.iter().enumerate() {
            ws.dq[i] = if fi != FIXED { ws.rhs[fi] } else { 0.0 };
        }
        if self.line_search {
            self.slope0 = slope_along(asm, &ws.rhs_prev, &ws.dq);
        }
        let collision_free = asm.max_step_fraction(&next.q, &ws.dq);
        let stiffness_kept = asm.max_correction_fraction(&next.q, &next.v, &ws.dq, self.coeffs.c);
        let fraction = collision_free.min(stiffness_kept);
        if fraction <= 0.0 {
            return Err(StepError::NoCollisionFreeStep);
        }
        if fraction < 1.0 {
            // The matrix did not see the contact that stopped the step, or
            // the stiffness changes where the step stops.
            out.limited_steps += 1;
            self.refresh |= stale || stiffness_kept < collision_free;
        }
        for (q, d) in next.q.iter_mut().zip(&ws.dq) {
            *q += fraction * d;
        }
        self.applied = fraction;
        if self.secant {
            ws.secant.applied(&ws.rhs, fraction == 1.0);
        }
        Ok(fraction)
    }

    /// Whether the iterate is converged: the remaining error (for a kept
    /// matrix, estimated from its contraction) below the tolerance, or a
    /// fresh matrix stuck at the round-off floor of an ill-conditioned
    /// (thin, membrane-stiff) system close to it.
    fn converged(
        &self,
        p: &IntegrationParameters,
        it: usize,
        stale: bool,
        rate: f64,
        norm: f64,
        fraction: f64,
    ) -> bool {
        let remaining = if fraction < 1.0 {
            f64::INFINITY
        } else if self.modified && stale {
            if rate < 1.0 {
                norm * (rate / (1.0 - rate)).max(1.0)
            } else {
                f64::INFINITY
            }
        } else {
            norm
        };
        let floor =
            !stale && it >= 2 && rate > p.floor_rate && norm <= p.floor_factor * self.tolerance;
        remaining <= self.tolerance || floor
    }

    /// Fail a diverging iteration; form the matrix anew where a kept one
    /// contracts slowly. Within `near_factor` of the tolerance the rate of
    /// two tiny corrections says little (they are no longer a geometric
    /// sequence), so slow contractions there get up to `near_chances` more
    /// iterations first; a diverging iterate refreshes as soon as it
    /// leaves the band.
    fn prepare_next(
        &mut self,
        ctx: &StepContext,
        it: usize,
        stale: bool,
        rate: f64,
        norm: f64,
    ) -> Result<(), StepError> {
        let p = ctx.params;
        if it >= 3 && rate > p.divergence_rate && self.last_rate > p.divergence_rate {
            return Err(StepError::Diverged {
                correction: norm,
                iterations: it + 1,
            });
        }
        let slow = rate > p.max_rate;
        let near = norm <= p.near_factor * self.tolerance;
        let let_through = slow && near && self.near_chances_used < p.near_chances;
        if self.modified && stale && slow && !let_through && it + 1 < ctx.settings.max_newton {
            self.refresh = true;
        }
        self.near_chances_used = if let_through {
            self.near_chances_used + 1
        } else {
            0
        };
        self.last_rate = rate;
        self.norm_before_last = self.last_norm;
        self.last_norm = norm;
        Ok(())
    }
}

/// The final consistent update of a converged iterate. It is evaluated in
/// full only where a term's powers are integrated over the step and may be
/// nonzero in it (contact's friction work, with pairs lagged at the step
/// start); otherwise only its crease angles (the next step's unwrapping
/// reference) are needed here, and outputs evaluate forces and energies
/// where they are read.
fn finish(
    ctx: &StepContext,
    next: &mut Dynamics,
    ws: &mut Workspace,
    out: &mut Outcome,
) -> Result<(), StepError> {
    let asm = ctx.asm;
    ctx.update_rates(next);
    let t0 = PhaseTimer::start();
    ws.evaluated = asm.dissipates_this_step();
    if ws.evaluated {
        asm.evaluate(&ctx.drive.at(next), &mut ws.eval, None)
            .map_err(StepError::from)?;
    } else {
        asm.crease_angles(&next.q, ctx.drive.theta_prev, &mut ws.eval.theta)
            .map_err(StepError::from)?;
    }
    out.assembly_time += t0.elapsed();
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
