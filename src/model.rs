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
}

use crate::scene::{ActuatorMode, Scene};

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
    /// Generalized coordinates.
    pub q: Vec<f64>,
    /// Generalized velocities.
    pub v: Vec<f64>,
    /// Generalized accelerations (and integrator memory).
    pub a: Vec<f64>,
    /// Unwrapped crease angles at the last step (continuity through 0 = 2 pi).
    pub crease_theta: Vec<f64>,
    /// Input values in force at `time`.
    pub inputs_now: Vec<f64>,
    /// Input values set for the next step.
    pub inputs_next: Vec<f64>,
    /// Parameter values.
    pub parameters: Vec<f64>,
    /// Phase.
    pub phase: Phase,
}

/// One origami scene with its state and stepper.
pub struct Model {
    scene: Scene,
    parameters: Vec<VariableSpec>,
    inputs: Vec<VariableSpec>,
    outputs: Vec<VariableSpec>,
    state: ModelState,
}

impl Model {
    /// Build a model of a validated scene.
    pub fn new(scene: Scene) -> Result<Model, Error> {
        let parameters = parameter_table(&scene);
        let inputs = input_table(&scene);
        let outputs = output_table(&scene);
        let n = 3 * scene.mesh.n_vertices();
        let mut q = vec![0.0; n];
        for (i, x) in scene.mesh.coords.iter().enumerate() {
            q[3 * i] = x.x;
            q[3 * i + 1] = x.y;
        }
        let state = ModelState {
            time: 0.0,
            q,
            v: vec![0.0; n],
            a: vec![0.0; n],
            crease_theta: vec![],
            inputs_now: inputs.iter().map(|v| v.start).collect(),
            inputs_next: inputs.iter().map(|v| v.start).collect(),
            parameters: parameters.iter().map(|v| v.start).collect(),
            phase: Phase::Setup,
        };
        Ok(Model {
            scene,
            parameters,
            inputs,
            outputs,
            state,
        })
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
        if !value.is_finite() {
            return Err(Error::BadValue {
                name: spec.name.clone(),
                value,
                reason: "not a finite number".into(),
            });
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

    /// End of setup: apply parameters and compute the initial state.
    pub fn initialize(&mut self) -> Result<(), Error> {
        if self.state.phase != Phase::Setup {
            return Err(Error::Phase("model is already initialized".into()));
        }
        self.state.phase = Phase::Running;
        Ok(())
    }

    /// Advance from the current time by `h` seconds with internal steps. On
    /// failure the state is exactly as before the call.
    // PLACEHOLDER until the stepper lands: keeps the sheet where it is.
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
        self.state.time += h;
        self.state.inputs_now.clone_from(&self.state.inputs_next);
        Ok(StepReport {
            steps: 1,
            min_step: h,
            ..Default::default()
        })
    }

    /// Current values of all outputs, in the order of [`Model::outputs`].
    pub fn output_values(&self) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.outputs.len());
        let o = self.scene.outputs;
        if o.positions {
            out.extend_from_slice(&self.state.q[..3 * self.scene.fold_vertex_count]);
        }
        if o.fold_angles {
            out.extend(fold_edges(&self.scene).iter().map(|_| 0.0));
        }
        if o.energies {
            out.extend([0.0, 0.0, 0.0]);
        }
        out
    }

    /// A copy of the complete state, enough to continue bit-identically.
    pub fn save_state(&self) -> ModelState {
        self.state.clone()
    }

    /// Restore a state saved from a model of the same scene.
    pub fn restore_state(&mut self, s: &ModelState) -> Result<(), Error> {
        let ok = s.q.len() == self.state.q.len()
            && s.v.len() == self.state.v.len()
            && s.inputs_next.len() == self.inputs.len()
            && s.parameters.len() == self.parameters.len();
        if !ok {
            return Err(Error::State("its sizes do not match this model".into()));
        }
        self.state = s.clone();
        Ok(())
    }
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
