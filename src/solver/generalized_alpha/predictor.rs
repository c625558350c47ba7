//! The predictor: Newton's starting guess, the better of two. Held
//! positions (q_{n+1} = q_n) suit a folding sheet: extrapolating its motion
//! starts Newton from stretched rotating gradients and from the unresolved
//! membrane vibration in qdd_n, and meets many more indefinite iteration
//! matrices. Constant acceleration suits fast rigid motion (a spin).
//! Choosing costs one force evaluation per step, saved where one guess
//! keeps winning ([`crate::solver::IntegrationParameters::skip_loser_after`]).

use super::{StepContext, Workspace};
use crate::assembly::FIXED;
use crate::solver::stepper::{Dynamics, Outcome};
// Phase times are CPU time, read where phase timing is on (phase_timer).
use crate::solver::phase_timer::PhaseTimer;

/// Which guess.
#[derive(Clone, Copy, PartialEq)]
enum Guess {
    /// Positions held.
    Held,
    /// Constant acceleration.
    Extrapolated,
}

/// Put the winning guess into `next` (and its rates), its residual into
/// `ws.rhs` where one could be evaluated (the return value), and the
/// streaks of the winner into `out.memory`.
pub(super) fn predict(
    ctx: &StepContext,
    next: &mut Dynamics,
    ws: &mut Workspace,
    out: &mut Outcome,
) -> bool {
    let (cur, co, h) = (ctx.cur, ctx.co, ctx.h);
    let n = cur.q.len();
    next.clone_from(cur);
    let mut alt = std::mem::take(&mut ws.guess);
    alt.clone_from(cur);
    let bh2 = co.beta * h * h;
    for i in 0..n {
        alt.abar[i] = (cur.qdd[i] - co.am * cur.abar[i]) / (1.0 - co.am);
        alt.q[i] =
            cur.q[i] + h * cur.v[i] + h * h * (0.5 - co.beta) * cur.abar[i] + bh2 * alt.abar[i];
    }
    let p = ctx.params;
    let memory = out.memory;
    let streak = memory.extrapolation_streak;
    let held = memory.held_streak;
    // Where one guess keeps winning, the other is skipped, and re-tried
    // every `recheck_every` steps of the streak or when the winner fails.
    let skip_held = streak >= p.skip_loser_after && !streak.is_multiple_of(p.recheck_every);
    let skip_extrapolated = held >= p.skip_loser_after && !held.is_multiple_of(p.recheck_every);
    let mut size = [f64::INFINITY; 2];
    if !p.two_guess_predictor {
        size[0] = residual_size(ctx, Guess::Held, next, ws, out);
    } else if skip_held {
        size[1] = residual_size(ctx, Guess::Extrapolated, &mut alt, ws, out);
        if !size[1].is_finite() {
            size[0] = residual_size(ctx, Guess::Held, next, ws, out);
        }
    } else {
        size[0] = residual_size(ctx, Guess::Held, next, ws, out);
        if !(skip_extrapolated && size[0].is_finite()) {
            size[1] = residual_size(ctx, Guess::Extrapolated, &mut alt, ws, out);
        }
    }
    // The winner's residual is Newton's first one (the same evaluation, so
    // the same numbers) unless the first iteration forms a matrix.
    let winner = if size[1] < size[0] {
        std::mem::swap(next, &mut alt);
        1
    } else {
        if size[0].is_finite() {
            std::mem::swap(&mut ws.rhs, &mut ws.first_rhs);
        }
        0
    };
    out.memory.extrapolation_streak = if winner == 1 { streak + 1 } else { 0 };
    out.memory.held_streak = if winner == 0 { held + 1 } else { 0 };
    ws.guess = alt;
    size[winner].is_finite()
}

/// The size of a guess's residual (a work-like norm: force times the DOF's
/// scale), infinite where it cannot be evaluated. The held guess's
/// residual is kept in `ws.first_rhs`, the other's stays in `ws.rhs`.
fn residual_size(
    ctx: &StepContext,
    which: Guess,
    guess: &mut Dynamics,
    ws: &mut Workspace,
    out: &mut Outcome,
) -> f64 {
    let (asm, cur) = (ctx.asm, ctx.cur);
    for &(i, x) in ctx.drive.prescribed {
        guess.q[i] = x;
    }
    // A guess the surfaces cannot reach without touching is no guess (a
    // held one can meet a moving obstacle).
    if which == Guess::Extrapolated || asm.moves_bodies() {
        for i in 0..cur.q.len() {
            ws.dq[i] = guess.q[i] - cur.q[i];
        }
        if asm.max_motion_fraction(&cur.q, &ws.dq) < 1.0 {
            return f64::INFINITY;
        }
    }
    ctx.update_rates(guess);
    let t0 = PhaseTimer::start();
    let ok = ctx.residual(guess, ws, None).is_ok();
    out.assembly_time += t0.elapsed();
    if !ok {
        return f64::INFINITY;
    }
    if which == Guess::Held {
        ws.first_rhs.clone_from(&ws.rhs);
    }
    let scales = &ctx.scales.newton;
    (0..cur.q.len())
        .filter(|&i| asm.free[i] != FIXED)
        .map(|i| (ws.rhs[asm.free[i]] * scales[i]).powi(2))
        .sum()
}
