//! How input values drive the assembly: rest angles, crease moments,
//! external forces and prescribed DOFs.

use super::Model;
use super::attach::FrameInput;
use crate::assembly::Assembler;
use crate::frame::{Motion, Pose};
use crate::scene::InputRamp;
use crate::solver::stepper::Drive;

/// Below this time constant (s) an actuator follows its input at once.
const INSTANT: f64 = 1e-12;

/// An actuator's value and rate `e` seconds after `start` (value, rate)
/// under the input `u0 + s1 t + s2 t^2 / 2` (`[s1, s2]` = `slopes`): the
/// critically damped response of natural frequency 1 / `tau`, in closed
/// form, `a'' + 2 a' / tau + a / tau^2 = u / tau^2`. With `tau` 0 the input
/// itself.
pub(super) fn actuator_response(
    tau: f64,
    start: [f64; 2],
    u0: f64,
    [s1, s2]: [f64; 2],
    e: f64,
) -> [f64; 2] {
    let input = |t: f64| [u0 + s1 * t + 0.5 * s2 * t * t, s1 + s2 * t];
    if tau.is_nan() || tau <= INSTANT {
        return input(e);
    }
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
/// response piece by piece, the rise (a polynomial of degree 1 or 3) and
/// the hold after it. With `tau` 0 the ramp itself.
pub(super) fn ramp_response(
    tau: f64,
    start: [f64; 2],
    ramp: &InputRamp,
    t0: f64,
    e: f64,
) -> [f64; 2] {
    if tau.is_nan() || tau <= INSTANT {
        return [ramp.value(t0 + e), ramp.derivatives(t0 + e)[1]];
    }
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

/// How input values become rest angles, moments, forces and prescribed
/// DOFs of the assembly.
pub(super) struct InputMap {
    /// For each crease end: (actuator index, fold target) of rest-angle actuators.
    pub(super) rest: Vec<Vec<(usize, f64)>>,
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
    /// Fill `d` from the input values `u`.
    pub(super) fn drive_into(&self, u: &[f64], d: &mut DriveValues) {
        let pi = std::f64::consts::PI;
        d.theta0.clear();
        d.theta0.extend(
            self.rest
                .iter()
                .map(|r| pi + r.iter().map(|&(a, tgt)| u[a] * tgt).sum::<f64>()),
        );
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
    /// held: the crease springs of its rest-angle actuators, at the crease
    /// angles `theta`, change their energy (a moment or a force does no
    /// work without motion).
    pub(super) fn jump_work(
        &self,
        asm: &Assembler,
        i: usize,
        new: f64,
        u: &[f64],
        theta: &[f64],
    ) -> f64 {
        let pi = std::f64::consts::PI;
        let kl = asm.physics.crease_k_per_length;
        let mut w = 0.0;
        for (e, r) in self.rest.iter().enumerate() {
            let dr: f64 = r
                .iter()
                .filter(|&&(a, _)| a == i)
                .map(|&(_, tgt)| (new - u[i]) * tgt)
                .sum();
            if dr == 0.0 {
                continue;
            }
            let r0 = pi + r.iter().map(|&(a, tgt)| u[a] * tgt).sum::<f64>();
            let k = kl * asm.creases[e].length;
            w += 0.5 * k * ((theta[e] - r0 - dr).powi(2) - (theta[e] - r0).powi(2));
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
    use super::{actuator_response, ramp_response};

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
