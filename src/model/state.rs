//! The model's state: what [`Model::save_state`] copies and
//! [`Model::restore_state`] puts back, and the changes of state outside a
//! step (a rigid velocity, accelerations consistent with the equation of
//! motion).

use super::{Error, Model, Phase};
use crate::assembly::{Evaluation, State};
use crate::ids::VertexId;
use crate::solver::stepper::{Dynamics, StepperMemory};
use serde::{Deserialize, Serialize};

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
    /// Whether `actuator.time_constant` was set (the automatic one is then off).
    #[serde(default)]
    pub actuator_set: bool,
    /// Each actuator's value and rate: what its input has moved it to
    /// ([`crate::model::actuator_time_constant`]).
    #[serde(default)]
    pub actuators: Vec<[f64; 2]>,
    /// What the stepper carries from one advance to the next: the step it
    /// proposes, the predictor's memory, where its iteration matrix was
    /// formed.
    pub memory: StepperMemory,
    /// Parameter values.
    pub parameters: Vec<f64>,
    /// Phase.
    pub phase: Phase,
    /// Output values at `time` where the last step evaluated them (its
    /// state was evaluated in full); None: they are evaluated from this
    /// state when read ([`Model::output_values`]), so a communication step
    /// pays for its outputs only if the master reads them.
    #[serde(default)]
    pub outputs: Option<Vec<f64>>,
    /// Work done so far.
    #[serde(default)]
    pub work: Work,
    /// Friction's and the contact dashpots' forces at the last accepted
    /// state (their work over the next step starts from them).
    #[serde(default)]
    pub dissipative_force: crate::assembly::DissipativeForce,
    /// Slot pairs the matrix pattern holds beyond the sheet's own (contact
    /// pairs met so far): a restore factors with the same pattern.
    #[serde(default)]
    pub extra_pairs: Vec<(usize, usize)>,
}

/// Work done so far (J): dissipated by contact, and put in by the inputs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Work {
    /// Friction work.
    pub friction: f64,
    /// Work of the normal dashpots.
    pub contact_damping: f64,
    /// Work done on the sheet by the crease actuators (rest angles moved
    /// against the springs' moments, applied crease moments) and by external
    /// forces (gravity, force inputs); prescribed motions not counted.
    /// Kinetic + strain + crease + contact energy + dissipated work - this
    /// is constant.
    #[serde(default)]
    pub input: f64,
}

impl Model {
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
        let n_act = self.scene.actuators.len();
        if s.actuators.is_empty() && n_act > 0 {
            // A state saved before actuators had a response: at rest at their inputs.
            s.actuators = s.inputs_now.iter().take(n_act).map(|&x| [x, 0.0]).collect();
        }
        let ok = dyn_ok
            && s.actuators.len() == n_act
            && s.actuators.iter().flatten().all(|x| x.is_finite())
            && s.input_slopes.len() == self.inputs.len()
            && s.inputs_now.len() == self.inputs.len()
            && s.inputs_next.len() == self.inputs.len()
            && s.parameters.len() == self.parameters.len()
            && s.outputs
                .as_ref()
                .is_none_or(|o| o.len() == self.outputs.len());
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
        if let Some(sys) = self.sys.as_mut()
            && sys.asm.extra_pairs() != &s.extra_pairs[..]
        {
            sys.asm.set_extra_pairs(s.extra_pairs.clone());
            sys.rebuild_solver().map_err(Error::State)?;
        }
        self.state = s;
        self.read_cache = Default::default();
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
        self.accelerations_or_roll_back(saved)
    }

    /// Move the listed vertices rigidly, `x -> R x + t` (their gradients
    /// turn with `R`), and make the accelerations consistent: to start a
    /// scene with parts placed apart from the flat pattern (a panel above
    /// another). List every vertex of a connected part, or the facets
    /// between moved and unmoved vertices are strained. After
    /// [`Model::initialize`]; supported and prescribed slots do not move.
    pub fn move_rigidly(
        &mut self,
        vertices: &[VertexId],
        rotation: [[f64; 3]; 3],
        translation: [f64; 3],
    ) -> Result<(), Error> {
        if self.state.phase != Phase::Running {
            return Err(Error::Phase(
                "move_rigidly needs an initialized model".into(),
            ));
        }
        let nv = self.scene.mesh.n_vertices();
        if let Some(&v) = vertices.iter().find(|&&v| v.index() >= nv) {
            return Err(Error::BadValue {
                name: "vertex".into(),
                value: v.index() as f64,
                reason: format!("the mesh has {nv} vertices"),
            });
        }
        let r = nalgebra::Matrix3::from_fn(|i, j| rotation[i][j]);
        if r.iter().chain(&translation).any(|x| !x.is_finite())
            || (r.transpose() * r - nalgebra::Matrix3::identity()).norm() > 1e-9
            || r.determinant() < 0.0
        {
            return Err(Error::BadValue {
                name: "rotation".into(),
                value: f64::NAN,
                reason: "must be a finite proper rotation (orthonormal, determinant 1) \
                         and the translation finite"
                    .into(),
            });
        }
        let sys = self.sys.as_ref().expect("initialized");
        let layout = &sys.asm.layout;
        let t = nalgebra::Vector3::from(translation);
        let saved = self.state.clone();
        let q = &mut self.state.dynamics.q;
        let mut done = vec![false; layout.n_slots()];
        for &v in vertices {
            for s in layout.vertex_slots(v) {
                if done[s] || sys.asm.free[3 * s] == crate::assembly::FIXED {
                    continue;
                }
                done[s] = true;
                let x = nalgebra::Vector3::new(q[3 * s], q[3 * s + 1], q[3 * s + 2]);
                let y = if s == layout.position_slot[v.index()] {
                    r * x + t
                } else {
                    r * x
                };
                q[3 * s..3 * s + 3].copy_from_slice(y.as_slice());
            }
        }
        self.accelerations_or_roll_back(saved)
    }

    /// After a change of positions or velocities outside a step: make the
    /// accelerations consistent with the inputs in force, or put `saved`
    /// back and fail.
    fn accelerations_or_roll_back(&mut self, saved: ModelState) -> Result<(), Error> {
        let theta = self.state.crease_theta.clone();
        let u = self.drive_inputs();
        if let Err(e) = self.consistent_accelerations(&u, &theta) {
            self.state = saved;
            self.read_cache = Default::default();
            return Err(e);
        }
        Ok(())
    }

    /// Accelerations from the equation of motion at the current positions
    /// and velocities, M qdd = f_ext - f_int on the free DOFs (the mass
    /// matrix is factored in the stepper's solver, so its iteration matrix
    /// is forgotten); also the crease angles and outputs.
    pub(super) fn consistent_accelerations(
        &mut self,
        u: &[f64],
        theta_prev: &[f64],
    ) -> Result<(), Error> {
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
        sys.stepper.invalidate_matrix();
        self.state.memory.jacobian = None;
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
        self.state.outputs = Some(self.compute_outputs(&ev));
        self.read_cache = Default::default();
        Ok(())
    }
}
