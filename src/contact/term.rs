//! Contact as a force term: a barrier in the surface distance offset by the
//! thickness (codimensional IPC, Li et al. 2020/2021), a normal dashpot,
//! and a smoothed Coulomb friction with the normal force and tangent basis
//! lagged from the start of the step.
//!
//! Per pair of primitives (point-triangle or edge-edge) with distance `d`
//! and gap `s = d - xi`: energy `kappa b(s)`, `b(s) = -(s - s_hat)^2
//! ln(s / s_hat)` for `0 < s < s_hat` (edge-edge pairs times IPC's
//! mollifier), a dashpot `c s_dot` with `c = 2 zeta sqrt(k m)` (critical at
//! `zeta = 1` for the pair's barrier stiffness `k` and sample mass `m`;
//! `c` is lagged from the step start, like friction),
//! and friction `mu lambda f1(|u|) u/|u|` on the tangential relative
//! velocity `u` (`f1` rises as `2y/eps - (y/eps)^2` up to the stick
//! velocity `eps`). Gradients and Hessians are exact (closed forms per
//! closest-feature type, [`super::distance_derivatives`]); the iteration matrix takes the Hessian projected to positive
//! semi-definite per pair. Every Newton step is limited by continuous
//! collision detection ([`ContactTerm::safe_fraction`]), so no iterate and no
//! output ever has two surfaces closer than the thickness, and stopped
//! where it would carry a sliding pair through sticking to the opposite
//! slip ([`ContactTerm::friction_fraction`]).
//!
//! `kappa` is per pair: the default, or more for a pair that approaches too
//! fast for the default barrier to stop it well inside the width, set while
//! the pair is outside the barrier and kept while it is inside (so it
//! changes no energy); the pairs' stiffnesses are the term's memory in a
//! saved state.
//!
//! The term's parts, by concept: its settings ([`settings`]), one pair of
//! primitives ([`pairs`]), the candidate search and its cache
//! ([`candidates`]), each pair's stiffness ([`stiffness`]), the lagged
//! dashpots and friction ([`friction`]), the memory a saved state carries
//! ([`memory`]), the contact report ([`report`]), the crease stops
//! ([`stops`]), and the matrix's contact part ([`batch`], [`psd`]).

use super::ccd;
use super::lagged::StepStart;
use super::scale::SheetScale;
use super::surface::ContactSurface;
use crate::assembly::{
    Assembler, BarrierTerm, EvalError, Evaluation, ForceTerm, MatrixCoeffs, MemoryError, State,
};
use crate::dofs::DofLayout;
use crate::mesh::Mesh;
use nalgebra::{SMatrix, SVector, Vector3};
use std::collections::HashMap;

mod batch;
mod candidates;
mod friction;
mod memory;
mod pairs;
mod psd;
mod report;
mod stiffness;
mod stops;

use super::settings::{ContactSettings, SettingsError};
pub use report::ContactReport;

use batch::{BlockPositions, MatrixBatch};
use candidates::{CandidateCache, NEAR_MOVE_MARGINS, NEAR_REACH_MARGINS, NearList, SlotBound};
use friction::Stencil;
use pairs::{Kind, Pair, PairKey, distance_sq, key, lift};
use psd::project_psd;
use stops::{Stops, stop_points};

/// The contact force term of one mesh.
pub struct ContactTerm {
    surf: ContactSurface,
    mesh: Mesh,
    xi: f64,
    s_hat: f64,
    kappa: f64,
    mu: f64,
    eps_v: f64,
    zeta: f64,
    /// Sample masses: fine and coarse primitives (kg).
    mass_fine: f64,
    mass_coarse: f64,
    /// The contact-vertex positions and velocities at the last step start,
    /// and the pairs lagged there.
    at_start: StepStart<Stencil>,
    /// Mean facet side (m): the default search of [`ContactTerm::report`].
    mean_side: f64,
    /// How far contact vertices may move from where candidates were last
    /// searched before they are searched again (m).
    cache_margin: f64,
    /// Project each pair's Hessian to positive semi-definite (for Newton).
    project: bool,
    /// Whether pairs were within the barrier at the step start.
    touching: bool,
    /// The step start's candidate pairs.
    cache: CandidateCache,
    /// How far the contact vertices can have moved, from the slots' moves.
    slot_bound: SlotBound,
    /// The cache's pairs near the last evaluations and near the last
    /// collision checks (emptied with the cache).
    near: std::sync::Mutex<NearList>,
    near_moves: std::sync::Mutex<NearList>,
    /// Whether the cache is still to be searched at its `q0` (a restored
    /// state's origin), at the next step start.
    cache_pending: bool,
    /// The model's DOFs (the length of the cache's `q0`).
    n_dofs: usize,
    /// A search the contact report made at a step end, with the cache's
    /// own padding: the next step start takes it instead of searching
    /// again at the same positions.
    spare: std::sync::Mutex<Option<CandidateCache>>,
    /// Where the matrix blocks of the pairs' slot groups sit.
    positions: std::sync::Mutex<BlockPositions>,
    /// The last slot vector whose contact-vertex positions were asked,
    /// and those positions (an iterate's evaluation and its collision
    /// check ask for the same).
    last_positions: std::sync::Mutex<(Vec<f64>, Vec<Vector3<f64>>)>,
    /// Barrier stiffness of each of `cache.pairs` (N/m, by index), set at
    /// the step start while the pair is outside the barrier and kept while
    /// it is inside (see [`ContactTerm::pair_stiffness`]). Pairs with one
    /// key hold one value (the map the saved state lists).
    kappas: Vec<f64>,
    /// The stiffnesses a restored state listed, by key: in force until the
    /// next step start sets `kappas` from them.
    restored: Option<HashMap<PairKey, f64>>,
    /// The slot pairs `cache.pairs`' matrices need (see
    /// [`ContactTerm::pattern_pairs`]), found once per search.
    blocks: Vec<(usize, usize)>,
    /// Width of the crease stops (rad): see [`ContactTerm::crease_stops`].
    flat_width: f64,
    /// The points along every crease where a stop acts.
    stops: Stops,
    /// Whether a crease end was within its stop at the step start.
    creases_near_flat: bool,
}

impl ContactTerm {
    /// Contact of `mesh` on the assembler `asm` built for it, with
    /// `settings`: its sample masses and default barrier stiffness from the
    /// assembler's material.
    pub fn on(
        asm: &Assembler,
        mesh: &Mesh,
        settings: &ContactSettings,
    ) -> Result<ContactTerm, SettingsError> {
        let m = &asm.physics.material;
        ContactTerm::new(
            mesh,
            &asm.layout,
            &asm.elements,
            settings,
            m.density * m.thickness,
            m.youngs_modulus * m.thickness,
        )
    }

    /// Contact of `mesh` (facets `elements`) with `settings`; `areal_mass`
    /// is density times thickness (kg/m^2), `membrane` the membrane
    /// stiffness E h (N/m) that sets the default barrier stiffness.
    pub fn new(
        mesh: &Mesh,
        layout: &DofLayout,
        elements: &[crate::element::ShellElement],
        settings: &ContactSettings,
        areal_mass: f64,
        membrane: f64,
    ) -> Result<ContactTerm, SettingsError> {
        settings.check()?;
        let surf = ContactSurface::new(
            mesh,
            layout,
            elements,
            settings.subdivisions,
            true,
            settings.kerf(),
        );
        let scale = SheetScale::new(mesh, elements, surf.n, settings, areal_mass, membrane);
        let edge = scale.side;
        // The barrier's reach, and the candidate cache's margin: a tenth of
        // a side (a step rarely moves a vertex that far, and a sheet has few
        // pairs that near), at least the reach.
        let reach = settings.thickness * (1.0 + settings.width);
        let cache_margin = reach.max(0.1 * edge);
        let slot_bound = SlotBound::new(&surf, layout);
        Ok(ContactTerm {
            surf,
            mesh: mesh.clone(),
            xi: settings.thickness,
            s_hat: settings.width * settings.thickness,
            kappa: scale.kappa,
            mu: settings.friction,
            eps_v: settings.stick_velocity,
            zeta: settings.damping_ratio,
            mass_fine: scale.sample_mass,
            mass_coarse: scale.corner_mass,
            at_start: StepStart::default(),
            mean_side: edge,
            cache_margin,
            project: true,
            touching: false,
            cache: CandidateCache::default(),
            slot_bound,
            near: Default::default(),
            near_moves: Default::default(),
            cache_pending: false,
            n_dofs: layout.n_dofs(),
            spare: Default::default(),
            last_positions: Default::default(),
            positions: Default::default(),
            kappas: Vec::new(),
            restored: None,
            blocks: Vec::new(),
            flat_width: settings.thickness / edge,
            stops: Stops::new(stop_points(mesh, layout, elements), layout),
            creases_near_flat: false,
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

    /// The distance kept between surfaces (m).
    pub fn thickness(&self) -> f64 {
        self.xi
    }

    /// Mean facet side (m).
    pub fn mean_side(&self) -> f64 {
        self.mean_side
    }

    /// Barrier stiffness kappa in force (N/m).
    pub fn stiffness(&self) -> f64 {
        self.kappa
    }

    /// The contact-vertex positions at slot vector `q` into `out`.
    fn positions_at(&self, q: &[f64], out: &mut Vec<Vector3<f64>>) {
        let mut last = self
            .last_positions
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        if last.0 != q {
            self.surf.positions(q, &mut last.1);
            last.0.clear();
            last.0.extend_from_slice(q);
        }
        out.clone_from(&last.1);
    }

    /// Largest fraction in (0, 1] of the motion `q -> q + dq` (all DOFs)
    /// that continuous collision detection proves free of surfaces coming
    /// closer than the thickness (conservatively: ACCD's separation margin).
    pub fn safe_fraction(&self, q: &[f64], dq: &[f64]) -> f64 {
        if self.nothing_near(q, Some(dq), self.xi) {
            return 1.0;
        }
        let mut x = Vec::new();
        let mut d = Vec::new();
        self.positions_at(q, &mut x);
        self.surf.positions(dq, &mut d);
        let mut t: f64 = 1.0;
        let pairs = self.near_pairs(&x, Some(&d), self.xi);
        // The cache's pairs near the move alone, in the same order: those
        // left out would find no time of impact (NEAR_MOVE_MARGINS).
        let cached = matches!(pairs, std::borrow::Cow::Borrowed(_));
        let idx = self.near_indices((&pairs, cached), &self.near_moves, &x, Some(&d), |p, m| {
            p.xi + NEAR_MOVE_MARGINS * m
        });
        for p in idx.into_iter().map(|i| &pairs[i]) {
            let (xs, ds) = (self.points(&x, p), self.points(&d, p));
            // Apart along an axis by more than the thickness and both
            // primitives' largest move up to `t`: no contact before `t`
            // (the swept boxes of a broad phase, per pair).
            let reach = ds.iter().map(|v| v.amax()).fold(0.0, f64::max);
            if p.apart(&xs, p.xi + 2.0 * t * reach) {
                continue;
            }
            let toi = match p.kind {
                Kind::PointTriangle { .. } => ccd::point_triangle_toi(xs, ds, p.xi, t),
                Kind::EdgeEdge { .. } => ccd::edge_edge_toi(xs, ds, p.xi, t),
            };
            if let Some(s) = toi {
                t = t.min(s);
            }
        }
        t
    }

    /// The active pairs at positions `x` (gap below the barrier width),
    /// with their gaps and stiffnesses. Fails when a pair is already closer
    /// than the thickness.
    fn active(&self, x: &[Vector3<f64>]) -> Result<Vec<(Pair, f64, f64)>, EvalError> {
        let mut out = Vec::new();
        let pairs = self.near_pairs(x, None, self.xi + self.s_hat);
        let cached = matches!(pairs, std::borrow::Cow::Borrowed(_));
        // The cache's pairs near `x` alone, in the same order: those left
        // out are apart by their reach here (NEAR_REACH_MARGINS).
        let idx = self.near_indices((&pairs, cached), &self.near, x, None, |p, m| {
            p.xi + self.s_hat_of(p) + NEAR_REACH_MARGINS * m
        });
        for i in idx {
            let p = pairs[i];
            let xs = self.points(x, &p);
            if p.apart(&xs, p.xi + self.s_hat_of(&p)) {
                continue;
            }
            let s = distance_sq::<f64>(&p.kind, &lift(&xs)).sqrt() - p.xi;
            if s >= self.s_hat_of(&p) {
                continue;
            }
            if s <= 0.0 {
                let ids = p.ids();
                return Err(EvalError::Penetration {
                    facets_a: self.surf.vertex_facets[ids[0]].clone(),
                    facets_b: self.surf.vertex_facets[ids[3]].clone(),
                    thickness: p.xi,
                    gap: s,
                });
            }
            out.push((p, s, self.kappa_at(&pairs, i, cached)));
        }
        Ok(out)
    }

    fn scatter_force(&self, ids: &[usize; 4], g: &SVector<f64, 12>, force: &mut [f64]) {
        super::surface::scatter_points(ids.map(|i| &self.surf.maps[i]), g.as_slice(), force);
    }

    /// The slots a pair's four points `ids` depend on, sorted, into `slots`
    /// (cleared first): the blocks its matrix touches.
    fn pair_slots(&self, ids: &[usize; 4], slots: &mut Vec<usize>) {
        let maps = ids.map(|i| &self.surf.maps[i]);
        slots.resize(maps.iter().map(|m| m.len()).sum(), 0);
        let n = super::surface::slot_union(&maps, slots);
        slots.truncate(n);
    }

    /// Add a pair's 12 x 12 matrix `h` (its four points' coordinates) to
    /// `batch`, mapped to the slots through the points' weights.
    fn scatter_matrix(&self, ids: &[usize; 4], h: &SMatrix<f64, 12, 12>, batch: &mut MatrixBatch) {
        let maps = ids.map(|i| &self.surf.maps[i]);
        batch.add_mapped(&maps, h.as_slice());
    }
}

impl BarrierTerm for ContactTerm {
    fn as_contact(&self) -> Option<&ContactTerm> {
        Some(self)
    }

    fn max_step_fraction(&self, _asm: &Assembler, q: &[f64], dq: &[f64]) -> f64 {
        self.safe_fraction(q, dq).min(self.crease_fraction(q, dq))
    }
    /// The pairs' and crease stop points' barrier stiffnesses (see
    /// [`ContactTerm::memory_list`]).
    fn memory(&self) -> Vec<f64> {
        self.memory_list()
    }

    fn check_memory(&self, memory: &[f64]) -> Result<(), MemoryError> {
        self.parse_memory(memory).map(|_| ())
    }

    fn restore_memory(&mut self, memory: &[f64]) -> Result<(), MemoryError> {
        let (pairs, stops, origin) = self.parse_memory(memory)?;
        self.restored = Some(pairs);
        self.stops.set_kappas(stops);
        self.restore_cache(origin);
        Ok(())
    }

    fn max_correction_fraction(
        &self,
        _asm: &Assembler,
        _q: &[f64],
        v: &[f64],
        dq: &[f64],
        dv_dq: f64,
    ) -> f64 {
        self.friction_fraction(v, dq, dv_dq)
    }

    fn limits_steps(&self) -> bool {
        self.touching || self.creases_near_flat || !self.cache.pairs.is_empty()
    }

    fn reports_power(&self) -> bool {
        true
    }

    /// Friction and the dashpots act on the pairs lagged at the step start
    /// alone: none, no dissipative force all step.
    fn dissipates_this_step(&self) -> bool {
        !self.at_start.lagged.is_empty()
    }
}

impl ForceTerm for ContactTerm {
    fn name(&self) -> &str {
        "contact"
    }

    fn before_step(&mut self, asm: &Assembler, q: &[f64], v: &[f64]) -> Vec<(usize, usize)> {
        self.lag(asm, q, v);
        self.pattern_pairs(asm)
    }

    fn lag(&mut self, asm: &Assembler, q: &[f64], v: &[f64]) {
        let mut x = Vec::new();
        let mut vx = Vec::new();
        self.surf.positions(q, &mut x);
        self.surf.positions(v, &mut vx);
        let old = self.cache_at(q, &x);
        self.lag_at(&x, &vx, old.as_ref());
        self.creases_near_flat = self.stops_at_step_start(asm, q, v);
    }

    fn add(
        &self,
        asm: &Assembler,
        st: &State,
        out: &mut Evaluation,
        mut matrix: Option<(&mut [f64], MatrixCoeffs)>,
    ) -> Result<(), EvalError> {
        let mut x = Vec::new();
        let mut v = Vec::new();
        // Positions only where a pair may be near.
        let quiet = self.nothing_near(st.q, None, self.xi + self.s_hat);
        if !quiet {
            self.positions_at(st.q, &mut x);
        }
        // Velocities only where lagged pairs (dashpots, friction) read them.
        if !self.at_start.lagged.is_empty() {
            self.surf.positions(st.v, &mut v);
        }
        out.dissipative_force.zeroed(out.force.len());
        let mut batch = MatrixBatch::default();
        let active = if quiet { Vec::new() } else { self.active(&x)? };
        out.barrier_pairs += active.len();
        // Matrices: each pair's barrier, dashpot and friction parts summed
        // (the lagged pairs are in the same canonical order) and scattered
        // once; lagged pairs out of the barrier on their own.
        let mut next_lagged = 0;
        for (p, _, kappa) in active {
            let ids = p.ids();
            let xs = self.points(&x, &p);
            let (e, points) = self.energy_derivatives(&p, &xs, kappa);
            out.term_energy += e.v;
            self.scatter_force(&ids, &e.g, &mut out.force);
            if let Some((_, co)) = matrix.as_ref() {
                let kp = key(&p);
                let lagged = &self.at_start.lagged;
                while next_lagged < lagged.len() && lagged[next_lagged].pair.key() < kp {
                    let lg = &lagged[next_lagged];
                    if let Some(h) = self.lagged_matrix(lg, &v, co) {
                        self.scatter_matrix(&lg.pair.ids, &h, &mut batch);
                    }
                    next_lagged += 1;
                }
                let mut h = match (co.k == 0.0, self.project) {
                    (true, _) => None,
                    (false, true) => Some(co.k * project_psd(&e.h, points)),
                    (false, false) => Some(co.k * e.h),
                };
                while next_lagged < lagged.len() && lagged[next_lagged].pair.key() == kp {
                    if let Some(hl) = self.lagged_matrix(&lagged[next_lagged], &v, co) {
                        h = Some(h.map_or(hl, |h| h + hl));
                    }
                    next_lagged += 1;
                }
                if let Some(h) = h {
                    self.scatter_matrix(&ids, &h, &mut batch);
                }
            }
        }
        if let Some((_, co)) = matrix.as_ref() {
            for lg in &self.at_start.lagged[next_lagged..] {
                if let Some(h) = self.lagged_matrix(lg, &v, co) {
                    self.scatter_matrix(&lg.pair.ids, &h, &mut batch);
                }
            }
        }
        self.crease_stops(asm, st, out, matrix.as_ref().map(|(_, co)| *co), &mut batch)?;
        self.add_lagged_forces(&v, out);
        if let Some((vals, _)) = matrix.as_mut() {
            let mut known = self.positions.lock().unwrap_or_else(|e| e.into_inner());
            batch.flush(asm, vals, &mut known);
        }
        Ok(())
    }
}
