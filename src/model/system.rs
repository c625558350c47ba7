//! The system built from the scene and parameters: assembly, sparse
//! solver, stepper settings and the input map ([`Model::build`]).

use super::drive::InputMap;
use super::{Error, Model, fold_edges, physics};
use crate::assembly::Assembler;
use crate::contact::ContactTerm;
use crate::element::ElementOptions;
use crate::ids::FoldEdgeId;
use crate::scene::{ActuatorMode, Fix, Integrator as SceneIntegrator, Scene, SolverSettings};
use crate::solver::central_difference::CentralDifference;
use crate::solver::generalized_alpha::{self as ga, GeneralizedAlpha};
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
    /// The actuators' time constant (s; 0: they follow their inputs at once).
    pub(super) actuator_tau: f64,
    /// The scene's solver settings it was built with (step bounds, the
    /// internal step limit, the numerical constants).
    pub(super) settings: SolverSettings,
    /// Where each free slot is in the reference sheet (the ordering of
    /// large systems cuts by it).
    pub(super) block_coords: Vec<[f64; 3]>,
}

impl System {
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
        let mesh = &sc.mesh;
        let layout = crate::dofs::DofLayout::new(mesh);
        let q_ref = layout.reference_state(mesh);
        let mut fixed = Vec::new();
        let mut is_fixed = vec![false; layout.n_slots()];
        let mut supported = Vec::new();
        for sup in &sc.supports {
            for &v in &sup.vertices {
                let slots = match sup.fix {
                    Fix::Position => vec![layout.position_slot[v.index()]],
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
            ..ElementOptions::default()
        };
        let mut asm = Assembler::new(mesh, physics, element, &fixed).map_err(Error::Scene)?;
        // Modified Newton's matrix takes the membrane geometric stiffness
        // from each step start (full Newton keeps the exact tangent).
        asm.lag_membrane_stiffness(
            sc.solver.integrator == SceneIntegrator::GeneralizedAlpha
                && sc.solver.newton == crate::scene::NewtonMode::Modified
                && sc.solver.integration.lag_membrane_stiffness,
        );
        if let Some(c) = &sc.contact {
            if sc.solver.integrator == SceneIntegrator::CentralDifference {
                return Err(Error::Scene(
                    "ancf:contact needs the implicit integrator (its Newton steps are \
                     collision-checked); remove \"integrator\": \"central_difference\""
                        .into(),
                ));
            }
            let m = &physics.material;
            let term = ContactTerm::new(
                mesh,
                &asm.layout,
                &asm.elements,
                c,
                m.density * m.thickness,
                m.youngs_modulus * m.thickness,
            )
            .map_err(Error::Scene)?;
            asm.add_term(Box::new(term));
        }
        // Damping leaves alone the rigid motion the supports allow.
        let supported_dofs: Vec<usize> = supported.iter().map(|&(i, _)| i).collect();
        asm.rigid
            .set_supports(&supported_dofs, &q_ref, mesh.size().max(f64::MIN_POSITIVE));
        // Free scalars come in slots of 3 with one pattern.
        let block_coords = asm.free_block_coords(mesh);
        let solver = SparseSolver::new_blocked(
            asm.n_free,
            asm.col_ptr.clone(),
            asm.row_idx.clone(),
            3,
            Some(&block_coords),
        )
        .map_err(|e| Error::Scene(e.to_string()))?;
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
        for (i, ce) in asm.creases.iter().enumerate() {
            for &a in &driven_by[ce.edge.index()] {
                match sc.actuators[a].mode {
                    ActuatorMode::RestAngle => rest[i].push((a, mesh.edge(ce.edge).fold_target)),
                    ActuatorMode::Torque => torque[i].push(a),
                }
            }
        }
        let gravity = sc.gravity.map(|g| {
            let mut qg = vec![0.0; asm.n_dofs()];
            for v in mesh.vertex_ids() {
                let s = asm.position_slot(v);
                qg[3 * s..3 * s + 3].copy_from_slice(&g);
            }
            let mut f = vec![0.0; asm.n_dofs()];
            asm.mass_mul(&qg, &mut f);
            f
        });
        // For each crease output (FOLD edge), its crease ends in order.
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
        let length = mesh.size().max(f64::MIN_POSITIVE);
        let stepper = stepper(sc, &asm, &q_ref, length)?;
        Ok(System {
            block_coords,
            solver,
            stepper,
            settings: sc.solver,
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
            angle_ends,
            actuator_tau: super::actuator_time_constant(sc),
            asm,
        })
    }
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
                .map_err(Error::Scene)?,
        ),
        SceneIntegrator::GeneralizedAlpha => {
            let params = s.integration;
            let coeffs = ga::Coefficients::new(s.rho_inf);
            let stick_bound = match &sc.contact {
                Some(c) if c.friction > 0.0 => {
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
            };
            let scales = ga::Scales {
                newton: asm.scales(length),
                error: crate::assembly::error_scales(&asm.layout, &sc.mesh, length),
            };
            Box::new(GeneralizedAlpha::new(s.rho_inf, settings, params, scales))
        }
    })
}
