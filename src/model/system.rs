//! The system built from the scene and parameters: assembly, sparse
//! solver, stepper settings and the input map ([`Model::build`]).

use super::attach::{self, About, FrameInput, Reaction, Reactions};
use super::inputs::{Actuation, DriveValues, InputMap, SequenceDrive};
use super::{Error, Model, fold_edges, physics};
use crate::assembly::{Assembler, EvalError, Evaluation, State};
use crate::contact::ContactTerm;
use crate::dofs::{DofLayout, SlotKind};
use crate::element::ElementOptions;
use crate::frame::HeldSlots;
use crate::ids::FoldEdgeId;
use crate::scene::{ActuatorMode, Fix, Integrator as SceneIntegrator, Scene, SolverSettings};
use crate::solver::central_difference::CentralDifference;
use crate::solver::generalized_alpha::{self as ga, GeneralizedAlpha};
use crate::solver::stepper::Dynamics;
use crate::solver::stepper::Stepper;
use crate::solver::{LinearError, SparseSolver};
use std::collections::HashMap;

/// Everything built from the scene and parameters: by [`Model::new`], and
/// again by [`Model::initialize`] or [`Model::restore_state`] only when the
/// parameters differ from the ones it was built with.
pub(super) struct System {
    pub(super) asm: Assembler,
    /// The solver of the implicit stepper's iteration matrix (and of the
    /// mass matrix for consistent accelerations).
    pub(super) solver: SparseSolver,
    /// The time integrator the scene asks for.
    pub(super) stepper: Box<dyn Stepper + Send>,
    pub(super) inputs: InputMap,
    /// For each `crease[e]` output: the crease ends averaged.
    pub(super) angle_ends: Vec<Vec<usize>>,
    /// How the actuators follow their inputs.
    pub(super) actuation: Actuation,
    /// The scene's solver settings it was built with (step bounds, the
    /// internal step limit, the numerical constants).
    pub(super) settings: SolverSettings,
    /// Where each free slot is in the reference sheet (the ordering of
    /// large systems cuts by it).
    pub(super) block_coords: Vec<[f64; 3]>,
    /// The reaction outputs (attachments' wrenches; supports' and
    /// motions' forces where the scene asks for them).
    pub(super) reactions: Reactions,
}

/// The reaction outputs of scene `sc` (see [`Reactions`]): the frames'
/// wrenches, and with the `reactions` output group each support's (about
/// its centroid) and each motion's force.
fn reactions(
    sc: &Scene,
    layout: &DofLayout,
    frames: &[FrameInput],
    support_slots: Vec<Vec<(usize, bool)>>,
) -> Reactions {
    let mut groups: Vec<Reaction> = frames
        .iter()
        .enumerate()
        .map(|(k, f)| Reaction {
            slots: f.held.slots.iter().map(|h| (h.slot, h.position)).collect(),
            about: About::Frame(k),
            moment: true,
        })
        .collect();
    if sc.outputs.reactions {
        for (sup, slots) in sc.supports.iter().zip(support_slots) {
            groups.push(Reaction {
                slots,
                about: About::Point(attach::centroid(sc, &sup.vertices)),
                moment: attach::support_has_moment(sup),
            });
        }
        for m in &sc.vertex_motions {
            groups.push(Reaction {
                slots: vec![(layout.position_slot[m.vertex.index()], true)],
                about: About::Point(nalgebra::Vector3::zeros()),
                moment: false,
            });
        }
    }
    Reactions { groups }
}

/// The assembler's view of positions and velocities `d` under `drive`,
/// crease angles unwrapped near `theta_prev`.
fn state_of<'a>(d: &'a Dynamics, drive: &'a DriveValues, theta_prev: &'a [f64]) -> State<'a> {
    State {
        q: &d.q,
        v: &d.v,
        theta0: &drive.theta0,
        moment: &drive.moment,
        theta_prev,
    }
}

impl System {
    /// The full evaluation (forces, energies) of positions and velocities
    /// `d` under the drive `drive`, crease angles unwrapped near `theta_prev`.
    pub(super) fn evaluate(
        &self,
        d: &Dynamics,
        drive: &DriveValues,
        theta_prev: &[f64],
    ) -> Result<Evaluation, EvalError> {
        let mut ev = Evaluation::default();
        self.asm
            .evaluate(&state_of(d, drive, theta_prev), &mut ev, None)?;
        Ok(ev)
    }

    /// The barrier terms' energy (J) at `d` under `drive`, from their
    /// evaluation alone: the full evaluation's `term_energy`.
    pub(super) fn barrier_energy(
        &self,
        d: &Dynamics,
        drive: &DriveValues,
        theta_prev: &[f64],
    ) -> Result<f64, EvalError> {
        self.asm.barrier_energy(&state_of(d, drive, theta_prev))
    }

    /// A new sparse solver for the assembler's pattern as it is now (after
    /// the pattern grew or was restored); the iteration matrix is gone.
    pub(super) fn rebuild_solver(&mut self) -> Result<(), LinearError> {
        let stats = self.solver.stats();
        self.solver = SparseSolver::new_blocked(
            self.asm.n_free,
            self.asm.col_ptr.clone(),
            self.asm.row_idx.clone(),
            3,
            Some(&self.block_coords),
        )?;
        self.solver.carry_stats(stats);
        self.stepper.invalidate_matrix();
        Ok(())
    }
}

impl Model {
    /// Build the system for the scene as it is now (parameters applied).
    pub(super) fn build(&mut self) -> Result<(), Error> {
        self.sys = Some(System::new(&self.scene)?);
        self.built_with = Some(self.state.parameters.clone());
        Ok(())
    }
}

impl System {
    /// The system of scene `sc` (parameters applied); nothing else changes,
    /// so a failure leaves the model as it was.
    pub(super) fn new(sc: &Scene) -> Result<System, Error> {
        check_sequence(sc)?;
        let mesh = &sc.mesh;
        let layout = crate::dofs::DofLayout::new(mesh);
        let q_ref = layout.reference_state(mesh);
        let mut is_fixed = vec![false; layout.n_slots()];
        let (mut fixed, supported, support_slots) =
            support_slots(sc, &layout, &q_ref, &mut is_fixed);
        let n_act = sc.actuators.len();
        let mut motion = Vec::new();
        let mut idx = n_act + 3 * sc.vertex_forces.len();
        for m in &sc.vertex_motions {
            let s = layout.position_slot[m.vertex.index()];
            if !is_fixed[s] {
                is_fixed[s] = true;
                fixed.push(s);
            }
            for c in 0..3 {
                motion.push((idx + c, 3 * s + c));
            }
            idx += 3;
        }
        let mut frames = Vec::with_capacity(sc.attachments.len());
        for a in &sc.attachments {
            let origin = attach::origin(sc, a);
            let held = HeldSlots::new(&layout, &q_ref, &a.vertices, origin, &mut is_fixed);
            fixed.extend(held.slots.iter().map(|h| h.slot));
            frames.push(FrameInput { input: idx, held });
            idx += attach::POSE_INPUTS;
        }
        let mut moving = Vec::new();
        for _ in sc.obstacles.iter().filter(|o| o.moving) {
            moving.push(idx);
            idx += attach::POSE_INPUTS;
        }
        let mut force = Vec::new();
        for (k, f) in sc.vertex_forces.iter().enumerate() {
            let s = layout.position_slot[f.vertex.index()];
            for c in 0..3 {
                force.push((n_act + 3 * k + c, 3 * s + c));
            }
        }
        let physics = physics(sc);
        let element = ElementOptions {
            rule: sc.solver.quadrature,
            bending: sc.solver.bending,
            ..ElementOptions::default()
        };
        let mut asm = Assembler::new(mesh, physics, element, &fixed).map_err(Error::Build)?;
        // Modified Newton's matrix takes the membrane geometric stiffness
        // from each step start (full Newton keeps the exact tangent).
        asm.lag_membrane_stiffness(
            sc.solver.integrator == SceneIntegrator::GeneralizedAlpha
                && sc.solver.newton == crate::scene::NewtonMode::Modified
                && sc.solver.integration.lag_membrane_stiffness,
        );
        if let Some(c) = &sc.contact {
            add_contact(sc, c, &mut asm)?;
        }
        if !sc.obstacles.is_empty() {
            add_obstacles(sc, &mut asm)?;
        }
        // Damping leaves alone the rigid motion the supports allow; a sheet
        // held by frames, the frames' motion.
        let mut held_dofs: Vec<usize> = supported.iter().map(|&(i, _)| i).collect();
        if !frames.is_empty() {
            held_dofs.extend(
                frames
                    .iter()
                    .flat_map(|f| f.held.slots.iter().flat_map(|h| 3 * h.slot..3 * h.slot + 3)),
            );
            let mut held: Vec<usize> = held_dofs.iter().map(|&i| i / 3).collect();
            held.dedup();
            asm.rigid.set_held(held);
        }
        asm.rigid
            .set_supports(&held_dofs, &q_ref, mesh.size().max(f64::MIN_POSITIVE));
        let reactions = reactions(sc, &layout, &frames, support_slots);
        // Free scalars come in slots of 3 with one pattern.
        let block_coords = asm.free_block_coords(mesh);
        let solver = SparseSolver::new_blocked(
            asm.n_free,
            asm.col_ptr.clone(),
            asm.row_idx.clone(),
            3,
            Some(&block_coords),
        )
        .map_err(Error::Solver)?;
        let (rest, torque) = crease_actuators(sc, &asm);
        let sequence = sequence_drive(sc, &asm);
        let gravity = sc.gravity.map(|g| gravity_force(mesh, &asm, g));
        let angle_ends = angle_ends(sc, &asm);
        let length = mesh.size().max(f64::MIN_POSITIVE);
        let stepper = stepper(sc, &asm, &q_ref, length)?;
        Ok(System {
            block_coords,
            solver,
            stepper,
            settings: sc.solver,
            inputs: InputMap {
                rest,
                sequence,
                torque,
                end_length: asm.creases.iter().map(|c| c.length).collect(),
                gravity,
                supported,
                motion,
                force,
                frames,
                obstacles: moving,
                n_dofs: asm.n_dofs(),
            },
            reactions,
            angle_ends,
            actuation: Actuation::of(sc),
            asm,
        })
    }
}

/// Self-contact's force term on the assembler (the implicit integrator only).
fn add_contact(
    sc: &Scene,
    c: &crate::contact::ContactSettings,
    asm: &mut Assembler,
) -> Result<(), Error> {
    let mesh = &sc.mesh;
    needs_implicit(sc, "ancf:contact")?;
    let term = ContactTerm::on(asm, mesh, c).map_err(Error::Contact)?;
    asm.add_barrier(Box::new(term));
    Ok(())
}

/// A barrier term (`key`) needs the implicit integrator: its Newton steps
/// are collision-checked.
fn needs_implicit(sc: &Scene, key: &str) -> Result<(), Error> {
    if sc.solver.integrator == SceneIntegrator::CentralDifference {
        return Err(Error::Scene(format!(
            "{key} needs the implicit integrator (its Newton steps are \
             collision-checked); remove \"integrator\": \"central_difference\""
        )));
    }
    Ok(())
}

/// The contact settings obstacles use: self-contact's, or its defaults
/// with the sheet's thickness where self-contact is off.
pub(super) fn obstacle_settings(sc: &Scene) -> crate::contact::ContactSettings {
    sc.contact.unwrap_or_else(|| sc.default_contact())
}

/// The rigid obstacles' force term on the assembler (the implicit
/// integrator only).
fn add_obstacles(sc: &Scene, asm: &mut Assembler) -> Result<(), Error> {
    needs_implicit(sc, "ancf:obstacles")?;
    let m = &asm.physics.material;
    let term = crate::contact::ObstacleTerm::new(
        &sc.mesh,
        &asm.layout,
        &asm.elements,
        &sc.obstacles,
        &obstacle_settings(sc),
        m.density * m.thickness,
        m.youngs_modulus * m.thickness,
    )
    .map_err(Error::Obstacles)?;
    asm.add_barrier(Box::new(term));
    Ok(())
}

/// The consistent nodal force of gravity `g` (m/s^2) on the sheet: M
/// times the uniform acceleration of every position slot.
fn gravity_force(mesh: &crate::mesh::Mesh, asm: &Assembler, g: [f64; 3]) -> Vec<f64> {
    let mut qg = vec![0.0; asm.n_dofs()];
    for v in mesh.vertex_ids() {
        let s = asm.position_slot(v);
        qg[3 * s..3 * s + 3].copy_from_slice(&g);
    }
    let mut f = vec![0.0; asm.n_dofs()];
    asm.mass_mul(&qg, &mut f);
    f
}

/// The slots the supports fix (marked in `is_fixed`), the supported
/// scalar DOFs with their reference values, and each support's slots
/// (slot, is a position).
#[allow(clippy::type_complexity)]
fn support_slots(
    sc: &Scene,
    layout: &crate::dofs::DofLayout,
    q_ref: &[f64],
    is_fixed: &mut [bool],
) -> (Vec<usize>, Vec<(usize, f64)>, Vec<Vec<(usize, bool)>>) {
    let mut fixed = Vec::new();
    let mut supported = Vec::new();
    // The slots each support holds (slot, is a position).
    let mut support_slots = Vec::with_capacity(sc.supports.len());
    for sup in &sc.supports {
        let mut mine = Vec::new();
        for &v in &sup.vertices {
            let slots = match sup.fix {
                Fix::Position => vec![layout.position_slot[v.index()]],
                Fix::Clamped => layout.vertex_slots(v),
            };
            for s in slots {
                if !is_fixed[s] {
                    is_fixed[s] = true;
                    fixed.push(s);
                    mine.push((s, layout.slot_kind[s] == SlotKind::Position));
                    for c in 0..3 {
                        supported.push((3 * s + c, q_ref[3 * s + c]));
                    }
                }
            }
        }
        support_slots.push(mine);
    }
    (fixed, supported, support_slots)
}

/// For each crease end, the rest-angle actuators (with the crease's full
/// target) and the torque actuators that drive it, in actuator order.
#[allow(clippy::type_complexity)]
fn crease_actuators(sc: &Scene, asm: &Assembler) -> (Vec<Vec<(usize, f64)>>, Vec<Vec<usize>>) {
    let mesh = &sc.mesh;
    let nends = asm.creases.len();
    let mut rest = vec![Vec::new(); nends];
    let mut torque = vec![Vec::new(); nends];
    // The actuators of each mesh edge, in actuator order.
    let mut driven_by: Vec<Vec<usize>> = vec![Vec::new(); mesh.edges().len()];
    for (a, act) in sc.actuators.iter().enumerate() {
        for &e in &act.edges {
            if driven_by[e.index()].last() != Some(&a) {
                driven_by[e.index()].push(a);
            }
        }
    }
    let sequence = sequence_actuator(sc);
    for (i, ce) in asm.creases.iter().enumerate() {
        for &a in &driven_by[ce.edge.index()] {
            if Some(a) == sequence {
                // Its rest angles follow the stages ([`sequence_drive`]).
                continue;
            }
            match sc.actuators[a].mode {
                ActuatorMode::RestAngle => rest[i].push((a, mesh.edge(ce.edge).fold_target)),
                ActuatorMode::Torque => torque[i].push(a),
            }
        }
    }
    (rest, torque)
}

/// A scene's sequence fits it: valid stages and a rest-angle actuator of
/// its name.
fn check_sequence(sc: &Scene) -> Result<(), Error> {
    let Some(sq) = &sc.sequence else {
        return Ok(());
    };
    sq.check(sc.fold_edge_count)
        .map_err(|m| Error::Scene(format!("sequence: {m}")))?;
    if sequence_actuator(sc).is_none() {
        return Err(Error::Scene(format!(
            "sequence: no rest_angle actuator is named '{}'",
            sq.actuator
        )));
    }
    Ok(())
}

/// The index of the actuator that walks the scene's sequence, if any.
fn sequence_actuator(sc: &Scene) -> Option<usize> {
    let sq = sc.sequence.as_ref()?;
    sc.actuators
        .iter()
        .position(|a| a.name == sq.actuator && a.mode == ActuatorMode::RestAngle)
}

/// The scene's folding sequence on the crease ends: each end of a crease
/// the sequence folds (by its FOLD edge) with that edge's stage targets.
fn sequence_drive(sc: &Scene, asm: &Assembler) -> Option<SequenceDrive> {
    let sq = sc.sequence.as_ref()?;
    let actuator = sequence_actuator(sc)?;
    let entries = sq.entries();
    let ends = asm
        .creases
        .iter()
        .enumerate()
        .filter_map(|(i, ce)| {
            let fe = sc.mesh.edge(ce.edge).fold_edge?;
            entries.get(&fe).map(|list| (i, list.clone()))
        })
        .collect();
    Some(SequenceDrive {
        actuator,
        breakpoints: sq.breakpoints(),
        ends,
    })
}

/// For each crease output (FOLD edge), its crease ends in order.
fn angle_ends(sc: &Scene, asm: &Assembler) -> Vec<Vec<usize>> {
    let mesh = &sc.mesh;
    let outputs = fold_edges(sc);
    let mut output_of: HashMap<FoldEdgeId, usize> = HashMap::with_capacity(outputs.len());
    for (k, &fe) in outputs.iter().enumerate() {
        output_of.insert(fe, k);
    }
    let mut angle_ends: Vec<Vec<usize>> = vec![Vec::new(); outputs.len()];
    for (i, ce) in asm.creases.iter().enumerate() {
        if let Some(&k) = mesh
            .edge(ce.edge)
            .fold_edge
            .and_then(|fe| output_of.get(&fe))
        {
            angle_ends[k].push(i);
        }
    }
    angle_ends
}

/// The time integrator scene `sc` asks for: generalized-alpha with its
/// Newton settings and DOF scales, or central differences with the stable
/// step estimated on the unstressed sheet `q_ref`.
fn stepper(
    sc: &Scene,
    asm: &Assembler,
    q_ref: &[f64],
    length: f64,
) -> Result<Box<dyn Stepper + Send>, Error> {
    let s = &sc.solver;
    Ok(match s.integrator {
        SceneIntegrator::CentralDifference => Box::new(
            CentralDifference::new(asm, q_ref, &vec![std::f64::consts::PI; asm.creases.len()])
                .map_err(Error::ExplicitSetup)?,
        ),
        SceneIntegrator::GeneralizedAlpha => {
            let params = s.integration;
            let coeffs = ga::Coefficients::new(s.rho_inf);
            let obstacle_friction = sc.obstacles.iter().any(|o| o.friction > 0.0);
            let stick_bound = match &sc.contact {
                Some(c) if c.friction > 0.0 || obstacle_friction => {
                    ga::stick_bound(coeffs, &params, c.stick_velocity, length)
                }
                None if obstacle_friction => {
                    let c = obstacle_settings(sc);
                    ga::stick_bound(coeffs, &params, c.stick_velocity, length)
                }
                _ => f64::INFINITY,
            };
            let settings = ga::Settings {
                tolerance: s.tolerance,
                newton_tolerance: params
                    .newton_tolerance(s.tolerance, sc.material.thickness / length),
                stick_bound,
                max_newton: s.max_newton,
                newton: s.newton,
                error_filter: s.error_filter,
            };
            let scales = ga::Scales {
                newton: asm.scales(length),
                error: crate::assembly::error_scales(&asm.layout, &sc.mesh, length),
            };
            Box::new(GeneralizedAlpha::new(s.rho_inf, settings, params, scales))
        }
    })
}
