//! Rigid obstacles as a force term: each contact sample of the sheet (the
//! points of [`ContactSurface`]) against each obstacle's analytic shape
//! ([`Shape`]), in the same barrier as self-contact ([`super::term`]):
//! energy `kappa b(s)` in the gap `s = d - xi` (`d` the sample's signed
//! distance to the shape, `xi` half the contact thickness: the sheet's
//! midsurface keeps half its thickness from the obstacle), a per-pair
//! stiffness raised for fast approaches, a normal dashpot and smoothed
//! Coulomb friction with the normal force and tangent basis lagged from
//! the step start. An obstacle is fixed in the world or moved by its pose
//! inputs ([`ObstacleTerm::place`]): its placement at the step start and at
//! the step end, where the Newton iterates are; the dashpot and friction act
//! on the velocity relative to the obstacle's surface, and a step's motion
//! is checked relative to the obstacle (its start and end placements).
//!
//! The pair Hessian is `kappa (b'' n n^T + b' H)`, `H` the distance's
//! Hessian; every shape is convex, so `H` is positive semi-definite with
//! `n` in its null space and `b' H` (`b' < 0`) is negative semi-definite
//! on the plane normal to `n`: its projection to positive semi-definite is
//! `kappa b'' n n^T` in closed form. Newton steps are limited by
//! conservative advancement of each sample's distance, which is convex
//! along a straight motion (it never falls below its tangent).
//!
//! Each evaluation also gives the wrench the sheet exerts on each obstacle
//! ([`Evaluation::obstacle_wrenches`]): the sum of the pairs' forces (the
//! barrier's, the dashpot's and friction's, in internal-force sign: what
//! pushes the obstacle), with their moments about the shape's origin
//! taken at the closest points of its surface.

use super::ccd;
use super::lagged::{Lagged, StepStart, dashpot};
use super::memory::{kept_stiffness, list_index, list_pairs, parse_pairs};
use super::potentials::{barrier, db, ddb, friction_matrix, speed_stiffness};
use super::scale::SheetScale;
use super::settings::{ContactSettings, SettingsError};
use super::shapes::{Closest, Obstacle, Shape, ShapeError};
use super::surface::{ContactSurface, VertexMap, eval_map, scatter_map};
use crate::assembly::{
    Assembler, BarrierTerm, EvalError, Evaluation, ForceTerm, MatrixCoeffs, MemoryError,
    ObstaclePower, State,
};
use crate::frame::Motion;
use crate::mesh::Mesh;
use nalgebra::{Matrix3, Vector3};
use std::collections::HashMap;

/// Why [`ObstacleTerm::new`] refused its obstacles or settings.
#[derive(Clone, Debug, PartialEq)]
pub enum ObstacleError {
    /// The contact settings (a thickness that is not positive).
    Settings(SettingsError),
    /// An obstacle's shape.
    Shape {
        /// The obstacle's name.
        obstacle: String,
        /// What is wrong with its shape.
        error: ShapeError,
    },
}

impl std::fmt::Display for ObstacleError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ObstacleError::Settings(e) => write!(f, "obstacles: {e}"),
            ObstacleError::Shape { obstacle, error } => write!(f, "obstacle {obstacle}: {error}"),
        }
    }
}

impl std::error::Error for ObstacleError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            ObstacleError::Settings(e) => Some(e),
            ObstacleError::Shape { error, .. } => Some(error),
        }
    }
}

/// An obstacle pair: an obstacle and a contact sample of the sheet.
#[derive(Clone, Copy, Debug)]
struct SamplePair {
    obstacle: usize,
    sample: usize,
}

/// Where the obstacles are for a computation: at the step start or at the
/// step end (where Newton's iterates are).
#[derive(Clone, Copy, Debug, PartialEq)]
enum When {
    Start,
    End,
}

/// A pair in the barrier: obstacle, sample, the sample's closest point
/// data and gap.
struct Active {
    obstacle: usize,
    sample: usize,
    closest: Closest,
    gap: f64,
}

/// The obstacle force term of one mesh.
pub struct ObstacleTerm {
    surf: ContactSurface,
    obstacles: Vec<Obstacle>,
    /// Distance the midsurface keeps from an obstacle (m): half the contact
    /// thickness.
    xi: f64,
    /// Barrier width (m).
    s_hat: f64,
    /// Default barrier stiffness (N/m).
    kappa: f64,
    eps_v: f64,
    zeta: f64,
    /// Sample mass (kg), for the dashpot and the speed stiffness.
    mass: f64,
    /// How far beyond the barrier a pair's stiffness is kept (m).
    margin: f64,
    /// Project each pair's Hessian to positive semi-definite (Newton).
    project: bool,
    /// The sample positions and velocities at the last step start, and the
    /// pairs lagged there.
    at_start: StepStart<SamplePair>,
    /// Barrier stiffness of the pairs near at the last step start (N/m),
    /// keyed by (obstacle, sample).
    pair_kappa: HashMap<(usize, usize), f64>,
    /// Whether a pair was within `margin` of the barrier at the step start.
    near: bool,
    /// Each obstacle's origin in the scene (where its pose inputs start).
    origins: Vec<Vector3<f64>>,
    /// Each moving obstacle's placement at the step start and at the step
    /// end (None: fixed).
    start: Vec<Option<Motion>>,
    end: Vec<Option<Motion>>,
}

impl ObstacleTerm {
    /// Obstacles against the sheet `mesh` (facets `elements`), with the
    /// contact `settings` (thickness, barrier width, stiffness, stick
    /// velocity, damping ratio, subdivisions: self-contact's); `areal_mass`
    /// is density times thickness (kg/m^2), `membrane` the membrane
    /// stiffness E h (N/m) that sets the default barrier stiffness.
    pub fn new(
        mesh: &Mesh,
        layout: &crate::dofs::DofLayout,
        elements: &[crate::element::ShellElement],
        obstacles: &[Obstacle],
        settings: &ContactSettings,
        areal_mass: f64,
        membrane: f64,
    ) -> Result<ObstacleTerm, ObstacleError> {
        settings.check().map_err(ObstacleError::Settings)?;
        for o in obstacles {
            o.shape.check().map_err(|error| ObstacleError::Shape {
                obstacle: o.name.clone(),
                error,
            })?;
        }
        let surf = ContactSurface::new(mesh, layout, elements, settings.subdivisions, false, 0.0);
        let scale = SheetScale::new(mesh, elements, surf.n, settings, areal_mass, membrane);
        let xi = 0.5 * settings.thickness;
        let s_hat = settings.width * xi;
        Ok(ObstacleTerm {
            surf,
            obstacles: obstacles.to_vec(),
            xi,
            s_hat,
            kappa: scale.kappa,
            eps_v: settings.stick_velocity,
            zeta: settings.damping_ratio,
            mass: scale.sample_mass,
            margin: (xi + s_hat).max(0.1 * scale.side),
            project: true,
            at_start: StepStart::default(),
            pair_kappa: HashMap::new(),
            near: false,
            origins: obstacles.iter().map(|o| o.shape.origin()).collect(),
            start: at_rest(obstacles),
            end: at_rest(obstacles),
        })
    }

    /// Keep the exact pair Hessians in the matrix (no projection to
    /// positive semi-definite): for derivative tests.
    pub fn with_exact_hessian(mut self) -> Self {
        self.project = false;
        self
    }

    /// The sampled surface.
    pub fn surface(&self) -> &ContactSurface {
        &self.surf
    }

    /// Distance the sheet's midsurface keeps from an obstacle (m).
    pub fn clearance(&self) -> f64 {
        self.xi
    }

    /// Barrier width (m).
    pub fn barrier_width(&self) -> f64 {
        self.s_hat
    }

    /// The gaps `d - xi` (m) of the samples at slot vector `q`, each to
    /// its nearest obstacle: the smallest and the largest (infinities
    /// without obstacles).
    pub fn gap_range(&self, q: &[f64]) -> (f64, f64) {
        let mut x = Vec::new();
        self.surf.positions(q, &mut x);
        let mut range = (f64::INFINITY, f64::NEG_INFINITY);
        for p in &x {
            let nearest = (0..self.obstacles.len())
                .map(|k| self.closest(k, p, When::End).distance - self.xi)
                .fold(f64::INFINITY, f64::min);
            range = (range.0.min(nearest), range.1.max(nearest));
        }
        range
    }

    /// The first obstacle (its name) that holds a sample of slot vector
    /// `q` within the clearance, with that sample's gap `d - xi` (m).
    pub fn overlapped(&self, q: &[f64]) -> Option<(&str, f64)> {
        let mut x = Vec::new();
        self.surf.positions(q, &mut x);
        (0..self.obstacles.len()).find_map(|k| {
            let gap = x
                .iter()
                .map(|p| self.closest(k, p, When::End).distance - self.xi)
                .fold(f64::INFINITY, f64::min);
            (gap <= 0.0).then_some((self.obstacles[k].name.as_str(), gap))
        })
    }

    /// The pairs within the barrier at positions `x` (the obstacles placed
    /// `when`); fails where a sample is already within the clearance.
    fn active(&self, x: &[Vector3<f64>], when: When) -> Result<Vec<Active>, EvalError> {
        let mut out = Vec::new();
        for (k, o) in self.obstacles.iter().enumerate() {
            for (i, p) in x.iter().enumerate() {
                let c = self.closest(k, p, when);
                let gap = c.distance - self.xi;
                if gap >= self.s_hat {
                    continue;
                }
                if gap <= 0.0 {
                    return Err(EvalError::Term {
                        term: format!("obstacle {}", o.name),
                        reason: format!(
                            "the sheet (facets {:?}) is closer than half the contact thickness \
                             {} m (gap {gap:.3e} m)",
                            self.surf.vertex_facets[i], self.xi
                        ),
                    });
                }
                out.push(Active {
                    obstacle: k,
                    sample: i,
                    closest: c,
                    gap,
                });
            }
        }
        Ok(out)
    }

    /// The stiffness a pair takes at a step start with sample positions
    /// `x` and velocities `v`: the default, or more where the sample
    /// approaches the obstacle fast ([`speed_stiffness`]).
    fn pair_stiffness(&self, k: usize, i: usize, x: &[Vector3<f64>], v: &[Vector3<f64>]) -> f64 {
        if v.len() != x.len() || i >= x.len() {
            return self.kappa;
        }
        let c = self.closest(k, &x[i], When::Start);
        let rel = v[i] - self.surface_velocity(k, &x[i], &c, When::Start);
        let approach = (-c.normal.dot(&rel)).max(0.0);
        speed_stiffness(self.kappa, self.mass, approach, self.s_hat)
    }

    /// A pair's barrier stiffness: the one kept at the last step start, or
    /// the one it would have been given there.
    fn kappa_of(&self, k: usize, i: usize) -> f64 {
        match self.pair_kappa.get(&(k, i)) {
            Some(&kap) => kap,
            None => self.pair_stiffness(k, i, &self.at_start.x, &self.at_start.v),
        }
    }

    /// Pair stiffnesses, dashpot coefficients, friction's normal forces
    /// and bases from the step start's sample positions `x` and velocities
    /// `v`.
    fn lag_at(&mut self, x: &[Vector3<f64>], v: &[Vector3<f64>]) {
        let mut kappa = HashMap::new();
        for k in 0..self.obstacles.len() {
            for (i, p) in x.iter().enumerate() {
                let gap = self.closest(k, p, When::Start).distance - self.xi;
                if gap >= self.s_hat + self.margin {
                    continue;
                }
                let last = self.pair_kappa.get(&(k, i)).copied();
                let kap = kept_stiffness(
                    last,
                    || gap < self.s_hat,
                    || self.pair_stiffness(k, i, x, v),
                );
                kappa.insert((k, i), kap);
            }
        }
        self.near = !kappa.is_empty();
        self.pair_kappa = kappa;
        self.at_start.begin(x, v);
        for a in self.active(x, When::Start).unwrap_or_default() {
            let kap = self.kappa_of(a.obstacle, a.sample);
            let vi = v.get(a.sample).copied().unwrap_or_default()
                - self.surface_velocity(a.obstacle, &x[a.sample], &a.closest, When::Start);
            let pair = SamplePair {
                obstacle: a.obstacle,
                sample: a.sample,
            };
            let c = dashpot(self.zeta, kap, self.mass, a.gap, self.s_hat);
            let lambda = -kap * db(a.gap, self.s_hat);
            let lagged = Lagged::new(pair, c, a.closest.normal, lambda, &vi);
            self.at_start.lagged.push(lagged);
        }
    }

    /// Largest fraction in (0, 1] of the motion `q -> q + dq` over which
    /// no sample comes within the clearance of an obstacle (conservative
    /// advancement, keeping [`ccd::MIN_SEPARATION`] of each gap), the
    /// obstacles at the step end: a Newton correction's.
    pub fn safe_fraction(&self, q: &[f64], dq: &[f64]) -> f64 {
        self.fraction(q, dq, When::End)
    }

    /// [`ObstacleTerm::safe_fraction`] of a motion from the step start,
    /// `q` where the obstacles were at the start, `q + dq` where they are
    /// at the end: the motion relative to each moving obstacle.
    pub fn motion_fraction(&self, q: &[f64], dq: &[f64]) -> f64 {
        self.fraction(q, dq, When::Start)
    }

    /// The collision-free fraction of the motion `q -> q + dq`, `q` with
    /// the obstacles placed `from`, `q + dq` with them at the step end;
    /// each sample's motion relative to an obstacle is taken as a straight
    /// line in the obstacle's own frame.
    fn fraction(&self, q: &[f64], dq: &[f64], from: When) -> f64 {
        let (x, d) = self.samples(q, dq);
        let mut t: f64 = 1.0;
        for (k, o) in self.obstacles.iter().enumerate() {
            for (xi, di) in x.iter().zip(&d) {
                let (p, dp) = if o.moving {
                    let p = self.local(k, xi, from);
                    (p, self.local(k, &(xi + di), When::End) - p)
                } else {
                    (*xi, *di)
                };
                let c0 = o.shape.closest(&p);
                // Out of reach over the whole motion (the distance is
                // 1-Lipschitz).
                if c0.distance - self.xi > dp.norm() {
                    continue;
                }
                let probe = |s: f64| {
                    let c = o.shape.closest(&(p + dp * s));
                    (c.distance, (-c.normal.dot(&dp)).max(0.0))
                };
                if let Some(s) = ccd::advance_by(probe, self.xi, t) {
                    t = t.min(s);
                }
            }
        }
        t
    }

    /// Obstacle `k`'s placement `when` (None: fixed).
    fn placement(&self, k: usize, when: When) -> Option<&Motion> {
        match when {
            When::Start => self.start[k].as_ref(),
            When::End => self.end[k].as_ref(),
        }
    }

    /// The point `x` in obstacle `k`'s scene frame (where its shape is
    /// given), the obstacle placed `when`.
    fn local(&self, k: usize, x: &Vector3<f64>, when: When) -> Vector3<f64> {
        match self.placement(k, when) {
            None => *x,
            Some(m) => m.pose.rotation.transpose() * (x - m.pose.origin) + self.origins[k],
        }
    }

    /// The signed distance of `x` to obstacle `k` placed `when`, with its
    /// gradient and Hessian in world axes.
    fn closest(&self, k: usize, x: &Vector3<f64>, when: When) -> Closest {
        let shape = &self.obstacles[k].shape;
        match self.placement(k, when) {
            None => shape.closest(x),
            Some(m) => {
                let r = &m.pose.rotation;
                let c = shape.closest(&self.local(k, x, when));
                Closest {
                    distance: c.distance,
                    normal: r * c.normal,
                    hessian: r * c.hessian * r.transpose(),
                }
            }
        }
    }

    /// The velocity of obstacle `k`'s surface (placed `when`) at the point
    /// closest to `x` (`c` its distance data); zero for a fixed one.
    fn surface_velocity(
        &self,
        k: usize,
        x: &Vector3<f64>,
        c: &Closest,
        when: When,
    ) -> Vector3<f64> {
        match self.placement(k, when) {
            None => Vector3::zeros(),
            Some(m) => m.point_velocity(&(x - c.distance * c.normal)),
        }
    }

    /// The point obstacle `k`'s wrench is taken about: its origin where
    /// it is now.
    fn wrench_origin(&self, k: usize) -> Vector3<f64> {
        match &self.end[k] {
            None => self.origins[k],
            Some(m) => m.pose.origin,
        }
    }

    /// Place the moving obstacles (in scene order): `start` at the step
    /// start, `end` at the step end, where the forces are evaluated.
    pub fn place(&mut self, start: &[Motion], end: &[Motion]) {
        let moving = self
            .end
            .iter_mut()
            .zip(&mut self.start)
            .filter(|(e, _)| e.is_some());
        for ((e, s), (m0, m1)) in moving.zip(start.iter().zip(end)) {
            *s = Some(*m0);
            *e = Some(*m1);
        }
    }

    /// The moving obstacles' placements at the step start and end (in
    /// scene order).
    pub fn placements(&self) -> (Vec<Motion>, Vec<Motion>) {
        (
            self.start.iter().flatten().copied().collect(),
            self.end.iter().flatten().copied().collect(),
        )
    }

    /// How many obstacles move.
    pub fn moving_count(&self) -> usize {
        self.obstacles.iter().filter(|o| o.moving).count()
    }

    /// The fraction of a Newton correction at which a sliding pair it
    /// would carry through sticking comes closest to rest (as
    /// [`super::ContactTerm::friction_fraction`]); 1 if none.
    pub fn friction_fraction(&self, q: &[f64], v: &[f64], dq: &[f64], dv_dq: f64) -> f64 {
        self.at_start.friction_fraction(self.eps_v, |lg| {
            let SamplePair {
                obstacle: k,
                sample,
            } = lg.pair;
            if self.obstacles[k].friction <= 0.0 {
                return None;
            }
            let m = &self.surf.maps[sample];
            let mut vr = eval_map(m, v);
            if self.obstacles[k].moving {
                let x = eval_map(m, q);
                vr = self.relative_velocity(k, &x, &self.closest(k, &x, When::End), vr);
            }
            Some((vr, eval_map(m, dq) * dv_dq))
        })
    }

    /// The velocity `v` of a sample at `x` relative to obstacle `k`'s
    /// surface at the step end (`c` the sample's distance data there).
    fn relative_velocity(
        &self,
        k: usize,
        x: &Vector3<f64>,
        c: &Closest,
        v: Vector3<f64>,
    ) -> Vector3<f64> {
        if !self.obstacles[k].moving {
            return v;
        }
        v - self.surface_velocity(k, x, c, When::End)
    }

    /// Add a sample's force `f` (internal-force sign) to the slots, and
    /// to the wrench on obstacle `k` at the shape's closest point to the
    /// sample `x` (`c` its distance data at the step end); gives the power
    /// `f` does on the obstacle (zero for a fixed one).
    fn apply(
        &self,
        k: usize,
        i: usize,
        (x, c): (&Vector3<f64>, &Closest),
        f: &Vector3<f64>,
        force: &mut [f64],
        wrenches: &mut [[f64; 6]],
    ) -> f64 {
        scatter_map(&self.surf.maps[i], f, force);
        let arm = x - c.distance * c.normal - self.wrench_origin(k);
        let m = arm.cross(f);
        let w = &mut wrenches[k];
        for a in 0..3 {
            w[a] += f[a];
            w[3 + a] += m[a];
        }
        f.dot(&self.surface_velocity(k, x, c, When::End))
    }

    /// [`ObstacleTerm::apply`] for a lagged pair's dissipative force `f`
    /// (its sample at `x` with distance data `c`), also added to its part
    /// of the force; gives its power on the obstacle.
    fn apply_lagged(
        &self,
        lg: &Lagged<SamplePair>,
        at: (&Vector3<f64>, &Closest),
        f: &Vector3<f64>,
        (force, part): (&mut [f64], &mut [f64]),
        wrenches: &mut [[f64; 6]],
    ) -> f64 {
        let SamplePair { obstacle, sample } = lg.pair;
        scatter_map(&self.surf.maps[sample], f, part);
        self.apply(obstacle, sample, at, f, force, wrenches)
    }

    /// The barrier's, dashpots' and friction's forces, energy and matrix
    /// at `st` (see [`ForceTerm::add`]).
    fn add_obstacles(
        &self,
        asm: &Assembler,
        st: &State,
        out: &mut Evaluation,
        matrix: Option<(&mut [f64], MatrixCoeffs)>,
    ) -> Result<(), EvalError> {
        let (x, v) = self.samples(st.q, st.v);
        let n = out.force.len();
        if out.dissipative_force.friction.len() != n {
            out.dissipative_force.zeroed(n);
        }
        let mut wrenches = vec![[0.0; 6]; self.obstacles.len()];
        let mut power = ObstaclePower::default();
        let mut matrix = matrix;
        let active = self.active(&x, When::End)?;
        out.barrier_pairs += active.len();
        for a in &active {
            let (k, i) = (a.obstacle, a.sample);
            let kap = self.kappa_of(k, i);
            let (b1, b2) = (db(a.gap, self.s_hat), ddb(a.gap, self.s_hat));
            let nrm = a.closest.normal;
            out.term_energy += kap * barrier(a.gap, self.s_hat);
            let f = (kap * b1) * nrm;
            let at = (&x[i], &a.closest);
            power.total += self.apply(k, i, at, &f, &mut out.force, &mut wrenches);
            if let Some((vals, co)) = matrix.as_mut()
                && co.k != 0.0
            {
                let mut h = (kap * b2) * nrm * nrm.transpose();
                if !self.project {
                    h += (kap * b1) * a.closest.hessian;
                }
                add_matrix(asm, &self.surf.maps[i], &(co.k * h), vals);
            }
        }
        // Each lagged sample's distance data at the step end, for both loops.
        let closest: Vec<Closest> = self
            .at_start
            .lagged
            .iter()
            .map(|lg| self.closest(lg.pair.obstacle, &x[lg.pair.sample], When::End))
            .collect();
        // Dashpots on the normal velocity along the lagged normals.
        for (lg, c) in self
            .at_start
            .lagged
            .iter()
            .zip(&closest)
            .filter(|(lg, _)| lg.c > 0.0)
        {
            let SamplePair { obstacle, sample } = lg.pair;
            let at = (&x[sample], c);
            let vi = self.relative_velocity(obstacle, at.0, c, v[sample]);
            let rate = lg.normal.dot(&vi);
            out.contact_damping_power += lg.c * rate * rate;
            let f = (lg.c * rate) * lg.normal;
            let part = &mut out.dissipative_force.damping;
            power.damping += self.apply_lagged(lg, at, &f, (&mut out.force, part), &mut wrenches);
            if let Some((vals, co)) = matrix.as_mut() {
                let h = (co.c * lg.c) * lg.normal * lg.normal.transpose();
                add_matrix(asm, &self.surf.maps[sample], &h, vals);
            }
        }
        // Friction with the lagged normal forces and bases.
        for (lg, c) in self.at_start.lagged.iter().zip(&closest) {
            let SamplePair { obstacle, sample } = lg.pair;
            let mu = self.obstacles[obstacle].friction;
            if mu <= 0.0 {
                continue;
            }
            let at = (&x[sample], c);
            let vi = self.relative_velocity(obstacle, at.0, c, v[sample]);
            let (f, u, slip) = lg.friction(mu, self.eps_v, &vi);
            out.friction_power += f.dot(&vi);
            let part = &mut out.dissipative_force.friction;
            power.friction += self.apply_lagged(lg, at, &f, (&mut out.force, part), &mut wrenches);
            if let Some((vals, co)) = matrix.as_mut() {
                let h = friction_matrix(co.c * (mu * lg.lambda), &lg.basis, u, slip);
                add_matrix(asm, &self.surf.maps[sample], &h, vals);
            }
        }
        power.total += power.damping + power.friction;
        out.dissipative_force.obstacles = power;
        out.obstacle_wrenches = wrenches;
        Ok(())
    }

    /// What [`BarrierTerm::memory`] gives: each moving obstacle's motion
    /// now ([`Motion::values`]), then the pair stiffnesses as triples
    /// (obstacle, sample, stiffness) in key order.
    fn memory_list(&self) -> Vec<f64> {
        let mut out: Vec<f64> = self.end.iter().flatten().flat_map(|m| m.values()).collect();
        let pairs = self
            .pair_kappa
            .iter()
            .map(|(&key, &kap)| (key, kap))
            .collect();
        list_pairs(pairs, |&(k, i)| [k as f64, i as f64], &mut out);
        out
    }

    /// The moving obstacles' motions and the pair stiffnesses of a memory
    /// list (untrusted: a restored state's): [`Motion::VALUES`] finite
    /// numbers up to MAX_MAGNITUDE per moving obstacle, then triples of an
    /// obstacle index, a sample index and a positive stiffness up to
    /// MAX_MAGNITUDE.
    #[allow(clippy::type_complexity)]
    fn parse_memory(
        &self,
        memory: &[f64],
    ) -> Result<(Vec<Motion>, HashMap<(usize, usize), f64>), MemoryError> {
        let max = crate::scene::limits::MAX_MAGNITUDE;
        let head = Motion::VALUES * self.moving_count();
        if memory.len() < head || !(memory.len() - head).is_multiple_of(3) {
            return Err(MemoryError::ObstaclePairLength {
                values: memory.len(),
                motions: head,
            });
        }
        let (motions, pairs) = memory.split_at(head);
        if let Some(k) = motions.iter().position(|x| x.is_nan() || x.abs() > max) {
            return Err(MemoryError::ObstacleMotion {
                index: k,
                value: motions[k],
                max,
            });
        }
        let index = |x: f64, n: usize, what: &'static str, pair: usize| {
            list_index(x, n).ok_or(MemoryError::ObstaclePairIndex {
                pair,
                what,
                value: x,
                count: n,
            })
        };
        let map = parse_pairs(pairs, 3, |pair, m| {
            let o = index(m[0], self.obstacles.len(), "obstacle", pair)?;
            let i = index(m[1], self.surf.n_vertices(), "contact sample", pair)?;
            Ok((o, i))
        })?;
        let motions = motions
            .chunks_exact(Motion::VALUES)
            .map(Motion::from_values)
            .collect();
        Ok((motions, map))
    }

    /// The samples' values of two slot vectors (positions and velocities,
    /// or positions and a move).
    fn samples(&self, q: &[f64], v: &[f64]) -> (Vec<Vector3<f64>>, Vec<Vector3<f64>>) {
        let mut x = Vec::new();
        let mut vx = Vec::new();
        self.surf.positions(q, &mut x);
        self.surf.positions(v, &mut vx);
        (x, vx)
    }

    /// The obstacles.
    pub fn obstacles(&self) -> &[Obstacle] {
        &self.obstacles
    }

    /// Obstacle `k`'s shape.
    pub fn shape(&self, k: usize) -> &Shape {
        &self.obstacles[k].shape
    }
}

/// Add a sample's 3x3 matrix `h` to the iteration matrix `vals` through
/// its slot weights.
fn add_matrix(asm: &Assembler, m: &VertexMap, h: &Matrix3<f64>, vals: &mut [f64]) {
    for &(a, ca) in m {
        for &(b, cb) in m {
            asm.try_add_block(a, b, &(ca * cb * h), vals);
        }
    }
}

impl ForceTerm for ObstacleTerm {
    fn name(&self) -> &str {
        "obstacles"
    }

    fn before_step(&mut self, _asm: &Assembler, q: &[f64], v: &[f64]) -> Vec<(usize, usize)> {
        let (x, vx) = self.samples(q, v);
        self.lag_at(&x, &vx);
        Vec::new()
    }

    fn lag(&mut self, _asm: &Assembler, q: &[f64], v: &[f64]) {
        let (x, vx) = self.samples(q, v);
        self.lag_at(&x, &vx);
    }

    fn add(
        &self,
        asm: &Assembler,
        st: &State,
        out: &mut Evaluation,
        matrix: Option<(&mut [f64], MatrixCoeffs)>,
    ) -> Result<(), EvalError> {
        self.add_obstacles(asm, st, out, matrix)
    }
}

impl BarrierTerm for ObstacleTerm {
    fn as_obstacles(&self) -> Option<&ObstacleTerm> {
        Some(self)
    }

    fn memory(&self) -> Vec<f64> {
        self.memory_list()
    }

    fn check_memory(&self, memory: &[f64]) -> Result<(), MemoryError> {
        self.parse_memory(memory).map(|_| ())
    }

    fn restore_memory(&mut self, memory: &[f64]) -> Result<(), MemoryError> {
        let (motions, kappa) = self.parse_memory(memory)?;
        self.pair_kappa = kappa;
        ObstacleTerm::place(self, &motions, &motions);
        Ok(())
    }

    fn max_step_fraction(&self, _asm: &Assembler, q: &[f64], dq: &[f64]) -> f64 {
        self.safe_fraction(q, dq)
    }

    fn max_motion_fraction(&self, _asm: &Assembler, q: &[f64], dq: &[f64]) -> f64 {
        self.motion_fraction(q, dq)
    }

    fn place(&mut self, start: &[Motion], end: &[Motion]) {
        ObstacleTerm::place(self, start, end);
    }

    fn moves(&self) -> bool {
        self.moving_count() > 0
    }

    fn max_correction_fraction(
        &self,
        _asm: &Assembler,
        q: &[f64],
        v: &[f64],
        dq: &[f64],
        dv_dq: f64,
    ) -> f64 {
        self.friction_fraction(q, v, dq, dv_dq)
    }

    fn limits_steps(&self) -> bool {
        self.near
    }

    fn reports_power(&self) -> bool {
        true
    }
}

/// The moving obstacles at rest where the scene puts them, None for the
/// fixed ones.
fn at_rest(obstacles: &[Obstacle]) -> Vec<Option<Motion>> {
    obstacles
        .iter()
        .map(|o| o.moving.then(|| Motion::at_rest(o.shape.origin())))
        .collect()
}
