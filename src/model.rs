//! The plain Rust `Model` API: one origami scene, its state, and a stepper.
//! The FMU, the CLI and the tests all drive the model through this API.
//!
//! Variables are flat, numbered tables (parameters, inputs, outputs) so that
//! the FMI layer only maps value references onto indices.
//!
//! Life cycle: [`Model::new`] validates and builds the scene;
//! [`Model::set_parameter`] may change parameters until
//! [`Model::initialize`]; then [`Model::set_input`] and [`Model::advance`]
//! alternate. Inputs are ramped linearly over each step from the value in
//! force at its start to the value last set (never held, never jumped).

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
use crate::element::Rule;
use crate::scene::{ActuatorMode, CreaseStiffness, Fix, Integrator, Scene};
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
    /// Input values set for the end of the next step.
    pub inputs_next: Vec<f64>,
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
            parameters: parameters.iter().map(|v| v.start).collect(),
            phase: Phase::Setup,
            h_next: scene.solver.max_step,
            outputs: outputs.iter().map(|v| v.start).collect(),
        };
        // Build once now so that a bad scene fails at instantiation.
        let mut m = Model {
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
        let bad = |reason: &str| Error::BadValue {
            name: spec.name.clone(),
            value,
            reason: reason.into(),
        };
        if !value.is_finite() {
            return Err(bad("not a finite number"));
        }
        match spec.name.as_str() {
            "material.youngs_modulus"
            | "material.thickness"
            | "material.density"
            | "crease.length_scale"
            | "solver.max_step"
            | "solver.tolerance"
                if value <= 0.0 =>
            {
                return Err(bad("must be positive"));
            }
            "material.poisson_ratio" if !(value > -1.0 && value < 0.5) => {
                return Err(bad("must be in (-1, 0.5)"));
            }
            "solver.rho_inf" if !(0.0..=1.0).contains(&value) => {
                return Err(bad("must be in [0, 1]"));
            }
            "crease.stiffness_per_length" | "damping.alpha" | "damping.beta" | "damping.crease"
                if value < 0.0 =>
            {
                return Err(bad("must not be negative"));
            }
            _ => {}
        }
        self.state.parameters[i] = value;
        Ok(())
    }

    /// Value of input `i` as last set.
    pub fn input(&self, i: usize) -> Result<f64, Error> {
        self.state
            .inputs_next
            .get(i)
            .copied()
            .ok_or(Error::NoSuchVariable {
                kind: "input",
                index: i,
            })
    }

    /// Set input `i`: the value reached at the end of the next step (ramped
    /// from the value in force now). Non-finite values are rejected.
    pub fn set_input(&mut self, i: usize, value: f64) -> Result<(), Error> {
        let spec = self.inputs.get(i).ok_or(Error::NoSuchVariable {
            kind: "input",
            index: i,
        })?;
        if !value.is_finite() {
            return Err(Error::BadValue {
                name: spec.name.clone(),
                value,
                reason: "not a finite number".into(),
            });
        }
        self.state.inputs_next[i] = value;
        if self.state.phase == Phase::Setup {
            self.state.inputs_now[i] = value;
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
        let d = sys.inputs.drive(&u);
        for &(i, x) in &d.prescribed {
            q[i] = x;
        }
        let v = vec![0.0; n];
        let theta_prev = vec![std::f64::consts::PI; sys.asm.creases.len()];
        let mut ev = Evaluation::default();
        sys.asm
            .evaluate(
                &State {
                    q: &q,
                    v: &v,
                    theta0: &d.theta0,
                    moment: &d.moment,
                    theta_prev: &theta_prev,
                },
                &mut ev,
                None,
            )
            .map_err(Error::Scene)?;
        // M qdd = f_ext - f_int on the free DOFs.
        let mut rhs = vec![0.0; sys.asm.n_free];
        for i in 0..n {
            let fi = sys.asm.free[i];
            if fi != crate::assembly::FIXED {
                rhs[fi] = d.f_ext[i] - ev.force[i];
            }
        }
        let mvals = sys.asm.mass_values().to_vec();
        sys.solver
            .factor(&mvals)
            .map_err(|e| Error::Scene(format!("mass matrix: {e}")))?;
        sys.solver
            .solve_in_place(&mut rhs)
            .map_err(|e| Error::Scene(format!("mass matrix: {e}")))?;
        let mut qdd = vec![0.0; n];
        for i in 0..n {
            let fi = sys.asm.free[i];
            if fi != crate::assembly::FIXED {
                qdd[i] = rhs[fi];
            }
        }
        self.state.dynamics = Dynamics {
            q,
            v,
            abar: qdd.clone(),
            qdd,
        };
        self.state.crease_theta = ev.theta.clone();
        self.state.h_next = sys.max_step;
        self.state.phase = Phase::Running;
        self.state.outputs = self.compute_outputs(&ev);
        Ok(())
    }

    /// Advance from the current time by `h` seconds with internal steps,
    /// ramping the inputs from their values in force to the values last
    /// set. On failure the state is exactly as before the call.
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
        // Every advance starts with a fresh iteration matrix: its result is a
        // function of the state alone (restored states repeat bit for bit).
        sys.ws.invalidate_jacobian();
        let stats0 = sys.solver.stats();
        let mut u = u0.clone();
        let mut d = DriveValues::default();
        if let Some(cd) = sys.cd.as_mut() {
            // Explicit: equal substeps below the stability limit.
            let n_sub = (big_h / cd.stable_step().min(sys.max_step)).ceil().max(1.0);
            let h = big_h / n_sub;
            let t_asm = cd.assembly_time;
            let t_solve = cd.solve_time();
            for k in 1..=n_sub as usize {
                let frac = k as f64 / n_sub;
                for k in 0..u.len() {
                    u[k] = u0[k] + (u1[k] - u0[k]) * frac;
                }
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
            let remaining = big_h - s;
            if h >= remaining || remaining - h < 1e-3 * h {
                h = remaining;
            }
            let frac = (s + h) / big_h;
            for k in 0..u.len() {
                u[k] = u0[k] + (u1[k] - u0[k]) * frac;
            }
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
                        let hn = (h * grow.clamp(0.2, 2.0)).clamp(sys.min_step, sys.max_step);
                        // A short final step must not shrink the next advance's step.
                        self.state.h_next = if h < remaining {
                            hn
                        } else {
                            hn.max(self.state.h_next)
                        };
                        h = hn;
                    } else {
                        report.rejected += 1;
                        h = (h * (0.9 * out.error.powf(-1.0 / 3.0)).clamp(0.2, 0.9))
                            .max(sys.min_step);
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
        }
        let ev = match &sys.cd {
            Some(cd) => cd.evaluation().clone(),
            None => sys.ws.evaluation().clone(),
        };
        self.state.time = t0 + big_h;
        self.state.inputs_now = u1;
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
        let ok = dyn_ok
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
        self.state = s.clone();
        Ok(())
    }

    fn apply_parameters(&mut self) {
        let sc = &mut self.scene;
        for (spec, &x) in self.parameters.iter().zip(&self.state.parameters) {
            match spec.name.as_str() {
                "material.youngs_modulus" => sc.material.youngs_modulus = x,
                "material.poisson_ratio" => sc.material.poisson_ratio = x,
                "material.thickness" => sc.material.thickness = x,
                "material.density" => sc.material.density = x,
                "crease.length_scale" => sc.crease = CreaseStiffness::LengthScale(x),
                "crease.stiffness_per_length" => sc.crease = CreaseStiffness::PerLength(x),
                "damping.alpha" => sc.damping.alpha = x,
                "damping.beta" => sc.damping.beta = x,
                "damping.crease" => sc.damping.crease = x,
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
                _ => {}
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
        let asm = Assembler::new(mesh, physics, Rule::default(), &fixed).map_err(Error::Scene)?;
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
/// length, damping (the automatic mass damping when the scene sets none).
pub fn physics(sc: &Scene) -> Physics {
    let material = sc.material;
    let k_pl = match sc.crease {
        CreaseStiffness::LengthScale(l) => material.bending_stiffness() / l,
        CreaseStiffness::PerLength(k) => k,
    };
    Physics {
        material,
        crease_k_per_length: k_pl,
        crease_c_per_length: sc.damping.crease,
        alpha: if sc.auto_damping {
            auto_alpha(sc, k_pl)
        } else {
            sc.damping.alpha
        },
        beta: sc.damping.beta,
    }
}

/// Default mass-proportional damping: damping ratio 0.2 on the folding mode
/// of a panel of the mean facet size hinged on its crease,
/// omega = sqrt(3 k / (rho h w^3)) per unit crease length.
fn auto_alpha(sc: &Scene, k_per_length: f64) -> f64 {
    let mesh = &sc.mesh;
    let nt = mesh.triangles.len().max(1);
    let mean_area: f64 = (0..mesh.triangles.len()).map(|t| mesh.area(t)).sum::<f64>() / nt as f64;
    let w = (2.0 * mean_area).sqrt();
    let m = &sc.material;
    let omega = (3.0 * k_per_length / (m.density * m.thickness * w.powi(3))).sqrt();
    2.0 * 0.2 * omega
}

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
    let d = &scene.damping;
    p.push(spec(
        "damping.alpha".into(),
        "1/s",
        "Rayleigh mass-proportional damping".into(),
        d.alpha,
    ));
    p.push(spec(
        "damping.beta".into(),
        "s",
        "Rayleigh stiffness-proportional damping".into(),
        d.beta,
    ));
    p.push(spec(
        "damping.crease".into(),
        "N.s/rad",
        "crease damping per unit length".into(),
        d.crease,
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
