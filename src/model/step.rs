//! Step control: [`Model::advance`] over one communication step with
//! internal steps (generalized-alpha with local error control and step
//! rejection, or central differences in equal substeps), and what it
//! reports.

use super::drive::DriveValues;
use super::{Error, Model, Phase};
use crate::solver::generalized_alpha as ga;
use serde::{Deserialize, Serialize};

/// Safety factor on the step size the error estimate proposes.
const SAFETY: f64 = 0.9;
/// The proposed step scales with error^(-1/3) (local error of order h^3).
const ERROR_EXPONENT: f64 = -1.0 / 3.0;
/// Smallest factor from one step to the next after an error estimate.
const MIN_FACTOR: f64 = 0.2;
/// Largest growth from one accepted step to the next.
const MAX_GROWTH: f64 = 2.0;
/// Largest factor after a step rejected for its error (it must shrink).
const MAX_FACTOR_REJECTED: f64 = 0.9;
/// Lowest observed order of the local error in h that a rejection trusts.
const MIN_ORDER: f64 = 0.5;
/// Factor after a step whose Newton iteration failed.
const FACTOR_FAILED: f64 = 0.25;
/// Largest growth of the step accepted right after a rejection (Hairer &
/// Wanner II, IV.8: no increase right after a rejected step). Where Newton
/// failed at h (a snapping sheet), the retry at h/4 would otherwise double
/// twice back to h and fail again. Measured (BoxPleatPyramid's 1 s,
/// `cargo bench --bench rigid_fold -- --pyramid 1`): 2027 -> 1766
/// factorizations, 6389 -> 5938 Newton iterations, 422.6 -> 350.1 CPU s
/// (the latter with another job on the machine); Miura full folds the
/// same steps, and the same counts but at 4x4 (787/154 against 791/155).
/// The path through the snaps is chaotic; its spread, measured later
/// (2026-12-04, with Newton's early give-up): at tolerances 1.0001e-4 and
/// 1.01e-4 1470 and 1420 factorizations against 1459 at 1e-4. (An earlier
/// figure here, 1990 at a slightly larger tolerance, came from a bench
/// whose tolerance flag did not reach the pyramid then.)
const MAX_GROWTH_AFTER_REJECTION: f64 = 1.0;
/// A rest of the advance shorter than this fraction of the step joins it.
const JOIN_FRACTION: f64 = 1e-3;
/// A step within this factor of `min_step` is at the minimum: accepted
/// whatever its error.
const AT_MIN_STEP: f64 = 1.000001;

/// The step factor the error estimate `error` (1 = the tolerance) proposes.
fn proposed_factor(error: f64) -> f64 {
    SAFETY * error.powf(ERROR_EXPONENT)
}

/// The step factor after a step of size `h` rejected with `error`, where
/// the attempt before it (`prev`: size and error) was rejected too. The
/// error of two attempts gives its observed order in h: right after an
/// input's kink or at the start, where the acceleration jumps, it falls as
/// h^1-1.5, not h^3, and the h^3 rule takes four or five rejections (each
/// several Newton iterations and factorizations) to get there.
fn rejected_factor(h: f64, error: f64, prev: Option<(f64, f64)>) -> f64 {
    let order = match prev {
        Some((h0, e0)) if h0 > h && e0 > error => {
            let k = (e0 / error).ln() / (h0 / h).ln();
            k.clamp(MIN_ORDER, -1.0 / ERROR_EXPONENT)
        }
        _ => -1.0 / ERROR_EXPONENT,
    };
    (SAFETY * error.powf(-1.0 / order)).clamp(MIN_FACTOR, MAX_FACTOR_REJECTED)
}

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
    /// CPU time assembling forces and matrices, s.
    pub assembly_time: f64,
    /// CPU time in sparse numeric factorizations, s.
    pub factor_time: f64,
    /// CPU time in sparse triangular solves, s.
    pub solve_time: f64,
    /// Newton steps cut short by contact's collision check.
    #[serde(default)]
    pub limited_steps: usize,
    /// Newton corrections the line search near contact shortened.
    #[serde(default)]
    pub line_search_cuts: usize,
    /// Times the matrix pattern grew (new contact pairs; each one a new
    /// symbolic analysis).
    #[serde(default)]
    pub pattern_growths: usize,
}

impl StepReport {
    /// Add another report's counts and times (the smallest step of both).
    pub fn accumulate(&mut self, r: &StepReport) {
        self.min_step = if self.steps == 0 {
            r.min_step
        } else {
            self.min_step.min(r.min_step)
        };
        self.steps += r.steps;
        self.rejected += r.rejected;
        self.newton_iterations += r.newton_iterations;
        self.factorizations += r.factorizations;
        self.assembly_time += r.assembly_time;
        self.factor_time += r.factor_time;
        self.solve_time += r.solve_time;
        self.limited_steps += r.limited_steps;
        self.line_search_cuts += r.line_search_cuts;
        self.pattern_growths += r.pattern_growths;
    }
}

impl Model {
    /// Advance from the current time by `h` seconds with internal steps,
    /// the inputs held at their values in force (plus their slopes), or
    /// ramped to the values last set when the scene ramps its inputs. The
    /// step size and the iteration matrix carry over from the last advance.
    /// On failure the state is exactly as before the call.
    pub fn advance(&mut self, h: f64) -> Result<StepReport, Error> {
        if self.state.phase != Phase::Running {
            return Err(Error::Phase("advance before initialize".into()));
        }
        if !(h.is_finite() && h > 0.0) {
            return Err(Error::BadValue {
                name: "step size".into(),
                value: h,
                reason: "must be a positive finite number".into(),
            });
        }
        let saved = self.state.clone();
        match self.advance_inner(h) {
            Ok(r) => Ok(r),
            Err(e) => {
                self.state = saved;
                self.read_cache = Default::default();
                Err(e)
            }
        }
    }

    fn advance_inner(&mut self, big_h: f64) -> Result<StepReport, Error> {
        let t0 = self.state.time;
        let sys = self.sys.as_mut().expect("initialized");
        let mut report = StepReport {
            min_step: f64::INFINITY,
            ..Default::default()
        };
        let mut s = 0.0; // elapsed within the advance
        let mut h = self.state.h_next.min(sys.settings.max_step);
        // The last attempt, where it was rejected for its error: size, error.
        let mut last_rejected: Option<(f64, f64)> = None;
        // Whether the last attempt was rejected (error or Newton failure):
        // the retry always lands in this advance, so no state carries it.
        let mut after_rejection = false;
        let u0 = self.state.inputs_now.clone();
        let u1 = self.state.inputs_next.clone();
        let slopes = self.state.input_slopes.clone();
        // The inputs at elapsed time `e` of this advance.
        let inputs_at = |e: f64, u: &mut [f64]| {
            let frac = e / big_h;
            for k in 0..u.len() {
                u[k] = u0[k] + (u1[k] - u0[k]) * frac + slopes[k] * e;
            }
        };
        let cap = sys.settings.max_internal_steps;
        let too_many = || Error::StepFailed {
            time: t0,
            reason: format!(
                "the step needs more than {cap} internal steps (solver.max_internal_steps); \
                 use a smaller communication step or raise the limit"
            ),
        };
        // The iteration matrix of the state's history (a restored state
        // re-forms the one it was saved with), so that modified Newton
        // keeps it across communication points.
        if sys.cd.is_none() {
            ga::restore_jacobian(
                &mut sys.asm,
                &mut sys.solver,
                sys.coeffs,
                self.state.jacobian.as_ref(),
                &mut sys.ws,
            )
            .map_err(|reason| Error::StepFailed { time: t0, reason })?;
        }
        let stats0 = sys.solver.stats();
        let mut u = u0.clone();
        let mut d = DriveValues::default();
        // The drive at the start of the next step (its work over the step).
        let mut d_start = sys.inputs.drive(&u0);
        if let Some(cd) = sys.cd.as_mut() {
            // Explicit: equal substeps below the stability limit.
            let n_sub = (big_h / cd.stable_step().min(sys.settings.max_step))
                .ceil()
                .max(1.0);
            if n_sub > cap as f64 {
                return Err(too_many());
            }
            let h = big_h / n_sub;
            let t_asm = cd.assembly_time;
            let t_solve = cd.solve_time();
            let mut q_start = Vec::new();
            for k in 1..=n_sub as usize {
                inputs_at(k as f64 * h, &mut u);
                sys.inputs.drive_into(&u, &mut d);
                let gd = d.stepper_drive(&self.state.crease_theta);
                sys.asm
                    .before_step(&self.state.dynamics.q, &self.state.dynamics.v);
                q_start.clone_from(&self.state.dynamics.q);
                cd.step(&sys.asm, &mut self.state.dynamics, h, &gd)
                    .map_err(|reason| Error::StepFailed {
                        time: t0 + (k - 1) as f64 * h,
                        reason,
                    })?;
                let theta = &cd.evaluation().theta;
                self.state.work.input += d_start.work_to(
                    &d,
                    &sys.asm,
                    (&q_start, &self.state.crease_theta),
                    (&self.state.dynamics.q, theta),
                );
                self.state.crease_theta.clone_from(theta);
                std::mem::swap(&mut d_start, &mut d);
            }
            report.steps = n_sub as usize;
            report.min_step = h;
            report.assembly_time = (cd.assembly_time - t_asm).as_secs_f64();
            report.solve_time = (cd.solve_time() - t_solve).as_secs_f64();
            s = big_h;
        }
        while s < big_h {
            if report.steps + report.rejected >= cap {
                return Err(too_many());
            }
            // Land on the communication point with the last two steps equal
            // halves of what is left once less than two proposed steps
            // remain (a rest within JOIN_FRACTION joins the step before):
            // they then share one step size, and modified Newton one
            // iteration matrix, where a long step and a short rest would
            // each form their own. Earlier steps keep the proposed size, so
            // a last-bit difference in the master's step reaches only these
            // two.
            // A proposal at the minimum step counts as at the minimum after
            // a join too (which may stretch it by up to JOIN_FRACTION,
            // where a large error would otherwise be rejected for ever).
            let remaining = big_h - s;
            let proposal_at_min = h <= sys.settings.min_step * AT_MIN_STEP;
            let ratio = remaining / h;
            if ratio <= 1.0 + JOIN_FRACTION {
                h = remaining;
            } else if ratio <= 2.0 {
                h = 0.5 * remaining;
            }
            inputs_at(s + h, &mut u);
            sys.inputs.drive_into(&u, &mut d);
            let gd = d.stepper_drive(&self.state.crease_theta);
            if sys
                .asm
                .before_step(&self.state.dynamics.q, &self.state.dynamics.v)
            {
                // Contact pairs appeared: new blocks, new symbolic analysis.
                sys.rebuild_solver().map_err(|reason| Error::StepFailed {
                    time: t0 + s,
                    reason,
                })?;
                report.pattern_growths += 1;
            }
            let res = ga::step(
                &sys.asm,
                &mut sys.solver,
                sys.coeffs,
                &self.state.dynamics,
                h,
                &gd,
                &sys.scales,
                ga::Settings {
                    // A failure is retried at FACTOR_FAILED times the step.
                    may_shorten: h * FACTOR_FAILED >= sys.settings.min_step,
                    ..sys.newton
                },
                &mut sys.ws,
            );
            // Keep the step within [min_step, max_step] (max wins, so a bad
            // pair of settings cannot panic here).
            let bounded = |x: f64| x.max(sys.settings.min_step).min(sys.settings.max_step);
            match res {
                Ok((next, out)) => {
                    report.newton_iterations += out.iterations;
                    report.factorizations += out.factorizations;
                    report.assembly_time += out.assembly_time.as_secs_f64();
                    report.limited_steps += out.limited_steps;
                    report.line_search_cuts += out.line_search_cuts;
                    let at_min = proposal_at_min || h <= sys.settings.min_step * AT_MIN_STEP;
                    if out.error <= 1.0 || at_min {
                        self.state.work.input += d_start.work_to(
                            &d,
                            &sys.asm,
                            (&self.state.dynamics.q, &self.state.crease_theta),
                            (&next.q, sys.ws.crease_angles()),
                        );
                        std::mem::swap(&mut d_start, &mut d);
                        if let Some(ev) = sys.ws.evaluation() {
                            let st = &mut self.state;
                            let (wf, wd) = st.dissipative_force.work_to(
                                &ev.dissipative_force,
                                &st.dynamics.q,
                                &next.q,
                            );
                            st.work.friction += wf;
                            st.work.contact_damping += wd;
                            st.dissipative_force.clone_from(&ev.dissipative_force);
                        }
                        self.state.dynamics = next;
                        self.state
                            .crease_theta
                            .clone_from_slice(sys.ws.crease_angles());
                        s += h;
                        report.steps += 1;
                        last_rejected = None;
                        report.min_step = report.min_step.min(h);
                        let grow = if out.error > 0.0 {
                            proposed_factor(out.error)
                        } else {
                            MAX_GROWTH
                        };
                        let max_growth = if after_rejection {
                            MAX_GROWTH_AFTER_REJECTION
                        } else {
                            MAX_GROWTH
                        };
                        after_rejection = false;
                        let hn = bounded(h * grow.clamp(MIN_FACTOR, max_growth));
                        // A short final step must not shrink the next advance's step.
                        self.state.h_next = if h < remaining {
                            hn
                        } else {
                            hn.max(self.state.h_next)
                        };
                        h = hn;
                    } else {
                        report.rejected += 1;
                        after_rejection = true;
                        let factor = rejected_factor(h, out.error, last_rejected);
                        last_rejected = Some((h, out.error));
                        h = bounded(h * factor);
                    }
                }
                Err(ga::Failure { reason, outcome }) => {
                    // The failed attempt's work counts too.
                    report.newton_iterations += outcome.iterations;
                    report.factorizations += outcome.factorizations;
                    report.assembly_time += outcome.assembly_time.as_secs_f64();
                    report.limited_steps += outcome.limited_steps;
                    report.line_search_cuts += outcome.line_search_cuts;
                    report.rejected += 1;
                    last_rejected = None;
                    after_rejection = true;
                    h *= FACTOR_FAILED;
                    if h < sys.settings.min_step {
                        return Err(Error::StepFailed {
                            time: t0 + s,
                            reason,
                        });
                    }
                }
            }
        }
        let stats = sys.solver.stats();
        if sys.cd.is_none() {
            report.factor_time = (stats.factor_time - stats0.factor_time).as_secs_f64();
            report.solve_time = (stats.solve_time - stats0.solve_time).as_secs_f64();
            self.state.jacobian = sys.ws.jacobian().cloned();
            self.state.extra_pairs = sys.asm.extra_pairs().to_vec();
        }
        // The outputs now, where the last step evaluated its state in full;
        // else they are evaluated from the state when read.
        let ev = match &sys.cd {
            Some(cd) => Some(cd.evaluation().clone()),
            None => sys.ws.evaluation().cloned(),
        };
        inputs_at(big_h, &mut u);
        self.state.time = t0 + big_h;
        self.state.inputs_now.clone_from(&u);
        self.state.inputs_next = u;
        self.state.outputs = ev.map(|ev| self.compute_outputs(&ev));
        self.read_cache = Default::default();
        let d = &self.state.dynamics;
        let finite = match &self.state.outputs {
            Some(o) => o.iter().all(|x| x.is_finite()),
            None => {
                d.q.iter()
                    .chain(&d.v)
                    .chain(&self.state.crease_theta)
                    .all(|x| x.is_finite())
            }
        };
        if !finite {
            return Err(Error::StepFailed {
                time: t0,
                reason: "outputs are not finite".into(),
            });
        }
        Ok(report)
    }

    /// Counts and times of the implicit stepper's sparse solver so far
    /// (None before initialize or with an explicit integrator): which
    /// factorizations (Cholesky, LDLT, LU) the iteration matrices needed.
    pub fn solver_stats(&self) -> Option<crate::solver::SolverStats> {
        let sys = self.sys.as_ref()?;
        if sys.cd.is_some() {
            return None;
        }
        Some(sys.solver.stats())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Where the error falls as h (not h^3), the second rejection reads the
    /// order off the two attempts and proposes the step that meets the
    /// tolerance: here one more attempt instead of four.
    #[test]
    fn a_second_rejection_uses_the_observed_order() {
        let error = |h: f64| 1000.0 * h; // 10 at 10 ms
        let h0 = 0.01;
        // First rejection: the h^3 rule (limited to 0.2 .. 0.9).
        let f0 = rejected_factor(h0, error(h0), None);
        assert!((f0 - 0.9 * 10f64.powf(-1.0 / 3.0)).abs() < 1e-12, "{f0}");
        let h1 = h0 * f0;
        let f1 = rejected_factor(h1, error(h1), Some((h0, error(h0))));
        let h2 = h1 * f1;
        assert!(
            (error(h2) - SAFETY).abs() < 1e-9,
            "error {} at {h2}",
            error(h2)
        );
        // An error that falls as h^3 keeps the h^3 rule; one that does not
        // fall trusts no order below 0.5 (and the factor stays >= 0.2).
        let cubic = |h: f64| 1e7 * h * h * h;
        let g = rejected_factor(0.005, cubic(0.005), Some((0.01, cubic(0.01))));
        assert!((g - proposed_factor(cubic(0.005))).abs() < 1e-12);
        let flat = rejected_factor(0.005, 3.0, Some((0.01, 3.0)));
        assert!((flat - proposed_factor(3.0).clamp(MIN_FACTOR, MAX_FACTOR_REJECTED)).abs() < 1e-12);
    }
}
