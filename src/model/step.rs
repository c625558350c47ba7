//! [`Model::advance`]: one communication step of internal steps, each
//! asked of the scene's integrator ([`crate::solver::stepper`]) at the
//! size the step control proposes ([`crate::solver::step_control`]), and
//! what it reports.

use super::inputs::{DriveValues, StepSignal};
use super::system::System;
use super::{Error, Model, ModelState, Phase};
use crate::cpu_time;
use crate::solver::step_control::{StepController, Verdict, equal_substeps};
use crate::solver::stepper::{
    Attempt, Dynamics, Failure, Mechanics, Outcome, StepError, StepPolicy,
};
use crate::text::num;
use serde::{Deserialize, Serialize};

/// Work of the viscous forces over a step from `q0` to `end` by the
/// trapezoidal rule (the integrator's own energy identity), `force` the
/// force at the step start (empty: zero), set to the one at its end.
fn viscous_work(
    asm: &crate::assembly::Assembler,
    force: &mut Vec<f64>,
    q0: &[f64],
    end: &Dynamics,
) -> f64 {
    let mut f1 = Vec::new();
    asm.viscous_force(&end.q, &end.v, &mut f1);
    let w = (0..q0.len())
        .map(|i| 0.5 * (force.get(i).copied().unwrap_or(0.0) + f1[i]) * (end.q[i] - q0[i]))
        .sum();
    *force = f1;
    w
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
    /// CPU time (the stepping thread's clock) assembling forces and
    /// matrices, s; zero unless phase timing is on
    /// ([`crate::solver::set_phase_timing`]), as the two below.
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
    /// Add the work of one step attempt (accepted, rejected or failed).
    fn add_attempt(&mut self, out: &Outcome) {
        self.newton_iterations += out.iterations;
        self.factorizations += out.factorizations;
        self.assembly_time += out.assembly_time.as_secs_f64();
        self.limited_steps += out.limited_steps;
        self.line_search_cuts += out.line_search_cuts;
    }

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
                if let Some(sys) = self.sys.as_mut() {
                    // Back to what the terms carried before the failed
                    // steps (their own memory: it fits).
                    let _ = sys.asm.restore_term_memory(&self.state.term_memory);
                }
                self.read_cache = Default::default();
                Err(self.with_suspects(e))
            }
        }
    }

    fn advance_inner(&mut self, big_h: f64) -> Result<StepReport, Error> {
        // Inputs the built-in ramp drives follow it, whatever was set.
        let ramped: Vec<usize> = (0..self.inputs.len())
            .filter(|&k| self.is_ramped(k))
            .collect();
        let ramp = (self.scene.ramp, ramped);
        let sys = self.sys.as_mut().expect("initialized");
        let state = &mut self.state;
        let t0 = state.time;
        sys.stepper
            .begin_advance(&mut sys.asm, &mut sys.solver, &state.memory)
            .map_err(|e| Error::StepFailed {
                time: t0,
                reason: e.to_string(),
            })?;
        let mut adv = Advance::new(sys, state, big_h, ramp);
        moved_obstacles_clear(sys, &adv.d_start, state, t0)?;
        adv.run(sys, state)?;
        let (factor_time, solve_time) = sys.stepper.linear_times(&sys.solver);
        adv.report.factor_time = (factor_time - adv.linear_times.0).as_secs_f64();
        adv.report.solve_time = (solve_time - adv.linear_times.1).as_secs_f64();
        sys.stepper.end_advance(&mut state.memory);
        state.extra_pairs = sys.asm.extra_pairs().to_vec();
        state.term_memory = sys.asm.term_memory();
        // The outputs now, where the last step evaluated its state in full
        // or the scene reports reactions (they need the forces at the step
        // end); else they are evaluated from the state when read.
        let d_end = std::mem::take(&mut adv.d_start);
        let ev = match sys.stepper.evaluation() {
            Some(ev) => Some(ev.clone()),
            None if sys.reactions.is_empty() => None,
            None => Some(
                sys.evaluate(&state.dynamics, &d_end, &state.crease_theta)
                    .map_err(|e| Error::StepFailed {
                        time: t0,
                        reason: e.to_string(),
                    })?,
            ),
        };
        adv.signal.finish(state);
        let report = adv.report;
        self.state.time = t0 + big_h;
        self.read_cache = Default::default();
        self.state.outputs = ev.map(|ev| self.compute_outputs(&ev, &d_end));
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

    #[doc(hidden)]
    /// Counts and times of the implicit stepper's sparse solver so far
    /// (None before initialize or with an explicit integrator): which
    /// factorizations (Cholesky, LDLT, LU) the iteration matrices needed.
    pub fn solver_stats(&self) -> Option<crate::solver::SolverStats> {
        let sys = self.sys.as_ref()?;
        if sys.stepper.policy() != StepPolicy::Adaptive {
            return None;
        }
        Some(sys.solver.stats())
    }
}

/// Place the moving obstacles where the inputs set at the communication
/// point `t0` put them (`d`); fails, naming the obstacle, where that is
/// into the sheet: held pose inputs jump there.
fn moved_obstacles_clear(
    sys: &mut System,
    d: &DriveValues,
    state: &ModelState,
    t0: f64,
) -> Result<(), Error> {
    if sys.inputs.obstacles.is_empty() {
        return Ok(());
    }
    sys.asm.place_bodies(&d.obstacles, &d.obstacles);
    let Some((name, gap)) = sys
        .asm
        .obstacles()
        .and_then(|o| o.overlapped(&state.dynamics.q))
    else {
        return Ok(());
    };
    Err(Error::StepFailed {
        time: t0,
        reason: format!(
            "the pose inputs of obstacle {name} put it into the sheet (gap {} m within the \
             clearance): held inputs jump at a communication point; give their derivatives \
             (fmi2SetRealInputDerivatives) or move the obstacle in shorter communication steps",
            num(gap)
        ),
    })
}

/// One advance in progress: its inputs' signals, the drive of the step at
/// hand, and the work so far.
struct Advance {
    t0: f64,
    big_h: f64,
    /// The inputs over the advance ([`crate::model::inputs`]).
    signal: StepSignal,
    /// Inputs acting at the step at hand's end.
    u: Vec<f64>,
    /// The drive at the start of the step at hand (its work over the step) ...
    d_start: DriveValues,
    /// ... and at its end.
    d: DriveValues,
    /// The candidate state of an attempt.
    next: Dynamics,
    report: StepReport,
    /// The integrator's linear-solver times at the start.
    linear_times: (std::time::Duration, std::time::Duration),
    /// The advance's CPU limit (`solver.max_step_cpu`; `None` where it is
    /// too large to count).
    deadline: Option<cpu_time::ThreadDeadline>,
}

impl Advance {
    fn new(
        sys: &System,
        state: &ModelState,
        big_h: f64,
        ramp: (crate::scene::InputRamp, Vec<usize>),
    ) -> Advance {
        let mut adv = Advance {
            t0: state.time,
            big_h,
            signal: StepSignal::new(state, sys.actuation, big_h, ramp),
            u: state.inputs_now.clone(),
            d_start: DriveValues::default(),
            d: DriveValues::default(),
            next: Dynamics::default(),
            report: StepReport {
                min_step: f64::INFINITY,
                ..Default::default()
            },
            linear_times: sys.stepper.linear_times(&sys.solver),
            deadline: cpu_time::ThreadDeadline::after(sys.settings.max_step_cpu),
        };
        let mut u = std::mem::take(&mut adv.u);
        adv.signal.inputs_at(0.0, &mut u);
        sys.inputs.drive_into(&u, &mut adv.d_start);
        adv.move_obstacles(sys, &u, 0.0, true);
        adv.u = u;
        adv
    }

    /// The moving obstacles' motions at elapsed time `e` under the inputs
    /// `u` (there), into the drive at the step start (`start`) or end.
    fn move_obstacles(&mut self, sys: &System, u: &[f64], e: f64, start: bool) {
        if sys.inputs.obstacles.is_empty() {
            return;
        }
        let d1: Vec<f64> = (0..u.len())
            .map(|k| self.signal.command_rate(k, e))
            .collect();
        let d2: Vec<f64> = (0..u.len())
            .map(|k| self.signal.command_acceleration(k))
            .collect();
        let d = if start {
            &mut self.d_start
        } else {
            &mut self.d
        };
        sys.inputs.move_obstacles(u, (&d1, &d2), d);
    }

    /// The advance's CPU passed `solver.max_step_cpu`, at elapsed time `s`.
    fn out_of_time(&self, cap: f64, s: f64) -> Error {
        Error::StepFailed {
            time: self.t0 + s,
            reason: format!(
                "the step from t = {} s used more than solver.max_step_cpu = {} s of CPU \
                 ({} internal steps, {} rejected, {} Newton iterations); the state is the \
                 one before it: use a smaller communication step or raise the limit",
                num(self.t0),
                num(cap),
                self.report.steps,
                self.report.rejected,
                self.report.newton_iterations
            ),
        }
    }

    fn too_many(&self, cap: usize) -> Error {
        Error::StepFailed {
            time: self.t0,
            reason: format!(
                "the step needs more than {cap} internal steps (solver.max_internal_steps); \
                 use a smaller communication step or raise the limit"
            ),
        }
    }

    /// Internal steps until the communication point: error-controlled
    /// steps, or the integrator's equal substeps.
    fn run(&mut self, sys: &mut System, state: &mut ModelState) -> Result<(), Error> {
        let settings = sys.settings;
        let cap = settings.max_internal_steps;
        let big_h = self.big_h;
        let (mut ctl, substeps) = match sys.stepper.policy() {
            StepPolicy::Adaptive => {
                // Internal steps are at most max_step (the last one up to the
                // join fraction longer): a step that needs more than the cap
                // fails before any work.
                let longest = settings.max_step * (1.0 + settings.integration.join_fraction);
                let fewest = (big_h / longest).ceil();
                if fewest > cap as f64 {
                    return Err(Error::StepFailed {
                        time: self.t0,
                        reason: format!(
                            "the step of {} s needs at least {} internal steps of at most \
                             solver.max_step = {} s, more than solver.max_internal_steps = \
                             {cap}; use shorter communication steps or raise the limit",
                            num(big_h),
                            num(fewest),
                            num(settings.max_step)
                        ),
                    });
                }
                let ctl = StepController::new(
                    settings.integration,
                    settings.min_step,
                    settings.max_step,
                    state.memory.h_next,
                );
                (Some(ctl), None)
            }
            StepPolicy::Fixed(h_max) => {
                let (n, h) = equal_substeps(big_h, h_max.min(settings.max_step));
                if n > cap {
                    return Err(self.too_many(cap));
                }
                (None, Some((n, h)))
            }
        };
        // Elapsed time within the advance, and steps accepted.
        let (mut s, mut k) = (0.0, 0usize);
        let done = |s: f64, k: usize| match substeps {
            Some((n, _)) => k >= n,
            None => s >= big_h,
        };
        while !done(s, k) {
            if self.report.steps + self.report.rejected >= cap {
                return Err(self.too_many(cap));
            }
            if self.deadline.is_some_and(|d| d.passed()) {
                return Err(self.out_of_time(settings.max_step_cpu, s));
            }
            let remaining = big_h - s;
            let (h, s_end) = match (&mut ctl, substeps) {
                (_, Some((_, h))) => (h, (k + 1) as f64 * h),
                (Some(c), None) => {
                    let h = c.next_step(remaining);
                    (h, s + h)
                }
                (None, None) => unreachable!("a policy gives a controller or substeps"),
            };
            let out = match self.attempt(sys, state, h, s_end) {
                Ok(out) => out,
                Err(Failure { reason, outcome }) => {
                    // The failed attempt's work counts too.
                    self.report.add_attempt(&outcome);
                    self.report.rejected += 1;
                    if matches!(reason, StepError::OutOfTime) {
                        return Err(self.out_of_time(settings.max_step_cpu, s));
                    }
                    if !ctl.as_mut().is_some_and(|c| c.failed(h)) {
                        return Err(Error::StepFailed {
                            time: self.t0 + s,
                            reason: reason.to_string(),
                        });
                    }
                    continue;
                }
            };
            self.report.add_attempt(&out);
            let verdict = match &mut ctl {
                Some(c) => c.judge(h, out.error),
                None => Verdict::Accept { next: h },
            };
            match verdict {
                Verdict::Accept { next } => {
                    self.accept(sys, state, &out, h);
                    s = s_end;
                    k += 1;
                    self.report.steps += 1;
                    self.report.min_step = self.report.min_step.min(h);
                    if ctl.is_some() {
                        // A short final step must not shrink the next advance's step.
                        let m = &mut state.memory;
                        m.h_next = if h < remaining {
                            next
                        } else {
                            next.max(m.h_next)
                        };
                    }
                }
                Verdict::Reject => self.report.rejected += 1,
            }
        }
        Ok(())
    }

    /// One attempt of size `h` ending at elapsed time `s_end`, its
    /// candidate state in `self.next`.
    fn attempt(
        &mut self,
        sys: &mut System,
        state: &ModelState,
        h: f64,
        s_end: f64,
    ) -> Result<Outcome, Failure> {
        let mut u = std::mem::take(&mut self.u);
        self.signal.inputs_at(s_end, &mut u);
        sys.inputs.drive_into(&u, &mut self.d);
        self.move_obstacles(sys, &u, s_end, false);
        self.u = u;
        if !sys.inputs.obstacles.is_empty() {
            sys.asm
                .place_bodies(&self.d_start.obstacles, &self.d.obstacles);
        }
        if sys.asm.before_step(&state.dynamics.q, &state.dynamics.v) {
            // Contact pairs appeared: new blocks, new symbolic analysis.
            sys.rebuild_solver().map_err(|e| Failure {
                reason: crate::solver::stepper::StepError::Linear(e),
                outcome: Outcome::default(),
            })?;
            self.report.pattern_growths += 1;
        }
        let drive = self.d.stepper_drive(&state.crease_theta);
        let attempt = Attempt {
            h,
            drive: &drive,
            memory: state.memory.newton,
            deadline: self.deadline,
        };
        let mech = Mechanics {
            asm: &sys.asm,
            solver: &mut sys.solver,
        };
        sys.stepper
            .step(mech, &state.dynamics, &mut self.next, &attempt)
    }

    /// Make the attempt's candidate the state: the work the inputs did
    /// over the step, the dissipated work, the crease angles and the
    /// stepper's memory (`h` the step's size).
    fn accept(&mut self, sys: &System, state: &mut ModelState, out: &Outcome, h: f64) {
        let angles = sys.stepper.crease_angles();
        state.work.input += self.d_start.work_to(
            &self.d,
            &sys.asm,
            (&state.dynamics.q, &state.crease_theta),
            (&self.next.q, angles),
        );
        std::mem::swap(&mut self.d_start, &mut self.d);
        if sys.asm.reports_power() {
            // A step whose end was not evaluated had no dissipative force.
            let ev = sys.stepper.evaluation();
            let none = crate::assembly::DissipativeForce::default();
            let end = ev.map_or(&none, |ev| &ev.dissipative_force);
            let (wf, wd) = state
                .dissipative_force
                .work_to(end, &state.dynamics.q, &self.next.q);
            // What moving obstacles take is put in, not dissipated.
            let on = state.dissipative_force.obstacle_work_to(end, h);
            state.work.friction += wf - on.friction;
            state.work.contact_damping += wd - on.damping;
            state.work.input -= on.total;
            match ev {
                Some(ev) => state.dissipative_force.clone_from(&ev.dissipative_force),
                // Zero, at the state's length.
                None => {
                    state.dissipative_force.zeroed(self.next.q.len());
                    state.dissipative_force.obstacles = Default::default();
                }
            }
        }
        state.work.viscous += viscous_work(
            &sys.asm,
            &mut state.viscous_force,
            &state.dynamics.q,
            &self.next,
        );
        std::mem::swap(&mut state.dynamics, &mut self.next);
        state.crease_theta.clone_from_slice(angles);
        state.memory.newton = out.memory;
    }
}
