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
//!
//! This file holds [`Model`], its errors and phases and the life cycle
//! (new, initialize); the rest is one job per file:
//! - `variables`: [`VariableSpec`], the input and output tables, outputs;
//! - `parameters`: the parameters, one typed list with name, unit,
//!   description, start value and how each is applied;
//! - `physics`: the physics a scene asks for ([`physics()`]) and the
//!   automatic damping;
//! - `system`: what is built from the scene and parameters (assembly,
//!   solver, stepper settings);
//! - `inputs`: the input path in one file: what a master sets, the signal
//!   over an advance, the actuators, and how the values become rest
//!   angles, loads and prescribed DOFs;
//! - `attach`: the attachments' frames and the reaction outputs;
//! - `step`: the step controller ([`Model::advance`], [`StepReport`]);
//! - `state`: [`ModelState`], save and restore, consistent accelerations.

mod attach;
mod inputs;
mod parameters;
mod physics;
mod state;
mod step;
mod system;
mod variables;

#[doc(hidden)]
pub use physics::{AUTO_DAMPING_RATIO, physics};
pub use physics::{actuator_time_constant, folding_frequency};
pub use state::ModelState;
#[doc(hidden)]
pub use state::Work;
pub use step::StepReport;
#[doc(hidden)]
pub use variables::fold_edges;
pub use variables::{InputId, OutputId, ParameterId, VariableSpec};

use crate::scene::Scene;
use crate::solver::stepper::{Dynamics, StepperMemory};
use crate::text::num;
use parameters::Parameter;
use serde::{Deserialize, Serialize};
use std::fmt;
use system::System;

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
    /// A value for a variable outside its limits
    /// ([`crate::scene::limits`]); nothing changed.
    OutOfLimits {
        name: String,
        value: f64,
        source: crate::scene::limits::LimitError,
    },
    /// The scene is over the size budget.
    Budget(crate::scene::SceneError),
    /// The scene's assembler could not be built (a degenerate facet).
    Build(crate::assembly::BuildError),
    /// The scene's contact settings are refused.
    Contact(crate::contact::SettingsError),
    /// The scene's obstacles are refused.
    Obstacles(crate::contact::ObstacleError),
    /// The scene's sparse solver could not be set up.
    Solver(crate::solver::LinearError),
    /// The explicit integrator could not be set up.
    ExplicitSetup(crate::solver::central_difference::SetupError),
    /// A call that is not allowed in the current phase.
    Phase(String),
    /// The stepper could not complete; the state is as it was before.
    StepFailed { time: f64, reason: String },
    /// A saved state does not fit this model.
    State(String),
    /// The accelerations of a state cannot be computed (forces or
    /// accelerations not finite); the message names the variables to check.
    Initialization(String),
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
                write!(f, "{name} = {}: {reason}; value not applied", num(*value))
            }
            Error::OutOfLimits {
                name,
                value,
                source,
            } => {
                write!(f, "{name} = {}: {source}; value not applied", num(*value))
            }
            Error::Budget(e) => write!(f, "invalid scene: {e}"),
            Error::Build(e) => write!(f, "invalid scene: {e}"),
            Error::Contact(e) => write!(f, "invalid scene: {e}"),
            Error::Obstacles(e) => write!(f, "invalid scene: {e}"),
            Error::Solver(e) => write!(f, "invalid scene: {e}"),
            Error::ExplicitSetup(e) => write!(f, "invalid scene: {e}"),
            Error::Phase(m) => write!(f, "{m}"),
            Error::StepFailed { time, reason } => {
                write!(
                    f,
                    "step from t = {} failed: {reason}; state rolled back",
                    num(*time)
                )
            }
            Error::State(m) => write!(f, "bad saved state: {m}"),
            Error::Initialization(m) => write!(f, "{m}"),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::OutOfLimits { source, .. } => Some(source),
            Error::Budget(e) => Some(e),
            Error::Build(e) => Some(e),
            Error::Contact(e) => Some(e),
            Error::Obstacles(e) => Some(e),
            Error::Solver(e) => Some(e),
            Error::ExplicitSetup(e) => Some(e),
            _ => None,
        }
    }
}

/// Life-cycle phase of a [`Model`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Phase {
    /// Built; parameters may change.
    Setup,
    /// [`Model::initialize`] done; inputs and steps.
    Running,
}

/// One origami scene with its state and stepper.
pub struct Model {
    scene: Scene,
    /// What each parameter is, in the order of `parameters`.
    parameter_kinds: Vec<Parameter>,
    parameters: Vec<VariableSpec>,
    inputs: Vec<VariableSpec>,
    outputs: Vec<VariableSpec>,
    state: ModelState,
    sys: Option<System>,
    /// Parameter values the current `sys` was built with.
    built_with: Option<Vec<f64>>,
    /// Whether the scene asked for automatic damping.
    auto_damping: bool,
    /// Outputs evaluated from the state on their first read (emptied
    /// whenever the state changes).
    read_cache: ReadCache,
}

/// Values of the current state evaluated on their first read: a master
/// pays only for the outputs it reads.
#[derive(Clone, Debug, Default)]
struct ReadCache {
    /// The energy outputs, where `state.outputs` is None.
    energies: std::sync::OnceLock<[f64; 3]>,
    /// The contact search's outputs (smallest gap, pairs, normal force).
    contact: std::sync::OnceLock<crate::contact::ContactReport>,
    /// The barrier terms' energy (`energy.contact`), where `state.outputs`
    /// is None.
    barrier_energy: std::sync::OnceLock<f64>,
    /// Every output from a full evaluation, where `state.outputs` is None
    /// and one is read that needs it.
    full: std::sync::OnceLock<Vec<f64>>,
}

impl Model {
    /// Build a model of a validated scene.
    pub fn new(scene: Scene) -> Result<Model, Error> {
        let facets = scene.mesh.triangles().len();
        if facets > crate::scene::build::MAX_FACETS {
            // Refused before the large allocations of the assembly.
            return Err(Error::Budget(crate::scene::build::over_budget(
                "mesh",
                facets,
                "the mesh has",
            )));
        }
        let (parameter_kinds, parameters) = parameters::parameter_table(&scene);
        let inputs = variables::input_table(&scene);
        let outputs = variables::output_table(&scene);
        let state = ModelState {
            time: 0.0,
            dynamics: Dynamics::default(),
            crease_theta: vec![],
            inputs_now: inputs.iter().map(|v| v.start).collect(),
            inputs_next: inputs.iter().map(|v| v.start).collect(),
            input_slopes: vec![0.0; inputs.len()],
            input_second_derivatives: vec![0.0; inputs.len()],
            damping_set: false,
            actuators: scene.actuators.iter().map(|a| [a.start, 0.0]).collect(),
            memory: StepperMemory {
                h_next: scene.solver.max_step,
                ..Default::default()
            },
            parameters: parameters.iter().map(|v| v.start).collect(),
            phase: Phase::Setup,
            outputs: Some(outputs.iter().map(|v| v.start).collect()),
            work: Default::default(),
            dissipative_force: Default::default(),
            extra_pairs: Vec::new(),
            term_memory: Vec::new(),
            viscous_force: Vec::new(),
        };
        // Build once now so that a bad scene fails at instantiation.
        let auto_damping = scene.auto_damping;
        let mut m = Model {
            auto_damping,
            scene,
            parameter_kinds,
            parameters,
            inputs,
            outputs,
            state,
            sys: None,
            built_with: None,
            read_cache: Default::default(),
        };
        m.build()?;
        Ok(m)
    }

    /// The scene the model was built from (with parameters as last set).
    pub fn scene(&self) -> &Scene {
        &self.scene
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
        // The actuators start at rest at their inputs.
        for (a, &x) in self.state.actuators.iter_mut().zip(&self.state.inputs_now) {
            *a = [x, 0.0];
        }
        let sys = self.sys.as_mut().expect("built");
        let n = sys.asm.n_dofs();
        let u = self.state.inputs_now.clone();
        // At rest in the reference; with attachments, carried along by the
        // first one's frame as its inputs place and move it.
        let mut dynamics = Dynamics {
            q: sys.asm.layout.reference_state(&self.scene.mesh),
            v: vec![0.0; n],
            qdd: vec![0.0; n],
            abar: vec![0.0; n],
        };
        let slopes = (
            &self.state.input_slopes[..],
            &self.state.input_second_derivatives[..],
        );
        attach::start_with_frames(&sys.asm, &sys.inputs, &u, slopes, &mut dynamics);
        let mut drive = sys.inputs.drive(&u);
        for &(i, x) in &drive.prescribed {
            dynamics.q[i] = x;
        }
        // Moving obstacles where their inputs put them.
        sys.inputs.move_obstacles(&u, slopes, &mut drive);
        sys.asm.place_bodies(&drive.obstacles, &drive.obstacles);
        let theta_prev = vec![std::f64::consts::PI; sys.asm.creases.len()];
        self.state.dynamics = dynamics;
        self.state.memory.newton = Default::default();
        self.consistent_accelerations(&u, &theta_prev)?;
        self.state.memory.h_next = self.sys.as_ref().expect("built").settings.max_step;
        self.state.phase = Phase::Running;
        Ok(())
    }
}

impl Model {
    #[doc(hidden)]
    /// Contact at the current state (None without contact, and before
    /// [`Model::initialize`], when there are no positions to search):
    /// smallest gap (up to [`crate::contact::ContactTerm::report_reach`]),
    /// active pairs, normal force. Each step reports its end state from its
    /// candidate pairs; reads return that report.
    pub fn contact(&self) -> Option<crate::contact::ContactReport> {
        if self.state.phase != Phase::Running {
            return None;
        }
        let sys = self.sys.as_ref()?;
        let c = sys.asm.contact()?;
        Some(
            *self
                .read_cache
                .contact
                .get_or_init(|| c.report_near(&self.state.dynamics.q)),
        )
    }

    /// The chord error of self-contact's sampled surface now: the largest
    /// distance (m) between the curved facets and the surface contact
    /// keeps apart (at the centroid and side midpoints of each sampled
    /// triangle), and the facets (mesh triangles) where it passes the
    /// contact thickness. None without self-contact or before
    /// [`Model::initialize`].
    pub fn chord_error(&self) -> Option<(f64, Vec<usize>)> {
        if self.state.phase != Phase::Running {
            return None;
        }
        let c = self.sys.as_ref()?.asm.contact()?;
        Some(
            c.surface()
                .chord_error(&self.state.dynamics.q, c.thickness()),
        )
    }

    #[doc(hidden)]
    /// Each facet's chord error now (m; see [`Model::chord_error`]), and
    /// the contact thickness. None without self-contact or before
    /// [`Model::initialize`].
    pub fn facet_chord_errors(&self) -> Option<(Vec<f64>, f64)> {
        if self.state.phase != Phase::Running {
            return None;
        }
        let c = self.sys.as_ref()?.asm.contact()?;
        Some((
            c.surface().facet_chord_errors(&self.state.dynamics.q),
            c.thickness(),
        ))
    }

    #[doc(hidden)]
    /// The gaps (m) of the sheet's contact samples now, each to its
    /// nearest rigid obstacle beyond the clearance it keeps (half the
    /// contact thickness): the smallest, the largest, and that clearance;
    /// None without obstacles or before [`Model::initialize`].
    pub fn obstacle_gap(&self) -> Option<(f64, f64, f64)> {
        if self.state.phase != Phase::Running {
            return None;
        }
        let t = self.sys.as_ref()?.asm.obstacles()?;
        let (min, max) = t.gap_range(&self.state.dynamics.q);
        Some((min, max, t.clearance()))
    }

    #[doc(hidden)]
    /// Work so far: dissipated by contact (friction and normal dashpots)
    /// and done by the inputs.
    pub fn work(&self) -> state::Work {
        self.state.work
    }

    #[doc(hidden)]
    /// Subdivisions per facet side of the sampled surface: self-contact's,
    /// else the default contact settings' (what the pictures draw).
    pub fn surface_subdivisions(&self) -> usize {
        self.sys.as_ref().and_then(|s| s.asm.contact()).map_or(
            crate::contact::ContactSettings::default().subdivisions,
            |c| c.surface().n,
        )
    }

    #[doc(hidden)]
    /// The sampled surface at [`Model::surface_subdivisions`], built anew
    /// (without chord probes): the same samples and sub-triangles as the
    /// surface self-contact keeps apart. None before the system is built.
    pub fn sampled_surface(&self) -> Option<crate::contact::surface::ContactSurface> {
        let sys = self.sys.as_ref()?;
        Some(crate::contact::surface::ContactSurface::new(
            &self.scene.mesh,
            &sys.asm.layout,
            &sys.asm.elements,
            self.surface_subdivisions(),
            false,
            sys.asm.contact().map_or(0.0, |c| c.surface().kerf),
        ))
    }

    #[doc(hidden)]
    /// Positions of `surf`'s samples now (its flat reference before
    /// [`Model::initialize`]).
    pub fn sampled_positions(
        &self,
        surf: &crate::contact::surface::ContactSurface,
        out: &mut Vec<nalgebra::Vector3<f64>>,
    ) {
        if self.state.phase == Phase::Running {
            surf.positions(&self.state.dynamics.q, out);
        } else {
            out.clear();
            out.extend_from_slice(&surf.rest);
        }
    }

    #[doc(hidden)]
    /// Run the intersection checker on the current state: facets sampled
    /// with `m` subdivisions, distances searched up to `search` (m), and
    /// the creases whose fold angle is past +-180 degrees.
    pub fn check_intersections(
        &self,
        m: usize,
        search: f64,
    ) -> Option<crate::contact::check::IntersectionReport> {
        let sys = self.sys.as_ref()?;
        let rep = crate::contact::check::check(
            &sys.asm,
            &self.scene.mesh,
            &self.state.dynamics.q,
            m,
            search,
        );
        Some(self.with_past_flat(rep))
    }

    #[doc(hidden)]
    /// [`Model::check_intersections`] on the sampled surface self-contact
    /// computes with (its own samples; without contact, the curved facets
    /// at the default subdivisions): the surface the model guarantees
    /// apart, and the one the pictures draw.
    pub fn check_sampled_surface(
        &self,
        search: f64,
    ) -> Option<crate::contact::check::IntersectionReport> {
        let sys = self.sys.as_ref()?;
        let Some(c) = sys.asm.contact() else {
            return self.check_intersections(self.surface_subdivisions(), search);
        };
        let rep = crate::contact::check::check_surface(
            c.surface(),
            &self.scene.mesh,
            &self.state.dynamics.q,
            search,
        );
        Some(self.with_past_flat(rep))
    }

    /// `rep` with the creases whose fold angle is past +-180 degrees.
    fn with_past_flat(
        &self,
        mut rep: crate::contact::check::IntersectionReport,
    ) -> crate::contact::check::IntersectionReport {
        let Some(sys) = self.sys.as_ref() else {
            return rep;
        };
        let tau = std::f64::consts::TAU;
        rep.past_flat = sys
            .asm
            .creases
            .iter()
            .zip(&self.state.crease_theta)
            .filter(|&(_, &theta)| !(0.0..=tau).contains(&theta))
            .map(|(c, _)| c.edge)
            .collect();
        rep.past_flat.dedup();
        rep
    }
}
