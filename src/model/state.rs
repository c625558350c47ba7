//! The model's state: what [`Model::save_state`] copies and
//! [`Model::restore_state`] puts back, and the changes of state outside a
//! step (a rigid velocity, accelerations consistent with the equation of
//! motion).

use super::{Error, Model, Phase};
use crate::assembly::{Evaluation, State};
use crate::ids::VertexId;
use crate::scene::Scene;
use crate::solver::stepper::{Dynamics, StepperMemory};
use crate::text::num;
use serde::{Deserialize, Serialize};

/// A saved model state (see [`Model::save_state`]): an opaque snapshot,
/// serde-serializable; its fields are the crate's internals.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModelState {
    /// Simulation time.
    #[doc(hidden)]
    pub time: f64,
    /// Positions, velocities, accelerations (all DOFs; empty before initialization).
    #[doc(hidden)]
    pub dynamics: Dynamics,
    /// Unwrapped angle of every crease end at `time` (continuity through 0 = 2 pi).
    #[doc(hidden)]
    pub crease_theta: Vec<f64>,
    /// Input values in force at `time`.
    #[doc(hidden)]
    pub inputs_now: Vec<f64>,
    /// Input values at the end of the next advance before slopes (equal to
    /// `inputs_now` unless the scene ramps its inputs).
    #[doc(hidden)]
    pub inputs_next: Vec<f64>,
    /// First time derivative of each input over the next advance.
    #[serde(default)]
    #[doc(hidden)]
    pub input_slopes: Vec<f64>,
    /// Second time derivative of each input over the next advance (empty
    /// in a state saved before inputs had them: zero).
    #[serde(default)]
    pub input_second_derivatives: Vec<f64>,
    /// Whether a damping parameter was set (automatic damping is then off).
    #[serde(default)]
    #[doc(hidden)]
    pub damping_set: bool,
    /// Each actuator's value and rate: what its input has moved it to
    /// ([`crate::model::actuator_time_constant`]).
    #[serde(default)]
    #[doc(hidden)]
    pub actuators: Vec<[f64; 2]>,
    /// What the stepper carries from one advance to the next: the step it
    /// proposes, the predictor's memory, where its iteration matrix was
    /// formed.
    #[doc(hidden)]
    pub memory: StepperMemory,
    /// Parameter values.
    #[doc(hidden)]
    pub parameters: Vec<f64>,
    /// Phase.
    #[doc(hidden)]
    pub phase: Phase,
    /// Output values at `time` where the last step evaluated them (its
    /// state was evaluated in full); None: they are evaluated from this
    /// state when read ([`Model::output_values`]), so a communication step
    /// pays for its outputs only if the master reads them.
    #[serde(default)]
    #[doc(hidden)]
    pub outputs: Option<Vec<f64>>,
    /// Work done so far.
    #[serde(default)]
    #[doc(hidden)]
    pub work: Work,
    /// Friction's and the contact dashpots' forces at the last accepted
    /// state (their work over the next step starts from them).
    #[serde(default)]
    #[doc(hidden)]
    pub dissipative_force: crate::assembly::DissipativeForce,
    /// Slot pairs the matrix pattern holds beyond the sheet's own (contact
    /// pairs met so far): a restore factors with the same pattern.
    #[serde(default)]
    #[doc(hidden)]
    pub extra_pairs: Vec<(usize, usize)>,
    /// What the force terms carry from step to step (contact: each pair's
    /// barrier stiffness), in the assembler's term order; empty: as built.
    #[serde(default)]
    pub term_memory: Vec<Vec<f64>>,
    /// The viscous force at the last accepted state (its work over the
    /// next step starts from it; empty: zero).
    #[serde(default)]
    pub viscous_force: Vec<f64>,
}

/// Work done so far (J): dissipated by contact, and put in by the inputs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Work {
    /// Friction work.
    pub friction: f64,
    /// Work of the normal dashpots.
    pub contact_damping: f64,
    /// Work of the viscous forces: mass and stiffness damping, crease
    /// dashpots.
    #[serde(default)]
    pub viscous: f64,
    /// Work done on the sheet by the crease actuators (rest angles moved
    /// against the springs' moments, applied crease moments) and by external
    /// forces (gravity, force inputs); prescribed motions not counted.
    /// Kinetic + strain + crease + contact energy + dissipated work
    /// ([`Work::dissipated`]) - this is constant (up to the integrator's
    /// error; generalized-alpha below rho_inf = 1 dissipates some more).
    #[serde(default)]
    pub input: f64,
}

impl Work {
    /// All work dissipated: friction, contact dashpots and viscous forces.
    pub fn dissipated(&self) -> f64 {
        self.friction + self.contact_damping + self.viscous
    }
}

impl Model {
    /// A copy of the complete state, enough to continue bit-identically.
    pub fn save_state(&self) -> ModelState {
        self.state.clone()
    }

    /// Restore a state saved from a model of the same scene. Every value
    /// is checked first ([`Model::check_state`]); a state that does not fit
    /// is refused with the reason and nothing changes.
    pub fn restore_state(&mut self, s: &ModelState) -> Result<(), Error> {
        let mut s = s.clone();
        if s.input_slopes.is_empty() {
            // A state saved before inputs had slopes.
            s.input_slopes = vec![0.0; s.inputs_now.len()];
        }
        if s.input_second_derivatives.is_empty() {
            // A state saved before inputs had second derivatives.
            s.input_second_derivatives = vec![0.0; s.inputs_now.len()];
        }
        let n_act = self.scene.actuators.len();
        if s.actuators.is_empty() && n_act > 0 {
            // A state saved before actuators had a response: at rest at their inputs.
            s.actuators = s.inputs_now.iter().take(n_act).map(|&x| [x, 0.0]).collect();
        }
        let (scene, parameters) = self.check_state_scene(&s).map_err(Error::State)?;
        // The saved state ran with other parameters: a system for them,
        // built aside so that a failure changes nothing.
        let mut fresh = match s.phase {
            Phase::Running if self.built_with.as_deref() != Some(&s.parameters[..]) => {
                Some(super::system::System::new(&scene)?)
            }
            _ => None,
        };
        let Some(sys) = fresh.as_mut().or(self.sys.as_mut()) else {
            return Err(Error::State("the model has no system".into()));
        };
        if sys.asm.extra_pairs() != &s.extra_pairs[..] {
            let old = sys.asm.extra_pairs().to_vec();
            sys.asm.set_extra_pairs(s.extra_pairs.clone());
            if let Err(e) = sys.rebuild_solver() {
                // Put the pattern back (it was factored before).
                sys.asm.set_extra_pairs(old);
                let _ = sys.rebuild_solver();
                return Err(Error::State(e.to_string()));
            }
        }
        if let Some(sys) = fresh {
            self.sys = Some(sys);
            self.scene = scene;
            self.built_with = Some(parameters);
        }
        if let Some(sys) = self.sys.as_mut() {
            sys.asm
                .restore_term_memory(&s.term_memory)
                .map_err(|e| Error::State(e.to_string()))?;
        }
        self.state = s;
        self.read_cache = Default::default();
        Ok(())
    }

    /// Check a saved state against this model without changing anything:
    /// every array's length and every index against the model, every
    /// number finite and within [`crate::scene::limits::MAX_MAGNITUDE`],
    /// the parameters by the rules of [`crate::scene::limits`] (as
    /// [`Model::set_parameter`] and the scene reader check them), the inputs
    /// as [`Model::set_input`] does. The error names the value and says
    /// what it must be.
    pub fn check_state(&self, s: &ModelState) -> Result<(), Error> {
        self.check_state_scene(s).map(|_| ()).map_err(Error::State)
    }

    /// [`Model::check_state`], returning the scene the state's parameters
    /// make and the parameter values once applied. One line per field of
    /// [`ModelState`] (and of the stepper's memory).
    fn check_state_scene(&self, s: &ModelState) -> Result<(Scene, Vec<f64>), String> {
        let Some(sys) = self.sys.as_ref() else {
            return Err("the model has no system".into());
        };
        let asm = &sys.asm;
        let (n, nc) = (asm.n_dofs(), asm.creases.len());
        let running = s.phase == Phase::Running;
        // Before initialization the dynamic arrays may be empty.
        let sizes = |len: usize| if running { vec![len] } else { vec![0, len] };
        number("time", s.time)?;
        let d = &s.dynamics;
        for (what, x) in [("q", &d.q), ("v", &d.v), ("qdd", &d.qdd), ("abar", &d.abar)] {
            values(&format!("dynamics.{what}"), x, &sizes(n))?;
        }
        values("crease_theta", &s.crease_theta, &sizes(nc))?;
        let ni = self.inputs.len();
        self.input_values("inputs_now", &s.inputs_now, &[ni])?;
        self.input_values("inputs_next", &s.inputs_next, &[ni])?;
        // Empty in a state saved before slopes, second derivatives and
        // actuator responses: the restore fills them in.
        self.input_values("input_slopes", &s.input_slopes, &[0, ni])?;
        self.input_values(
            "input_second_derivatives",
            &s.input_second_derivatives,
            &[0, ni],
        )?;
        let flat: Vec<f64> = s.actuators.iter().flatten().copied().collect();
        values("actuators", &flat, &[0, 2 * self.scene.actuators.len()])?;
        let moving = self.scene.obstacles.iter().filter(|o| o.moving).count();
        check_memory(&s.memory, running, (n, nc, moving))?;
        let checked = self
            .check_parameters(&s.parameters, s.damping_set)
            .map_err(|e| e.to_string())?;
        if let Some(o) = &s.outputs {
            if o.len() != self.outputs.len() {
                return Err(format!(
                    "outputs: {} values; this model has {}",
                    o.len(),
                    self.outputs.len()
                ));
            }
            for (spec, &x) in self.outputs.iter().zip(o) {
                number(&format!("outputs ({})", spec.name), x)?;
            }
        }
        let w = &s.work;
        number("work.friction", w.friction)?;
        number("work.contact_damping", w.contact_damping)?;
        number("work.input", w.input)?;
        number("work.viscous", w.viscous)?;
        let f = &s.dissipative_force;
        values("dissipative_force.friction", &f.friction, &[0, n])?;
        values("dissipative_force.damping", &f.damping, &[0, n])?;
        values("viscous_force", &s.viscous_force, &[0, n])?;
        asm.check_term_memory(&s.term_memory)
            .map_err(|e| format!("term_memory: {e}"))?;
        let slots = asm.layout.n_slots();
        for (k, &(a, b)) in s.extra_pairs.iter().enumerate() {
            let sorted = k == 0 || s.extra_pairs[k - 1] < (a, b);
            if !(a < b && b < slots && sorted) {
                return Err(format!(
                    "extra_pairs[{k}] = ({a}, {b}): slot pairs are sorted, each a < b < {slots} \
                     (the slots of this model)"
                ));
            }
        }
        if self.scene.contact.is_none() && s.extra_pairs != asm.extra_pairs() {
            return Err(format!(
                "extra_pairs: {} pairs, but a scene without contact never adds any",
                s.extra_pairs.len()
            ));
        }
        Ok(checked)
    }

    /// Input values `x` (one per input, or one of `sizes`) by the rules
    /// of [`Model::set_input`].
    fn input_values(&self, what: &str, x: &[f64], sizes: &[usize]) -> Result<(), String> {
        length(what, x.len(), sizes)?;
        for (spec, &v) in self.inputs.iter().zip(x) {
            crate::scene::limits::check_number(v)
                .map_err(|e| format!("{what} ({}) = {e}", spec.name))?;
        }
        Ok(())
    }

    #[doc(hidden)]
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

    #[doc(hidden)]
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
    /// and velocities, M qdd = f_ext - f_int on the free DOFs, the fixed
    /// DOFs' accelerations as they are (the mass matrix is factored in the
    /// stepper's solver, so its iteration matrix is forgotten); also the
    /// crease angles and outputs.
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
        let st = State {
            q: &dynm.q,
            v: &dynm.v,
            theta0: &d.theta0,
            moment: &d.moment,
            theta_prev,
        };
        if let Err(e) = sys.asm.evaluate(&st, &mut ev, None) {
            let term = sys.asm.non_finite_term(&st).unwrap_or("").to_string();
            return Err(self.not_finite(&e.to_string(), &term));
        }
        // The fixed DOFs' accelerations (a moving frame's) push the free ones.
        let mut m_fixed = vec![0.0; n];
        let fixed_qdd: Vec<f64> = (0..n)
            .map(|i| match sys.asm.free[i] {
                crate::assembly::FIXED => dynm.qdd.get(i).copied().unwrap_or(0.0),
                _ => 0.0,
            })
            .collect();
        if fixed_qdd.iter().any(|&a| a != 0.0) {
            sys.asm.mass_mul(&fixed_qdd, &mut m_fixed);
        }
        let mut rhs = vec![0.0; sys.asm.n_free];
        for (i, &fi) in sys.asm.free.iter().enumerate() {
            if fi != crate::assembly::FIXED {
                rhs[fi] = d.f_ext[i] - ev.force[i] - m_fixed[i];
            }
        }
        sys.stepper.invalidate_matrix();
        self.state.memory.jacobian = None;
        let mvals = sys.asm.mass_values().to_vec();
        let solved = sys
            .solver
            .factor(&mvals)
            .and_then(|()| sys.solver.solve_in_place(&mut rhs));
        if let Err(e) = solved {
            return Err(self.not_finite(&format!("the accelerations: mass matrix: {e}"), ""));
        }
        let mut qdd = fixed_qdd;
        for (a, &fi) in qdd.iter_mut().zip(&sys.asm.free) {
            if fi != crate::assembly::FIXED {
                *a = rhs[fi];
            }
        }
        self.state.dynamics.abar = qdd.clone();
        self.state.dynamics.qdd = qdd;
        self.state.crease_theta = ev.theta.clone();
        self.read_cache = Default::default();
        self.state.outputs = Some(self.compute_outputs(&ev, &d));
        Ok(())
    }
}

/// The stepper's memory of a saved state: the next step size, the
/// predictor's counters, the point of the kept iteration matrix (`n`
/// DOFs, `nc` crease ends, `moving` obstacles; an iteration matrix only
/// once `running`).
fn check_memory(
    m: &StepperMemory,
    running: bool,
    (n, nc, moving): (usize, usize, usize),
) -> Result<(), String> {
    number("memory.h_next", m.h_next)?;
    if m.h_next <= 0.0 {
        return Err(format!(
            "memory.h_next = {}: a step size must be positive",
            num(m.h_next)
        ));
    }
    let c = &m.newton;
    for (what, k) in [
        ("extrapolation_streak", c.extrapolation_streak),
        ("held_streak", c.held_streak),
    ] {
        if k > MAX_COUNT {
            return Err(format!(
                "memory.newton.{what} = {k} is larger than {MAX_COUNT}"
            ));
        }
    }
    if let Some(j) = &m.jacobian {
        if !running {
            return Err("memory.jacobian: an iteration matrix before initialization".into());
        }
        number("memory.jacobian.h", j.h)?;
        if j.h <= 0.0 {
            return Err(format!(
                "memory.jacobian.h = {}: a step size must be positive",
                num(j.h)
            ));
        }
        values("memory.jacobian.q", &j.q, &[n])?;
        values("memory.jacobian.v", &j.v, &[n])?;
        values("memory.jacobian.theta0", &j.theta0, &[nc])?;
        values("memory.jacobian.moment", &j.moment, &[nc])?;
        values("memory.jacobian.theta_prev", &j.theta_prev, &[nc])?;
        values("memory.jacobian.q_start", &j.q_start, &[0, n])?;
        values("memory.jacobian.v_start", &j.v_start, &[j.q_start.len()])?;
        let motions = 2 * crate::frame::Motion::VALUES * moving;
        values("memory.jacobian.obstacles", &j.obstacles, &[0, motions])?;
    }
    Ok(())
}

/// The variables that set the forces of each force term (by its name;
/// "" for the accelerations: the mass and the external forces), for the
/// message of an evaluation that is not finite. An entry ending in '.'
/// stands for every parameter it begins; inputs are named by their group.
const SUSPECTS: &[(&str, &[&str])] = &[
    (
        "shell",
        &[
            "material.youngs_modulus",
            "material.poisson_ratio",
            "material.thickness",
            "<motions>",
        ],
    ),
    (
        "crease springs",
        &[
            "crease.",
            "damping.crease",
            "material.youngs_modulus",
            "material.thickness",
            "<actuators>",
        ],
    ),
    (
        "mass damping",
        &[
            "damping.alpha",
            "damping.beta",
            "material.density",
            "material.thickness",
        ],
    ),
    ("contact", &["contact.", "material.", "<motions>"]),
    (
        "",
        &[
            "material.density",
            "material.thickness",
            "gravity.",
            "<forces>",
            "<actuators>",
        ],
    ),
];

impl Model {
    /// The error of an initial evaluation that is not finite (`what`, in
    /// the force term `term`, "" for the accelerations), naming the
    /// variables that set it with their values: what to change.
    fn not_finite(&self, what: &str, term: &str) -> Error {
        Error::Initialization(format!("{what}{}", self.suspects(term)))
    }

    /// A failed step's error, with the variables to check where its forces
    /// were not finite (the assembler names the force term).
    pub(super) fn with_suspects(&self, e: Error) -> Error {
        match e {
            Error::StepFailed { time, reason } => {
                let term = reason
                    .split_once("(those of the ")
                    .and_then(|(_, rest)| rest.split_once(')'))
                    .map(|(term, _)| term.to_string());
                let reason = match term {
                    Some(t) => format!("{reason}{}", self.suspects(&t)),
                    None => reason,
                };
                Error::StepFailed { time, reason }
            }
            e => e,
        }
    }

    /// "; check name = value, ..." for the variables of force term `term`
    /// (see [`SUSPECTS`]); "" when it has none.
    fn suspects(&self, term: &str) -> String {
        let names = SUSPECTS
            .iter()
            .find(|(t, _)| *t == term)
            .map_or(&[][..], |(_, n)| *n);
        let n_act = self.scene.actuators.len();
        let n_force = 3 * self.scene.vertex_forces.len();
        let mut listed = Vec::new();
        for &pat in names {
            let inputs = match pat {
                "<actuators>" => 0..n_act,
                "<forces>" => n_act..n_act + n_force,
                "<motions>" => n_act + n_force..self.inputs.len(),
                _ => {
                    let matches = |name: &str| match pat.strip_suffix('.') {
                        Some(prefix) => name.starts_with(prefix),
                        None => name == pat,
                    };
                    for (spec, &x) in self.parameters.iter().zip(&self.state.parameters) {
                        if matches(&spec.name) {
                            listed.push(format!("{} = {}", spec.name, num(x)));
                        }
                    }
                    continue;
                }
            };
            // The inputs of the group set furthest from zero first.
            let mut group: Vec<(usize, f64)> = inputs
                .filter_map(|i| Some((i, *self.state.inputs_now.get(i)?)))
                .collect();
            group.retain(|g| g.1 != 0.0);
            group.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
            for (i, x) in group.into_iter().take(3) {
                listed.push(format!("{} = {}", self.inputs[i].name, num(x)));
            }
        }
        if listed.is_empty() {
            String::new()
        } else {
            format!("; check {}", listed.join(", "))
        }
    }
}

/// Largest count of the stepper's memory a restored state may hold (the
/// stepper adds one to them).
const MAX_COUNT: u32 = u32::MAX / 2;

/// `x` finite and of sensible magnitude (what every stored number must be).
fn number(what: &str, x: f64) -> Result<(), String> {
    crate::scene::limits::check_number(x).map_err(|e| format!("{what} = {e}"))
}

/// `len` is one of `sizes`.
fn length(what: &str, len: usize, sizes: &[usize]) -> Result<(), String> {
    if sizes.contains(&len) {
        return Ok(());
    }
    let want: Vec<String> = sizes.iter().map(|n| n.to_string()).collect();
    Err(format!(
        "{what}: {len} values; this model has {}",
        want.join(" or ")
    ))
}

/// Every value of `x` a [`number`], and its length one of `sizes`.
fn values(what: &str, x: &[f64], sizes: &[usize]) -> Result<(), String> {
    length(what, x.len(), sizes)?;
    let max = crate::scene::limits::MAX_MAGNITUDE;
    match x.iter().position(|v| v.is_nan() || v.abs() > max) {
        Some(i) => number(&format!("{what}[{i}]"), x[i]),
        None => Ok(()),
    }
}
