//! A scene: the crease pattern plus everything physical about it (material,
//! crease stiffness, actuators, supports, loads, solver settings, outputs).
//!
//! This module holds the scene as plain data with documented SI defaults,
//! and the front door that makes one from a FOLD file:
//!
//! ```
//! let text = r#"{
//!   "frame_unit": "mm",
//!   "vertices_coords": [[0,0],[10,0],[20,0],[20,10],[10,10],[0,10]],
//!   "edges_vertices": [[1,4],[0,1],[1,2],[2,3],[3,4],[4,5],[5,0]],
//!   "edges_assignment": ["V","B","B","B","B","B","B"],
//!   "edges_foldAngle": [90,0,0,0,0,0,0],
//!   "faces_vertices": [[0,1,4,5],[1,2,3,4]],
//!   "ancf:supports": [{"vertices": [0, 5], "fix": "position"}]
//! }"#;
//! let (scene, warnings) = origami_fmu::scene::from_str(text).unwrap();
//! assert_eq!(scene.fold_vertex_count, 6);
//! assert_eq!(scene.mesh.triangles().len(), 4);
//! assert_eq!(scene.actuators[0].name, "fold");
//! // Every face side is listed, so nothing is guessed and nothing warned.
//! assert!(warnings.is_empty());
//! ```
//!
//! Submodules: [`fold`] (FOLD 1.2 reading and writing), [`keys`] (the
//! `ancf:` physics keys), [`build`] (validation and the mesh), [`refine`],
//! [`patterns`] (generators). The key reference with a complete example is
//! `docs/scenes.md`.
//!
//! Conventions: the reference (stress-free) state is the flat crease
//! pattern. 2D `vertices_coords` are used as they are; 3D ones with a single
//! z as x, y; other 3D ones must be coplanar (within [`build::COPLANAR_TOLERANCE`]
//! of the sheet size) and are expressed in their own plane, seen from the
//! side where the faces are counter-clockwise (a 2D sheet whose faces are all
//! clockwise is mirrored in y, with a warning). Sizes: a real `frame_unit`
//! (`m`, `cm`, `mm`, `um`, `nm`, `in`, `pt`) scales to metres; a file without
//! one (or with `unit`, the FOLD default) is scaled so that the longest side
//! of its bounding box is [`build::DEFAULT_SIZE`] (0.1 m);
//! [`LoadOptions::size`], [`LoadOptions::unit`] and the `ancf:import` key
//! change that (docs/scenes.md, "Size").

use crate::ids::{EdgeId, VertexId};
use crate::mesh::Mesh;
use serde::{Deserialize, Serialize};
use std::path::Path;

#[doc(hidden)]
pub mod build;
mod error;
pub mod fold;
mod keyframes;
#[doc(hidden)]
pub mod keys;
#[doc(hidden)]
pub mod limits;
pub mod patterns;
mod planar;
#[doc(hidden)]
pub mod refine;
pub mod sequence;
#[doc(hidden)]
pub mod triangulate;

pub use crate::contact::ContactSettings;
pub use crate::element::Rule as Quadrature;
pub use crate::material::Material;
pub use crate::solver::IntegrationParameters;
pub use build::from_fold;
pub use error::SceneError;
pub use fold::{FoldFile, FrameSelector};
pub use sequence::{Sequence, Stage};

/// Options of [`load_with`] and [`from_str_with`]: what the command-line
/// options `--frame`, `--size`, `--unit`, `--f-edges` and `--contact` set. The geometry
/// options override the file's `ancf:import` key and `frame_unit`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadOptions {
    /// Which frame of a multi-frame file (default: the top level if it has
    /// vertices, else the first of `file_frames`).
    pub frame: Option<FrameSelector>,
    /// Model name when the file has no `ancf:name` (e.g. the file stem).
    pub name: Option<String>,
    /// Scale the sheet so that the longest side of its bounding box is this
    /// many metres, whatever the file's unit.
    pub size: Option<f64>,
    /// Read the coordinates in this unit (`m`, `cm`, `mm`, `um`, `nm`, `in`,
    /// `pt`) instead of the file's `frame_unit`.
    pub unit: Option<String>,
    /// What FOLD `F` edges are (default: creases, smooth edges in Origami
    /// Simulator exports).
    pub f_edges: Option<FlatEdges>,
    /// Self-contact on, with the file's `ancf:contact` settings (enabled or
    /// not) where it has them, else the defaults: the CLI's `--contact`.
    pub contact: bool,
    /// Whether the frames after the one read are keyframes of a folding
    /// sequence (the CLI's `--keyframes`; default: when they all carry fold
    /// angles).
    pub keyframes: Keyframes,
}

/// Whether the frames of a FOLD file after the crease pattern read are a
/// folding sequence, one stage per frame (docs/scenes.md, "Frames as
/// keyframes").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Keyframes {
    /// When every frame after it folds the same pattern and carries fold
    /// angles (its own `edges_foldAngle` or folded `vertices_coords`), and
    /// the file has no `ancf:sequence`; otherwise the frame is read alone
    /// (with a note saying why, where some frame carries angles).
    #[default]
    Auto,
    /// Always: a frame that is not a keyframe is an error.
    On,
    /// Never: the frame is read alone.
    Off,
}

/// How FOLD `F` edges are read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FlatEdges {
    /// As the FOLD specification says: a flat (unfolded) fold line, i.e. a
    /// crease whose target is 0 unless `edges_foldAngle` gives one.
    Crease,
    /// Triangulation lines (Origami Simulator's meaning): smooth edges.
    Smooth,
}

/// A loaded scene with what the loader said about it.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The validated scene.
    pub scene: Scene,
    /// Things that may be wrong (also returned by [`load`]).
    pub warnings: Vec<String>,
    /// What the loader did: the unit or scale it used, how F edges were
    /// read, faces traced, vertices split. One line each, for `check` and
    /// `build` to print.
    pub notes: Vec<String>,
}

/// Load a FOLD scene file. Returns the validated scene and warnings; the
/// model name defaults to the file stem.
pub fn load(path: impl AsRef<Path>) -> Result<(Scene, Vec<String>), SceneError> {
    load_with(path, &LoadOptions::default())
}

/// [`load`] with options.
pub fn load_with(
    path: impl AsRef<Path>,
    options: &LoadOptions,
) -> Result<(Scene, Vec<String>), SceneError> {
    load_report(path, options).map(|l| (l.scene, l.warnings))
}

/// [`load_with`], returning the loader's notes too.
pub fn load_report(path: impl AsRef<Path>, options: &LoadOptions) -> Result<Loaded, SceneError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| SceneError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    let mut options = options.clone();
    if options.name.is_none() {
        options.name = path.file_stem().map(|s| s.to_string_lossy().into_owned());
    }
    from_str_report(&text, &options)
}

/// A scene from FOLD text (the first frame, default name).
pub fn from_str(text: &str) -> Result<(Scene, Vec<String>), SceneError> {
    from_str_with(text, &LoadOptions::default())
}

/// [`from_str`] with options.
pub fn from_str_with(
    text: &str,
    options: &LoadOptions,
) -> Result<(Scene, Vec<String>), SceneError> {
    from_str_report(text, options).map(|l| (l.scene, l.warnings))
}

/// [`from_str_with`], returning the loader's notes too. When the frame read
/// is a folded state, the error names the frames of the file that are
/// crease patterns.
pub fn from_str_report(text: &str, options: &LoadOptions) -> Result<Loaded, SceneError> {
    let frames = fold::Frames::new(text)?;
    let (file, warnings) = frames.frame(options.frame.as_ref())?;
    let cp = frames.index(options.frame.as_ref())?;
    let (keys, note) = keyframes_of(&frames, cp, &file, options.keyframes)?;
    match build::from_fold_keyframes(&file, options, &keys) {
        Ok(mut loaded) => {
            let mut all = warnings;
            all.append(&mut loaded.warnings);
            loaded.warnings = all;
            loaded.notes.extend(note);
            Ok(loaded)
        }
        Err(SceneError::Invalid { key, message }) if build::is_folded_state(&message) => {
            Err(SceneError::Invalid {
                key,
                message: format!(
                    "{message}{}",
                    crease_pattern_frames(&frames, &file, options)
                ),
            })
        }
        Err(e) => Err(e),
    }
}

/// The keyframes of the file after frame `cp` (read as `file`), as
/// `mode` asks, with a note for the user: which frames were read as
/// keyframes, or why they were not (where some frame carries angles).
fn keyframes_of(
    frames: &fold::Frames,
    cp: usize,
    file: &FoldFile,
    mode: Keyframes,
) -> Result<(Vec<keyframes::KeyFrame>, Option<String>), SceneError> {
    if mode == Keyframes::Off || (mode == Keyframes::Auto && frames.len() <= cp + 1) {
        return Ok((vec![], None));
    }
    if file.ancf.contains_key("ancf:sequence") {
        if mode == Keyframes::On {
            return Err(SceneError::invalid(
                "ancf:sequence",
                "the file has a sequence of its own; keyframes (--keyframes on) would be a \
                 second one: remove one of the two",
            ));
        }
        return Ok((vec![], None));
    }
    match keyframes::read(frames, cp, file) {
        Ok(keys) => {
            let (first, last) = (keys[0].frame, keys[keys.len() - 1].frame);
            let range = if first == last {
                format!("frame {first}")
            } else {
                format!("frames {first}-{last}")
            };
            Ok((
                keys,
                Some(format!(
                    "keyframes: {range} read as a folding sequence after frame {cp}, one stage \
                     each (the fold input walks them; --keyframes off reads frame {cp} alone)"
                )),
            ))
        }
        Err(e) if mode == Keyframes::On => Err(e.error),
        Err(e) if e.any_angles => Ok((
            vec![],
            Some(format!(
                "keyframes: the frames after frame {cp} are not read as a folding sequence: \
                 {}",
                e.error
            )),
        )),
        Err(_) => Ok((vec![], None)),
    }
}

/// At most this many crease-pattern frames are looked for and named.
const FRAMES_NAMED: usize = 5;

/// "; frame 1 ('cp') is a crease pattern: read it with --frame 1", or what
/// to do when no frame is one. Each frame is read and built once (the
/// search stops at [`FRAMES_NAMED`]), so this is linear in the file.
fn crease_pattern_frames(
    frames: &fold::Frames,
    failed: &FoldFile,
    options: &LoadOptions,
) -> String {
    let titles = frames.titles();
    let mut good = Vec::new();
    let mut more = false;
    for (k, title) in titles.iter().enumerate() {
        let sel = FrameSelector::Index(k);
        let Ok((f, _)) = frames.frame(Some(&sel)) else {
            continue;
        };
        if f == *failed {
            continue;
        }
        let o = LoadOptions {
            frame: Some(sel),
            ..options.clone()
        };
        if build::from_fold_with(&f, &o).is_ok() {
            if good.len() == FRAMES_NAMED {
                more = true;
                break;
            }
            good.push(match title {
                Some(t) => format!("{k} ('{t}')"),
                None => format!("{k}"),
            });
        }
    }
    let more = if more { " and more" } else { "" };
    match good.len() {
        0 if titles.len() > 1 => "; no frame of this file is a flat crease pattern: export the \
             unfolded crease pattern from the program that made it"
            .to_string(),
        0 => "; this file has no other frame: export the unfolded crease pattern from the \
             program that made it"
            .to_string(),
        1 => format!(
            "; frame {} is a crease pattern: read it with --frame {} (LoadOptions::frame)",
            good[0],
            good[0].split(' ').next().unwrap_or("1")
        ),
        _ => format!(
            "; frames {}{more} are crease patterns: pick one with --frame N (LoadOptions::frame)",
            good.join(", ")
        ),
    }
}

/// How stiff the creases are (MATH.md section 5).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum CreaseStiffness {
    /// k_crease = (L_F / L*) D with the length scale L* in m.
    LengthScale(f64),
    /// Rotational stiffness per unit crease length in N m / (rad m) = N / rad.
    PerLength(f64),
}

impl Default for CreaseStiffness {
    /// L* = 10 mm.
    fn default() -> Self {
        CreaseStiffness::LengthScale(0.01)
    }
}

impl CreaseStiffness {
    /// Whole-crease rotational stiffness (N m / rad) of a crease of length `len`.
    pub fn stiffness(&self, material: &Material, len: f64) -> f64 {
        match *self {
            CreaseStiffness::LengthScale(l) => len / l * material.bending_stiffness(),
            CreaseStiffness::PerLength(k) => k * len,
        }
    }
}

/// How an actuator's input acts on its creases.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ActuatorMode {
    /// Input u = fold fraction: each crease's rest angle is u times its target.
    RestAngle,
    /// Input = moment per unit crease length (N m / m), folding positive.
    Torque,
}

/// A named group of creases driven by one input.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Actuator {
    /// FMI variable name of the input.
    pub name: String,
    /// Mesh edge indices (creases) it drives.
    pub edges: Vec<EdgeId>,
    /// Rest-angle or torque actuation.
    pub mode: ActuatorMode,
    /// Input value at t = 0.
    pub start: f64,
}

/// What a support fixes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Fix {
    /// The vertex position is fixed; the sheet may rotate about it.
    Position,
    /// Position and all surface gradients at the vertex are fixed.
    Clamped,
}

/// A set of supported vertices.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Support {
    /// Mesh vertex indices.
    pub vertices: Vec<VertexId>,
    /// What is fixed.
    pub fix: Fix,
}

/// A named input attached to one vertex (a force vector, or a prescribed
/// position). Creates the inputs `<name>.x`, `<name>.y`, `<name>.z`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VertexInput {
    /// Variable name prefix.
    pub name: String,
    /// Mesh vertex index.
    pub vertex: VertexId,
}

/// A rigid attachment: vertices clamped to a frame (position and every
/// surface gradient follow it) whose pose is an input, `NAME.x/y/z` (the
/// origin, m; at the reference it is the centroid of the listed FOLD
/// vertices) and `NAME.rx/ry/rz` (a rotation vector, rad); the wrench the
/// sheet exerts on the frame is an output (`NAME.force.x/y/z`,
/// `NAME.moment.x/y/z`, about the origin, world axes).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Attachment {
    /// Variable name prefix.
    pub name: String,
    /// Mesh vertices held (a listed FOLD vertex with all its split copies).
    pub vertices: Vec<VertexId>,
}

/// Time integrator choice.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Integrator {
    /// Generalized-alpha (Chung & Hulbert 1993), implicit, second order.
    GeneralizedAlpha,
    /// Central differences with the constant mass matrix, explicit.
    CentralDifference,
}

/// How the implicit stepper keeps Newton's iteration matrix.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum NewtonMode {
    /// Assemble and factor the tangent at every iteration.
    Full,
    /// Keep the factorization across iterations and steps while the
    /// iteration contracts fast; refresh it when it does not.
    #[default]
    Modified,
}

/// Solver settings: the scene's `ancf:solver` keys and the FMU's `solver.*`
/// parameters. The one place of the solver's defaults is its [`Default`];
/// the numerical constants behind them are [`SolverSettings::integration`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SolverSettings {
    /// Integrator.
    pub integrator: Integrator,
    /// Spectral radius at infinite frequency for generalized-alpha, in [0, 1].
    pub rho_inf: f64,
    /// Largest internal step in s.
    pub max_step: f64,
    /// Smallest internal step before the advance fails, in s.
    pub min_step: f64,
    /// Relative tolerance of the local error control; Newton's tolerance
    /// follows from it
    /// ([`crate::solver::IntegrationParameters::newton_tolerance`]).
    pub tolerance: f64,
    /// Maximum Newton iterations per step. The default leaves room for
    /// jams with friction, where the collision and friction bounds cut
    /// corrections and the tolerance shrinks with the step.
    pub max_newton: usize,
    /// Full or modified Newton (generalized-alpha).
    #[serde(default)]
    pub newton: NewtonMode,
    /// Default experiment stop time in s.
    pub stop_time: f64,
    /// Most internal steps one advance (one `fmi2DoStep`) may take before
    /// it fails cleanly, whatever the integrator: bounds the work of a call.
    #[serde(default = "default_max_internal_steps")]
    pub max_internal_steps: usize,
    /// Most CPU time (s, the calling thread's clock) one advance (one
    /// `fmi2DoStep`) may take before it fails cleanly with the state from
    /// before it: a master never waits on a step without end.
    #[serde(default = "default_max_step_cpu")]
    pub max_step_cpu: f64,
    /// How an input set before a step acts over it (parameter
    /// `input.first_order_hold`).
    #[serde(default)]
    pub input_timing: InputTiming,
    /// Filter the local error estimate through the iteration matrix
    /// (parameter `solver.error_filter`): see
    /// [`crate::solver::generalized_alpha`]. Off by default.
    #[serde(default)]
    pub error_filter: bool,
    /// Quadrature of the shell energy: the 7-point rule (default) or the
    /// 12-point rule, 1.7x the element's cost with errors equal to two
    /// digits on refined meshes (`src/element/quadrature.rs`).
    #[serde(default)]
    pub quadrature: crate::element::Rule,
    /// The shell's bending energy (Rust API only, not a scene key: the
    /// benches compare the split energy with the default).
    #[serde(skip)]
    pub bending: crate::element::Bending,
    /// The stepper's numerical constants (Rust API only, not a scene key).
    #[serde(skip)]
    pub integration: crate::solver::IntegrationParameters,
}

/// Default of [`SolverSettings::max_internal_steps`].
pub const DEFAULT_MAX_INTERNAL_STEPS: usize = 100_000;

fn default_max_internal_steps() -> usize {
    DEFAULT_MAX_INTERNAL_STEPS
}

/// Default of [`SolverSettings::max_step_cpu`], s.
pub const DEFAULT_MAX_STEP_CPU: f64 = 300.0;

fn default_max_step_cpu() -> f64 {
    DEFAULT_MAX_STEP_CPU
}

/// How an input value set before a step acts over that step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum InputTiming {
    /// FMI 2.0 co-simulation (zero-order hold): the value set before a
    /// step from t is the input at t, held over the step (plus the slope
    /// the master gives with `fmi2SetRealInputDerivatives`).
    #[default]
    Hold,
    /// First-order hold: the value set before a step from t is reached at
    /// its end, ramped linearly from the value in force at t; a sample acts
    /// one step late, without the jumps of a held staircase.
    #[serde(alias = "Ramp")]
    FirstOrderHold,
}

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings {
            integrator: Integrator::GeneralizedAlpha,
            rho_inf: 0.6,
            max_step: 1e-2,
            min_step: 1e-9,
            tolerance: 1e-4,
            max_newton: 30,
            newton: NewtonMode::Modified,
            stop_time: 1.0,
            max_internal_steps: DEFAULT_MAX_INTERNAL_STEPS,
            max_step_cpu: DEFAULT_MAX_STEP_CPU,
            input_timing: InputTiming::Hold,
            error_filter: false,
            quadrature: crate::element::Rule::Dunavant7,
            bending: crate::element::Bending::Pointwise,
            integration: Default::default(),
        }
    }
}

/// Damping.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Damping {
    /// Rayleigh mass-proportional coefficient alpha (1/s).
    pub alpha: f64,
    /// Rayleigh stiffness-proportional coefficient beta (s).
    pub beta: f64,
    /// Crease damping per unit crease length, N m s / (rad m).
    pub crease: f64,
}

impl Default for Damping {
    fn default() -> Self {
        Damping {
            alpha: 0.0,
            beta: 0.0,
            crease: 0.0,
        }
    }
}

/// Which output groups the FMU exposes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Outputs {
    /// `vertex[i].x/y/z`.
    pub positions: bool,
    /// `crease[e].angle`.
    pub fold_angles: bool,
    /// `energy.kinetic`, `energy.strain`, `energy.crease`.
    pub energies: bool,
    /// The reaction of each support (`support[k].force.x/y/z`, and its
    /// moment) and each prescribed motion (`NAME.force.x/y/z`); off unless
    /// asked for (attachments always report their wrench).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub reactions: bool,
}

impl Default for Outputs {
    fn default() -> Self {
        Outputs {
            positions: true,
            fold_angles: true,
            energies: true,
            reactions: false,
        }
    }
}

/// Everything the model needs, validated.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Scene {
    /// Scene name (model name of the FMU).
    pub name: String,
    /// The crease pattern.
    pub mesh: Mesh,
    /// Number of FOLD vertices: mesh vertices `0..n` are FOLD vertices `0..n`
    /// (refinement appends new vertices after them).
    pub fold_vertex_count: usize,
    /// Number of FOLD edges (mesh edges carry `fold_edge` tags).
    pub fold_edge_count: usize,
    /// Sheet material.
    pub material: Material,
    /// Crease stiffness rule.
    pub crease: CreaseStiffness,
    /// Damping.
    pub damping: Damping,
    /// True when the scene does not set `ancf:damping`: the model then
    /// chooses a mass-proportional damping of the deformation rate from the
    /// facet size and crease stiffness (damping ratio 0.2 on the folding
    /// mode of a mean facet; rigid motion undamped), and `damping.alpha` and
    /// `damping.beta` are not used (crease dashpots still are).
    pub auto_damping: bool,
    /// Actuators (one input each).
    pub actuators: Vec<Actuator>,
    /// Time constant of the actuators' response to their inputs (s): each
    /// actuator follows its input as a critically damped second-order
    /// system of natural frequency 1 / time_constant, a servo the user
    /// chooses. `None` or 0: ideal actuators, the input acts at once (the
    /// default).
    #[serde(default)]
    pub actuator_time_constant: Option<f64>,
    /// Supports.
    pub supports: Vec<Support>,
    /// Gravity in m/s^2, `None` when absent.
    pub gravity: Option<[f64; 3]>,
    /// Self-contact with friction, `None` when off (nothing is searched).
    pub contact: Option<crate::contact::ContactSettings>,
    /// Vertex force inputs.
    pub vertex_forces: Vec<VertexInput>,
    /// Prescribed vertex position inputs.
    pub vertex_motions: Vec<VertexInput>,
    /// Rigid attachments: parts of the sheet clamped to frames whose poses
    /// are inputs. (Left out of the scene file when empty, so a scene
    /// without attachments writes the same file, and has the same GUID, as
    /// before.)
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub attachments: Vec<Attachment>,
    /// Rigid obstacles the sheet touches through the contact barrier
    /// (left out of the scene file when empty, as attachments are).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub obstacles: Vec<crate::contact::Obstacle>,
    /// Solver settings.
    pub solver: SolverSettings,
    /// Output groups.
    pub outputs: Outputs,
    /// The built-in input signal of the rest-angle actuators (off by
    /// default: the master drives them).
    #[serde(default)]
    pub ramp: InputRamp,
    /// A folding sequence: stages one rest-angle actuator walks
    /// (`ancf:sequence`, or a FOLD file's frames as keyframes). Left out of
    /// the scene file when absent, as attachments are.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sequence: Option<Sequence>,
}

/// Shape of the built-in ramp.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum RampShape {
    /// Straight from 0 to 1.
    #[default]
    Linear,
    /// Cubic smoothstep `3 x^2 - 2 x^3`: zero slope at both ends, so the
    /// sheet starts and stops folding without a jolt.
    Smooth,
}

/// A built-in signal for every rest-angle actuator: 0 at t = 0, 1 from
/// `time` on. With `time` 0 it is off and the actuators follow their
/// inputs; on, it replaces them (values set on those inputs are not used).
/// The CLI's default schedule and the FMU's `ramp.time` parameter are this.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct InputRamp {
    /// Time to reach full actuation, s (0 = off).
    pub time: f64,
    /// Shape of the rise.
    pub shape: RampShape,
}

impl InputRamp {
    /// Whether the ramp replaces the actuator inputs.
    pub fn is_on(&self) -> bool {
        self.time > 0.0
    }

    /// The signal at time `t` (s).
    pub fn value(&self, t: f64) -> f64 {
        if !self.is_on() {
            return 0.0;
        }
        let x = (t / self.time).clamp(0.0, 1.0);
        match self.shape {
            RampShape::Linear => x,
            RampShape::Smooth => x * x * (3.0 - 2.0 * x),
        }
    }

    /// The signal and its first three time derivatives at `t` (s): the
    /// rise's before its end, zero slopes after it.
    pub fn derivatives(&self, t: f64) -> [f64; 4] {
        if !self.is_on() {
            return [0.0; 4];
        }
        if t >= self.time {
            return [1.0, 0.0, 0.0, 0.0];
        }
        self.rise_derivatives(t.max(0.0))
    }

    /// The rise's polynomial and its first three time derivatives at `t`
    /// (also at and past the rise's end).
    pub fn rise_derivatives(&self, t: f64) -> [f64; 4] {
        let big_t = self.time;
        let x = t / big_t;
        match self.shape {
            RampShape::Linear => [x, 1.0 / big_t, 0.0, 0.0],
            RampShape::Smooth => [
                x * x * (3.0 - 2.0 * x),
                6.0 * x * (1.0 - x) / big_t,
                (6.0 - 12.0 * x) / (big_t * big_t),
                -12.0 / big_t.powi(3),
            ],
        }
    }
}

impl Scene {
    /// Self-contact's default settings for this sheet: its thickness, the
    /// rest as [`ContactSettings::default`] (what `--contact` and
    /// `"ancf:contact": {"enabled": true}` give).
    pub fn default_contact(&self) -> ContactSettings {
        ContactSettings {
            thickness: self.material.thickness,
            ..Default::default()
        }
    }

    /// A scene around `mesh` with every default of a plain FOLD file: paper
    /// material, no supports, no gravity, automatic damping, one rest-angle
    /// actuator `fold` over every crease.
    pub fn with_defaults(name: &str, mut mesh: Mesh) -> Scene {
        // A mesh built in code has no FOLD file behind it: its edge indices
        // are the FOLD edge indices.
        mesh.tag_creases_as_fold_edges();
        let creases: Vec<EdgeId> = mesh
            .edge_ids()
            .filter(|&e| mesh.edge(e).kind == crate::mesh::EdgeKind::Crease)
            .collect();
        let fold_vertex_count = mesh.n_vertices();
        let fold_edge_count = mesh.edges().len();
        Scene {
            name: name.to_string(),
            mesh,
            fold_vertex_count,
            fold_edge_count,
            material: Material::default(),
            crease: CreaseStiffness::default(),
            damping: Damping::default(),
            auto_damping: true,
            actuators: vec![Actuator {
                name: "fold".into(),
                edges: creases,
                mode: ActuatorMode::RestAngle,
                start: 0.0,
            }],
            actuator_time_constant: None,
            supports: vec![],
            gravity: None,
            contact: None,
            vertex_forces: vec![],
            vertex_motions: vec![],
            attachments: vec![],
            obstacles: vec![],
            solver: SolverSettings::default(),
            outputs: Outputs::default(),
            ramp: InputRamp::default(),
            sequence: None,
        }
    }
}
