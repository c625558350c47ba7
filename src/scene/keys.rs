//! The `ancf:` physics keys of a FOLD scene (documented in `docs/scenes.md`).
//!
//! | key | value |
//! |-----|-------|
//! | `ancf:name` | model name (string) |
//! | `ancf:material` | `{youngs_modulus, poisson_ratio, thickness, density}` |
//! | `ancf:crease` | `{length_scale}` or `{stiffness_per_length}`, optional `damping_per_length` |
//! | `ancf:damping` | `{alpha, beta}` or `"auto"` |
//! | `ancf:actuators` | `[{name, edges, mode, start}]` |
//! | `ancf:actuation` | `{time_constant}` (s: the actuators' servo; 0 or absent: ideal) |
//! | `ancf:sequence` | `[{edges, fraction \| degrees, share, title}]`: stages the `fold` input walks |
//! | `ancf:supports` | `[{vertices, fix}]` |
//! | `ancf:loads` | `{gravity, vertex_forces: [{name, vertex}]}` |
//! | `ancf:motions` | `[{name, vertex}]` |
//! | `ancf:attachments` | `[{name, vertices}]` |
//! | `ancf:contact` | `{enabled, friction, stiffness, thickness, barrier_width, stick_velocity, damping_ratio, subdivisions}` |
//! | `ancf:obstacles` | `[{name, shape, ...its parameters, friction, moving}]` |
//! | `ancf:solver` | `{integrator, rho_inf, max_step, min_step, tolerance, max_newton, newton, stop_time, max_internal_steps, max_step_cpu, input_timing, error_filter, quadrature}` |
//! | `ancf:outputs` | `["positions", "fold_angles", "energies", "reactions"]` |
//! | `ancf:refine` | levels of uniform refinement (integer) |
//! | `ancf:import` | `{size, unit, f_edges}`: how the FOLD geometry is read |
//!
//! This module checks each key on its own (types, ranges, names, unknown
//! fields with a "did you mean"); checks against the mesh (indices, crease
//! membership) happen when the scene is built.

use super::error::{SceneError, suggestion};
use super::fold::{
    Assignment, expect_array, expect_index, expect_number, expect_string, type_name,
};
use super::{
    ActuatorMode, CreaseStiffness, Fix, FlatEdges, InputTiming, Integrator, Material, NewtonMode,
    Outputs, SolverSettings, VertexInput,
};
use crate::contact::ContactSettings;
use crate::element::Rule;
use crate::ids::VertexId;
use crate::text::num;
use serde_json::{Map, Value};

/// First components of generated variable names; user-chosen input names
/// may not use them.
pub const RESERVED_NAMES: &[&str] = &[
    "vertex", "crease", "energy", "material", "damping", "gravity", "solver", "contact", "time",
    "support", "sequence",
];

/// Most levels of `ancf:refine` (each multiplies the triangles by 4).
pub const MAX_REFINE: usize = 6;

/// Which creases an actuator drives, in FOLD terms.
#[derive(Clone, Debug, PartialEq)]
pub enum EdgeSelection {
    /// Every crease.
    All,
    /// Every crease with this assignment (M, V, U, or F when F edges are
    /// creases).
    Assignment(Assignment),
    /// These FOLD edge indices.
    List(Vec<usize>),
}

/// An actuator as written in the file (edges not yet resolved).
#[derive(Clone, Debug, PartialEq)]
pub struct ActuatorSpec {
    /// Input name.
    pub name: String,
    /// Creases driven.
    pub edges: EdgeSelection,
    /// Rest-angle or torque.
    pub mode: ActuatorMode,
    /// Input value at t = 0.
    pub start: f64,
    /// `ancf:actuators[i]`, for messages.
    pub key: String,
}

/// What a stage's creases reach at its end, as written.
#[derive(Clone, Debug, PartialEq)]
pub enum StageTarget {
    /// `fraction`: this share of each crease's target in the file
    /// (`edges_foldAngle`, or +-180 degrees by its letter); default 1.
    Fraction(f64),
    /// `degrees` as a number: every crease of the stage to this angle.
    Degrees(f64),
    /// `degrees` as a list: one angle per edge of the `edges` list.
    DegreesEach(Vec<f64>),
}

/// A stage of `ancf:sequence` as written in the file (edges not yet resolved).
#[derive(Clone, Debug, PartialEq)]
pub struct StageSpec {
    /// Creases it folds (actuator syntax).
    pub edges: EdgeSelection,
    /// Where they end.
    pub target: StageTarget,
    /// Its share of the drive (`None`: all stages share equally).
    pub share: Option<f64>,
    /// A label.
    pub title: Option<String>,
    /// `ancf:sequence[i]`, for messages.
    pub key: String,
}

/// Longest stage title (characters).
pub const MAX_TITLE: usize = 200;

/// A support as written in the file.
#[derive(Clone, Debug, PartialEq)]
pub struct SupportSpec {
    /// FOLD vertex indices.
    pub vertices: Vec<usize>,
    /// What is fixed.
    pub fix: Fix,
    /// `ancf:supports[i]`, for messages.
    pub key: String,
}

/// A rigid attachment as written in the file.
#[derive(Clone, Debug, PartialEq)]
pub struct AttachmentSpec {
    /// Variable name prefix.
    pub name: String,
    /// FOLD vertex indices.
    pub vertices: Vec<usize>,
    /// `ancf:attachments[i]`, for messages.
    pub key: String,
}

/// A rigid obstacle as written in the file.
#[derive(Clone, Debug, PartialEq)]
pub struct ObstacleSpec {
    /// Variable name prefix, shape and placement (friction filled in when
    /// the scene is built).
    pub obstacle: crate::contact::Obstacle,
    /// `friction` as given (`None`: the contact's).
    pub friction: Option<f64>,
    /// `ancf:obstacles[i]`, for messages.
    pub key: String,
}

/// Everything the `ancf:` keys say, checked key by key; defaults filled in.
/// (Not to be confused with [`crate::assembly::Physics`], the coefficients
/// the assembly is given once the scene is built.)
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PhysicsKeys {
    /// `ancf:name`.
    pub name: Option<String>,
    /// `ancf:material`.
    pub material: Material,
    /// `ancf:crease` stiffness rule.
    pub crease: CreaseStiffness,
    /// `ancf:crease.damping_per_length` (`None`: not given).
    pub crease_damping: Option<f64>,
    /// `ancf:damping` (alpha, beta); `None`: automatic damping.
    pub damping: Option<(f64, f64)>,
    /// `ancf:actuators`; `None`: the default actuator `fold`.
    pub actuators: Option<Vec<ActuatorSpec>>,
    /// `ancf:actuation.time_constant`; `None`: ideal actuators.
    pub actuator_time_constant: Option<f64>,
    /// `ancf:sequence`: the stages the `fold` input walks.
    pub sequence: Option<Vec<StageSpec>>,
    /// `ancf:supports`.
    pub supports: Vec<SupportSpec>,
    /// `ancf:loads.gravity`.
    pub gravity: Option<[f64; 3]>,
    /// `ancf:loads.vertex_forces` with their keys.
    pub vertex_forces: Vec<(VertexInput, String)>,
    /// `ancf:motions` with their keys.
    pub vertex_motions: Vec<(VertexInput, String)>,
    /// `ancf:attachments`.
    pub attachments: Vec<AttachmentSpec>,
    /// `ancf:solver`.
    pub solver: SolverSettings,
    /// `ancf:outputs`.
    pub outputs: Outputs,
    /// `ancf:contact` as given, enabled or not (thickness 0: the sheet's):
    /// what `--contact` turns on.
    pub contact: Option<ContactSettings>,
    /// `ancf:contact.enabled`.
    pub contact_enabled: bool,
    /// `ancf:contact.friction` as given (enabled or not).
    pub contact_friction: Option<f64>,
    /// `ancf:obstacles`.
    pub obstacles: Vec<ObstacleSpec>,
    /// `ancf:refine`.
    pub refine: usize,
    /// `ancf:import`.
    pub import: Import,
}

/// `ancf:import`: how the FOLD geometry is read (command-line options
/// override it).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Import {
    /// `size`: the longest side of the sheet's bounding box, m.
    pub size: Option<f64>,
    /// `unit`: the unit of the coordinates (one of [`super::fold::UNITS`]
    /// but `unit`), instead of `frame_unit`.
    pub unit: Option<String>,
    /// `f_edges`: what F edges are.
    pub f_edges: Option<FlatEdges>,
}

/// A JSON object with a fixed set of allowed fields.
struct Obj<'a> {
    key: String,
    map: &'a Map<String, Value>,
}

impl<'a> Obj<'a> {
    fn new(key: &str, v: &'a Value, fields: &[&str]) -> Result<Obj<'a>, SceneError> {
        let map = v.as_object().ok_or_else(|| {
            SceneError::invalid(key, format!("expected an object, found {}", type_name(v)))
        })?;
        let mut names: Vec<&String> = map.keys().collect();
        names.sort();
        for f in names {
            if !fields.contains(&f.as_str()) {
                return Err(SceneError::invalid(
                    key,
                    format!(
                        "unknown field '{f}'{}; allowed: {}",
                        suggestion(f, fields),
                        fields.join(", ")
                    ),
                ));
            }
        }
        Ok(Obj {
            key: key.to_string(),
            map,
        })
    }
    fn path(&self, f: &str) -> String {
        format!("{}.{f}", self.key)
    }
    fn get(&self, f: &str) -> Option<&'a Value> {
        self.map.get(f)
    }
    fn num(&self, f: &str) -> Result<Option<f64>, SceneError> {
        self.get(f).map(|v| number(v, &self.path(f))).transpose()
    }
    /// A number satisfying `ok`, described by `what` in the error.
    fn num_where(
        &self,
        f: &str,
        ok: impl Fn(f64) -> bool,
        what: &str,
    ) -> Result<Option<f64>, SceneError> {
        match self.num(f)? {
            Some(x) if !ok(x) => Err(SceneError::invalid(
                self.path(f),
                format!("{} is out of range; it must be {what}", num(x)),
            )),
            x => Ok(x),
        }
    }
    /// A number checked by the one validator under its parameter name
    /// ([`super::limits`]).
    fn num_limited(&self, f: &str, name: &str) -> Result<Option<f64>, SceneError> {
        let x = self.num(f)?;
        if let Some(x) = x {
            super::limits::check(name, x).map_err(|source| SceneError::Limit {
                key: self.path(f),
                source,
            })?;
        }
        Ok(x)
    }
    fn string(&self, f: &str) -> Result<Option<&'a str>, SceneError> {
        self.get(f)
            .map(|v| expect_string(v, &self.path(f)))
            .transpose()
    }
    fn boolean(&self, f: &str) -> Result<Option<bool>, SceneError> {
        match self.get(f) {
            None => Ok(None),
            Some(Value::Bool(b)) => Ok(Some(*b)),
            Some(other) => Err(SceneError::invalid(
                self.path(f),
                format!("expected true or false, found {}", type_name(other)),
            )),
        }
    }
    fn required(&self, f: &str) -> Result<&'a Value, SceneError> {
        self.get(f)
            .ok_or_else(|| SceneError::invalid(self.path(f), "missing (required)"))
    }
}

/// Largest magnitude of a physical number in the keys: beyond it products
/// of a few parameters would overflow.
pub const MAX_MAGNITUDE: f64 = super::limits::MAX_MAGNITUDE;

/// A finite number of sensible magnitude.
fn number(v: &Value, key: &str) -> Result<f64, SceneError> {
    let x = expect_number(v, key)?;
    if x.abs() > MAX_MAGNITUDE {
        return Err(SceneError::invalid(
            key,
            format!(
                "{} is too large (at most {MAX_MAGNITUDE:e} in magnitude)",
                num(x)
            ),
        ));
    }
    Ok(x)
}

/// Check an input name: a C-like identifier that does not start a
/// generated variable name.
pub fn check_name(key: &str, name: &str) -> Result<(), SceneError> {
    let mut chars = name.chars();
    let ok = match chars.next() {
        Some(c) if c.is_ascii_alphabetic() || c == '_' => {
            chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
        }
        _ => false,
    };
    if !ok {
        return Err(SceneError::invalid(
            key,
            format!(
                "'{name}' is not a valid variable name: use letters, digits and '_', \
                 starting with a letter or '_'"
            ),
        ));
    }
    if RESERVED_NAMES.contains(&name) {
        return Err(SceneError::invalid(
            key,
            format!(
                "'{name}' clashes with generated variable names ({}.*); choose another name",
                name
            ),
        ));
    }
    Ok(())
}

/// A real length unit (one of [`super::fold::UNITS`] but `unit`): the
/// name, checked, with a "did you mean" for a misspelling.
pub fn check_unit(key: &str, unit: &str) -> Result<String, SceneError> {
    if super::fold::unit_scale(unit).is_some() {
        return Ok(unit.to_string());
    }
    let real: Vec<&str> = super::fold::UNITS
        .iter()
        .copied()
        .filter(|u| *u != "unit")
        .collect();
    Err(SceneError::invalid(
        key,
        format!(
            "unknown unit \"{unit}\"{}; expected one of {}",
            suggestion(unit, &real),
            real.join(", ")
        ),
    ))
}

fn enum_value<T: Copy>(key: &str, s: &str, options: &[(&str, T)]) -> Result<T, SceneError> {
    options
        .iter()
        .find(|(n, _)| *n == s)
        .map(|(_, v)| *v)
        .ok_or_else(|| {
            let names: Vec<&str> = options.iter().map(|(n, _)| *n).collect();
            SceneError::invalid(
                key,
                format!(
                    "unknown value \"{s}\"{}; expected one of {}",
                    suggestion(s, &names),
                    names.join(", ")
                ),
            )
        })
}

fn index_list(v: &Value, key: &str) -> Result<Vec<usize>, SceneError> {
    expect_array(v, key)?
        .iter()
        .enumerate()
        .map(|(i, x)| expect_index(x, &format!("{key}[{i}]")))
        .collect()
}

fn vertex_inputs(v: &Value, key: &str) -> Result<Vec<(VertexInput, String)>, SceneError> {
    let mut out = Vec::new();
    for (i, item) in expect_array(v, key)?.iter().enumerate() {
        let k = format!("{key}[{i}]");
        let o = Obj::new(&k, item, &["name", "vertex"])?;
        let name = expect_string(o.required("name")?, &o.path("name"))?;
        check_name(&o.path("name"), name)?;
        let vertex = expect_index(o.required("vertex")?, &o.path("vertex"))?;
        out.push((
            VertexInput {
                name: name.to_string(),
                vertex: VertexId::of_fold_vertex(vertex),
            },
            k,
        ));
    }
    Ok(out)
}

/// Read all `ancf:` keys. Unknown `ancf:` keys and unknown fields are errors
/// with a suggestion; notes for the user go to `warnings`.
pub fn parse(
    ancf: &Map<String, Value>,
    warnings: &mut Vec<String>,
) -> Result<PhysicsKeys, SceneError> {
    check_known_keys(ancf)?;
    let mut p = PhysicsKeys::default();
    for (key, parse_key) in PARSERS {
        if let Some(v) = ancf.get(*key) {
            parse_key(v, &mut p, warnings)?;
        }
    }
    check_unique_names(&p)?;
    Ok(p)
}

/// Reads one `ancf:` key's value into the physics keys.
type KeyParser = fn(&Value, &mut PhysicsKeys, &mut Vec<String>) -> Result<(), SceneError>;

/// Every `ancf:` key with its reader, in the order their errors are reported.
const PARSERS: &[(&str, KeyParser)] = &[
    ("ancf:name", key_name),
    ("ancf:material", key_material),
    ("ancf:crease", key_crease),
    ("ancf:damping", key_damping),
    ("ancf:actuators", key_actuators),
    ("ancf:actuation", key_actuation),
    ("ancf:sequence", key_sequence),
    ("ancf:supports", key_supports),
    ("ancf:loads", key_loads),
    ("ancf:motions", key_motions),
    ("ancf:attachments", key_attachments),
    ("ancf:contact", key_contact),
    ("ancf:obstacles", key_obstacles),
    ("ancf:solver", key_solver),
    ("ancf:outputs", key_outputs),
    ("ancf:refine", key_refine),
    ("ancf:import", key_import),
];

/// Every key is one that [`PARSERS`] reads (else the nearest is suggested).
fn check_known_keys(ancf: &Map<String, Value>) -> Result<(), SceneError> {
    let known: Vec<&str> = PARSERS.iter().map(|(k, _)| *k).collect();
    let mut keys: Vec<&String> = ancf.keys().collect();
    keys.sort();
    for k in keys {
        if !known.contains(&k.as_str()) {
            return Err(SceneError::invalid(
                k.as_str(),
                format!(
                    "unknown key{}; known keys: {}",
                    suggestion(k, &known),
                    known.join(", ")
                ),
            ));
        }
    }
    Ok(())
}

/// Input names are unique across actuators, forces, motions and attachments.
fn check_unique_names(p: &PhysicsKeys) -> Result<(), SceneError> {
    // Input names must be unique across actuators, forces, motions and
    // attachments.
    let mut seen: Vec<(&str, String)> = Vec::new();
    if p.sequence.is_some() {
        seen.push((
            super::sequence::INPUT,
            "ancf:sequence (the input that walks its stages)".into(),
        ));
    }
    let names = p
        .actuators
        .iter()
        .flatten()
        .map(|a| (a.name.as_str(), format!("{}.name", a.key)))
        .chain(
            p.vertex_forces
                .iter()
                .chain(&p.vertex_motions)
                .map(|(vi, k)| (vi.name.as_str(), format!("{k}.name"))),
        )
        .chain(
            p.attachments
                .iter()
                .map(|a| (a.name.as_str(), format!("{}.name", a.key))),
        )
        .chain(
            p.obstacles
                .iter()
                .map(|o| (o.obstacle.name.as_str(), format!("{}.name", o.key))),
        );
    for (name, key) in names {
        if let Some((_, first)) = seen.iter().find(|(n, _)| *n == name) {
            return Err(SceneError::invalid(
                key,
                format!("the name '{name}' is already used by {first}"),
            ));
        }
        seen.push((name, key));
    }
    Ok(())
}

/// `ancf:name`: the scene's name.
fn key_name(v: &Value, p: &mut PhysicsKeys, _warnings: &mut Vec<String>) -> Result<(), SceneError> {
    let s = expect_string(v, "ancf:name")?;
    if s.trim().is_empty() {
        return Err(SceneError::invalid("ancf:name", "must not be empty"));
    }
    p.name = Some(s.to_string());
    Ok(())
}

/// `ancf:material`: the sheet's material.
fn key_material(
    v: &Value,
    p: &mut PhysicsKeys,
    _warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    let o = Obj::new(
        "ancf:material",
        v,
        &["youngs_modulus", "poisson_ratio", "thickness", "density"],
    )?;
    let m = &mut p.material;
    if let Some(x) = o.num_limited("youngs_modulus", "material.youngs_modulus")? {
        m.youngs_modulus = x;
    }
    if let Some(x) = o.num_limited("poisson_ratio", "material.poisson_ratio")? {
        m.poisson_ratio = x;
    }
    if let Some(x) = o.num_limited("thickness", "material.thickness")? {
        m.thickness = x;
    }
    if let Some(x) = o.num_limited("density", "material.density")? {
        m.density = x;
    }
    Ok(())
}

/// `ancf:crease`: the crease stiffness rule and dashpots.
fn key_crease(
    v: &Value,
    p: &mut PhysicsKeys,
    _warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    let o = Obj::new(
        "ancf:crease",
        v,
        &["length_scale", "stiffness_per_length", "damping_per_length"],
    )?;
    let ls = o.num_limited("length_scale", "crease.length_scale")?;
    let k = o.num_limited("stiffness_per_length", "crease.stiffness_per_length")?;
    p.crease = match (ls, k) {
        (Some(_), Some(_)) => {
            return Err(SceneError::invalid(
                "ancf:crease",
                "give either length_scale or stiffness_per_length, not both",
            ));
        }
        (Some(l), None) => CreaseStiffness::LengthScale(l),
        (None, Some(k)) => CreaseStiffness::PerLength(k),
        (None, None) => CreaseStiffness::default(),
    };
    if let Some(c) = o.num_limited("damping_per_length", "damping.crease")? {
        p.crease_damping = Some(c);
    }
    Ok(())
}

/// `ancf:damping`: `"auto"` or Rayleigh's alpha and beta.
fn key_damping(
    v: &Value,
    p: &mut PhysicsKeys,
    _warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    if v.as_str() == Some("auto") {
        p.damping = None;
    } else if v.is_string() {
        return Err(SceneError::invalid(
            "ancf:damping",
            "expected \"auto\" or an object {alpha, beta}",
        ));
    } else {
        let o = Obj::new("ancf:damping", v, &["alpha", "beta"])?;
        let a = o.num_limited("alpha", "damping.alpha")?;
        let b = o.num_limited("beta", "damping.beta")?;
        p.damping = Some((a.unwrap_or(0.0), b.unwrap_or(0.0)));
    }
    Ok(())
}

/// `ancf:actuators`: each actuator's name, creases, mode and start.
fn key_actuators(
    v: &Value,
    p: &mut PhysicsKeys,
    _warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    let mut list = Vec::new();
    for (i, item) in expect_array(v, "ancf:actuators")?.iter().enumerate() {
        let key = format!("ancf:actuators[{i}]");
        let o = Obj::new(&key, item, &["name", "edges", "mode", "start"])?;
        let name = expect_string(o.required("name")?, &o.path("name"))?;
        check_name(&o.path("name"), name)?;
        let edges = edge_selection(&o, "an actuator")?;
        let mode = match o.string("mode")? {
            None => ActuatorMode::RestAngle,
            Some(s) => enum_value(
                &o.path("mode"),
                s,
                &[
                    ("rest_angle", ActuatorMode::RestAngle),
                    ("torque", ActuatorMode::Torque),
                ],
            )?,
        };
        let start = o.num("start")?.unwrap_or(0.0);
        list.push(ActuatorSpec {
            name: name.to_string(),
            edges,
            mode,
            start,
            key,
        });
    }
    p.actuators = Some(list);
    Ok(())
}

/// An `edges` field: "all", an assignment letter or a list of FOLD edge
/// indices (default "all"); `who` says what needs a crease ("an actuator").
fn edge_selection(o: &Obj, who: &str) -> Result<EdgeSelection, SceneError> {
    Ok(match o.get("edges") {
        None => EdgeSelection::All,
        Some(Value::String(s)) => match s.as_str() {
            "all" => EdgeSelection::All,
            "M" => EdgeSelection::Assignment(Assignment::Mountain),
            "V" => EdgeSelection::Assignment(Assignment::Valley),
            "U" => EdgeSelection::Assignment(Assignment::Unassigned),
            "F" => EdgeSelection::Assignment(Assignment::Flat),
            other => {
                return Err(SceneError::invalid(
                    o.path("edges"),
                    format!(
                        "unknown selection \"{other}\"; expected \"all\", \"M\", \"V\", \"U\", \
                         \"F\" or a list of FOLD edge indices"
                    ),
                ));
            }
        },
        Some(list @ Value::Array(_)) => {
            let l = index_list(list, &o.path("edges"))?;
            if l.is_empty() {
                return Err(SceneError::invalid(
                    o.path("edges"),
                    format!("the list is empty; {who} needs at least one crease"),
                ));
            }
            EdgeSelection::List(l)
        }
        Some(other) => {
            return Err(SceneError::invalid(
                o.path("edges"),
                format!(
                    "expected \"all\", \"M\", \"V\", \"U\", \"F\" or a list of FOLD edge indices, found {}",
                    type_name(other)
                ),
            ));
        }
    })
}

/// `ancf:sequence`: the stages, each with its creases, their targets, its
/// share of the drive and a title.
fn key_sequence(
    v: &Value,
    p: &mut PhysicsKeys,
    _warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    let items = expect_array(v, "ancf:sequence")?;
    if items.is_empty() {
        return Err(SceneError::invalid(
            "ancf:sequence",
            "the list is empty; a sequence needs at least one stage",
        ));
    }
    let max = super::sequence::MAX_STAGES;
    if items.len() > max {
        return Err(SceneError::invalid(
            "ancf:sequence",
            format!("{} stages; at most {max}", items.len()),
        ));
    }
    let mut stages = Vec::with_capacity(items.len());
    for (i, item) in items.iter().enumerate() {
        let key = format!("ancf:sequence[{i}]");
        let o = Obj::new(
            &key,
            item,
            &["edges", "fraction", "degrees", "share", "title"],
        )?;
        let edges = edge_selection(&o, "a stage")?;
        let target = match (o.get("fraction"), o.get("degrees")) {
            (Some(_), Some(_)) => {
                return Err(SceneError::invalid(
                    key,
                    "give either fraction (of the file's fold angles) or degrees, not both",
                ));
            }
            (Some(_), None) => StageTarget::Fraction(o.num("fraction")?.unwrap_or(1.0)),
            (None, Some(list @ Value::Array(_))) => {
                let path = o.path("degrees");
                let EdgeSelection::List(edge_list) = &edges else {
                    return Err(SceneError::invalid(
                        path,
                        "a list of angles needs a list of edges (one angle each); with a \
                         selection such as \"M\" give one number",
                    ));
                };
                let angles = expect_array(list, &path)?
                    .iter()
                    .enumerate()
                    .map(|(j, x)| number(x, &format!("{path}[{j}]")))
                    .collect::<Result<Vec<f64>, _>>()?;
                if angles.len() != edge_list.len() {
                    return Err(SceneError::invalid(
                        path,
                        format!(
                            "{} angles for {} edges; give one angle per edge",
                            angles.len(),
                            edge_list.len()
                        ),
                    ));
                }
                StageTarget::DegreesEach(angles)
            }
            (None, Some(_)) => StageTarget::Degrees(o.num("degrees")?.unwrap_or(0.0)),
            (None, None) => StageTarget::Fraction(1.0),
        };
        let share = o.num_where(
            "share",
            |x| x > 0.0 && x <= 1.0,
            "in (0, 1]: the stage's part of the fold input's range 0..1",
        )?;
        let title = o.string("title")?.map(str::to_string);
        if let Some(t) = &title
            && t.chars().count() > MAX_TITLE
        {
            return Err(SceneError::invalid(
                o.path("title"),
                format!("is longer than {MAX_TITLE} characters"),
            ));
        }
        stages.push(StageSpec {
            edges,
            target,
            share,
            title,
            key,
        });
    }
    check_shares(&stages)?;
    p.sequence = Some(stages);
    Ok(())
}

/// Every stage gives a share or none does (equal shares); given shares add
/// up to 1 (within [`super::sequence::SHARE_TOLERANCE`]).
fn check_shares(stages: &[StageSpec]) -> Result<(), SceneError> {
    let given: Vec<f64> = stages.iter().filter_map(|s| s.share).collect();
    if given.is_empty() {
        return Ok(());
    }
    if let Some(s) = stages.iter().find(|s| s.share.is_none()) {
        return Err(SceneError::invalid(
            format!("{}.share", s.key),
            "missing; give every stage a share, or none (then the stages share the drive \
             equally)",
        ));
    }
    let sum: f64 = given.iter().sum();
    if (sum - 1.0).abs() > super::sequence::SHARE_TOLERANCE {
        let mut list: Vec<String> = stages
            .iter()
            .enumerate()
            .take(8)
            .map(|(k, s)| format!("stage {k}: {}", num(s.share.unwrap_or(0.0))))
            .collect();
        if stages.len() > 8 {
            list.push("...".into());
        }
        return Err(SceneError::invalid(
            "ancf:sequence",
            format!(
                "the shares add up to {} ({}); they must add up to 1 (the fold input's range)",
                num(sum),
                list.join(", ")
            ),
        ));
    }
    Ok(())
}

/// `ancf:actuation`: the actuators' time constant.
fn key_actuation(
    v: &Value,
    p: &mut PhysicsKeys,
    warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    let o = Obj::new("ancf:actuation", v, &["time_constant"])?;
    if o.get("time_constant").and_then(Value::as_str) == Some("auto") {
        // Before 2026-12-06 "auto" chose a mesh-dependent servo; there is
        // no automatic value any more.
        warnings.push(
            "ancf:actuation.time_constant: \"auto\" is no longer supported (there is no automatic \
             servo); the actuators are ideal. Give a time constant in seconds for a servo"
                .into(),
        );
    } else {
        p.actuator_time_constant = o.num_limited("time_constant", "actuator.time_constant")?;
    }
    Ok(())
}

/// `ancf:supports`: the supported vertices and how.
fn key_supports(
    v: &Value,
    p: &mut PhysicsKeys,
    _warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    for (i, item) in expect_array(v, "ancf:supports")?.iter().enumerate() {
        let key = format!("ancf:supports[{i}]");
        let o = Obj::new(&key, item, &["vertices", "fix"])?;
        let vertices = index_list(o.required("vertices")?, &o.path("vertices"))?;
        if vertices.is_empty() {
            return Err(SceneError::invalid(o.path("vertices"), "the list is empty"));
        }
        let fix = match o.string("fix")? {
            None => Fix::Position,
            Some(s) => enum_value(
                &o.path("fix"),
                s,
                &[("position", Fix::Position), ("clamped", Fix::Clamped)],
            )?,
        };
        p.supports.push(SupportSpec { vertices, fix, key });
    }
    Ok(())
}

/// `ancf:loads`: gravity and vertex force inputs.
fn key_loads(
    v: &Value,
    p: &mut PhysicsKeys,
    _warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    let o = Obj::new("ancf:loads", v, &["gravity", "vertex_forces"])?;
    if let Some(g) = o.get("gravity") {
        let key = o.path("gravity");
        let arr = expect_array(g, &key)?;
        if arr.len() != 3 {
            return Err(SceneError::invalid(
                key,
                format!(
                    "expected 3 components [x, y, z] in m/s^2, found {}",
                    arr.len()
                ),
            ));
        }
        let mut gv = [0.0; 3];
        for (c, x) in arr.iter().enumerate() {
            gv[c] = number(x, &format!("{key}[{c}]"))?;
        }
        p.gravity = Some(gv);
    }
    if let Some(f) = o.get("vertex_forces") {
        p.vertex_forces = vertex_inputs(f, &o.path("vertex_forces"))?;
    }
    Ok(())
}

/// `ancf:motions`: vertex motion inputs.
fn key_motions(
    v: &Value,
    p: &mut PhysicsKeys,
    _warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    p.vertex_motions = vertex_inputs(v, "ancf:motions")?;
    Ok(())
}

/// `ancf:attachments`: vertices held by a rigid frame.
fn key_attachments(
    v: &Value,
    p: &mut PhysicsKeys,
    _warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    for (i, item) in expect_array(v, "ancf:attachments")?.iter().enumerate() {
        let key = format!("ancf:attachments[{i}]");
        let o = Obj::new(&key, item, &["name", "vertices"])?;
        let name = expect_string(o.required("name")?, &o.path("name"))?;
        check_name(&o.path("name"), name)?;
        let vertices = index_list(o.required("vertices")?, &o.path("vertices"))?;
        if vertices.is_empty() {
            return Err(SceneError::invalid(o.path("vertices"), "the list is empty"));
        }
        p.attachments.push(AttachmentSpec {
            name: name.to_string(),
            vertices,
            key,
        });
    }
    Ok(())
}

/// `ancf:contact`: self-contact and friction.
fn key_contact(
    v: &Value,
    p: &mut PhysicsKeys,
    _warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    let o = Obj::new(
        "ancf:contact",
        v,
        &[
            "enabled",
            "friction",
            "stiffness",
            "thickness",
            "barrier_width",
            "stick_velocity",
            "damping_ratio",
            "subdivisions",
        ],
    )?;
    let enabled = o.boolean("enabled")?.unwrap_or(false);
    let d = ContactSettings::default();
    // The rules of scene::limits, which the FMU's scene check runs too.
    let friction = o.num_limited("friction", "contact.friction")?;
    let stiffness = o.num_limited("stiffness", "contact.stiffness")?;
    let thickness = o.num_limited("thickness", "contact.thickness")?;
    let width = o.num_limited("barrier_width", "contact.barrier_width")?;
    let stick = o.num_limited("stick_velocity", "contact.stick_velocity")?;
    let zeta = o.num_limited("damping_ratio", "contact.damping_ratio")?;
    let subdivisions = o.num_limited("subdivisions", "contact.subdivisions")?;
    p.contact_friction = friction;
    p.contact_enabled = enabled;
    p.contact = Some(ContactSettings {
        // 0 = the sheet thickness (filled in with the material).
        thickness: thickness.unwrap_or(0.0),
        width: width.unwrap_or(d.width),
        stiffness,
        friction: friction.unwrap_or(d.friction),
        stick_velocity: stick.unwrap_or(d.stick_velocity),
        damping_ratio: zeta.unwrap_or(d.damping_ratio),
        subdivisions: subdivisions.map(|x| x as usize).unwrap_or(d.subdivisions),
    });
    Ok(())
}

/// A 3-vector field of an obstacle (m, or rad for a rotation vector).
fn vector3(o: &Obj, f: &str) -> Result<[f64; 3], SceneError> {
    let key = o.path(f);
    let arr = expect_array(o.required(f)?, &key)?;
    if arr.len() != 3 {
        return Err(SceneError::invalid(
            key,
            format!("expected 3 components [x, y, z], found {}", arr.len()),
        ));
    }
    let mut out = [0.0; 3];
    for (c, x) in arr.iter().enumerate() {
        out[c] = number(x, &format!("{key}[{c}]"))?;
    }
    Ok(out)
}

/// `ancf:obstacles`: rigid shapes, fixed in the world or moved by pose
/// inputs, that the sheet touches through the contact barrier.
fn key_obstacles(
    v: &Value,
    p: &mut PhysicsKeys,
    _warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    use crate::contact::Obstacle;
    for (i, item) in expect_array(v, "ancf:obstacles")?.iter().enumerate() {
        let key = format!("ancf:obstacles[{i}]");
        // The shape first: it says which fields are allowed.
        let shape_name = obstacle_shape_name(item, &key)?;
        let fields: &[&str] = match shape_name {
            "half_space" => &["name", "shape", "friction", "moving", "point", "normal"],
            "sphere" => &["name", "shape", "friction", "moving", "center", "radius"],
            "box" => &[
                "name",
                "shape",
                "friction",
                "moving",
                "center",
                "half_extents",
                "rotation",
            ],
            "capsule" => &["name", "shape", "friction", "moving", "ends", "radius"],
            _ => &["name", "shape"],
        };
        let o = Obj::new(&key, item, fields)?;
        let name = expect_string(o.required("name")?, &o.path("name"))?;
        check_name(&o.path("name"), name)?;
        let moving = obstacle_moving(&o)?;
        let shape = obstacle_shape(&o, shape_name)?;
        shape
            .check()
            .map_err(|e| SceneError::invalid(key.clone(), e.to_string()))?;
        let friction = o.num_limited("friction", "contact.friction")?;
        p.obstacles.push(ObstacleSpec {
            obstacle: Obstacle {
                name: name.to_string(),
                shape,
                friction: friction.unwrap_or(0.0),
                moving,
            },
            friction,
            key,
        });
    }
    Ok(())
}

/// An obstacle's `shape` (one of the known ones; "" for an item that is
/// not an object, which the object check then names).
fn obstacle_shape_name<'a>(item: &'a Value, key: &str) -> Result<&'a str, SceneError> {
    const SHAPES: &[&str] = &["half_space", "sphere", "box", "capsule"];
    let shape_name = match item.get("shape") {
        Some(s) => expect_string(s, &format!("{key}.shape"))?,
        None if item.is_object() => {
            return Err(SceneError::invalid(
                format!("{key}.shape"),
                format!("missing (required): one of {}", SHAPES.join(", ")),
            ));
        }
        None => "",
    };
    if item.is_object() && !SHAPES.contains(&shape_name) {
        let options: Vec<(&str, ())> = SHAPES.iter().map(|&s| (s, ())).collect();
        enum_value(&format!("{key}.shape"), shape_name, &options)?;
    }
    Ok(shape_name)
}

/// An obstacle's `moving`: true for pose inputs, false (or absent) for
/// an obstacle fixed in the world.
fn obstacle_moving(o: &Obj) -> Result<bool, SceneError> {
    match o.get("moving") {
        None => Ok(false),
        Some(Value::Bool(b)) => Ok(*b),
        Some(other) => Err(SceneError::invalid(
            o.path("moving"),
            format!("expected true or false, found {}", type_name(other)),
        )),
    }
}

/// An obstacle's shape from its fields (`shape_name` one of the known
/// ones).
fn obstacle_shape(o: &Obj, shape_name: &str) -> Result<crate::contact::Shape, SceneError> {
    use crate::contact::Shape;
    let length = |f: &str| -> Result<f64, SceneError> {
        let x = number(o.required(f)?, &o.path(f))?;
        if x > 0.0 {
            Ok(x)
        } else {
            Err(SceneError::invalid(
                o.path(f),
                format!("{} is not a positive length (m)", num(x)),
            ))
        }
    };
    Ok(match shape_name {
        "half_space" => {
            let normal = vector3(o, "normal")?;
            let len = normal.iter().map(|x| x * x).sum::<f64>().sqrt();
            if !(len > 0.0 && len.is_finite()) {
                return Err(SceneError::invalid(
                    o.path("normal"),
                    "the outward normal must be a nonzero vector",
                ));
            }
            Shape::HalfSpace {
                point: vector3(o, "point")?,
                normal: normal.map(|x| x / len),
            }
        }
        "sphere" => Shape::Sphere {
            center: vector3(o, "center")?,
            radius: length("radius")?,
        },
        "box" => {
            let half = vector3(o, "half_extents")?;
            if let Some(c) = half.iter().position(|&h| h <= 0.0) {
                return Err(SceneError::invalid(
                    format!("{}[{c}]", o.path("half_extents")),
                    format!("{} is not a positive length (m)", num(half[c])),
                ));
            }
            Shape::Box {
                center: vector3(o, "center")?,
                half_extents: half,
                rotation: match o.get("rotation") {
                    Some(_) => vector3(o, "rotation")?,
                    None => [0.0; 3],
                },
            }
        }
        _ => Shape::Capsule {
            ends: capsule_ends(o)?,
            radius: length("radius")?,
        },
    })
}

/// A capsule's `ends`: two points `[[x, y, z], [x, y, z]]`.
fn capsule_ends(o: &Obj) -> Result<[[f64; 3]; 2], SceneError> {
    let key = o.path("ends");
    let arr = expect_array(o.required("ends")?, &key)?;
    if arr.len() != 2 {
        return Err(SceneError::invalid(
            key,
            format!(
                "expected the segment's 2 end points [[x, y, z], [x, y, z]], found {}",
                arr.len()
            ),
        ));
    }
    let mut ends = [[0.0; 3]; 2];
    for (e, end) in arr.iter().enumerate() {
        let ke = format!("{key}[{e}]");
        let xs = expect_array(end, &ke)?;
        if xs.len() != 3 {
            return Err(SceneError::invalid(
                ke,
                format!("expected 3 components [x, y, z], found {}", xs.len()),
            ));
        }
        for (c, x) in xs.iter().enumerate() {
            ends[e][c] = number(x, &format!("{ke}[{c}]"))?;
        }
    }
    Ok(ends)
}

/// `ancf:solver`: the integrator and its settings.
fn key_solver(
    v: &Value,
    p: &mut PhysicsKeys,
    _warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    let o = Obj::new(
        "ancf:solver",
        v,
        &[
            "integrator",
            "rho_inf",
            "max_step",
            "min_step",
            "tolerance",
            "max_newton",
            "newton",
            "stop_time",
            "max_internal_steps",
            "max_step_cpu",
            "input_timing",
            "error_filter",
            "quadrature",
        ],
    )?;
    let s = &mut p.solver;
    if let Some(name) = o.string("integrator")? {
        s.integrator = enum_value(
            &o.path("integrator"),
            name,
            &[
                ("generalized-alpha", Integrator::GeneralizedAlpha),
                ("central-difference", Integrator::CentralDifference),
            ],
        )?;
    }
    if let Some(x) = o.num_limited("rho_inf", "solver.rho_inf")? {
        s.rho_inf = x;
    }
    if let Some(x) = o.num_limited("max_step", "solver.max_step")? {
        s.max_step = x;
    }
    if let Some(x) = o.num_limited("min_step", "solver.min_step")? {
        s.min_step = x;
    }
    if let Err(source) = super::limits::check_solver_relations(s) {
        return Err(SceneError::Limit {
            key: o.path("min_step"),
            source,
        });
    }
    if let Some(x) = o.num_limited("tolerance", "solver.tolerance")? {
        s.tolerance = x;
    }
    if let Some(n) = o.num_limited("max_newton", "solver.max_newton")? {
        s.max_newton = n as usize;
    }
    if let Some(n) = o.num_limited("max_internal_steps", "solver.max_internal_steps")? {
        s.max_internal_steps = n as usize;
    }
    if let Some(x) = o.num_limited("max_step_cpu", "solver.max_step_cpu")? {
        s.max_step_cpu = x;
    }
    if let Some(name) = o.string("input_timing")? {
        s.input_timing = enum_value(
            &o.path("input_timing"),
            name,
            &[
                ("hold", InputTiming::Hold),
                ("first_order_hold", InputTiming::FirstOrderHold),
                // The name before 2026-12-06.
                ("ramp", InputTiming::FirstOrderHold),
            ],
        )?;
    }
    if let Some(b) = o.boolean("error_filter")? {
        s.error_filter = b;
    }
    if let Some(name) = o.string("newton")? {
        s.newton = enum_value(
            &o.path("newton"),
            name,
            &[
                ("full", NewtonMode::Full),
                ("modified", NewtonMode::Modified),
            ],
        )?;
    }
    if let Some(x) = o.num_limited("stop_time", "solver.stop_time")? {
        s.stop_time = x;
    }
    if let Some(name) = o.string("quadrature")? {
        s.quadrature = enum_value(
            &o.path("quadrature"),
            name,
            &[("12-point", Rule::Dunavant12), ("7-point", Rule::Dunavant7)],
        )?;
    }
    Ok(())
}

/// `ancf:outputs`: the output groups.
fn key_outputs(
    v: &Value,
    p: &mut PhysicsKeys,
    warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    let mut o = Outputs {
        positions: false,
        fold_angles: false,
        energies: false,
        reactions: false,
    };
    const GROUPS: &[&str] = &["positions", "fold_angles", "energies", "reactions"];
    for (i, item) in expect_array(v, "ancf:outputs")?.iter().enumerate() {
        let key = format!("ancf:outputs[{i}]");
        let s = expect_string(item, &key)?;
        let flag = match s {
            "positions" => &mut o.positions,
            "fold_angles" => &mut o.fold_angles,
            "energies" => &mut o.energies,
            "reactions" => &mut o.reactions,
            other => {
                return Err(SceneError::invalid(
                    key,
                    format!(
                        "unknown output group \"{other}\"{}; expected one of {}",
                        suggestion(other, GROUPS),
                        GROUPS.join(", ")
                    ),
                ));
            }
        };
        if *flag {
            warnings.push(format!("{key}: \"{s}\" is listed twice"));
        }
        *flag = true;
    }
    if !(o.positions || o.fold_angles || o.energies || o.reactions) {
        warnings.push("ancf:outputs: the list is empty; the model has no outputs".into());
    }
    p.outputs = o;
    Ok(())
}

/// `ancf:refine`: levels of refinement.
fn key_refine(
    v: &Value,
    p: &mut PhysicsKeys,
    _warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    let n = expect_index(v, "ancf:refine")?;
    if n > MAX_REFINE {
        return Err(SceneError::invalid(
            "ancf:refine",
            format!("{n} levels is too many; at most {MAX_REFINE}"),
        ));
    }
    p.refine = n;
    Ok(())
}

/// `ancf:import`: the import's size, unit and flat edges.
fn key_import(
    v: &Value,
    p: &mut PhysicsKeys,
    _warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    // As scene::limits: positive means at least MIN_POSITIVE.
    let positive = |x: f64| x >= super::limits::MIN_POSITIVE;
    let o = Obj::new("ancf:import", v, &["size", "unit", "f_edges"])?;
    p.import.size = o.num_where("size", positive, "positive, at least 1e-30 (m)")?;
    if let Some(u) = o.string("unit")? {
        p.import.unit = Some(check_unit(&o.path("unit"), u)?);
    }
    if p.import.size.is_some() && p.import.unit.is_some() {
        return Err(SceneError::invalid(
            "ancf:import",
            "give either size or unit, not both",
        ));
    }
    if let Some(s) = o.string("f_edges")? {
        p.import.f_edges = Some(enum_value(
            &o.path("f_edges"),
            s,
            &[("crease", FlatEdges::Crease), ("smooth", FlatEdges::Smooth)],
        )?);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn keys(json: &str) -> Result<PhysicsKeys, SceneError> {
        let map: Map<String, Value> = serde_json::from_str(json).unwrap();
        parse(&map, &mut Vec::new())
    }
    fn err(json: &str) -> String {
        keys(json).unwrap_err().to_string()
    }

    #[test]
    fn defaults_without_keys() {
        let p = keys("{}").unwrap();
        assert_eq!(p.material, Material::default());
        assert_eq!(p.crease, CreaseStiffness::default());
        assert_eq!(p.damping, None);
        assert_eq!(p.actuators, None);
        assert_eq!(p.outputs, Outputs::default());
        assert_eq!(p.refine, 0);
    }

    #[test]
    fn full_set_of_keys() {
        let p = keys(
            r#"{
            "ancf:name": "sheet",
            "ancf:material": {"youngs_modulus": 4e9, "poisson_ratio": 0.35, "thickness": 2e-4, "density": 1000},
            "ancf:crease": {"stiffness_per_length": 0.02, "damping_per_length": 1e-5},
            "ancf:damping": {"alpha": 0.5, "beta": 1e-4},
            "ancf:actuators": [{"name": "m", "edges": "M", "mode": "torque", "start": 0.1},
                               {"name": "v", "edges": [1, 2]}],
            "ancf:supports": [{"vertices": [0, 1], "fix": "clamped"}],
            "ancf:loads": {"gravity": [0, 0, -9.81], "vertex_forces": [{"name": "tip", "vertex": 3}]},
            "ancf:motions": [{"name": "grip", "vertex": 2}],
            "ancf:contact": {"enabled": false, "friction": 0.3},
            "ancf:solver": {"integrator": "central-difference", "rho_inf": 0.5, "max_step": 1e-4,
                            "min_step": 1e-10, "tolerance": 1e-7, "max_newton": 50, "newton": "full", "stop_time": 2,
                            "quadrature": "7-point"},
            "ancf:outputs": ["positions", "energies"],
            "ancf:refine": 2,
            "ancf:import": {"size": 0.2, "f_edges": "smooth"}
        }"#,
        )
        .unwrap();
        assert_eq!(p.name.as_deref(), Some("sheet"));
        assert_eq!(p.material.thickness, 2e-4);
        assert_eq!(p.crease, CreaseStiffness::PerLength(0.02));
        assert_eq!(p.crease_damping, Some(1e-5));
        assert_eq!(p.damping, Some((0.5, 1e-4)));
        let a = p.actuators.unwrap();
        assert_eq!(a[0].edges, EdgeSelection::Assignment(Assignment::Mountain));
        assert_eq!(a[0].mode, ActuatorMode::Torque);
        assert_eq!(a[1].edges, EdgeSelection::List(vec![1, 2]));
        assert_eq!(a[1].mode, ActuatorMode::RestAngle);
        assert_eq!(p.supports[0].fix, Fix::Clamped);
        assert_eq!(p.gravity, Some([0.0, 0.0, -9.81]));
        assert_eq!(p.vertex_forces[0].0.vertex, VertexId(3));
        assert_eq!(p.vertex_motions[0].0.name, "grip");
        assert_eq!(p.solver.integrator, Integrator::CentralDifference);
        assert_eq!(p.solver.max_newton, 50);
        assert_eq!(p.solver.newton, NewtonMode::Full);
        assert_eq!(p.solver.quadrature, Rule::Dunavant7);
        assert!(p.outputs.positions && !p.outputs.fold_angles && p.outputs.energies);
        assert_eq!(p.refine, 2);
        assert_eq!(p.import.size, Some(0.2));
        assert_eq!(p.import.f_edges, Some(FlatEdges::Smooth));
    }

    #[test]
    fn unknown_keys_and_fields_suggest() {
        let e = err(r#"{"ancf:materail": {}}"#);
        assert!(
            e.starts_with("ancf:materail: unknown key; did you mean 'ancf:material'?"),
            "{e}"
        );
        let e = err(r#"{"ancf:material": {"thicknes": 1e-4}}"#);
        assert!(
            e.contains("unknown field 'thicknes'; did you mean 'thickness'?"),
            "{e}"
        );
        let e = err(r#"{"ancf:solver": {"integrator": "generalised-alpha"}}"#);
        assert!(e.contains("did you mean 'generalized-alpha'"), "{e}");
        let e = err(r#"{"ancf:outputs": ["fold_angle"]}"#);
        assert!(
            e.starts_with("ancf:outputs[0]:") && e.contains("'fold_angles'"),
            "{e}"
        );
    }

    #[test]
    fn material_ranges() {
        for (json, key) in [
            (r#"{"thickness": 0}"#, "thickness"),
            (r#"{"thickness": -1e-4}"#, "thickness"),
            (r#"{"youngs_modulus": 0}"#, "youngs_modulus"),
            (r#"{"density": -800}"#, "density"),
            (r#"{"poisson_ratio": 0.5}"#, "poisson_ratio"),
            (r#"{"poisson_ratio": -1}"#, "poisson_ratio"),
            (r#"{"density": "heavy"}"#, "density"),
        ] {
            let e = err(&format!(r#"{{"ancf:material": {json}}}"#));
            assert!(e.starts_with(&format!("ancf:material.{key}:")), "{e}");
        }
        assert!(keys(r#"{"ancf:material": {"poisson_ratio": -0.99}}"#).is_ok());
    }

    #[test]
    fn names_are_identifiers_unique_and_not_reserved() {
        let e = err(r#"{"ancf:actuators": [{"name": "2fold"}]}"#);
        assert!(
            e.starts_with("ancf:actuators[0].name:") && e.contains("not a valid"),
            "{e}"
        );
        let e = err(r#"{"ancf:actuators": [{"name": "a.b"}]}"#);
        assert!(e.contains("not a valid"), "{e}");
        let e = err(r#"{"ancf:actuators": [{"name": "vertex"}]}"#);
        assert!(e.contains("clashes with generated"), "{e}");
        let e = err(r#"{"ancf:actuators": [{"name": "f"}, {"name": "f"}]}"#);
        assert!(
            e.starts_with("ancf:actuators[1].name:") && e.contains("already used"),
            "{e}"
        );
        let e = err(
            r#"{"ancf:actuators": [{"name": "tip"}], "ancf:loads": {"vertex_forces": [{"name": "tip", "vertex": 0}]}}"#,
        );
        assert!(e.starts_with("ancf:loads.vertex_forces[0].name:"), "{e}");
        let e = err(r#"{"ancf:motions": [{"name": "energy", "vertex": 0}]}"#);
        assert!(e.contains("clashes"), "{e}");
        let e = err(r#"{"ancf:actuators": [{"edges": "all"}]}"#);
        assert!(e.starts_with("ancf:actuators[0].name: missing"), "{e}");
    }

    #[test]
    fn other_value_errors() {
        let e = err(r#"{"ancf:contact": {"enabled": true, "subdivisions": 0}}"#);
        assert!(
            e.contains("ancf:contact.subdivisions") && e.contains("whole number"),
            "{e}"
        );
        let e = err(r#"{"ancf:contact": {"enabled": true, "barrier_width": 2}}"#);
        assert!(e.contains("barrier_width"), "{e}");
        let e = err(r#"{"ancf:crease": {"length_scale": 0.01, "stiffness_per_length": 1}}"#);
        assert!(e.contains("not both"), "{e}");
        let e = err(r#"{"ancf:actuators": [{"name": "a", "edges": []}]}"#);
        assert!(e.contains("empty"), "{e}");
        let e = err(r#"{"ancf:actuators": [{"name": "a", "edges": "X"}]}"#);
        assert!(e.starts_with("ancf:actuators[0].edges:"), "{e}");
        let e = err(r#"{"ancf:actuators": [{"name": "a", "mode": "angle"}]}"#);
        assert!(e.starts_with("ancf:actuators[0].mode:"), "{e}");
        let e = err(r#"{"ancf:loads": {"gravity": [0, -9.81]}}"#);
        assert!(e.starts_with("ancf:loads.gravity:"), "{e}");
        let e = err(r#"{"ancf:solver": {"min_step": 1, "max_step": 0.1}}"#);
        assert!(e.contains("larger than max_step"), "{e}");
        let e = err(r#"{"ancf:solver": {"max_newton": 0}}"#);
        assert!(e.starts_with("ancf:solver.max_newton:"), "{e}");
        let e = err(r#"{"ancf:solver": {"quadrature": "6-point"}}"#);
        assert!(
            e.starts_with("ancf:solver.quadrature:") && e.contains("12-point, 7-point"),
            "{e}"
        );
        let e = err(r#"{"ancf:refine": 9}"#);
        assert!(e.contains("too many"), "{e}");
        let e = err(r#"{"ancf:refine": -1}"#);
        assert!(e.starts_with("ancf:refine:"), "{e}");
        let e = err(r#"{"ancf:material": {"youngs_modulus": 1e300}}"#);
        assert!(e.contains("too large"), "{e}");
        let e = err(r#"{"ancf:loads": {"gravity": [0, 0, -1e31]}}"#);
        assert!(e.starts_with("ancf:loads.gravity[2]:"), "{e}");
        let e = err(r#"{"ancf:import": {"size": 0.1, "unit": "mm"}}"#);
        assert!(e.contains("not both"), "{e}");
        let e = err(r#"{"ancf:import": {"unit": "mn"}}"#);
        assert!(
            e.starts_with("ancf:import.unit:") && e.contains("did you mean"),
            "{e}"
        );
        let e = err(r#"{"ancf:import": {"unit": "unit"}}"#);
        assert!(e.starts_with("ancf:import.unit:"), "{e}");
        let e = err(r#"{"ancf:import": {"f_edges": "flat"}}"#);
        assert!(e.starts_with("ancf:import.f_edges:"), "{e}");
        assert_eq!(
            keys(r#"{"ancf:import": {"unit": "in"}}"#)
                .unwrap()
                .import
                .unit
                .as_deref(),
            Some("in")
        );
        let e = err(r#"{"ancf:damping": "none"}"#);
        assert!(e.starts_with("ancf:damping:"), "{e}");
        assert_eq!(keys(r#"{"ancf:damping": "auto"}"#).unwrap().damping, None);
        assert_eq!(
            keys(r#"{"ancf:damping": {}}"#).unwrap().damping,
            Some((0.0, 0.0))
        );
    }
}
