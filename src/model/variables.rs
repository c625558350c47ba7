//! The model's variables as the FMU and CSV files name them: inputs and
//! outputs ([`VariableSpec`] tables in value-reference order), setting
//! inputs and reading outputs. Parameters are in [`super::parameters`].

use super::inputs::DriveValues;
use super::{Error, Model, Phase};
use crate::assembly::Evaluation;
use crate::ids::{FoldEdgeId, VertexId};
use crate::scene::{ActuatorMode, Scene};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

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

fn spec(name: String, unit: &str, description: String, start: f64) -> VariableSpec {
    VariableSpec {
        name,
        unit: unit.into(),
        description,
        start,
    }
}

/// The inputs of `scene`: one per actuator, then the x, y, z of each
/// vertex force and each prescribed vertex motion, then each attachment's
/// pose (x, y, z, rx, ry, rz), then each moving obstacle's.
pub(super) fn input_table(scene: &Scene) -> Vec<VariableSpec> {
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
        let x = scene.mesh.coord(m.vertex);
        for (c, start) in ["x", "y", "z"].iter().zip([x.x, x.y, 0.0]) {
            v.push(spec(
                format!("{}.{c}", m.name),
                "m",
                format!("prescribed position of vertex {}, {c}", m.vertex),
                start,
            ));
        }
    }
    for a in &scene.attachments {
        let o = super::attach::origin(scene, a);
        let what = format!("attachment {}'s frame", a.name);
        pose_inputs(&a.name, &what, &o, &mut v);
    }
    for o in scene.obstacles.iter().filter(|o| o.moving) {
        let what = format!("obstacle {} ({})", o.name, origin_name(&o.shape));
        pose_inputs(&o.name, &what, &o.shape.origin(), &mut v);
    }
    v
}

/// The six pose inputs `NAME.x/y/z` (the origin of `what`, starting at
/// `origin`) and `NAME.rx/ry/rz` (its rotation vector, starting at 0).
fn pose_inputs(name: &str, what: &str, origin: &Vector3<f64>, v: &mut Vec<VariableSpec>) {
    for (c, start) in ["x", "y", "z"].iter().zip(origin.iter()) {
        v.push(spec(
            format!("{name}.{c}"),
            "m",
            format!("origin of {what}, {c}"),
            *start,
        ));
    }
    for c in ["x", "y", "z"] {
        v.push(spec(
            format!("{name}.r{c}"),
            "rad",
            format!("rotation vector of {what} (axis times angle), {c}"),
            0.0,
        ));
    }
}

/// The point an obstacle's pose inputs and wrench outputs refer to.
fn origin_name(shape: &crate::contact::Shape) -> &'static str {
    match shape {
        crate::contact::Shape::HalfSpace { .. } => "its plane's point",
        crate::contact::Shape::Capsule { .. } => "its segment's midpoint",
        _ => "its centre",
    }
}

/// The outputs of `scene`, as its output groups select: vertex positions,
/// crease angles (one per FOLD crease edge), energies.
pub(super) fn output_table(scene: &Scene) -> Vec<VariableSpec> {
    let mut v = Vec::new();
    let o = scene.outputs;
    if o.positions {
        for i in 0..scene.fold_vertex_count {
            let x = scene.mesh.coords()[i];
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
        for (name, unit, what) in ENERGY_TABLE {
            v.push(spec(name.into(), unit, what.into(), 0.0));
        }
    }
    if scene.contact.is_some() {
        for (name, unit, what) in CONTACT_OUTPUTS.into_iter().chain([CHORD_OUTPUT]) {
            v.push(spec(name.into(), unit, what.into(), 0.0));
        }
    } else if !scene.obstacles.is_empty() {
        // Obstacles without self-contact: the barrier's energy and the
        // friction work (the search's outputs are self-contact's).
        for (name, unit, what) in &CONTACT_OUTPUTS[3..] {
            v.push(spec((*name).into(), unit, (*what).into(), 0.0));
        }
    }
    wrench_outputs(scene, &mut v);
    if scene.sequence.is_some() {
        for (name, unit, what) in SEQUENCE_OUTPUTS {
            v.push(spec(name.into(), unit, what.into(), 0.0));
        }
    }
    v
}

/// The outputs of a scene with a folding sequence (last): where the drive is.
const SEQUENCE_OUTPUTS: [(&str, &str, &str); 2] = [
    (
        "sequence.stage",
        "",
        "the stage of the folding sequence the fold input is in (0-based; at a boundary, the \
         stage just finished)",
    ),
    (
        "sequence.progress",
        "",
        "progress through that stage, 0 to 1",
    ),
];

/// The wrench outputs: attachments', the reactions' (where the scene
/// asks for them) and obstacles'.
fn wrench_outputs(scene: &Scene, v: &mut Vec<VariableSpec>) {
    let o = scene.outputs;
    let mut wrench = |prefix: &str, what: &str, about: &str, moment: bool| {
        for c in ["x", "y", "z"] {
            v.push(spec(
                format!("{prefix}.force.{c}"),
                "N",
                format!("force the sheet exerts on {what} (world axes), {c}"),
                0.0,
            ));
        }
        for c in ["x", "y", "z"].iter().filter(|_| moment) {
            v.push(spec(
                format!("{prefix}.moment.{c}"),
                "N.m",
                format!("moment the sheet exerts on {what} about {about} (world axes), {c}"),
                0.0,
            ));
        }
    };
    for a in &scene.attachments {
        let what = format!("attachment {}", a.name);
        wrench(&a.name, &what, "its frame's origin", true);
    }
    if o.reactions {
        for (k, s) in scene.supports.iter().enumerate() {
            let moment = super::attach::support_has_moment(s);
            let what = format!("ancf:supports[{k}]");
            wrench(
                &format!("support[{k}]"),
                &what,
                "its vertices' centroid",
                moment,
            );
        }
        for m in &scene.vertex_motions {
            let what = format!("the motion {} at vertex {}", m.name, m.vertex);
            wrench(&m.name, &what, "", false);
        }
    }
    for o in &scene.obstacles {
        let what = format!("obstacle {}", o.name);
        wrench(&o.name, &what, origin_name(&o.shape), true);
    }
}

/// The energy outputs: kinetic, strain, crease, input work, dissipated.
const ENERGY_OUTPUTS: usize = ENERGY_TABLE.len();

/// The energy outputs' names, units and descriptions.
const ENERGY_TABLE: [(&str, &str, &str); 5] = [
    ("energy.kinetic", "J", "kinetic energy"),
    (
        "energy.strain",
        "J",
        "shell strain energy (membrane + bending)",
    ),
    ("energy.crease", "J", "crease spring energy"),
    (
        "energy.input_work",
        "J",
        "work done on the sheet by the inputs so far (crease actuators, applied moments, \
         forces and gravity)",
    ),
    (
        "energy.dissipated",
        "J",
        "work dissipated so far (damping, crease dashpots, contact dashpots and friction): \
         kinetic + strain + crease (+ contact) energy + this - energy.input_work is constant",
    ),
];

/// The outputs of a scene with contact (after the energies).
const CONTACT_OUTPUTS: [(&str, &str, &str); 5] = [
    (
        "contact.min_gap",
        "m",
        "smallest surface distance minus the contact thickness (looked for up to a tenth of a facet side)",
    ),
    (
        "contact.pairs",
        "",
        "contact pairs within the barrier width",
    ),
    ("contact.normal_force", "N", "total normal contact force"),
    ("energy.contact", "J", "contact barrier energy"),
    ("energy.friction", "J", "work dissipated by friction"),
];

/// Self-contact's outputs: [`CONTACT_OUTPUTS`] then [`CHORD_OUTPUT`].
const CONTACT_VALUES: usize = CONTACT_OUTPUTS.len() + 1;

/// The output of a scene with self-contact after [`CONTACT_OUTPUTS`].
const CHORD_OUTPUT: (&str, &str, &str) = (
    "contact.chord_error",
    "m",
    "largest distance between the curved facets and the sampled surface that contact keeps apart",
);

/// FOLD edge indices that are creases, in increasing order: the `crease[e]`
/// outputs.
pub fn fold_edges(scene: &Scene) -> Vec<FoldEdgeId> {
    let mut es: Vec<FoldEdgeId> = scene.mesh.creases().filter_map(|e| e.fold_edge).collect();
    es.sort_unstable();
    es.dedup();
    es
}

/// Declares a typed handle to one kind of a model's variables: its
/// position in the model's table of that kind.
macro_rules! handle {
    ($(#[doc = $doc:literal])* $name:ident) => {
        $(#[doc = $doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub struct $name(pub(crate) usize);

        impl $name {
            /// Its position in the model's table of this kind (what the
            /// FMU's value references follow).
            pub fn index(self) -> usize {
                self.0
            }
        }
    };
}

handle! {
    /// One of a model's parameters ([`Model::parameter_id`]).
    ParameterId
}
handle! {
    /// One of a model's inputs ([`Model::input_id`]).
    InputId
}
handle! {
    /// One of a model's outputs ([`Model::output_id`]).
    OutputId
}

impl Model {
    /// The parameter named `name`.
    pub fn parameter_id(&self, name: &str) -> Option<ParameterId> {
        self.parameters
            .iter()
            .position(|v| v.name == name)
            .map(ParameterId)
    }
    /// The input named `name`.
    pub fn input_id(&self, name: &str) -> Option<InputId> {
        self.inputs.iter().position(|v| v.name == name).map(InputId)
    }
    /// The output named `name`.
    pub fn output_id(&self, name: &str) -> Option<OutputId> {
        self.outputs
            .iter()
            .position(|v| v.name == name)
            .map(OutputId)
    }
    /// The parameter at position `i` of [`Model::parameters`], if there is one.
    pub fn parameter_at(&self, i: usize) -> Option<ParameterId> {
        (i < self.parameters.len()).then_some(ParameterId(i))
    }
    /// The input at position `i` of [`Model::inputs`], if there is one.
    pub fn input_at(&self, i: usize) -> Option<InputId> {
        (i < self.inputs.len()).then_some(InputId(i))
    }
    /// The output at position `i` of [`Model::outputs`], if there is one.
    pub fn output_at(&self, k: usize) -> Option<OutputId> {
        (k < self.outputs.len()).then_some(OutputId(k))
    }

    /// Every input, in the order of [`Model::inputs`].
    pub fn input_ids(&self) -> impl Iterator<Item = InputId> + use<> {
        (0..self.inputs.len()).map(InputId)
    }
    /// Every output, in the order of [`Model::outputs`].
    pub fn output_ids(&self) -> impl Iterator<Item = OutputId> + use<> {
        (0..self.outputs.len()).map(OutputId)
    }

    /// Parameters (settable before [`Model::initialize`]).
    pub fn parameters(&self) -> &[VariableSpec] {
        &self.parameters
    }
    /// Inputs, one per actuator, then vertex forces and motions (x, y, z),
    /// then attachment poses (x, y, z, rx, ry, rz).
    pub fn inputs(&self) -> &[VariableSpec] {
        &self.inputs
    }
    /// Outputs: vertex positions, crease angles, energies (as the scene selects).
    pub fn outputs(&self) -> &[VariableSpec] {
        &self.outputs
    }

    /// Current values of all outputs, in the order of [`Model::outputs`].
    pub fn output_values(&self) -> Vec<f64> {
        (0..self.outputs.len())
            .map(|k| self.output_value(k))
            .collect()
    }

    /// Current value of output `k` (in the order of [`Model::outputs`]).
    /// Where the last step did not evaluate the outputs (scenes without
    /// contact), positions and fold angles are read from the state and the
    /// energies evaluated from it on their first read: a master pays only
    /// for the outputs it reads. The energies are then those under the
    /// inputs in force (a rest angle set since the step changes the crease
    /// energy); where the step evaluated the outputs, those of its end. The
    /// contact search's outputs (smallest gap, pairs, normal force) are
    /// likewise searched on their first read of a state.
    pub fn output(&self, id: OutputId) -> Result<f64, Error> {
        if id.0 >= self.outputs.len() {
            return Err(Error::NoSuchVariable {
                kind: "output",
                index: id.0,
            });
        }
        Ok(self.output_value(id.0))
    }

    /// [`Model::output`] at position `k` (in range).
    pub(crate) fn output_value(&self, k: usize) -> f64 {
        if let Some(x) = self.sequence_output(k) {
            return x;
        }
        if let Some(o) = &self.state.outputs {
            return self.contact_output(k).unwrap_or(o[k]);
        }
        let sys = match &self.sys {
            Some(sys) if self.state.phase == Phase::Running => sys,
            _ => return self.outputs[k].start,
        };
        let o = self.scene.outputs;
        let mut i = k;
        if o.positions {
            let n = 3 * self.scene.fold_vertex_count;
            if i < n {
                return self.vertex_position(VertexId(i / 3))[i % 3];
            }
            i -= n;
        }
        if o.fold_angles {
            if let Some(ends) = sys.angle_ends.get(i) {
                return fold_angle(ends, &self.state.crease_theta);
            }
            i -= sys.angle_ends.len();
        }
        if o.energies && i < 3 {
            return self
                .read_cache
                .energies
                .get_or_init(|| self.evaluate_energies())[i];
        }
        if o.energies && i < ENERGY_OUTPUTS {
            let w = &self.state.work;
            return [w.input, w.dissipated()][i - 3];
        }
        // Contact's outputs where the step's end was not evaluated in full:
        // its search's, its barriers' energy alone, the friction work, the
        // chord error.
        if let Some(x) = self.contact_output(k) {
            return x;
        }
        if let Some(j) = self
            .contact_outputs()
            .and_then(|first| k.checked_sub(first))
            .filter(|&j| j < CONTACT_VALUES)
        {
            return self.contact_value(j, || {
                *self
                    .read_cache
                    .barrier_energy
                    .get_or_init(|| self.evaluate_barrier_energy())
            });
        }
        // Anything else (not reached: a scene whose outputs need more
        // evaluates each step's end in full): one full evaluation.
        self.read_cache.full.get_or_init(|| self.evaluate_outputs())[k]
    }

    /// Kinetic, strain and crease energy of the current state.
    fn evaluate_energies(&self) -> [f64; 3] {
        let sys = self.sys.as_ref().expect("running");
        let d = sys.inputs.drive(&self.drive_inputs());
        let q = &self.state.dynamics.q;
        let (strain, crease) = sys.asm.energies(q, &self.state.crease_theta, &d.theta0);
        [self.kinetic_energy(), strain, crease]
    }

    /// The barrier terms' energy now (J): contact's pairs and crease stops.
    fn evaluate_barrier_energy(&self) -> f64 {
        let sys = self.sys.as_ref().expect("running");
        let d = sys.inputs.drive(&self.drive_inputs());
        // Not failing in practice (the step evaluated this state); zero
        // as a full evaluation's fallback has it.
        sys.barrier_energy(&self.state.dynamics, &d, &self.state.crease_theta)
            .unwrap_or(0.0)
    }

    /// Kinetic energy v^T M v / 2 now.
    fn kinetic_energy(&self) -> f64 {
        let sys = self.sys.as_ref().expect("running");
        let v = &self.state.dynamics.v;
        let mut mv = vec![0.0; v.len()];
        sys.asm.mass_mul(v, &mut mv);
        0.5 * v.iter().zip(&mv).map(|(a, b)| a * b).sum::<f64>()
    }

    /// All outputs of the current state from a full evaluation of it under
    /// the inputs in force.
    fn evaluate_outputs(&self) -> Vec<f64> {
        let sys = self.sys.as_ref().expect("running");
        let d = sys.inputs.drive(&self.drive_inputs());
        let ev = sys
            .evaluate(&self.state.dynamics, &d, &self.state.crease_theta)
            .unwrap_or_else(|_| {
                // Not reached in practice: the step checked these crease
                // angles and evaluated forces within Newton's tolerance of
                // this state. Outputs stay finite: angles as tracked,
                // energies zero.
                Evaluation {
                    theta: self.state.crease_theta.clone(),
                    force: vec![0.0; self.state.dynamics.q.len()],
                    ..Default::default()
                }
            });
        self.compute_outputs(&ev, &d)
    }

    /// Kinetic, strain and crease energy now (J).
    pub fn energies(&self) -> [f64; 3] {
        if let Some(k) = self.outputs.iter().position(|v| v.name == "energy.kinetic") {
            [
                self.output_value(k),
                self.output_value(k + 1),
                self.output_value(k + 2),
            ]
        } else {
            [f64::NAN; 3]
        }
    }

    /// The sheet's mass (kg) and centre of mass now (m; in the reference
    /// before initialization).
    pub fn mass_properties(&self) -> (f64, [f64; 3]) {
        let Some(sys) = &self.sys else {
            return (0.0, [0.0; 3]);
        };
        let q = match self.state.phase {
            Phase::Running => self.state.dynamics.q.clone(),
            Phase::Setup => sys.asm.layout.reference_state(&self.scene.mesh),
        };
        let (m, c) = sys.asm.rigid.mass_center(&q);
        (m, c.into())
    }

    /// Current position of mesh vertex `v`.
    pub fn vertex_position(&self, v: VertexId) -> [f64; 3] {
        match &self.sys {
            Some(sys) if self.state.phase == Phase::Running => {
                let s = sys.asm.position_slot(v);
                let q = &self.state.dynamics.q;
                [q[3 * s], q[3 * s + 1], q[3 * s + 2]]
            }
            _ => {
                let x = self.scene.mesh.coord(v);
                [x.x, x.y, 0.0]
            }
        }
    }

    #[doc(hidden)]
    /// Strain energy (membrane + bending, J) of each mesh triangle now, in
    /// the order of `scene().mesh.triangles()`; zeros before initialization
    /// (the flat reference state is stress-free).
    pub fn facet_strain_energies(&self) -> Vec<f64> {
        match &self.sys {
            Some(sys) if self.state.phase == Phase::Running => {
                sys.asm.facet_strain_energies(&self.state.dynamics.q)
            }
            _ => vec![0.0; self.scene.mesh.triangles().len()],
        }
    }

    /// All outputs from the evaluation `ev` of the current state under the
    /// drive `d` (the reactions need its external forces and frames).
    pub(super) fn compute_outputs(&self, ev: &Evaluation, d: &DriveValues) -> Vec<f64> {
        let sys = self.sys.as_ref().expect("built");
        let mut out = Vec::with_capacity(self.outputs.len());
        let o = self.scene.outputs;
        if o.positions {
            // FOLD vertex i is mesh vertex i.
            for v in (0..self.scene.fold_vertex_count).map(VertexId) {
                out.extend(self.vertex_position(v));
            }
        }
        if o.fold_angles {
            out.extend(
                sys.angle_ends
                    .iter()
                    .map(|ends| fold_angle(ends, &ev.theta)),
            );
        }
        if o.energies {
            let w = &self.state.work;
            out.extend([
                self.kinetic_energy(),
                ev.strain_energy,
                ev.crease_energy,
                w.input,
                w.dissipated(),
            ]);
        }
        if self.contact_outputs().is_some() {
            out.extend((0..CONTACT_VALUES).map(|j| self.contact_value(j, || ev.term_energy)));
        } else if !self.scene.obstacles.is_empty() {
            out.extend([ev.term_energy, self.state.work.friction]);
        }
        let dynm = &self.state.dynamics;
        sys.reactions.values(
            &sys.asm,
            (&dynm.q, &dynm.qdd),
            (&d.f_ext, &ev.force),
            &d.frames,
            &mut out,
        );
        // The wrench on each obstacle (zero where the evaluation has none).
        for k in 0..self.scene.obstacles.len() {
            out.extend(ev.obstacle_wrenches.get(k).copied().unwrap_or_default());
        }
        if let Some(p) = self.sequence_position() {
            out.extend([p.stage as f64, p.progress]);
        }
        out
    }

    /// The fold angle (rad, valley positive) of every FOLD crease now, in
    /// increasing edge order: the `crease[e].angle` outputs (read from the
    /// state where the scene has no such outputs).
    pub fn crease_angles(&self) -> Vec<(FoldEdgeId, f64)> {
        let edges = fold_edges(&self.scene);
        let Some(sys) = self
            .sys
            .as_ref()
            .filter(|_| self.state.phase == Phase::Running)
        else {
            return edges.into_iter().map(|e| (e, 0.0)).collect();
        };
        let first = self
            .scene
            .outputs
            .fold_angles
            .then(|| self.output_id(&format!("crease[{}].angle", edges.first()?)))
            .flatten();
        edges
            .into_iter()
            .enumerate()
            .map(|(k, e)| {
                let angle = match first {
                    Some(OutputId(o)) => self.output_value(o + k),
                    None => fold_angle(&sys.angle_ends[k], &self.state.crease_theta),
                };
                (e, angle)
            })
            .collect()
    }

    /// Where the folding sequence's drive is now (its actuator's value):
    /// None without a sequence or before initialization.
    pub fn sequence_position(&self) -> Option<crate::scene::sequence::Position> {
        let sys = self.sys.as_ref()?;
        let sq = sys.inputs.sequence.as_ref()?;
        (self.state.phase == Phase::Running).then(|| sq.locate(&self.drive_inputs()))
    }

    /// Output `k` if it is one of the sequence's (stage, progress).
    fn sequence_output(&self, k: usize) -> Option<f64> {
        self.scene.sequence.as_ref()?;
        let first = self.outputs.len().checked_sub(2)?;
        if k < first {
            return None;
        }
        let p = self.sequence_position()?;
        Some(if k == first {
            p.stage as f64
        } else {
            p.progress
        })
    }

    /// Index of the first contact output (`contact.min_gap`), if any.
    fn contact_outputs(&self) -> Option<usize> {
        self.scene.contact?;
        let o = self.scene.outputs;
        let sys = self.sys.as_ref()?;
        let mut k = 0;
        if o.positions {
            k += 3 * self.scene.fold_vertex_count;
        }
        if o.fold_angles {
            k += sys.angle_ends.len();
        }
        if o.energies {
            k += ENERGY_OUTPUTS;
        }
        Some(k)
    }

    /// Output `k` if it is one of the contact search's (smallest gap, pairs,
    /// normal force): the search runs on the first read of the state.
    fn contact_output(&self, k: usize) -> Option<f64> {
        let j = k.checked_sub(self.contact_outputs()?)?;
        if j >= 3 {
            return None;
        }
        self.contact()?;
        Some(self.contact_value(j, || 0.0))
    }

    /// Self-contact's output `j` of this state, in the order of
    /// [`CONTACT_OUTPUTS`] then [`CHORD_OUTPUT`]: the search's report (kept
    /// for its reads), the barrier energy `barrier_energy` gives, the
    /// friction work, the chord error.
    fn contact_value(&self, j: usize, barrier_energy: impl FnOnce() -> f64) -> f64 {
        match j {
            0..=2 => {
                let r = self.contact().unwrap_or_default();
                [r.min_gap, r.pairs as f64, r.normal_force][j]
            }
            3 => barrier_energy(),
            4 => self.state.work.friction,
            _ => self.chord_error().map_or(0.0, |c| c.0),
        }
    }
}

/// The fold angle output of one crease: the mean of its ends' angles
/// `theta - pi` (radians, valley positive).
fn fold_angle(ends: &[usize], theta: &[f64]) -> f64 {
    let sum: f64 = ends.iter().map(|&i| theta[i] - std::f64::consts::PI).sum();
    sum / ends.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Outputs read from the state (positions, angles) and the energy-only
    /// evaluation agree with a full evaluation of the same state, value by
    /// value and through `output_values`.
    #[test]
    fn outputs_read_from_the_state_equal_a_full_evaluation() {
        reads_equal_a_full_evaluation(crate::benchmarks::miura_scene(1), false);
    }

    /// With self-contact and nothing touching, a step's end is not
    /// evaluated in full: contact's outputs read from its search, its
    /// barriers' energy alone and the chord error equal a full evaluation's.
    #[test]
    fn contact_outputs_read_from_the_state_equal_a_full_evaluation() {
        let mut scene = crate::benchmarks::miura_scene(1);
        scene.contact = Some(scene.default_contact());
        reads_equal_a_full_evaluation(scene, true);
    }

    /// A diagonal folded onto its contact (the deployable of
    /// tests/contact.rs): at every step end with no pair in the barrier at
    /// the step's start, whose end is read from the state, contact's
    /// outputs equal a full evaluation's, the steps where pairs entered
    /// the barrier (its energy nonzero) among them.
    #[test]
    fn contact_outputs_read_as_pairs_enter_equal_a_full_evaluation() {
        let mut scene = crate::benchmarks::deployable_scene();
        scene.contact = Some(scene.default_contact());
        let mut m = Model::new(scene).unwrap();
        m.initialize().unwrap();
        let fold = m.input_id("fold").unwrap();
        let energy = m.output_id("energy.contact").unwrap();
        let mut entered = 0;
        for k in 0..70 {
            let t = k as f64 * 0.005;
            let (u, slope) = if t < 0.3 {
                (t / 0.3, 1.0 / 0.3)
            } else {
                (1.0, 0.0)
            };
            m.set_input(fold, u).unwrap();
            m.set_input_derivative(fold, 1, slope).unwrap();
            m.advance(0.005).unwrap();
            if m.state.outputs.is_some() {
                continue;
            }
            let full = m.evaluate_outputs();
            let read = m.output_values();
            for (i, (a, b)) in full.iter().zip(&read).enumerate() {
                let name = &m.outputs()[i].name;
                // Contact's exactly; the strain and crease energies by their
                // energy-only sum, as without contact.
                if name.contains("contact") {
                    assert_eq!(a, b, "step {k}: {name}");
                } else {
                    assert!(
                        (a - b).abs() <= 1e-12 * a.abs().max(1e-12),
                        "step {k}: {name}"
                    );
                }
            }
            if m.output(energy).unwrap() > 0.0 {
                entered += 1;
            }
        }
        assert!(
            entered > 0,
            "pairs entered the barrier in a step read from the state"
        );
    }

    fn reads_equal_a_full_evaluation(scene: crate::Scene, contact: bool) {
        let mut m = Model::new(scene).unwrap();
        m.initialize().unwrap();
        let fold = m.input_id("fold").unwrap();
        m.set_input(fold, 0.5).unwrap();
        for _ in 0..3 {
            m.advance(0.01).unwrap();
        }
        assert!(
            m.state.outputs.is_none(),
            "nothing dissipates: evaluated where read"
        );
        assert_eq!(m.contact_outputs().is_some(), contact);
        let full = m.evaluate_outputs();
        let read = m.output_values();
        assert_eq!(full.len(), read.len());
        let mut energy_seen = false;
        for (k, (a, b)) in full.iter().zip(&read).enumerate() {
            let name = &m.outputs()[k].name;
            energy_seen |= name.starts_with("energy.") && *a > 0.0;
            assert!(
                (a - b).abs() <= 1e-12 * a.abs().max(1e-12),
                "{name}: full {a}, read {b}"
            );
            assert_eq!(
                m.output(m.output_at(k).unwrap()).unwrap(),
                *b,
                "{name}: output(k) and output_values differ"
            );
        }
        assert!(energy_seen, "the fold has strain or crease energy");
    }

    /// A value refused by the limits is a typed error holding the limit's
    /// reason as its source; the message names the input and the value.
    #[test]
    fn refused_inputs_keep_the_limit_error() {
        use crate::scene::limits::LimitError;
        let mut m = Model::new(crate::benchmarks::miura_scene(1)).unwrap();
        let fold = m.input_id("fold").unwrap();
        let e = m.set_input(fold, f64::NAN).unwrap_err();
        assert!(
            matches!(&e, Error::OutOfLimits { name, source: LimitError::NotFinite(_), .. } if name == "fold"),
            "{e:?}"
        );
        assert_eq!(
            e.to_string(),
            "fold = NaN: NaN is not a finite number; value not applied"
        );
        let source = std::error::Error::source(&e).expect("the limit's reason");
        assert_eq!(source.to_string(), "NaN is not a finite number");
        let e = m.set_input(fold, 1e31).unwrap_err();
        assert!(
            matches!(
                e,
                Error::OutOfLimits {
                    source: LimitError::TooLarge(_),
                    ..
                }
            ),
            "{e:?}"
        );
    }
}
