//! The plain Rust `Model` API: one origami scene, its state, and a stepper.
//! The FMU, the CLI and the tests all drive the model through this API.
//!
//! Variables are flat, numbered tables (parameters, inputs, outputs) so that
//! the FMI layer only maps value references onto indices.
//!
//! Life cycle: [`Model::new`] validates and builds the scene;
//! [`Model::set_parameter`] may change parameters until
//! [`Model::initialize`]; then [`Model::set_input`] and [`Model::advance`]
//! alternate. As in FMI 2.0 co-simulation, an input set before an advance
//! from t is the input at t, held over the advance (plus a slope given with
//! [`Model::set_input_derivative`]); a scene with `input_timing: "ramp"`
//! instead ramps each input over the advance to the value set.

use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::fmt;

/// One scalar variable of the model, as the FMU and CSV files name it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VariableSpec {
    /// Structured name, e.g. `vertex[3].x`, `crease[7].angle`, `fold`.
    pub name: String,
    /// SI unit symbol ("" for dimensionless).
    pub unit: String,
    /// One line for a user.
    pub description: String,
    /// Start value.
    pub start: f64,
}

/// Errors of the model API; each names what is wrong.
#[derive(Clone, Debug, PartialEq)]
#[allow(missing_docs)] // variant fields are named for what they hold
pub enum Error {
    /// The scene cannot be turned into a model.
    Scene(String),
    /// A variable index is out of range.
    NoSuchVariable { kind: &'static str, index: usize },
    /// A non-finite or out-of-range value for a variable; nothing changed.
    BadValue {
        name: String,
        value: f64,
        reason: String,
    },
    /// A call that is not allowed in the current phase.
    Phase(String),
    /// The stepper could not complete; the state is as it was before.
    StepFailed { time: f64, reason: String },
    /// A saved state does not fit this model.
    State(String),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Scene(m) => write!(f, "invalid scene: {m}"),
            Error::NoSuchVariable { kind, index } => write!(f, "no {kind} with index {index}"),
            Error::BadValue {
                name,
                value,
                reason,
            } => {
                write!(f, "{name} = {value}: {reason}; value not applied")
            }
            Error::Phase(m) => write!(f, "{m}"),
            Error::StepFailed { time, reason } => {
                write!(
                    f,
                    "step from t = {time} failed: {reason}; state rolled back"
                )
            }
            Error::State(m) => write!(f, "bad saved state: {m}"),
        }
    }
}

impl std::error::Error for Error {}

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
    }
}

use crate::assembly::{Assembler, Evaluation, Physics, State};
use crate::element::ElementOptions;
use crate::scene::{ActuatorMode, CreaseStiffness, Fix, InputTiming, Integrator, Scene};
use crate::solver::SparseSolver;
use crate::solver::central_difference::CentralDifference;
use crate::solver::generalized_alpha::{self as ga, Dynamics};

/// Life-cycle phase of a [`Model`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Phase {
    /// Built; parameters may change.
    Setup,
    /// [`Model::initialize`] done; inputs and steps.
    Running,
}

/// A saved model state (see [`Model::save_state`]); serde-serializable.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModelState {
    /// Simulation time.
    pub time: f64,
    /// Positions, velocities, accelerations (all DOFs; empty before initialization).
    pub dynamics: Dynamics,
    /// Unwrapped angle of every crease end at `time` (continuity through 0 = 2 pi).
    pub crease_theta: Vec<f64>,
    /// Input values in force at `time`.
    pub inputs_now: Vec<f64>,
    /// Input values at the end of the next advance before slopes (equal to
    /// `inputs_now` unless the scene ramps its inputs).
    pub inputs_next: Vec<f64>,
    /// First time derivative of each input over the next advance.
    #[serde(default)]
    pub input_slopes: Vec<f64>,
    /// Whether a damping parameter was set (automatic damping is then off).
    #[serde(default)]
    pub damping_set: bool,
    /// Where the implicit stepper's iteration matrix was formed (kept across
    /// advances by modified Newton; None: the next step forms one).
    #[serde(default)]
    pub jacobian: Option<ga::JacobianPoint>,
    /// Parameter values.
    pub parameters: Vec<f64>,
    /// Phase.
    pub phase: Phase,
    /// Internal step size the controller proposes next.
    pub h_next: f64,
    /// Output values at `time`.
    pub outputs: Vec<f64>,
}

/// Everything built at initialization from the scene and parameters.
struct System {
    asm: Assembler,
    solver: SparseSolver,
    coeffs: ga::Coefficients,
    settings: ga::Settings,
    scales: Vec<f64>,
    inputs: InputMap,
    /// For each `crease[e]` output: the crease ends averaged.
    angle_ends: Vec<Vec<usize>>,
    ws: ga::Workspace,
    /// The explicit stepper when the scene asks for central differences
    /// (made at initialization).
    cd: Option<CentralDifference>,
    max_step: f64,
    min_step: f64,
    max_internal_steps: usize,
}

/// How input values become rest angles, moments, forces and prescribed
/// DOFs of the assembly.
struct InputMap {
    /// For each crease end: (actuator index, fold target) of rest-angle actuators.
    rest: Vec<Vec<(usize, f64)>>,
    /// For each crease end: torque actuators acting on it.
    torque: Vec<Vec<usize>>,
    /// Length share of each crease end (moments are per unit length).
    end_length: Vec<f64>,
    /// Constant external force (gravity), all DOFs; None without gravity.
    gravity: Option<Vec<f64>>,
    /// Slots fixed by supports (value = reference value), scalar indices.
    supported: Vec<(usize, f64)>,
    /// Scalar indices of each motion input component (input index, scalar).
    motion: Vec<(usize, usize)>,
    /// Scalar index of each force input component (input index, scalar).
    force: Vec<(usize, usize)>,
    n_dofs: usize,
}

/// One origami scene with its state and stepper.
pub struct Model {
    scene: Scene,
    parameters: Vec<VariableSpec>,
    inputs: Vec<VariableSpec>,
    outputs: Vec<VariableSpec>,
    state: ModelState,
    sys: Option<System>,
    /// Parameter values the current `sys` was built with.
    built_with: Option<Vec<f64>>,
    /// Whether the scene asked for automatic damping.
    auto_damping: bool,
}

impl Model {
    /// Build a model of a validated scene.
    pub fn new(scene: Scene) -> Result<Model, Error> {
        let facets = scene.mesh.triangles.len();
        if facets > crate::scene::build::MAX_FACETS {
            // Refused before the large allocations of the assembly.
            return Err(Error::Scene(
                crate::scene::build::over_budget("mesh", facets, "the mesh has").to_string(),
            ));
        }
        let parameters = parameter_table(&scene);
        let inputs = input_table(&scene);
        let outputs = output_table(&scene);
        let state = ModelState {
            time: 0.0,
            dynamics: Dynamics {
                q: vec![],
                v: vec![],
                qdd: vec![],
                abar: vec![],
            },
            crease_theta: vec![],
            inputs_now: inputs.iter().map(|v| v.start).collect(),
            inputs_next: inputs.iter().map(|v| v.start).collect(),
            input_slopes: vec![0.0; inputs.len()],
            damping_set: false,
            jacobian: None,
            parameters: parameters.iter().map(|v| v.start).collect(),
            phase: Phase::Setup,
            h_next: scene.solver.max_step,
            outputs: outputs.iter().map(|v| v.start).collect(),
        };
        // Build once now so that a bad scene fails at instantiation.
        let auto_damping = scene.auto_damping;
        let mut m = Model {
            auto_damping,
            scene,
            parameters,
            inputs,
            outputs,
            state,
            sys: None,
            built_with: None,
        };
        m.build()?;
        Ok(m)
    }

    /// The scene the model was built from (with parameters as last set).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }
    /// Parameters (settable before [`Model::initialize`]).
    pub fn parameters(&self) -> &[VariableSpec] {
        &self.parameters
    }
    /// Inputs, one per actuator, then vertex forces and motions (x, y, z).
    pub fn inputs(&self) -> &[VariableSpec] {
        &self.inputs
    }
    /// Outputs: vertex positions, crease angles, energies (as the scene selects).
    pub fn outputs(&self) -> &[VariableSpec] {
        &self.outputs
    }
    /// Current simulation time in s.
    pub fn time(&self) -> f64 {
        self.state.time
    }
    /// Current phase.
    pub fn phase(&self) -> Phase {
        self.state.phase
    }
    /// Number of scalar degrees of freedom (free and fixed).
    pub fn n_dofs(&self) -> usize {
        self.sys.as_ref().map(|s| s.asm.n_dofs()).unwrap_or(0)
    }

    /// Value of parameter `i`.
    pub fn parameter(&self, i: usize) -> Result<f64, Error> {
        self.state
            .parameters
            .get(i)
            .copied()
            .ok_or(Error::NoSuchVariable {
                kind: "parameter",
                index: i,
            })
    }

    /// Set parameter `i`; only before [`Model::initialize`]. A non-finite or
    /// out-of-range value is rejected and nothing changes.
    pub fn set_parameter(&mut self, i: usize, value: f64) -> Result<(), Error> {
        let spec = self.parameters.get(i).ok_or(Error::NoSuchVariable {
            kind: "parameter",
            index: i,
        })?;
        if self.state.phase != Phase::Setup {
            return Err(Error::Phase(format!(
                "parameter {} can only be set before initialization",
                spec.name
            )));
        }
        let bad = |reason: String| Error::BadValue {
            name: spec.name.clone(),
            value,
            reason,
        };
        crate::scene::limits::check(&spec.name, value).map_err(bad)?;
        if spec.name == "solver.max_step" {
            let mut so = self.scene.solver;
            so.max_step = value;
            crate::scene::limits::check_solver_relations(&so).map_err(|(_, why)| bad(why))?;
        }
        if spec.name.starts_with("damping.") {
            self.state.damping_set = true;
        }
        self.state.parameters[i] = value;
        Ok(())
    }

    /// Value of input `i` as last set (in force now; with ramped inputs,
    /// the value the next advance ends at).
    pub fn input(&self, i: usize) -> Result<f64, Error> {
        self.input_spec(i)?;
        Ok(match self.scene.solver.input_timing {
            InputTiming::Hold => self.state.inputs_now[i],
            InputTiming::Ramp => self.state.inputs_next[i],
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
    /// Ramped inputs: the value the next advance ends at. Non-finite values
    /// are rejected.
    pub fn set_input(&mut self, i: usize, value: f64) -> Result<(), Error> {
        let spec = self.input_spec(i)?;
        if !value.is_finite() {
            return Err(Error::BadValue {
                name: spec.name.clone(),
                value,
                reason: "not a finite number".into(),
            });
        }
        self.state.inputs_next[i] = value;
        if self.state.phase == Phase::Setup || self.scene.solver.input_timing == InputTiming::Hold {
            self.state.inputs_now[i] = value;
        }
        self.state.input_slopes[i] = 0.0;
        Ok(())
    }

    /// Set the `order`-th time derivative of input `i` (only order 1: the
    /// input then grows linearly from its value over the advance, as
    /// `fmi2SetRealInputDerivatives` asks). It applies until the input or
    /// its derivative is set again. Not with ramped inputs.
    pub fn set_input_derivative(&mut self, i: usize, order: i32, value: f64) -> Result<(), Error> {
        let spec = self.input_spec(i)?;
        let bad = |reason: &str| Error::BadValue {
            name: format!("derivative of order {order} of {}", spec.name),
            value,
            reason: reason.into(),
        };
        if order != 1 {
            return Err(bad("only first derivatives are taken (order 1)"));
        }
        if self.scene.solver.input_timing == InputTiming::Ramp {
            return Err(bad(
                "the scene ramps its inputs (solver input_timing \"ramp\"); derivatives need held inputs",
            ));
        }
        if !value.is_finite() {
            return Err(bad("not a finite number"));
        }
        self.state.input_slopes[i] = value;
        Ok(())
    }

    /// Give the sheet a rigid velocity field v(x) = linear + angular x (x -
    /// center), on every free DOF (supports and prescribed motions keep
    /// theirs), and make the accelerations consistent with it. Allowed after
    /// [`Model::initialize`]; the next advance starts from this state.
    pub fn set_rigid_velocity(
        &mut self,
        linear: [f64; 3],
        angular: [f64; 3],
        center: [f64; 3],
    ) -> Result<(), Error> {
        if self.state.phase != Phase::Running {
            return Err(Error::Phase(
                "set_rigid_velocity needs an initialized model".into(),
            ));
        }
        if linear
            .iter()
            .chain(&angular)
            .chain(&center)
            .any(|x| !x.is_finite())
        {
            return Err(Error::BadValue {
                name: "rigid velocity".into(),
                value: f64::NAN,
                reason: "every component must be finite".into(),
            });
        }
        let sys = self.sys.as_ref().expect("initialized");
        let q = &self.state.dynamics.q;
        let mut v = vec![0.0; q.len()];
        sys.asm
            .rigid
            .rigid_velocity(q, linear.into(), angular.into(), center.into(), &mut v);
        // Supports and prescribed motions keep their velocities.
        for (i, x) in v.iter_mut().enumerate() {
            if sys.asm.free[i] == crate::assembly::FIXED {
                *x = self.state.dynamics.v[i];
            }
        }
        let saved = self.state.clone();
        self.state.dynamics.v = v;
        let theta = self.state.crease_theta.clone();
        let u = self.state.inputs_now.clone();
        if let Err(e) = self.consistent_accelerations(&u, &theta) {
            self.state = saved;
            return Err(e);
        }
        Ok(())
    }

    /// End of setup: apply parameters, build the system and compute the
    /// initial accelerations.
    pub fn initialize(&mut self) -> Result<(), Error> {
        if self.state.phase != Phase::Setup {
            return Err(Error::Phase("model is already initialized".into()));
        }
        self.apply_parameters();
        // Model::new built the system; build again only for changed parameters.
        if self.sys.is_none() || self.built_with.as_deref() != Some(&self.state.parameters[..]) {
            self.build()?;
        }
        let sys = self.sys.as_mut().expect("built");
        let n = sys.asm.n_dofs();
        let mut q = sys.asm.layout.reference_state(&self.scene.mesh);
        let u = self.state.inputs_now.clone();
        for &(i, x) in &sys.inputs.drive(&u).prescribed {
            q[i] = x;
        }
        let theta_prev = vec![std::f64::consts::PI; sys.asm.creases.len()];
        self.state.dynamics = Dynamics {
            q,
            v: vec![0.0; n],
            qdd: vec![0.0; n],
            abar: vec![0.0; n],
        };
        self.consistent_accelerations(&u, &theta_prev)?;
        self.state.h_next = self.sys.as_ref().expect("built").max_step;
        self.state.phase = Phase::Running;
        Ok(())
    }

    /// Accelerations from the equation of motion at the current positions
    /// and velocities, M qdd = f_ext - f_int on the free DOFs (the mass
    /// matrix is factored in the stepper's solver, so its iteration matrix
    /// is forgotten); also the crease angles and outputs.
    fn consistent_accelerations(&mut self, u: &[f64], theta_prev: &[f64]) -> Result<(), Error> {
        let sys = self.sys.as_mut().expect("built");
        let n = sys.asm.n_dofs();
        let d = sys.inputs.drive(u);
        let dynm = &self.state.dynamics;
        let mut ev = Evaluation::default();
        sys.asm
            .evaluate(
                &State {
                    q: &dynm.q,
                    v: &dynm.v,
                    theta0: &d.theta0,
                    moment: &d.moment,
                    theta_prev,
                },
                &mut ev,
                None,
            )
            .map_err(Error::Scene)?;
        let mut rhs = vec![0.0; sys.asm.n_free];
        for i in 0..n {
            let fi = sys.asm.free[i];
            if fi != crate::assembly::FIXED {
                rhs[fi] = d.f_ext[i] - ev.force[i];
            }
        }
        sys.ws.invalidate_jacobian();
        self.state.jacobian = None;
        let mvals = sys.asm.mass_values().to_vec();
        sys.solver
            .factor(&mvals)
            .map_err(|e| Error::Scene(format!("mass matrix: {e}")))?;
        sys.solver
            .solve_in_place(&mut rhs)
            .map_err(|e| Error::Scene(format!("mass matrix: {e}")))?;
        let mut qdd = vec![0.0; n];
        for (a, &fi) in qdd.iter_mut().zip(&sys.asm.free) {
            if fi != crate::assembly::FIXED {
                *a = rhs[fi];
            }
        }
        self.state.dynamics.abar = qdd.clone();
        self.state.dynamics.qdd = qdd;
        self.state.crease_theta = ev.theta.clone();
        self.state.outputs = self.compute_outputs(&ev);
        Ok(())
    }

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
        let mut h = self.state.h_next.min(sys.max_step);
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
        let cap = sys.max_internal_steps;
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
                &sys.asm,
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
        if let Some(cd) = sys.cd.as_mut() {
            // Explicit: equal substeps below the stability limit.
            let n_sub = (big_h / cd.stable_step().min(sys.max_step)).ceil().max(1.0);
            if n_sub > cap as f64 {
                return Err(too_many());
            }
            let h = big_h / n_sub;
            let t_asm = cd.assembly_time;
            let t_solve = cd.solve_time();
            for k in 1..=n_sub as usize {
                inputs_at(k as f64 * h, &mut u);
                sys.inputs.drive_into(&u, &mut d);
                let gd = ga::Drive {
                    theta0: &d.theta0,
                    moment: &d.moment,
                    f_ext: &d.f_ext,
                    prescribed: &d.prescribed,
                    theta_prev: &self.state.crease_theta,
                };
                cd.step(&sys.asm, &mut self.state.dynamics, h, &gd)
                    .map_err(|reason| Error::StepFailed {
                        time: t0 + (k - 1) as f64 * h,
                        reason,
                    })?;
                self.state.crease_theta.clone_from(&cd.evaluation().theta);
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
            let remaining = big_h - s;
            if h >= remaining || remaining - h < 1e-3 * h {
                h = remaining;
            }
            inputs_at(s + h, &mut u);
            sys.inputs.drive_into(&u, &mut d);
            let gd = ga::Drive {
                theta0: &d.theta0,
                moment: &d.moment,
                f_ext: &d.f_ext,
                prescribed: &d.prescribed,
                theta_prev: &self.state.crease_theta,
            };
            let res = ga::step(
                &sys.asm,
                &mut sys.solver,
                sys.coeffs,
                &self.state.dynamics,
                h,
                &gd,
                &sys.scales,
                sys.settings,
                &mut sys.ws,
            );
            // Keep the step within [min_step, max_step] (max wins, so a bad
            // pair of settings cannot panic here).
            let bounded = |x: f64| x.max(sys.min_step).min(sys.max_step);
            match res {
                Ok((next, out)) => {
                    report.newton_iterations += out.iterations;
                    report.factorizations += out.factorizations;
                    report.assembly_time += out.assembly_time.as_secs_f64();
                    let at_min = h <= sys.min_step * 1.000001;
                    if out.error <= 1.0 || at_min {
                        self.state.dynamics = next;
                        self.state
                            .crease_theta
                            .clone_from(&sys.ws.evaluation().theta);
                        s += h;
                        report.steps += 1;
                        report.min_step = report.min_step.min(h);
                        let grow = if out.error > 0.0 {
                            0.9 * out.error.powf(-1.0 / 3.0)
                        } else {
                            2.0
                        };
                        let hn = bounded(h * grow.clamp(0.2, 2.0));
                        // A short final step must not shrink the next advance's step.
                        self.state.h_next = if h < remaining {
                            hn
                        } else {
                            hn.max(self.state.h_next)
                        };
                        h = hn;
                    } else {
                        report.rejected += 1;
                        h = bounded(h * (0.9 * out.error.powf(-1.0 / 3.0)).clamp(0.2, 0.9));
                    }
                }
                Err(reason) => {
                    report.rejected += 1;
                    h *= 0.25;
                    if h < sys.min_step {
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
        }
        let ev = match &sys.cd {
            Some(cd) => cd.evaluation().clone(),
            None => sys.ws.evaluation().clone(),
        };
        inputs_at(big_h, &mut u);
        self.state.time = t0 + big_h;
        self.state.inputs_now.clone_from(&u);
        self.state.inputs_next = u;
        self.state.outputs = self.compute_outputs(&ev);
        if self.state.outputs.iter().any(|x| !x.is_finite()) {
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

    /// Current values of all outputs, in the order of [`Model::outputs`].
    pub fn output_values(&self) -> Vec<f64> {
        self.state.outputs.clone()
    }

    /// Kinetic, strain and crease energy now (J).
    pub fn energies(&self) -> [f64; 3] {
        let o = &self.state.outputs;
        if self.scene.outputs.energies {
            [o[o.len() - 3], o[o.len() - 2], o[o.len() - 1]]
        } else {
            [f64::NAN; 3]
        }
    }

    /// Current position of mesh vertex `v`.
    pub fn vertex_position(&self, v: usize) -> [f64; 3] {
        match &self.sys {
            Some(sys) if self.state.phase == Phase::Running => {
                let s = sys.asm.position_slot(v);
                let q = &self.state.dynamics.q;
                [q[3 * s], q[3 * s + 1], q[3 * s + 2]]
            }
            _ => {
                let x = self.scene.mesh.coords[v];
                [x.x, x.y, 0.0]
            }
        }
    }

    /// Strain energy (membrane + bending, J) of each mesh triangle now, in
    /// the order of `scene().mesh.triangles`; zeros before initialization
    /// (the flat reference state is stress-free).
    pub fn facet_strain_energies(&self) -> Vec<f64> {
        match &self.sys {
            Some(sys) if self.state.phase == Phase::Running => {
                sys.asm.facet_strain_energies(&self.state.dynamics.q)
            }
            _ => vec![0.0; self.scene.mesh.triangles.len()],
        }
    }

    fn compute_outputs(&self, ev: &Evaluation) -> Vec<f64> {
        let sys = self.sys.as_ref().expect("built");
        let mut out = Vec::with_capacity(self.outputs.len());
        let o = self.scene.outputs;
        if o.positions {
            for v in 0..self.scene.fold_vertex_count {
                out.extend(self.vertex_position(v));
            }
        }
        if o.fold_angles {
            for ends in &sys.angle_ends {
                let sum: f64 = ends
                    .iter()
                    .map(|&i| ev.theta[i] - std::f64::consts::PI)
                    .sum();
                out.push(sum / ends.len().max(1) as f64);
            }
        }
        if o.energies {
            let v = &self.state.dynamics.v;
            let mut mv = vec![0.0; v.len()];
            sys.asm.mass_mul(v, &mut mv);
            let ke = 0.5 * v.iter().zip(&mv).map(|(a, b)| a * b).sum::<f64>();
            out.extend([ke, ev.strain_energy, ev.crease_energy]);
        }
        out
    }

    /// A copy of the complete state, enough to continue bit-identically.
    pub fn save_state(&self) -> ModelState {
        self.state.clone()
    }

    /// Restore a state saved from a model of the same scene.
    pub fn restore_state(&mut self, s: &ModelState) -> Result<(), Error> {
        let n = self.sys.as_ref().map(|s| s.asm.n_dofs()).unwrap_or(0);
        let dyn_ok = match s.phase {
            Phase::Setup => true,
            Phase::Running => {
                let d = &s.dynamics;
                [d.q.len(), d.v.len(), d.qdd.len(), d.abar.len()]
                    .iter()
                    .all(|&l| l == n)
                    && s.crease_theta.len()
                        == self.sys.as_ref().map(|s| s.asm.creases.len()).unwrap_or(0)
            }
        };
        let mut s = s.clone();
        if s.input_slopes.is_empty() {
            // A state saved before inputs had slopes.
            s.input_slopes = vec![0.0; s.inputs_now.len()];
        }
        let ok = dyn_ok
            && s.input_slopes.len() == self.inputs.len()
            && s.inputs_now.len() == self.inputs.len()
            && s.inputs_next.len() == self.inputs.len()
            && s.parameters.len() == self.parameters.len()
            && s.outputs.len() == self.outputs.len();
        if !ok {
            return Err(Error::State("its sizes do not match this model".into()));
        }
        if s.phase == Phase::Running && self.built_with.as_deref() != Some(&s.parameters[..]) {
            // The saved state ran with other parameters: rebuild for them.
            let keep = std::mem::replace(&mut self.state.parameters, s.parameters.clone());
            self.apply_parameters();
            if let Err(e) = self.build() {
                self.state.parameters = keep;
                self.apply_parameters();
                self.build()?;
                return Err(e);
            }
        }
        self.state = s;
        Ok(())
    }

    /// Put the parameter values into the scene. Automatic damping stays on
    /// until a damping parameter is set; while on, the damping parameters
    /// show the values it chose for the current material.
    fn apply_parameters(&mut self) {
        let sc = &mut self.scene;
        sc.auto_damping = self.auto_damping && !self.state.damping_set;
        let auto = sc.auto_damping;
        for (spec, &x) in self.parameters.iter().zip(&self.state.parameters) {
            match spec.name.as_str() {
                "material.youngs_modulus" => sc.material.youngs_modulus = x,
                "material.poisson_ratio" => sc.material.poisson_ratio = x,
                "material.thickness" => sc.material.thickness = x,
                "material.density" => sc.material.density = x,
                "crease.length_scale" => sc.crease = CreaseStiffness::LengthScale(x),
                "crease.stiffness_per_length" => sc.crease = CreaseStiffness::PerLength(x),
                "damping.alpha" if !auto => sc.damping.alpha = x,
                "damping.beta" if !auto => sc.damping.beta = x,
                "damping.crease" if !auto => sc.damping.crease = x,
                "gravity.x" | "gravity.y" | "gravity.z" => {
                    let c = match spec.name.as_bytes()[8] {
                        b'x' => 0,
                        b'y' => 1,
                        _ => 2,
                    };
                    if let Some(g) = sc.gravity.as_mut() {
                        g[c] = x;
                    }
                }
                "solver.rho_inf" => sc.solver.rho_inf = x,
                "solver.max_step" => sc.solver.max_step = x,
                "solver.tolerance" => sc.solver.tolerance = x,
                "solver.max_internal_steps" => sc.solver.max_internal_steps = x as usize,
                _ => {}
            }
        }
        if auto {
            let ph = physics(sc);
            for (spec, x) in self.parameters.iter().zip(&mut self.state.parameters) {
                match spec.name.as_str() {
                    "damping.alpha" => *x = ph.alpha,
                    "damping.beta" => *x = ph.beta,
                    "damping.crease" => *x = ph.crease_c_per_length,
                    _ => {}
                }
            }
        }
    }

    fn build(&mut self) -> Result<(), Error> {
        let sc = &self.scene;
        let mesh = &sc.mesh;
        let layout = crate::dofs::DofLayout::new(mesh);
        let q_ref = layout.reference_state(mesh);
        let mut fixed = Vec::new();
        let mut is_fixed = vec![false; layout.n_slots()];
        let mut supported = Vec::new();
        for sup in &sc.supports {
            for &v in &sup.vertices {
                let slots = match sup.fix {
                    Fix::Position => vec![layout.position_slot[v]],
                    Fix::Clamped => layout.vertex_slots(v),
                };
                for s in slots {
                    if !is_fixed[s] {
                        is_fixed[s] = true;
                        fixed.push(s);
                        for c in 0..3 {
                            supported.push((3 * s + c, q_ref[3 * s + c]));
                        }
                    }
                }
            }
        }
        let n_act = sc.actuators.len();
        let mut motion = Vec::new();
        let mut idx = n_act + 3 * sc.vertex_forces.len();
        for m in &sc.vertex_motions {
            let s = layout.position_slot[m.vertex];
            if !is_fixed[s] {
                is_fixed[s] = true;
                fixed.push(s);
            }
            for c in 0..3 {
                motion.push((idx + c, 3 * s + c));
            }
            idx += 3;
        }
        let mut force = Vec::new();
        for (k, f) in sc.vertex_forces.iter().enumerate() {
            let s = layout.position_slot[f.vertex];
            for c in 0..3 {
                force.push((n_act + 3 * k + c, 3 * s + c));
            }
        }
        let physics = physics(sc);
        let mut asm = Assembler::new(mesh, physics, ElementOptions::default(), &fixed)
            .map_err(Error::Scene)?;
        // Damping leaves alone the rigid motion the supports allow.
        let supported_dofs: Vec<usize> = supported.iter().map(|&(i, _)| i).collect();
        asm.rigid
            .set_supports(&supported_dofs, &q_ref, mesh.size().max(f64::MIN_POSITIVE));
        // Free scalars come in slots of 3 with one pattern.
        let solver =
            SparseSolver::new_blocked(asm.n_free, asm.col_ptr.clone(), asm.row_idx.clone(), 3)
                .map_err(Error::Scene)?;
        let nends = asm.creases.len();
        let mut rest = vec![Vec::new(); nends];
        let mut torque = vec![Vec::new(); nends];
        // The actuators of each mesh edge, in actuator order.
        let mut driven_by: Vec<Vec<usize>> = vec![Vec::new(); mesh.edges.len()];
        for (a, act) in sc.actuators.iter().enumerate() {
            for &e in &act.edges {
                if driven_by[e].last() != Some(&a) {
                    driven_by[e].push(a);
                }
            }
        }
        for (i, ce) in asm.creases.iter().enumerate() {
            for &a in &driven_by[ce.edge] {
                match sc.actuators[a].mode {
                    ActuatorMode::RestAngle => rest[i].push((a, mesh.edges[ce.edge].fold_target)),
                    ActuatorMode::Torque => torque[i].push(a),
                }
            }
        }
        let gravity = sc.gravity.map(|g| {
            let mut qg = vec![0.0; asm.n_dofs()];
            for v in 0..mesh.n_vertices() {
                let s = asm.position_slot(v);
                qg[3 * s..3 * s + 3].copy_from_slice(&g);
            }
            let mut f = vec![0.0; asm.n_dofs()];
            asm.mass_mul(&qg, &mut f);
            f
        });
        // For each crease output (FOLD edge), its crease ends in order.
        let outputs = fold_edges(sc);
        let mut output_of: HashMap<usize, usize> = HashMap::with_capacity(outputs.len());
        for (k, &fe) in outputs.iter().enumerate() {
            output_of.insert(fe, k);
        }
        let mut angle_ends: Vec<Vec<usize>> = vec![Vec::new(); outputs.len()];
        for (i, ce) in asm.creases.iter().enumerate() {
            if let Some(&k) = mesh.edges[ce.edge]
                .fold_edge
                .and_then(|fe| output_of.get(&fe))
            {
                angle_ends[k].push(i);
            }
        }
        let length = mesh.size().max(f64::MIN_POSITIVE);
        let scales = asm.scales(length);
        // The explicit stepper's stable step, estimated on the unstressed sheet.
        let cd = match sc.solver.integrator {
            Integrator::CentralDifference => Some(
                CentralDifference::new(&asm, &q_ref, &vec![std::f64::consts::PI; nends])
                    .map_err(Error::Scene)?,
            ),
            Integrator::GeneralizedAlpha => None,
        };
        let tol = sc.solver.tolerance;
        let sys = System {
            scales,
            solver,
            coeffs: ga::Coefficients::new(sc.solver.rho_inf),
            settings: ga::Settings {
                tolerance: tol,
                newton_tolerance: (1e-3 * tol).max(1e-13),
                max_newton: sc.solver.max_newton,
                newton: sc.solver.newton,
            },
            inputs: InputMap {
                rest,
                torque,
                end_length: asm.creases.iter().map(|c| c.length).collect(),
                gravity,
                supported,
                motion,
                force,
                n_dofs: asm.n_dofs(),
            },
            cd,
            angle_ends,
            ws: ga::Workspace::default(),
            max_step: sc.solver.max_step,
            min_step: sc.solver.min_step,
            max_internal_steps: sc.solver.max_internal_steps,
            asm,
        };
        self.sys = Some(sys);
        self.built_with = Some(self.state.parameters.clone());
        Ok(())
    }
}

/// Inputs of one step turned into what the assembly needs (buffers
/// reused from step to step).
#[derive(Default)]
struct DriveValues {
    theta0: Vec<f64>,
    moment: Vec<f64>,
    f_ext: Vec<f64>,
    prescribed: Vec<(usize, f64)>,
}

impl InputMap {
    /// Fill `d` from the input values `u`.
    fn drive_into(&self, u: &[f64], d: &mut DriveValues) {
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
    }

    /// The drive values for `u`, freshly allocated.
    fn drive(&self, u: &[f64]) -> DriveValues {
        let mut d = DriveValues::default();
        self.drive_into(u, &mut d);
        d
    }
}

/// The physics a scene asks for: material, crease stiffness per unit
/// length, damping (the automatic damping when the scene sets none).
pub fn physics(sc: &Scene) -> Physics {
    let material = sc.material;
    let k_pl = match sc.crease {
        CreaseStiffness::LengthScale(l) => material.bending_stiffness() / l,
        CreaseStiffness::PerLength(k) => k,
    };
    let (alpha, beta, crease) = if sc.auto_damping {
        (auto_alpha(sc, k_pl), 0.0, sc.damping.crease)
    } else {
        (sc.damping.alpha, sc.damping.beta, sc.damping.crease)
    };
    Physics {
        material,
        crease_k_per_length: k_pl,
        crease_c_per_length: crease,
        alpha,
        beta,
    }
}

/// Default damping: mass-proportional damping of the deformation rate
/// (rigid motion undamped, see [`crate::rigid`]) with damping ratio
/// [`AUTO_DAMPING_RATIO`] on the folding mode of a panel of the mean facet
/// size w hinged on its crease, omega = sqrt(3 k / (rho h w^3)) per unit
/// crease length. Every deformation mode then decays at the same rate
/// alpha / 2, so a fold settles within a few of its periods.
fn auto_alpha(sc: &Scene, k_per_length: f64) -> f64 {
    let mesh = &sc.mesh;
    let nt = mesh.triangles.len().max(1);
    let mean_area: f64 = (0..mesh.triangles.len()).map(|t| mesh.area(t)).sum::<f64>() / nt as f64;
    let w = (2.0 * mean_area).sqrt();
    let m = &sc.material;
    let omega = (3.0 * k_per_length / (m.density * m.thickness * w.powi(3))).sqrt();
    2.0 * AUTO_DAMPING_RATIO * omega
}

/// Damping ratio of the automatic damping on a mean facet's folding mode.
pub const AUTO_DAMPING_RATIO: f64 = 0.2;

/// FOLD edge indices that are creases, in increasing order: the `crease[e]`
/// outputs.
pub fn fold_edges(scene: &Scene) -> Vec<usize> {
    let mut es: Vec<usize> = scene
        .mesh
        .edges
        .iter()
        .filter(|e| e.kind == crate::mesh::EdgeKind::Crease)
        .filter_map(|e| e.fold_edge)
        .collect();
    es.sort_unstable();
    es.dedup();
    es
}

fn spec(name: String, unit: &str, description: String, start: f64) -> VariableSpec {
    VariableSpec {
        name,
        unit: unit.into(),
        description,
        start,
    }
}

fn parameter_table(scene: &Scene) -> Vec<VariableSpec> {
    let m = &scene.material;
    let mut p = vec![
        spec(
            "material.youngs_modulus".into(),
            "Pa",
            "Young's modulus".into(),
            m.youngs_modulus,
        ),
        spec(
            "material.poisson_ratio".into(),
            "",
            "Poisson's ratio".into(),
            m.poisson_ratio,
        ),
        spec(
            "material.thickness".into(),
            "m",
            "sheet thickness".into(),
            m.thickness,
        ),
        spec(
            "material.density".into(),
            "kg/m3",
            "mass density".into(),
            m.density,
        ),
    ];
    match scene.crease {
        crate::scene::CreaseStiffness::LengthScale(l) => p.push(spec(
            "crease.length_scale".into(),
            "m",
            "crease stiffness = (crease length / length_scale) * bending stiffness".into(),
            l,
        )),
        crate::scene::CreaseStiffness::PerLength(k) => p.push(spec(
            "crease.stiffness_per_length".into(),
            "N/rad",
            "rotational crease stiffness per unit crease length".into(),
            k,
        )),
    }
    // Start values: the damping in effect (the automatic choice, unless the
    // scene sets damping); setting any of them switches automatic damping off.
    let d = physics(scene);
    let auto = if scene.auto_damping {
        " (automatic damping until a damping parameter is set)"
    } else {
        ""
    };
    p.push(spec(
        "damping.alpha".into(),
        "1/s",
        format!("Rayleigh mass-proportional damping{auto}"),
        d.alpha,
    ));
    p.push(spec(
        "damping.beta".into(),
        "s",
        format!("Rayleigh stiffness-proportional damping{auto}"),
        d.beta,
    ));
    p.push(spec(
        "damping.crease".into(),
        "N.s/rad",
        format!("crease damping per unit length{auto}"),
        d.crease_c_per_length,
    ));
    if let Some(g) = scene.gravity {
        for (c, gc) in ["x", "y", "z"].iter().zip(g) {
            p.push(spec(
                format!("gravity.{c}"),
                "m/s2",
                format!("gravity, {c} component"),
                gc,
            ));
        }
    }
    let s = &scene.solver;
    p.push(spec(
        "solver.rho_inf".into(),
        "",
        "generalized-alpha spectral radius".into(),
        s.rho_inf,
    ));
    p.push(spec(
        "solver.max_step".into(),
        "s",
        "largest internal step".into(),
        s.max_step,
    ));
    p.push(spec(
        "solver.tolerance".into(),
        "",
        "relative solver tolerance".into(),
        s.tolerance,
    ));
    p.push(spec(
        "solver.max_internal_steps".into(),
        "",
        "most internal steps one communication step may take before it fails".into(),
        s.max_internal_steps as f64,
    ));
    p
}

fn input_table(scene: &Scene) -> Vec<VariableSpec> {
    let mut v = Vec::new();
    for a in &scene.actuators {
        let (unit, what) = match a.mode {
            ActuatorMode::RestAngle => ("", "fold fraction: rest angle = value * target angle"),
            ActuatorMode::Torque => ("N", "crease moment per unit crease length"),
        };
        v.push(spec(
            a.name.clone(),
            unit,
            format!("actuator {}: {what}", a.name),
            a.start,
        ));
    }
    for f in &scene.vertex_forces {
        for c in ["x", "y", "z"] {
            v.push(spec(
                format!("{}.{c}", f.name),
                "N",
                format!("force on vertex {}, {c}", f.vertex),
                0.0,
            ));
        }
    }
    for m in &scene.vertex_motions {
        let x = scene.mesh.coords[m.vertex];
        for (c, start) in ["x", "y", "z"].iter().zip([x.x, x.y, 0.0]) {
            v.push(spec(
                format!("{}.{c}", m.name),
                "m",
                format!("prescribed position of vertex {}, {c}", m.vertex),
                start,
            ));
        }
    }
    v
}

fn output_table(scene: &Scene) -> Vec<VariableSpec> {
    let mut v = Vec::new();
    let o = scene.outputs;
    if o.positions {
        for i in 0..scene.fold_vertex_count {
            let x = scene.mesh.coords[i];
            for (c, start) in ["x", "y", "z"].iter().zip([x.x, x.y, 0.0]) {
                v.push(spec(
                    format!("vertex[{i}].{c}"),
                    "m",
                    format!("position of vertex {i}, {c}"),
                    start,
                ));
            }
        }
    }
    if o.fold_angles {
        for e in fold_edges(scene) {
            v.push(spec(
                format!("crease[{e}].angle"),
                "rad",
                format!("fold angle of FOLD edge {e} (valley positive)"),
                0.0,
            ));
        }
    }
    if o.energies {
        v.push(spec(
            "energy.kinetic".into(),
            "J",
            "kinetic energy".into(),
            0.0,
        ));
        v.push(spec(
            "energy.strain".into(),
            "J",
            "shell strain energy (membrane + bending)".into(),
            0.0,
        ));
        v.push(spec(
            "energy.crease".into(),
            "J",
            "crease spring energy".into(),
            0.0,
        ));
    }
    v
}
