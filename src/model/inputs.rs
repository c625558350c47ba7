//! The input path, in one place: what the sheet feels from an input.
//!
//! 1. A master records a value ([`Model::set_input`]) or its derivatives
//!    ([`Model::set_input_derivative`]) in the state (`inputs_now`,
//!    `inputs_next`, `input_slopes`, `input_second_derivatives`).
//! 2. Over an advance each input follows its signal ([`StepSignal`]): held
//!    at the value set, plus its slope and second derivative (FMI 2.0);
//!    ramped from the value in force to the one set (first-order hold,
//!    [`InputTiming::FirstOrderHold`]); or, for the rest-angle actuators,
//!    the built-in ramp ([`InputRamp`]) whatever was set.
//! 3. An actuator's value follows its input's signal ([`Actuation`]): at
//!    once (ideal, the default) or through a critically damped servo.
//! 4. [`InputMap::drive_into`] turns the values into what the assembly
//!    takes: rest angles `pi + u x target`, crease moments, forces and
//!    prescribed DOFs, the attachments' and obstacles' poses.

use super::attach::FrameInput;
use super::{Error, InputId, Model, ModelState, Phase, VariableSpec};
use crate::assembly::Assembler;
use crate::frame::{Motion, Pose};
use crate::scene::{ActuatorMode, InputRamp, InputTiming, Scene, sequence};
use crate::solver::stepper::Drive;

/// How the actuators follow their inputs: ideal (a time constant of 0, at
/// once) or a critically damped servo of time constant `tau` (s),
/// `tau^2 a'' + 2 tau a' + a = u`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Actuation {
    tau: f64,
}

/// Below this time constant (s) an actuator follows its input at once.
const INSTANT: f64 = 1e-12;

impl Actuation {
    /// The scene's actuation ([`crate::model::actuator_time_constant`]).
    pub(super) fn of(sc: &Scene) -> Actuation {
        Actuation {
            tau: super::actuator_time_constant(sc),
        }
    }

    /// Whether the actuators follow their inputs at once.
    pub(super) fn is_ideal(self) -> bool {
        // A NaN time constant counts as none.
        self.tau.is_nan() || self.tau <= INSTANT
    }

    /// An actuator's value and rate `e` seconds after `start` (value, rate)
    /// under the input `u0 + s1 t + s2 t^2 / 2` (`[s1, s2]` = `slopes`): the
    /// critically damped response in closed form; ideal, the input itself.
    pub(super) fn response(self, start: [f64; 2], u0: f64, [s1, s2]: [f64; 2], e: f64) -> [f64; 2] {
        let input = |t: f64| [u0 + s1 * t + 0.5 * s2 * t * t, s1 + s2 * t];
        if self.is_ideal() {
            return input(e);
        }
        let tau = self.tau;
        // The particular solution of a polynomial input: u - 2 tau u' + 3 tau^2 u''
        // (a ramp lags by 2 tau).
        respond(tau, start, e, |t| {
            let [u, du] = input(t);
            [
                u - 2.0 * tau * du + 3.0 * tau * tau * s2,
                du - 2.0 * tau * s2,
            ]
        })
    }

    /// An actuator's value and rate `e` seconds after `start` under the
    /// built-in ramp (which starts at t = 0), `t0` the time at `start`: its
    /// response piece by piece, the rise (a polynomial of degree 1 or 3)
    /// and the hold after it. Ideal, the ramp itself.
    pub(super) fn ramp_response(
        self,
        start: [f64; 2],
        ramp: &InputRamp,
        t0: f64,
        e: f64,
    ) -> [f64; 2] {
        if self.is_ideal() {
            return [ramp.value(t0 + e), ramp.derivatives(t0 + e)[1]];
        }
        let tau = self.tau;
        // The particular solution of a polynomial input c: sum over k of
        // (-1)^k (k + 1) tau^k c^(k) (the series of (1 + tau d/dt)^-2).
        let particular = |t: f64, rising: bool| {
            let c = if rising {
                ramp.rise_derivatives(t)
            } else {
                [1.0, 0.0, 0.0, 0.0]
            };
            let v = c[0] - 2.0 * tau * c[1] + 3.0 * tau * tau * c[2] - 4.0 * tau.powi(3) * c[3];
            let r = c[1] - 2.0 * tau * c[2] + 3.0 * tau * tau * c[3];
            [v, r]
        };
        let rise = (ramp.time - t0).clamp(0.0, e);
        let mid = if rise > 0.0 {
            respond(tau, start, rise, |t| particular(t0 + t, true))
        } else {
            start
        };
        if e > rise {
            respond(tau, mid, e - rise, |t| particular(t0 + rise + t, false))
        } else {
            mid
        }
    }
}

/// The critically damped response (time constant `tau`) `e` seconds after
/// `start` to an input whose particular solution (value, rate) at elapsed
/// time t is `p(t)`: that solution plus the decaying deviation from it.
fn respond(tau: f64, start: [f64; 2], e: f64, p: impl Fn(f64) -> [f64; 2]) -> [f64; 2] {
    let [p0, p0_rate] = p(0.0);
    let [pe, pe_rate] = p(e);
    let d0 = start[0] - p0;
    let r0 = start[1] - p0_rate;
    let x = (-e / tau).exp();
    let (dev, rate) = if x > 0.0 {
        let k = e / tau;
        ((d0 + r0 * e + k * d0) * x, (r0 - k * r0 - k * d0 / tau) * x)
    } else {
        (0.0, 0.0)
    };
    [pe + dev, pe_rate + rate]
}

impl Model {
    /// Value of input `i` as last set (in force now; with ramped inputs,
    /// the value the next advance ends at).
    pub fn input(&self, id: InputId) -> Result<f64, Error> {
        let i = id.0;
        self.input_spec(i)?;
        Ok(match self.scene.solver.input_timing {
            InputTiming::Hold => self.state.inputs_now[i],
            InputTiming::FirstOrderHold => self.state.inputs_next[i],
        })
    }

    fn input_spec(&self, i: usize) -> Result<&VariableSpec, Error> {
        self.inputs.get(i).ok_or(Error::NoSuchVariable {
            kind: "input",
            index: i,
        })
    }

    /// Set input `i`. Held inputs (the default): the value is in force from
    /// now and held over the next advance; its slope is reset to zero.
    /// Ramped inputs: the value the next advance ends at. Non-finite values,
    /// and values beyond [`crate::scene::limits::MAX_MAGNITUDE`], are
    /// rejected.
    pub fn set_input(&mut self, id: InputId, value: f64) -> Result<(), Error> {
        let i = id.0;
        let spec = self.input_spec(i)?;
        if let Err(source) = crate::scene::limits::check_number(value) {
            return Err(Error::OutOfLimits {
                name: spec.name.clone(),
                value,
                source,
            });
        }
        if self.is_ramped(i) {
            // The built-in ramp drives it (parameter ramp.time): not used.
            return Ok(());
        }
        self.state.inputs_next[i] = value;
        if self.state.phase == Phase::Setup || self.scene.solver.input_timing == InputTiming::Hold {
            self.hold(i, value);
        }
        self.state.input_slopes[i] = 0.0;
        if let Some(s2) = self.state.input_second_derivatives.get_mut(i) {
            *s2 = 0.0;
        }
        Ok(())
    }

    /// Set the `order`-th time derivative of input `id` (order 1 or 2: the
    /// input then follows its Taylor polynomial from its value over the
    /// advance, as `fmi2SetRealInputDerivatives` asks). It applies until the
    /// input or the derivative is set again (an input with a second
    /// derivative goes on along its parabola: its first derivative grows
    /// by the second times each advance). Not with ramped inputs.
    pub fn set_input_derivative(
        &mut self,
        id: InputId,
        order: i32,
        value: f64,
    ) -> Result<(), Error> {
        let i = id.0;
        let spec = self.input_spec(i)?;
        let bad = |reason: &str| Error::BadValue {
            name: format!("derivative of order {order} of {}", spec.name),
            value,
            reason: reason.into(),
        };
        if !(1..=2).contains(&order) {
            return Err(bad("first and second derivatives are taken (order 1 or 2)"));
        }
        if self.scene.solver.input_timing == InputTiming::FirstOrderHold {
            return Err(bad(
                "the inputs are on first-order hold (input.first_order_hold = 1); derivatives need held inputs",
            ));
        }
        if let Err(source) = crate::scene::limits::check_number(value) {
            return Err(Error::OutOfLimits {
                name: format!("derivative of order {order} of {}", spec.name),
                value,
                source,
            });
        }
        if !self.is_ramped(i) {
            if order == 1 {
                self.state.input_slopes[i] = value;
            } else {
                self.state
                    .input_second_derivatives
                    .resize(self.inputs.len(), 0.0);
                self.state.input_second_derivatives[i] = value;
            }
        }
        Ok(())
    }

    /// Put the held value `value` of input `i` in force now. An ideal
    /// actuator (and any before initialization, where it starts at rest)
    /// follows at once: its rest angles jump, doing their work at once, and
    /// the crease energy is read under them.
    fn hold(&mut self, i: usize, value: f64) {
        let at_once = match (&self.sys, self.state.phase) {
            (Some(sys), Phase::Running) => sys.actuation.is_ideal(),
            _ => true,
        };
        if i < self.state.actuators.len() && at_once {
            if let (Some(sys), Phase::Running) = (&self.sys, self.state.phase) {
                let u = self.drive_inputs();
                self.state.work.input +=
                    sys.inputs
                        .jump_work(&sys.asm, i, value, &u, &self.state.crease_theta);
            }
            self.state.actuators[i] = [value, 0.0];
            self.read_cache = Default::default();
        }
        self.state.inputs_now[i] = value;
    }

    /// Whether input `i` follows the built-in ramp (`ramp.time` > 0 and a
    /// rest-angle actuator) instead of the values set on it.
    pub(super) fn is_ramped(&self, i: usize) -> bool {
        self.state.phase == Phase::Running
            && self.scene.ramp.is_on()
            && self
                .scene
                .actuators
                .get(i)
                .is_some_and(|a| a.mode == ActuatorMode::RestAngle)
    }

    /// The inputs as they act on the sheet now: each actuator's value in
    /// place of its input, the other inputs as set.
    pub(super) fn drive_inputs(&self) -> Vec<f64> {
        let mut u = self.state.inputs_now.clone();
        for (x, a) in u.iter_mut().zip(&self.state.actuators) {
            *x = a[0];
        }
        u
    }
}

/// The inputs' signals over one advance from `t0` of `big_h` seconds:
/// what the master set (values at the start and end, derivatives), the
/// built-in ramp, and where each actuator starts.
pub(super) struct StepSignal {
    big_h: f64,
    t0: f64,
    /// Inputs at the start, at the end before slopes, and their first and
    /// second derivatives.
    u0: Vec<f64>,
    u1: Vec<f64>,
    slopes: Vec<f64>,
    second: Vec<f64>,
    /// The actuators and their values and rates at the start.
    actuation: Actuation,
    act0: Vec<[f64; 2]>,
    /// The built-in ramp and the inputs it drives (in place of the
    /// master's values).
    ramp: InputRamp,
    ramped: Vec<usize>,
}

impl StepSignal {
    /// The signals of the advance of `big_h` from `state`, the inputs
    /// `ramped` following `ramp`.
    pub(super) fn new(
        state: &ModelState,
        actuation: Actuation,
        big_h: f64,
        (ramp, ramped): (InputRamp, Vec<usize>),
    ) -> StepSignal {
        StepSignal {
            big_h,
            t0: state.time,
            u0: state.inputs_now.clone(),
            u1: state.inputs_next.clone(),
            slopes: state.input_slopes.clone(),
            second: state.input_second_derivatives.clone(),
            actuation,
            act0: state.actuators.clone(),
            ramp,
            ramped,
        }
    }

    /// The inputs as the master set them at elapsed time `e` of this
    /// advance (held, ramped, with their slopes).
    pub(super) fn commands_at(&self, e: f64, u: &mut [f64]) {
        for (k, x) in u.iter_mut().enumerate() {
            *x = self.command(k, e);
        }
        for &k in &self.ramped {
            u[k] = self.ramp.value(self.t0 + e);
        }
    }

    /// Input `k` as the master set it at elapsed time `e`.
    fn command(&self, k: usize, e: f64) -> f64 {
        let s2 = self.second.get(k).copied().unwrap_or(0.0);
        self.u0[k]
            + (self.u1[k] - self.u0[k]) * (e / self.big_h)
            + (self.slopes[k] + 0.5 * s2 * e) * e
    }

    /// Input `k`'s rate of change as the master set it, at elapsed time
    /// `e` (the derivative of [`StepSignal::command`]).
    pub(super) fn command_rate(&self, k: usize, e: f64) -> f64 {
        let s2 = self.second.get(k).copied().unwrap_or(0.0);
        (self.u1[k] - self.u0[k]) / self.big_h + self.slopes[k] + s2 * e
    }

    /// Input `k`'s second derivative as the master set it.
    pub(super) fn command_acceleration(&self, k: usize) -> f64 {
        self.second.get(k).copied().unwrap_or(0.0)
    }

    /// The inputs acting on the sheet at elapsed time `e`: the commands,
    /// each actuator's replaced by its response.
    pub(super) fn inputs_at(&self, e: f64, u: &mut [f64]) {
        self.commands_at(e, u);
        if !self.actuation.is_ideal() {
            for (k, x) in u.iter_mut().enumerate().take(self.act0.len()) {
                *x = self.actuator(k, e)[0];
            }
        }
    }

    /// Actuator `k`'s value and rate at elapsed time `e` (its response to
    /// the master's input or to the built-in ramp).
    pub(super) fn actuator(&self, k: usize, e: f64) -> [f64; 2] {
        if self.ramped.contains(&k) {
            return self
                .actuation
                .ramp_response(self.act0[k], &self.ramp, self.t0, e);
        }
        let slope = (self.u1[k] - self.u0[k]) / self.big_h + self.slopes[k];
        let s2 = self.second.get(k).copied().unwrap_or(0.0);
        if self.actuation.is_ideal() {
            [self.command(k, e), self.command_rate(k, e)]
        } else {
            self.actuation
                .response(self.act0[k], self.u0[k], [slope, s2], e)
        }
    }

    /// The state's inputs at the end of the advance: each actuator where
    /// its response ends, an input with a second derivative along its
    /// parabola (its slope grown), and the values in force.
    pub(super) fn finish(&self, state: &mut ModelState) {
        for (k, a) in state.actuators.iter_mut().enumerate() {
            *a = self.actuator(k, self.big_h);
        }
        for (s1, s2) in state
            .input_slopes
            .iter_mut()
            .zip(&state.input_second_derivatives)
        {
            *s1 += s2 * self.big_h;
        }
        let mut u = state.inputs_now.clone();
        self.commands_at(self.big_h, &mut u);
        state.inputs_now.clone_from(&u);
        state.inputs_next = u;
    }
}

/// A folding sequence in the input path: the rest angles of the creases
/// it folds as a function of its actuator's value (piecewise linear,
/// continuous; [`crate::scene::sequence`]).
pub(super) struct SequenceDrive {
    /// The actuator (input) whose value walks the stages.
    pub(super) actuator: usize,
    /// The drive at each stage start, and 1.
    pub(super) breakpoints: Vec<f64>,
    /// Each crease end it folds with its (stage, target) entries.
    pub(super) ends: Vec<(usize, Vec<(usize, f64)>)>,
}

impl SequenceDrive {
    /// Where the drive is under the actuator values `u`.
    pub(super) fn locate(&self, u: &[f64]) -> sequence::Position {
        sequence::locate(&self.breakpoints, u[self.actuator])
    }

    /// Add the sequence's fold angles under `u` to the rest angles `theta0`.
    fn add_rest(&self, u: &[f64], theta0: &mut [f64]) {
        let p = self.locate(u);
        for (end, entries) in &self.ends {
            theta0[*end] += sequence::angle_at(entries, p);
        }
    }
}

/// How input values become rest angles, moments, forces and prescribed
/// DOFs of the assembly.
pub(super) struct InputMap {
    /// For each crease end: (actuator index, fold target) of rest-angle
    /// actuators (not the sequence's).
    pub(super) rest: Vec<Vec<(usize, f64)>>,
    /// The folding sequence, if the scene has one.
    pub(super) sequence: Option<SequenceDrive>,
    /// For each crease end: torque actuators acting on it.
    pub(super) torque: Vec<Vec<usize>>,
    /// Length share of each crease end (moments are per unit length).
    pub(super) end_length: Vec<f64>,
    /// Constant external force (gravity), all DOFs; None without gravity.
    pub(super) gravity: Option<Vec<f64>>,
    /// Slots fixed by supports (value = reference value), scalar indices.
    pub(super) supported: Vec<(usize, f64)>,
    /// Scalar indices of each motion input component (input index, scalar).
    pub(super) motion: Vec<(usize, usize)>,
    /// Scalar index of each force input component (input index, scalar).
    pub(super) force: Vec<(usize, usize)>,
    /// The attachments: their pose inputs and held slots.
    pub(super) frames: Vec<FrameInput>,
    /// The first pose input of each moving obstacle.
    pub(super) obstacles: Vec<usize>,
    pub(super) n_dofs: usize,
}

/// Inputs of one step turned into what the assembly needs (buffers
/// reused from step to step).
#[derive(Default)]
pub(super) struct DriveValues {
    pub(super) theta0: Vec<f64>,
    pub(super) moment: Vec<f64>,
    pub(super) f_ext: Vec<f64>,
    pub(super) prescribed: Vec<(usize, f64)>,
    /// The attachments' frames.
    pub(super) frames: Vec<Pose>,
    /// The moving obstacles' placements and velocities (set by
    /// [`InputMap::move_obstacles`]).
    pub(super) obstacles: Vec<Motion>,
}

impl InputMap {
    /// The rest angle of every crease end under the input values `u`:
    /// `pi + u x target` of its rest-angle actuator, or where its folding
    /// sequence puts it.
    fn rest_into(&self, u: &[f64], theta0: &mut Vec<f64>) {
        let pi = std::f64::consts::PI;
        theta0.clear();
        theta0.extend(
            self.rest
                .iter()
                .map(|r| pi + r.iter().map(|&(a, tgt)| u[a] * tgt).sum::<f64>()),
        );
        if let Some(sq) = &self.sequence {
            sq.add_rest(u, theta0);
        }
    }

    /// Fill `d` from the input values `u`.
    pub(super) fn drive_into(&self, u: &[f64], d: &mut DriveValues) {
        self.rest_into(u, &mut d.theta0);
        d.moment.clear();
        d.moment.extend(
            self.torque
                .iter()
                .zip(&self.end_length)
                .map(|(t, l)| t.iter().map(|&a| u[a]).sum::<f64>() * l),
        );
        match &self.gravity {
            Some(g) => d.f_ext.clone_from(g),
            None => {
                d.f_ext.clear();
                d.f_ext.resize(self.n_dofs, 0.0);
            }
        }
        for &(k, i) in &self.force {
            d.f_ext[i] += u[k];
        }
        d.prescribed.clone_from(&self.supported);
        d.prescribed
            .extend(self.motion.iter().map(|&(k, i)| (i, u[k])));
        d.frames.clear();
        for f in &self.frames {
            let pose = f.pose(u);
            f.held.prescribe(&pose, &mut d.prescribed);
            d.frames.push(pose);
        }
    }

    /// The moving obstacles' motions under the inputs `u` and their first
    /// and second derivatives `d1`, `d2`, into `d`.
    pub(super) fn move_obstacles(
        &self,
        u: &[f64],
        (d1, d2): (&[f64], &[f64]),
        d: &mut DriveValues,
    ) {
        d.obstacles.clear();
        d.obstacles.extend(
            self.obstacles
                .iter()
                .map(|&i| super::attach::motion(i, u, d1, d2)),
        );
    }

    /// Work done at once when input `i` jumps from `u[i]` to `new` while
    /// held: the crease springs whose rest angles it moves (its rest-angle
    /// actuator's creases, or its sequence's), at the crease angles
    /// `theta`, change their energy (a moment or a force does no work
    /// without motion).
    pub(super) fn jump_work(
        &self,
        asm: &Assembler,
        i: usize,
        new: f64,
        u: &[f64],
        theta: &[f64],
    ) -> f64 {
        let mut before = Vec::new();
        self.rest_into(u, &mut before);
        let mut moved = u.to_vec();
        moved[i] = new;
        let mut after = Vec::new();
        self.rest_into(&moved, &mut after);
        let kl = asm.physics.crease_k_per_length;
        let mut w = 0.0;
        for (e, (r0, r1)) in before.iter().zip(&after).enumerate() {
            if r1 == r0 {
                continue;
            }
            let k = kl * asm.creases[e].length;
            w += 0.5 * k * ((theta[e] - r1).powi(2) - (theta[e] - r0).powi(2));
        }
        w
    }

    /// The drive values for `u`, freshly allocated.
    pub(super) fn drive(&self, u: &[f64]) -> DriveValues {
        let mut d = DriveValues::default();
        self.drive_into(u, &mut d);
        d
    }
}

impl DriveValues {
    /// Work done by the drive over a step from `self` (state `q0`, crease
    /// angles `theta0`) to `next` (`q1`, `theta1`), by the trapezoidal rule:
    /// rest angles moved against the springs (`dU/dtheta0 = k (theta0 -
    /// theta)`), crease moments through the angle change, external forces
    /// through the displacement.
    pub(super) fn work_to(
        &self,
        next: &DriveValues,
        asm: &Assembler,
        (q0, theta0): (&[f64], &[f64]),
        (q1, theta1): (&[f64], &[f64]),
    ) -> f64 {
        let kl = asm.physics.crease_k_per_length;
        let mut w = 0.0;
        for (e, ce) in asm.creases.iter().enumerate() {
            let k = kl * ce.length;
            let (r0, r1) = (self.theta0[e], next.theta0[e]);
            w += 0.5 * k * ((r0 - theta0[e]) + (r1 - theta1[e])) * (r1 - r0);
            w += 0.5 * (self.moment[e] + next.moment[e]) * (theta1[e] - theta0[e]);
        }
        for i in 0..q0.len() {
            w += 0.5 * (self.f_ext[i] + next.f_ext[i]) * (q1[i] - q0[i]);
        }
        w
    }

    /// What a stepper takes for a step from crease angles `theta_prev`.
    pub(super) fn stepper_drive<'a>(&'a self, theta_prev: &'a [f64]) -> Drive<'a> {
        Drive {
            theta0: &self.theta0,
            moment: &self.moment,
            f_ext: &self.f_ext,
            prescribed: &self.prescribed,
            theta_prev,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Actuation;

    fn actuator_response(tau: f64, start: [f64; 2], u0: f64, slopes: [f64; 2], e: f64) -> [f64; 2] {
        Actuation { tau }.response(start, u0, slopes, e)
    }

    fn ramp_response(
        tau: f64,
        start: [f64; 2],
        ramp: &crate::scene::InputRamp,
        t0: f64,
        e: f64,
    ) -> [f64; 2] {
        Actuation { tau }.ramp_response(start, ramp, t0, e)
    }

    /// The closed form solves tau^2 a'' + 2 tau a' + a = u0 + s t from its
    /// start, its rate is the derivative of its value, a ramp is followed
    /// with the lag 2 tau, and tau = 0 gives the input itself.
    #[test]
    fn actuator_response_solves_its_equation() {
        let (tau, start, u0, s) = (0.02, [0.3, -1.5], 1.0, 2.0);
        let at = |t: f64| actuator_response(tau, start, u0, [s, 0.0], t);
        let [a0, r0] = at(0.0);
        assert!((a0 - start[0]).abs() < 1e-15 && (r0 - start[1]).abs() < 1e-15);
        let d = 1e-6;
        for t in [0.001, 0.01, 0.05] {
            let [a, r] = at(t);
            let rate = (at(t + d)[0] - at(t - d)[0]) / (2.0 * d);
            let acc = (at(t + d)[1] - at(t - d)[1]) / (2.0 * d);
            assert!(
                (rate - r).abs() < 1e-6 * (1.0 + r.abs()),
                "rate {rate} vs {r}"
            );
            let residual = tau * tau * acc + 2.0 * tau * r + a - (u0 + s * t);
            assert!(residual.abs() < 1e-6, "residual {residual} at {t}");
        }
        let [a, r] = at(2.0);
        assert!((a - (u0 + s * (2.0 - 2.0 * tau))).abs() < 1e-12);
        assert!((r - s).abs() < 1e-12);
        assert_eq!(
            actuator_response(0.0, start, u0, [s, 0.0], 0.5),
            [u0 + s * 0.5, s]
        );
        // A second derivative: the equation with u0 + s t + c t^2 / 2.
        let c = -3.0;
        let at = |t: f64| actuator_response(tau, start, u0, [s, c], t);
        for t in [0.001, 0.03, 0.2] {
            let [a, r] = at(t);
            let rate = (at(t + d)[0] - at(t - d)[0]) / (2.0 * d);
            let acc = (at(t + d)[1] - at(t - d)[1]) / (2.0 * d);
            assert!((rate - r).abs() < 1e-6 * (1.0 + r.abs()), "{rate} vs {r}");
            let u = u0 + s * t + 0.5 * c * t * t;
            let residual = tau * tau * acc + 2.0 * tau * r + a - u;
            assert!(residual.abs() < 1e-6, "residual {residual} at {t}");
        }
        let [a, r] = at(0.0);
        assert!((a - start[0]).abs() < 1e-15 && (r - start[1]).abs() < 1e-14);
    }

    /// The ramp's response solves the same equation on both sides of the
    /// ramp's end, is continuous in value and rate across it, splits into
    /// pieces at any point, and settles at 1.
    #[test]
    fn ramp_response_solves_its_equation() {
        use crate::scene::{InputRamp, RampShape};
        let tau = 0.01;
        for shape in [RampShape::Linear, RampShape::Smooth] {
            let ramp = InputRamp { time: 0.1, shape };
            let at = |t: f64| ramp_response(tau, [0.0, 0.0], &ramp, 0.0, t);
            let d = 1e-6;
            for t in [0.003, 0.05, 0.0999, 0.1001, 0.2] {
                let [a, r] = at(t);
                let rate = (at(t + d)[0] - at(t - d)[0]) / (2.0 * d);
                let acc = (at(t + d)[1] - at(t - d)[1]) / (2.0 * d);
                assert!(
                    (rate - r).abs() < 1e-5 * (1.0 + r.abs()),
                    "{shape:?} {t}: {rate} vs {r}"
                );
                let residual = tau * tau * acc + 2.0 * tau * r + a - ramp.value(t);
                assert!(
                    residual.abs() < 1e-5,
                    "{shape:?}: residual {residual} at {t}"
                );
            }
            // Two pieces give what one does.
            let mid = at(0.07);
            let [a, r] = ramp_response(tau, mid, &ramp, 0.07, 0.06);
            let [b, q] = at(0.13);
            assert!((a - b).abs() < 1e-12 && (r - q).abs() < 1e-10);
            let [a, r] = at(1.0);
            assert!((a - 1.0).abs() < 1e-12 && r.abs() < 1e-12);
        }
    }
}
