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

use super::broad::{Aabb, overlapping, overlapping_few};
use super::ccd;
use super::distance::{self, V3};
use super::distance_derivatives::{
    edge_edge_mollifier_derivatives, edge_edge_points, edge_edge_sq_derivatives,
    point_triangle_points, point_triangle_sq_derivatives,
};
use super::scalar::{Dual2, Real};
use super::surface::ContactSurface;
use crate::assembly::{
    Assembler, BarrierTerm, EvalError, Evaluation, ForceTerm, MatrixCoeffs, MemoryError, State,
};
use crate::dofs::DofLayout;
use crate::mesh::Mesh;
use nalgebra::{Matrix3, SMatrix, SVector, Vector2, Vector3};
use std::collections::HashMap;

mod batch;
mod psd;
mod stops;

use super::potentials::{
    barrier, db, ddb, friction_matrix, reversal_fraction, slip_factor, speed_stiffness,
    tangent_basis,
};
use batch::{BlockPositions, MatrixBatch};
use psd::project_psd;
use stops::{Stops, stop_points};

/// Contact settings (scene keys under `ancf:contact`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ContactSettings {
    /// Distance kept between surfaces (m): the sheet thickness by default.
    pub thickness: f64,
    /// Barrier width `s_hat` as a fraction of the thickness: pairs act
    /// below a gap of `thickness * width`.
    pub width: f64,
    /// Barrier stiffness `kappa` (N/m); `None`: `E h xi / l` (membrane
    /// stiffness times contact thickness over the mean facet side).
    pub stiffness: Option<f64>,
    /// Coulomb friction coefficient.
    pub friction: f64,
    /// Tangential speed (m/s) below which friction sticks (smoothed).
    pub stick_velocity: f64,
    /// Damping ratio of the normal dashpot.
    pub damping_ratio: f64,
    /// Subdivisions of each facet side for the contact samples.
    pub subdivisions: usize,
}

impl Default for ContactSettings {
    fn default() -> Self {
        ContactSettings {
            thickness: 0.0,
            width: 0.1,
            stiffness: None,
            friction: 0.3,
            stick_velocity: 1e-4,
            damping_ratio: 1.0,
            subdivisions: 3,
        }
    }
}

/// Why [`ContactTerm::new`] refused its settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SettingsError {
    /// The thickness (given) is not positive.
    Thickness(f64),
}

impl std::fmt::Display for SettingsError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SettingsError::Thickness(_) => write!(f, "contact needs a positive thickness"),
        }
    }
}

impl std::error::Error for SettingsError {}

/// Which primitives a pair joins (contact vertex indices).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    /// Point `p` against triangle `t`.
    PointTriangle { p: usize, t: [usize; 3] },
    /// Edge `a` against edge `b`, with the mollifier threshold from rest.
    EdgeEdge {
        a: [usize; 2],
        b: [usize; 2],
        eps_x: f64,
    },
}

#[derive(Clone, Copy, Debug)]
struct Pair {
    kind: Kind,
    /// Sample mass for the dashpot (kg).
    mass: f64,
    /// Distance the pair keeps (m): the contact thickness, or less between
    /// neighbouring facets (see [`ContactTerm::candidates`]).
    xi: f64,
}

impl Pair {
    /// Whether the pair's primitives at `xs` are farther than `d` apart by
    /// an axis-aligned bound (false says nothing).
    fn apart(&self, xs: &[Vector3<f64>; 4], d: f64) -> bool {
        let k = match self.kind {
            Kind::PointTriangle { .. } => 1,
            Kind::EdgeEdge { .. } => 2,
        };
        distance::axis_apart(xs, k, d)
    }

    fn ids(&self) -> [usize; 4] {
        match self.kind {
            Kind::PointTriangle { p, t } => [p, t[0], t[1], t[2]],
            Kind::EdgeEdge { a, b, .. } => [a[0], a[1], b[0], b[1]],
        }
    }
}

/// The candidate pairs of the step start, found with boxes padded by
/// `pad + 2 margin`: a superset of the pairs any search with pad up to `pad`
/// finds while every contact vertex (and its swept end) stays within
/// `margin` of its step-start position `x0`. A step's many evaluations and
/// collision checks then filter this list by distance instead of searching
/// again (the pairs' final test is their distance in both cases).
#[derive(Clone, Debug, Default)]
struct CandidateCache {
    x0: Vec<Vector3<f64>>,
    pad: f64,
    pairs: Vec<Pair>,
}

impl CandidateCache {
    /// Whether positions `x` (and `x + dx`) are within `margin` of `x0`
    /// (the margin the cache was searched with, or less).
    fn covers(
        &self,
        x: &[Vector3<f64>],
        dx: Option<&[Vector3<f64>]>,
        pad: f64,
        margin: f64,
    ) -> bool {
        let m2 = margin * margin;
        pad <= self.pad
            && x.len() == self.x0.len()
            && x.iter().zip(&self.x0).enumerate().all(|(i, (y, y0))| {
                (y - y0).norm_squared() <= m2
                    && dx.is_none_or(|d| (y + d[i] - y0).norm_squared() <= m2)
            })
    }
}

/// Dashpot and friction data of one pair, lagged from the start of the
/// step: within a step both are smooth in the iterate (a coefficient read
/// from the iterate's own gap would put `sqrt(b''(s))`, whose slope is
/// infinite where a pair enters the barrier, into Newton's residual).
#[derive(Clone, Debug)]
struct Lagged {
    /// Edge-edge or not: with `ids`, the pair's key.
    edge: bool,
    ids: [usize; 4],
    /// Normal dashpot coefficient (N s/m).
    c: f64,
    /// Relative velocity at the closest points: `sum w_i v_i`.
    w: [f64; 4],
    /// Unit normal at the closest points (second side to first).
    normal: Vector3<f64>,
    /// Orthonormal tangent basis.
    basis: [Vector3<f64>; 2],
    /// Normal force (N).
    lambda: f64,
    /// Tangential relative velocity at the step start (in `basis`).
    slide: Vector2<f64>,
}

impl Lagged {
    fn key(&self) -> PairKey {
        (self.edge, self.ids)
    }
}

/// What contact looks like at one state (for outputs and tests).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactReport {
    /// Smallest surface distance minus the thickness (m) over the pairs
    /// searched (within `search` of each other).
    pub min_gap: f64,
    /// Pairs within the barrier width.
    pub pairs: usize,
    /// Sum of the pairs' normal forces (N).
    pub normal_force: f64,
}

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
    lagged: Vec<Lagged>,
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
    /// Contact-vertex positions and velocities at the last step start.
    x_start: Vec<Vector3<f64>>,
    v_start: Vec<Vector3<f64>>,
    /// Width of the crease stops (rad): see [`ContactTerm::crease_stops`].
    flat_width: f64,
    /// The points along every crease where a stop acts.
    stops: Stops,
    /// Whether a crease end was within its stop at the step start.
    creases_near_flat: bool,
}

/// Share of the wedge's opening that neighbouring facets keep (see
/// [`ContactTerm::neighbour_pairs`]): room for the facets to bend.
const NEIGHBOUR_SHARE: f64 = 0.5;

/// Neighbour pairs keeping less than this share of the thickness are left
/// out (near the shared vertex or crease, where the crease stops act).
const NEIGHBOUR_MIN: f64 = 0.02;

/// A pair's identity: edge-edge or not, and its four contact vertices.
type PairKey = (bool, [usize; 4]);

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
        if settings.thickness.is_nan() || settings.thickness <= 0.0 {
            return Err(SettingsError::Thickness(settings.thickness));
        }
        let surf = ContactSurface::new(mesh, layout, elements, settings.subdivisions, true);
        let nf = mesh.triangles().len().max(1);
        let area: f64 = elements.iter().map(|e| e.area()).sum::<f64>() / nf as f64;
        let edge = mesh.edge_ids().map(|e| mesh.edge_length(e)).sum::<f64>()
            / mesh.edges().len().max(1) as f64;
        let n = surf.n as f64;
        // The barrier must absorb impacts: kappa s_hat^2 is its energy scale.
        // D / l^2 (bending) leaves 1e-11 J against the 1e-6 J of a 4 cm
        // paper panel falling 5 mm; E h xi / l stops it within the width.
        let kappa = settings
            .stiffness
            .unwrap_or(membrane * settings.thickness / edge);
        // The barrier's reach, and the candidate cache's margin: a tenth of
        // a side (a step rarely moves a vertex that far, and a sheet has few
        // pairs that near), at least the reach.
        let reach = settings.thickness * (1.0 + settings.width);
        let cache_margin = reach.max(0.1 * edge);
        Ok(ContactTerm {
            surf,
            mesh: mesh.clone(),
            xi: settings.thickness,
            s_hat: settings.width * settings.thickness,
            kappa,
            mu: settings.friction,
            eps_v: settings.stick_velocity,
            zeta: settings.damping_ratio,
            mass_fine: areal_mass * area / (n * n),
            mass_coarse: areal_mass * area / 3.0,
            lagged: Vec::new(),
            mean_side: edge,
            cache_margin,
            project: true,
            touching: false,
            cache: CandidateCache::default(),
            spare: Default::default(),
            last_positions: Default::default(),
            positions: Default::default(),
            kappas: Vec::new(),
            restored: None,
            blocks: Vec::new(),
            x_start: Vec::new(),
            v_start: Vec::new(),
            flat_width: settings.thickness / edge,
            stops: Stops::new(stop_points(mesh, layout, elements)),
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

    /// How far beyond the thickness [`ContactTerm::report_near`] looks for
    /// the smallest gap (m): the candidate search's margin, a tenth of a
    /// facet side or the barrier's reach if more.
    pub fn report_reach(&self) -> f64 {
        self.cache_margin
    }

    /// [`ContactTerm::report`] with the search up to
    /// [`ContactTerm::report_reach`], from the step's candidate pairs where
    /// they hold every pair that close (the contact vertices have moved
    /// less than the slack their search left): what the contact outputs
    /// read after each step, with no search of their own.
    pub fn report_near(&self, q: &[f64]) -> ContactReport {
        let mut x = Vec::new();
        self.surf.positions(q, &mut x);
        let reach = self.report_reach();
        // The cache holds every pair within `pad + 2 margin` of its search
        // positions; a pair within `xi + reach` now was within that of
        // them while no vertex moved more than `slack`.
        let slack = 0.5 * (self.cache.pad + 2.0 * self.cache_margin - self.xi - reach);
        if slack >= 0.0 && self.cache.covers(&x, None, self.cache.pad, slack) {
            return self.report_over(&x, &self.cache.pairs, true, reach);
        }
        // The next step starts here and would search again: search once,
        // as it would (a wider search than the report needs), and leave it.
        let pad = self.xi + self.s_hat;
        let searched = CandidateCache {
            pairs: self.candidates(&x, None, pad + 2.0 * self.cache_margin),
            x0: x,
            pad,
        };
        let r = self.report_over(&searched.x0, &searched.pairs, false, reach);
        if let Ok(mut spare) = self.spare.lock() {
            *spare = Some(searched);
        }
        r
    }

    /// Barrier stiffness kappa in force (N/m).
    pub fn stiffness(&self) -> f64 {
        self.kappa
    }

    /// Candidate pairs with boxes padded by `pad` at positions `x` (and,
    /// with `dx`, swept over the motion `x -> x + dx`).
    fn candidates(&self, x: &[Vector3<f64>], dx: Option<&[Vector3<f64>]>, pad: f64) -> Vec<Pair> {
        let s = &self.surf;
        let bx = |ids: &[usize]| {
            let mut pts: Vec<Vector3<f64>> = ids.iter().map(|&i| x[i]).collect();
            if let Some(d) = dx {
                pts.extend(ids.iter().map(|&i| x[i] + d[i]));
            }
            Aabb::around(&pts, 0.5 * pad)
        };
        let mut out = Vec::new();
        // Facets first: only facets near a facet they share no vertex with
        // take part in the fine search (most of a sheet, most of the time,
        // takes part in none).
        let facet_boxes_all: Vec<Aabb> = s.facet_vertices.iter().map(|vs| bx(vs)).collect();
        let mut fine_active = vec![false; facet_boxes_all.len()];
        let mut near_neighbours = Vec::new();
        let mut normals: Vec<Option<Vector3<f64>>> = vec![None; facet_boxes_all.len()];
        for (f, g) in overlapping(&facet_boxes_all, &facet_boxes_all, true) {
            if s.are_neighbours(f, g) {
                near_neighbours.push((f, g));
            } else if !self.facets_apart(x, dx, pad, (f, g), &mut normals) {
                fine_active[f] = true;
                fine_active[g] = true;
            }
        }
        let active = |fs: &[usize]| fs.iter().any(|&f| fine_active[f]);
        // Fine: points against sub-triangles, edges against edges, between
        // facets that share no vertex.
        let pts: Vec<usize> = (0..s.n_vertices())
            .filter(|&i| active(&s.vertex_facets[i]))
            .collect();
        let tris: Vec<usize> = (0..s.fine_tris.len())
            .filter(|&k| fine_active[s.fine_tris[k].1])
            .collect();
        let pt_boxes: Vec<Aabb> = pts.iter().map(|&i| bx(&[i])).collect();
        let tri_boxes: Vec<Aabb> = tris.iter().map(|&k| bx(&s.fine_tris[k].0)).collect();
        for (pi, ti) in overlapping(&pt_boxes, &tri_boxes, false) {
            let p = pts[pi];
            let (t, g) = s.fine_tris[tris[ti]];
            let fp = &s.vertex_facets[p];
            if s.any_neighbours(fp, &[g]) {
                continue;
            }
            out.push(Pair {
                kind: Kind::PointTriangle { p, t },
                mass: self.mass_fine,
                xi: self.xi,
            });
        }
        let edges: Vec<usize> = (0..s.fine_edges.len())
            .filter(|&k| active(&s.fine_edges[k].1))
            .collect();
        let edge_boxes: Vec<Aabb> = edges.iter().map(|&k| bx(&s.fine_edges[k].0)).collect();
        for (i, j) in overlapping(&edge_boxes, &edge_boxes, true) {
            let (a, fa) = &s.fine_edges[edges[i]];
            let (b, fb) = &s.fine_edges[edges[j]];
            if s.any_neighbours(fa, fb) {
                continue;
            }
            out.push(self.edge_pair(*a, *b, self.mass_fine));
        }
        // Coarse: corners against corner triangles and mesh edges against
        // mesh edges, between neighbours (sharing no vertex themselves),
        // straight from the neighbouring facet pairs that are near.
        let mut corner_pairs: Vec<(usize, usize)> = Vec::new();
        let mut edge_pairs: Vec<(usize, usize)> = Vec::new();
        // Each corner's, corner triangle's and mesh edge's box once.
        let corner_boxes: Vec<Aabb> = s.corner.iter().map(|&c| bx(&[c])).collect();
        let tri_boxes: Vec<Aabb> = (0..facet_boxes_all.len())
            .map(|f| bx(&s.coarse_tri(&self.mesh, f)))
            .collect();
        let edge_boxes: Vec<Aabb> = s.coarse_edges.iter().map(|(e, _)| bx(e)).collect();
        for &(f, g) in &near_neighbours {
            for (a, b) in [(f, g), (g, f)] {
                for &v in &self.mesh.triangles()[a] {
                    if !self.mesh.triangles()[b].contains(&v)
                        && corner_boxes[v.index()].overlaps(&tri_boxes[b])
                    {
                        corner_pairs.push((v.index(), b));
                    }
                }
            }
            for &i in &self.mesh.face_edges()[f] {
                for &j in &self.mesh.face_edges()[g] {
                    let (ea, eb) = (s.coarse_edges[i.index()].0, s.coarse_edges[j.index()].0);
                    if i != j
                        && !ea.iter().any(|v| eb.contains(v))
                        && edge_boxes[i.index()].overlaps(&edge_boxes[j.index()])
                    {
                        edge_pairs.push((i.min(j).index(), i.max(j).index()));
                    }
                }
            }
        }
        corner_pairs.sort_unstable();
        corner_pairs.dedup();
        edge_pairs.sort_unstable();
        edge_pairs.dedup();
        for (v, g) in corner_pairs {
            out.push(Pair {
                kind: Kind::PointTriangle {
                    p: s.corner[v],
                    t: s.coarse_tri(&self.mesh, g),
                },
                mass: self.mass_coarse,
                xi: self.xi,
            });
        }
        for (i, j) in edge_pairs {
            out.push(self.edge_pair(s.coarse_edges[i].0, s.coarse_edges[j].0, self.mass_coarse));
        }
        self.neighbour_pairs(x, &bx, &near_neighbours, &mut out);
        self.corner_pairs(&bx, &near_neighbours, &mut out);
        // Pairs that are (nearly) in contact in the flat sheet are the
        // sheet itself, not contact.
        out.retain(|p| self.rest_distance(p) >= p.xi + self.s_hat_of(p));
        // Boxes overlap where primitives may be within `pad`; without a
        // sweep, keep the pairs that are (the boxes of tilted facets
        // overlap far more often than the facets come near).
        if dx.is_none() {
            out.retain(|p| {
                let xs = self.points(x, p);
                !p.apart(&xs, pad) && distance_sq::<f64>(&p.kind, &lift(&xs)) <= pad * pad
            });
        }
        // A canonical order: sums over pairs do not depend on the search.
        out.sort_unstable_by_key(|p| (matches!(p.kind, Kind::EdgeEdge { .. }), p.ids()));
        out
    }

    /// Whether facets `f` and `g` are more than `pad` apart along the
    /// normal of either one's corner triangle at `x`: the samples of each
    /// (and their ends swept by `dx`) projected on it, every primitive of a
    /// facet being in their hull. Tilted facets' boxes overlap far more
    /// often than the facets come near. `normals` caches the axes.
    fn facets_apart(
        &self,
        x: &[Vector3<f64>],
        dx: Option<&[Vector3<f64>]>,
        pad: f64,
        (f, g): (usize, usize),
        normals: &mut [Option<Vector3<f64>>],
    ) -> bool {
        let s = &self.surf;
        let span = |h: usize, axis: &Vector3<f64>| {
            let mut lo = f64::INFINITY;
            let mut hi = f64::NEG_INFINITY;
            for &i in &s.facet_vertices[h] {
                let a = axis.dot(&x[i]);
                let b = dx.map_or(a, |d| axis.dot(&(x[i] + d[i])));
                lo = lo.min(a.min(b));
                hi = hi.max(a.max(b));
            }
            (lo, hi)
        };
        [f, g].into_iter().any(|h| {
            let axis = *normals[h].get_or_insert_with(|| {
                let c = s.coarse_tri(&self.mesh, h).map(|i| x[i]);
                (c[1] - c[0])
                    .cross(&(c[2] - c[0]))
                    .try_normalize(0.0)
                    .unwrap_or_else(Vector3::zeros)
            });
            if axis == Vector3::zeros() {
                return false;
            }
            let (a0, a1) = span(f, &axis);
            let (b0, b1) = span(g, &axis);
            b0 - a1 > pad || a0 - b1 > pad
        })
    }

    /// Fine pairs between neighbouring facets sharing a side (a crease) that
    /// face each other, folded past a right angle (facets sharing only a
    /// corner: [`ContactTerm::corner_pairs`]): each one's samples off the
    /// other against the other's sub-triangles. A midsurface crease folded
    /// flat closes to a wedge (its facets meet at the crease, their far
    /// corners a thickness apart), so such a pair keeps a thickness that
    /// grows with the two points' distance in the flat pattern `d`:
    /// `NEIGHBOUR_SHARE xi min(1, d / (2 w))` (`w` the mean facet side: the
    /// wedge's own opening at mirror points is `xi d / (2 w)`), and pairs
    /// closer than [`NEIGHBOUR_MIN`] of the thickness are left to the crease
    /// stops. Without them the facets beside a crease folded flat, bent
    /// towards each other, crossed within a sixteenth of a facet of it.
    fn neighbour_pairs(
        &self,
        x: &[Vector3<f64>],
        bx: &dyn Fn(&[usize]) -> Aabb,
        near: &[(usize, usize)],
        out: &mut Vec<Pair>,
    ) {
        let s = &self.surf;
        let normal = |f: usize| {
            let c = s.coarse_tri(&self.mesh, f).map(|i| x[i]);
            (c[1] - c[0]).cross(&(c[2] - c[0]))
        };
        for &(f, g) in near {
            if self.share_a_corner_only(f, g) || normal(f).dot(&normal(g)) >= 0.0 {
                continue;
            }
            for (a, b) in [(f, g), (g, f)] {
                for pair in self.samples_against(a, b, bx) {
                    let xi = self.wedge_share(&pair);
                    if xi >= NEIGHBOUR_MIN * self.xi {
                        out.push(Pair { xi, ..pair });
                    }
                }
            }
        }
    }

    /// Point-triangle pairs (at the full thickness) of facet `a`'s samples
    /// off facet `b` against `b`'s sub-triangles, their boxes overlapping.
    fn samples_against(&self, a: usize, b: usize, bx: &dyn Fn(&[usize]) -> Aabb) -> Vec<Pair> {
        let s = &self.surf;
        let pts: Vec<usize> = s.facet_vertices[a]
            .iter()
            .copied()
            .filter(|&p| s.vertex_facets[p].binary_search(&b).is_err())
            .collect();
        let tris = &s.facet_fine_tris[b];
        let pt_boxes: Vec<Aabb> = pts.iter().map(|&p| bx(&[p])).collect();
        let tri_boxes: Vec<Aabb> = tris.iter().map(|&k| bx(&s.fine_tris[k].0)).collect();
        overlapping_few(&pt_boxes, &tri_boxes)
            .into_iter()
            .map(|(i, j)| Pair {
                kind: Kind::PointTriangle {
                    p: pts[i],
                    t: s.fine_tris[tris[j]].0,
                },
                mass: self.mass_fine,
                xi: self.xi,
            })
            .collect()
    }

    /// The share of the thickness a pair between neighbouring facets keeps:
    /// [`NEIGHBOUR_SHARE`] of the wedge's opening at its distance `d` in the
    /// flat pattern, `xi min(1, d / (2 w))`.
    fn wedge_share(&self, pair: &Pair) -> f64 {
        NEIGHBOUR_SHARE * self.xi * (self.rest_distance(pair) / (2.0 * self.mean_side)).min(1.0)
    }

    /// Whether facets `f` and `g` share one mesh vertex and no side.
    fn share_a_corner_only(&self, f: usize, g: usize) -> bool {
        let (tf, tg) = (self.mesh.triangles()[f], self.mesh.triangles()[g]);
        tf.iter().filter(|v| tg.contains(v)).count() == 1
    }

    /// Fine pairs between facets that share one vertex and no side,
    /// whichever way they face: each one's samples against the other's
    /// sub-triangles, and their fine edges against each other's (sharing no
    /// sample). No crease stop acts between such facets, and their coarse
    /// pairs (corners against the corner triangle, mesh edges) do not see
    /// the sampled interiors: the Kresling folded flat crossed its sampled
    /// surface in a scissor about a shared vertex, no corner passing
    /// through the other facet. A crossing of two sampled surfaces starts
    /// with a sample through a sub-triangle or a fine edge through a fine
    /// edge, so these pairs and the collision check on them keep the
    /// sampled facets apart. Thickness as across a crease (the layers
    /// between them close to the shared vertex), tapered towards the
    /// vertex but never below [`NEIGHBOUR_MIN`] of the thickness: near the
    /// vertex nothing else keeps them apart. Pairs another family already
    /// holds keep its thickness.
    fn corner_pairs(
        &self,
        bx: &dyn Fn(&[usize]) -> Aabb,
        near: &[(usize, usize)],
        out: &mut Vec<Pair>,
    ) {
        let s = &self.surf;
        let mut mine = Vec::new();
        let thin = |pair: Pair| {
            let xi = self.wedge_share(&pair).max(NEIGHBOUR_MIN * self.xi);
            Pair { xi, ..pair }
        };
        for &(f, g) in near
            .iter()
            .filter(|&&(f, g)| self.share_a_corner_only(f, g))
        {
            for (a, b) in [(f, g), (g, f)] {
                mine.extend(self.samples_against(a, b, bx).into_iter().map(thin));
            }
            let (ef, eg) = (&s.facet_fine_edges[f], &s.facet_fine_edges[g]);
            let boxes = |es: &[usize]| -> Vec<Aabb> {
                es.iter().map(|&k| bx(&s.fine_edges[k].0)).collect()
            };
            for (i, j) in overlapping_few(&boxes(ef), &boxes(eg)) {
                let (a, b) = (s.fine_edges[ef[i]].0, s.fine_edges[eg[j]].0);
                if !a.iter().any(|v| b.contains(v)) {
                    mine.push(thin(self.edge_pair(a, b, self.mass_fine)));
                }
            }
        }
        mine.sort_unstable_by_key(key);
        mine.dedup_by_key(|p| key(p));
        let held: std::collections::HashSet<PairKey> = out.iter().map(key).collect();
        out.extend(mine.into_iter().filter(|p| !held.contains(&key(p))));
    }

    /// The candidate pairs at `x` (swept by `dx`) with pad `pad`, or a
    /// superset of them: the step start's cache where it covers them.
    fn near_pairs(
        &self,
        x: &[Vector3<f64>],
        dx: Option<&[Vector3<f64>]>,
        pad: f64,
    ) -> std::borrow::Cow<'_, [Pair]> {
        if self.cache.covers(x, dx, pad, self.cache_margin) {
            std::borrow::Cow::Borrowed(&self.cache.pairs)
        } else {
            std::borrow::Cow::Owned(self.candidates(x, dx, pad))
        }
    }

    /// Search at the step start `x` for every pair the step's evaluations
    /// and collision checks may need (pads up to the barrier's reach,
    /// motions up to the margin), unless the last search covers `x`
    /// with half its margin to spare. (Pairs are in a canonical order, so
    /// which search found them does not change a result.)
    /// Returns the cache it replaced, if it searched.
    fn cache_at(&mut self, x: &[Vector3<f64>]) -> Option<CandidateCache> {
        let pad = self.xi + self.s_hat;
        let margin = self.cache_margin;
        if self.cache.covers(x, None, pad, 0.5 * margin) {
            return None;
        }
        let spare = self.spare.get_mut().ok().and_then(Option::take);
        let cache = match spare.filter(|c| c.pad == pad && c.x0 == x) {
            Some(c) => c,
            None => CandidateCache {
                pairs: self.candidates(x, None, pad + 2.0 * margin),
                x0: x.to_vec(),
                pad,
            },
        };
        let old = std::mem::replace(&mut self.cache, cache);
        self.blocks = self.cache_blocks();
        Some(old)
    }

    fn edge_pair(&self, a: [usize; 2], b: [usize; 2], mass: f64) -> Pair {
        let r = &self.surf.rest;
        let eps_x = distance::mollifier_threshold(&r[a[0]], &r[a[1]], &r[b[0]], &r[b[1]]);
        Pair {
            kind: Kind::EdgeEdge { a, b, eps_x },
            mass,
            xi: self.xi,
        }
    }

    fn rest_distance(&self, p: &Pair) -> f64 {
        let r = &self.surf.rest;
        let ids = p.ids();
        let x = [r[ids[0]], r[ids[1]], r[ids[2]], r[ids[3]]];
        distance_sq::<f64>(&p.kind, &lift(&x)).sqrt()
    }

    /// Slot pairs that the cached candidate pairs' matrices need (the
    /// slots of each pair's four points, among themselves) and the pattern
    /// lacks. The cache holds every pair within the barrier's reach plus
    /// twice the cache margin of the step start, so every pair a step can
    /// activate from it has its blocks (a pair found by a new search
    /// within the step would only leave the iteration matrix; the next
    /// step adds its blocks);
    /// facets that only share a vertex and lie flat get none (they are no
    /// candidates): blocks between every two facets sharing a vertex would
    /// multiply the factorization's work on a large flat sheet.
    fn pattern_pairs(&self, asm: &Assembler) -> Vec<(usize, usize)> {
        let mut out = self.blocks.clone();
        out.retain(|&(a, b)| !asm.has_pair(a, b));
        out
    }

    /// Every slot pair `(a, b)`, `a < b`, among the slots of each of
    /// `cache.pairs` (sorted).
    fn cache_blocks(&self) -> Vec<(usize, usize)> {
        // Pairs between the same facets share their slots: each set once.
        let mut sets: Vec<Vec<usize>> = self
            .cache
            .pairs
            .iter()
            .map(|p| {
                let mut slots = Vec::with_capacity(48);
                self.pair_slots(&p.ids(), &mut slots);
                slots
            })
            .collect();
        sets.sort_unstable();
        sets.dedup();
        let mut out = Vec::new();
        for slots in &sets {
            for &a in slots {
                for &b in slots {
                    if a < b {
                        out.push((a, b));
                    }
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        out
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
        let mut x = Vec::new();
        let mut d = Vec::new();
        self.positions_at(q, &mut x);
        self.surf.positions(dq, &mut d);
        let mut t: f64 = 1.0;
        for p in self.near_pairs(&x, Some(&d), self.xi).iter() {
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

    /// The fraction of a Newton correction at which the first sliding
    /// friction pair it would carry through sticking (to sliding the other
    /// way, beyond the stick velocity) comes closest to rest; 1 if none.
    /// In slip the friction force is constant along the slide and Newton's
    /// linear model does not see it stop, so a correction that should stop
    /// a pair overshoots to the opposite slip, and the next one back: the
    /// iteration cycles (a line search only creeps towards the stick). At
    /// rest the pair's stick stiffness is in the next matrix.
    pub fn friction_fraction(&self, v: &[f64], dq: &[f64], dv_dq: f64) -> f64 {
        if self.mu <= 0.0 || self.lagged.is_empty() {
            return 1.0;
        }
        let mut t: f64 = 1.0;
        let at = |x: &[f64], i: usize| -> Vector3<f64> {
            super::surface::eval_map(&self.surf.maps[i], x)
        };
        for lg in self.lagged.iter().filter(|lg| lg.lambda > 0.0) {
            let vr: Vector3<f64> = (0..4).map(|k| lg.w[k] * at(v, lg.ids[k])).sum();
            let dr: Vector3<f64> = (0..4)
                .map(|k| lg.w[k] * at(dq, lg.ids[k]))
                .sum::<Vector3<f64>>()
                * dv_dq;
            let u = Vector2::new(lg.basis[0].dot(&vr), lg.basis[1].dot(&vr));
            let du = Vector2::new(lg.basis[0].dot(&dr), lg.basis[1].dot(&dr));
            if let Some(stop) = reversal_fraction(u, du, lg.slide, self.eps_v)
                && stop < t
            {
                t = stop;
            }
        }
        t
    }

    /// Gap, pair count and normal force at slot vector `q`; the smallest
    /// gap is searched up to `search` (m) apart (`search` if none is closer).
    pub fn report(&self, q: &[f64], search: f64) -> ContactReport {
        let mut x = Vec::new();
        self.surf.positions(q, &mut x);
        self.report_over(
            &x,
            &self.candidates(&x, None, search + self.xi),
            false,
            search,
        )
    }

    /// The report over `pairs` at contact-vertex positions `x`, the
    /// smallest gap capped at `search`.
    /// `cached`: `pairs` are the candidate cache's.
    fn report_over(
        &self,
        x: &[Vector3<f64>],
        pairs: &[Pair],
        cached: bool,
        search: f64,
    ) -> ContactReport {
        let mut r = ContactReport {
            min_gap: search,
            ..Default::default()
        };
        for (i, p) in pairs.iter().enumerate() {
            let xs = self.points(x, p);
            let d = distance_sq::<f64>(&p.kind, &lift(&xs)).sqrt();
            let s = d - p.xi;
            r.min_gap = r.min_gap.min(s);
            if s < self.s_hat_of(p) {
                r.pairs += 1;
                if s > 0.0 {
                    r.normal_force += self.normal_force(p, &xs, s, self.kappa_at(pairs, i, cached));
                }
            }
        }
        r
    }

    /// Normal force of a pair at gap `s` (N): `-kappa m(x) b'(s)`.
    fn normal_force(&self, p: &Pair, xs: &[Vector3<f64>; 4], s: f64, kappa: f64) -> f64 {
        kappa * mollifier::<f64>(&p.kind, &lift(xs)) * -db(s, self.s_hat_of(p))
    }

    /// Dashpot coefficients, friction's normal forces and bases from
    /// contact-vertex positions `x`.
    /// `old` is the candidate cache the step start replaced, if it did.
    fn lag_at(&mut self, x: &[Vector3<f64>], v: &[Vector3<f64>], old: Option<&CandidateCache>) {
        // Pair stiffnesses: kept for pairs inside the barrier (their energy
        // is not zero), set anew for the others. The last ones are by index
        // while the cache is the same, else by key.
        let restored = self.restored.take();
        let old_kappas = std::mem::take(&mut self.kappas);
        let last = |i: usize, p: &Pair| -> Option<f64> {
            match (&restored, old) {
                (Some(map), _) => map.get(&key(p)).copied(),
                (None, Some(c)) => find_key(&c.pairs, p).and_then(|j| old_kappas.get(j).copied()),
                (None, None) => old_kappas.get(i).copied(),
            }
        };
        let mut kappas = Vec::with_capacity(self.cache.pairs.len());
        for (i, p) in self.cache.pairs.iter().enumerate() {
            let xs = self.points(x, p);
            let s_hat = self.s_hat_of(p);
            let inside = || {
                !p.apart(&xs, p.xi + s_hat)
                    && distance_sq::<f64>(&p.kind, &lift(&xs)).sqrt() - p.xi < s_hat
            };
            let k = match last(i, p) {
                Some(k) if inside() => k,
                _ => self.pair_stiffness(p, x, v),
            };
            kappas.push(k);
        }
        // Pairs with one key (adjacent in the canonical order) take the
        // last one's value, as a map by key keeps it.
        for i in (1..kappas.len()).rev() {
            if key(&self.cache.pairs[i - 1]) == key(&self.cache.pairs[i]) {
                kappas[i - 1] = kappas[i];
            }
        }
        self.kappas = kappas;
        self.x_start.clear();
        self.x_start.extend_from_slice(x);
        self.v_start.clear();
        self.v_start.extend_from_slice(v);
        self.lagged.clear();
        let act = self.active(x).unwrap_or_default();
        self.touching = !act.is_empty();
        for (p, s, kappa) in act {
            let xs = self.points(x, &p);
            let (w, n) = self.closest(&p, &xs);
            // Critical for zeta = 1 at the pair's barrier stiffness.
            let k = kappa * ddb(s, self.s_hat_of(&p)).max(0.0);
            let basis = tangent_basis(&n);
            let ids = p.ids();
            let vr: Vector3<f64> = (0..4).map(|k| w[k] * v[ids[k]]).sum();
            self.lagged.push(Lagged {
                edge: matches!(p.kind, Kind::EdgeEdge { .. }),
                ids,
                c: 2.0 * self.zeta * (k * p.mass).sqrt(),
                w,
                normal: n,
                basis,
                lambda: self.normal_force(&p, &xs, s, kappa),
                slide: Vector2::new(basis[0].dot(&vr), basis[1].dot(&vr)),
            });
        }
    }

    /// The barrier stiffness a pair outside the barrier takes at a step
    /// start with contact-vertex positions `x` and velocities `v`: the
    /// default, or more where the pair approaches so fast that the default
    /// barrier's energy scale `kappa s_hat^2` would let it come much
    /// closer than a few hundredths of the barrier width:
    /// `m v_n^2 / (PAIR_SPEED_DIVISOR s_hat^2)` for its sample mass `m` and
    /// normal approach `v_n` (IPC raises one global stiffness where the
    /// smallest gap falls, which changes the energy of every pair in the
    /// barrier). Set while the pair's barrier energy is zero and kept while
    /// it is inside, the stiffness changes no energy. A panel's corner
    /// whipping onto the layer below (a flat stack released in one held
    /// step) reaches the default barrier's energy scale many times over and
    /// would be stopped at a gap of 1e-13 m, where Newton cannot move it.
    fn pair_stiffness(&self, p: &Pair, x: &[Vector3<f64>], v: &[Vector3<f64>]) -> f64 {
        if v.len() != x.len() || x.is_empty() {
            return self.kappa;
        }
        let xs = self.points(x, p);
        let (w, n) = self.closest(p, &xs);
        let ids = p.ids();
        let vr: Vector3<f64> = (0..4).map(|k| w[k] * v[ids[k]]).sum();
        // Along the normal of the second primitive's surface (the
        // triangle's; for two edges, a facet of the second), not the
        // closest points' direction: a sample sliding onto the next
        // sub-triangle, or an edge sliding sideways onto a parallel one,
        // comes closer to it at the sliding speed, but it does not
        // approach the surface.
        let surface = match p.kind {
            Kind::PointTriangle { .. } => (xs[2] - xs[1]).cross(&(xs[3] - xs[1])),
            Kind::EdgeEdge { b, .. } => {
                let fb = &self.surf.vertex_facets;
                match fb[b[0]].iter().find(|f| fb[b[1]].contains(f)) {
                    Some(&f) => {
                        let c = self.surf.coarse_tri(&self.mesh, f).map(|i| x[i]);
                        (c[1] - c[0]).cross(&(c[2] - c[0]))
                    }
                    None => n,
                }
            }
        };
        let normal = match surface.try_normalize(0.0) {
            Some(u) if u.dot(&n) < 0.0 => -u,
            Some(u) => u,
            None => n,
        };
        let approach = (-normal.dot(&vr)).max(0.0);
        speed_stiffness(self.kappa, p.mass, approach, self.s_hat_of(p))
    }

    /// A pair's barrier width (m): the same share of its thickness for all.
    fn s_hat_of(&self, p: &Pair) -> f64 {
        self.s_hat * p.xi / self.xi
    }

    /// The pair stiffnesses of [`BarrierTerm::memory`]'s list (untrusted: a
    /// restored state's): sixes of edge flag (0 or 1), four contact-vertex
    /// ids and a positive stiffness up to MAX_MAGNITUDE.
    fn parse_memory(&self, memory: &[f64]) -> Result<HashMap<PairKey, f64>, MemoryError> {
        if !memory.len().is_multiple_of(6) {
            return Err(MemoryError::PairLength {
                values: memory.len(),
            });
        }
        let n = self.surf.n_vertices();
        let max = crate::scene::limits::MAX_MAGNITUDE;
        let mut map = HashMap::with_capacity(memory.len() / 6);
        for (k, m) in memory.chunks_exact(6).enumerate() {
            let id = |x: f64| {
                (x >= 0.0 && x < n as f64 && x.fract() == 0.0)
                    .then_some(x as usize)
                    .ok_or(MemoryError::PairVertex {
                        pair: k,
                        vertex: x,
                        vertices: n,
                    })
            };
            if m[0] != 0.0 && m[0] != 1.0 {
                return Err(MemoryError::PairKind {
                    pair: k,
                    kind: m[0],
                });
            }
            let ids = [id(m[1])?, id(m[2])?, id(m[3])?, id(m[4])?];
            if !(m[5] > 0.0 && m[5] <= max) {
                return Err(MemoryError::PairStiffness {
                    pair: k,
                    stiffness: m[5],
                    max,
                });
            }
            map.insert((m[0] == 1.0, ids), m[5]);
        }
        Ok(map)
    }

    /// A pair's barrier stiffness: the one set at the last step start, or
    /// (a pair found since) the one it would have been given there (a
    /// pair the next step start finds inside the barrier and not in the
    /// map, having come closer than the candidate search's margin in one
    /// step, takes the stiffness of that step start).
    fn kappa_of(&self, p: &Pair) -> f64 {
        let set = match &self.restored {
            Some(map) => map.get(&key(p)).copied(),
            None => find_key(&self.cache.pairs, p).and_then(|i| self.kappas.get(i).copied()),
        };
        set.unwrap_or_else(|| self.pair_stiffness(p, &self.x_start, &self.v_start))
    }

    /// The stiffness of the `i`th pair of `pairs`, which are the cache's
    /// when `cached`.
    fn kappa_at(&self, pairs: &[Pair], i: usize, cached: bool) -> f64 {
        match self.kappas.get(i) {
            Some(&k) if cached && self.restored.is_none() => k,
            _ => self.kappa_of(&pairs[i]),
        }
    }

    fn points(&self, x: &[Vector3<f64>], p: &Pair) -> [Vector3<f64>; 4] {
        let ids = p.ids();
        [x[ids[0]], x[ids[1]], x[ids[2]], x[ids[3]]]
    }

    /// The active pairs at positions `x` (gap below the barrier width),
    /// with their gaps and stiffnesses. Fails when a pair is already closer
    /// than the thickness.
    fn active(&self, x: &[Vector3<f64>]) -> Result<Vec<(Pair, f64, f64)>, EvalError> {
        let mut out = Vec::new();
        let pairs = self.near_pairs(x, None, self.xi + self.s_hat);
        let cached = matches!(pairs, std::borrow::Cow::Borrowed(_));
        for (i, &p) in pairs.iter().enumerate() {
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

fn key(p: &Pair) -> PairKey {
    (matches!(p.kind, Kind::EdgeEdge { .. }), p.ids())
}

/// The index of a pair with `p`'s key in `pairs` (in the canonical order).
fn find_key(pairs: &[Pair], p: &Pair) -> Option<usize> {
    let k = key(p);
    pairs.binary_search_by(|q| key(q).cmp(&k)).ok()
}

/// Points in the scalar type, each coordinate variable `3k + c`.
fn lift<T: Real>(x: &[Vector3<f64>; 4]) -> [V3<T>; 4] {
    V3::stencil(x)
}

fn distance_sq<T: Real>(kind: &Kind, x: &[V3<T>; 4]) -> T {
    match kind {
        Kind::PointTriangle { .. } => {
            distance::point_triangle_distance_sq(&x[0], &x[1], &x[2], &x[3])
        }
        Kind::EdgeEdge { .. } => distance::edge_edge_distance_sq(&x[0], &x[1], &x[2], &x[3]),
    }
}

fn mollifier<T: Real>(kind: &Kind, x: &[V3<T>; 4]) -> T {
    match kind {
        Kind::PointTriangle { .. } => T::cst(1.0),
        Kind::EdgeEdge { eps_x, .. } => {
            distance::edge_edge_mollifier(&x[0], &x[1], &x[2], &x[3], *eps_x)
        }
    }
}

impl ContactTerm {
    /// Pair energy `kappa m(x) b(s(x))` with its gradient and Hessian in the
    /// 12 stencil coordinates, from the closed-form derivatives of the
    /// squared distance `D` (and of the edge-edge mollifier `m`).
    /// Also the stencil points the energy depends on.
    fn energy_derivatives(
        &self,
        p: &Pair,
        x: &[Vector3<f64>; 4],
        k: f64,
    ) -> (Dual2<12>, &'static [usize]) {
        let [a, b, c, d] = x;
        match p.kind {
            Kind::PointTriangle { .. } => {
                let ty = distance::point_triangle_type(a, b, c, d);
                let f = self.barrier_of_sq(p, point_triangle_sq_derivatives(ty, x), k);
                (f, point_triangle_points(ty))
            }
            Kind::EdgeEdge { eps_x, .. } => {
                let ty = distance::edge_edge_type(a, b, c, d);
                let f = self.barrier_of_sq(p, edge_edge_sq_derivatives(ty, x), k);
                match edge_edge_mollifier_derivatives(x, eps_x) {
                    Some(m) => (f * m, &[0, 1, 2, 3]),
                    None => (f, edge_edge_points(ty)),
                }
            }
        }
    }

    /// `k b(sqrt(D) - xi)` of the squared distance `D` by one chain rule
    /// in `D` (its derivatives in closed form), `k` the pair's stiffness.
    fn barrier_of_sq<T: Real>(&self, p: &Pair, d2: T, k: f64) -> T {
        let dv = d2.val();
        let r = dv.sqrt();
        let s = r - p.xi;
        let s_hat = self.s_hat_of(p);
        let (b1, b2) = (db(s, s_hat), ddb(s, s_hat));
        // ds/dD and d2s/dD2.
        let (sd, sdd) = (0.5 / r, -0.25 / (r * dv));
        d2.map(
            k * barrier(s, s_hat),
            k * b1 * sd,
            k * (b2 * sd * sd + b1 * sdd),
        )
    }

    /// The iteration matrix of a lagged pair's dashpot and friction (`co.c`
    /// times their velocity derivatives) over its four points, at contact
    /// vertex velocities `v` (none if neither acts).
    fn lagged_matrix(
        &self,
        lg: &Lagged,
        v: &[Vector3<f64>],
        co: &MatrixCoeffs,
    ) -> Option<SMatrix<f64, 12, 12>> {
        if lg.c <= 0.0 && self.mu <= 0.0 {
            return None;
        }
        let mut k3 = Matrix3::zeros();
        if lg.c > 0.0 {
            k3 += (co.c * lg.c) * lg.normal * lg.normal.transpose();
        }
        if self.mu > 0.0 {
            // d f / d v_rel = mu lambda T [phi I + (phi'/y) u u^T] T^T.
            let vr: Vector3<f64> = (0..4).map(|k| lg.w[k] * v[lg.ids[k]]).sum();
            let u = Vector2::new(lg.basis[0].dot(&vr), lg.basis[1].dot(&vr));
            let slip = slip_factor(u.norm(), self.eps_v);
            k3 += friction_matrix(co.c * self.mu * lg.lambda, &lg.basis, u, slip);
        }
        let mut h = SMatrix::<f64, 12, 12>::zeros();
        for a in 0..4 {
            for b in 0..4 {
                h.fixed_view_mut::<3, 3>(3 * a, 3 * b)
                    .copy_from(&(lg.w[a] * lg.w[b] * k3));
            }
        }
        Some(h)
    }

    /// Closest-point weights (relative velocity `sum w_i v_i`) and the unit
    /// normal of a pair.
    fn closest(&self, p: &Pair, x: &[Vector3<f64>; 4]) -> ([f64; 4], Vector3<f64>) {
        let w = match p.kind {
            Kind::PointTriangle { .. } => {
                let b = distance::point_triangle_closest(&x[0], &x[1], &x[2], &x[3]);
                [1.0, -b[0], -b[1], -b[2]]
            }
            Kind::EdgeEdge { .. } => {
                let (s, t) = distance::edge_edge_closest(&x[0], &x[1], &x[2], &x[3]);
                [1.0 - s, s, -(1.0 - t), -t]
            }
        };
        let r: Vector3<f64> = (0..4).map(|k| w[k] * x[k]).sum();
        let n = if r.norm() > 0.0 {
            r.normalize()
        } else {
            Vector3::z()
        };
        (w, n)
    }
}

impl BarrierTerm for ContactTerm {
    fn as_contact(&self) -> Option<&ContactTerm> {
        Some(self)
    }

    fn max_step_fraction(&self, _asm: &Assembler, q: &[f64], dq: &[f64]) -> f64 {
        self.safe_fraction(q, dq).min(self.crease_fraction(q, dq))
    }

    /// The pairs' barrier stiffnesses: six numbers a pair (edge-edge or
    /// not, its four contact vertices, the stiffness), in key order.
    fn memory(&self) -> Vec<f64> {
        let mut pairs: Vec<(PairKey, f64)> = match &self.restored {
            Some(map) => map.iter().map(|(k, &v)| (*k, v)).collect(),
            None => self
                .cache
                .pairs
                .iter()
                .map(key)
                .zip(self.kappas.iter().copied())
                .collect(),
        };
        pairs.sort_unstable_by_key(|a| a.0);
        pairs.dedup_by(|a, b| a.0 == b.0);
        let mut out = Vec::with_capacity(6 * pairs.len());
        for ((edge, ids), k) in pairs {
            out.push(if edge { 1.0 } else { 0.0 });
            out.extend(ids.iter().map(|&i| i as f64));
            out.push(k);
        }
        out
    }

    fn check_memory(&self, memory: &[f64]) -> Result<(), MemoryError> {
        self.parse_memory(memory).map(|_| ())
    }

    fn restore_memory(&mut self, memory: &[f64]) -> Result<(), MemoryError> {
        self.restored = Some(self.parse_memory(memory)?);
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
}

impl ForceTerm for ContactTerm {
    fn name(&self) -> &str {
        "contact"
    }

    fn before_step(&mut self, asm: &Assembler, q: &[f64], v: &[f64]) -> Vec<(usize, usize)> {
        self.lag(asm, q, v);
        self.pattern_pairs(asm)
    }

    fn lag(&mut self, _asm: &Assembler, q: &[f64], v: &[f64]) {
        let mut x = Vec::new();
        let mut vx = Vec::new();
        self.surf.positions(q, &mut x);
        self.surf.positions(v, &mut vx);
        let old = self.cache_at(&x);
        self.lag_at(&x, &vx, old.as_ref());
        self.creases_near_flat = self.near_flat(q);
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
        self.positions_at(st.q, &mut x);
        // Velocities only where lagged pairs (dashpots, friction) read them.
        if !self.lagged.is_empty() {
            self.surf.positions(st.v, &mut v);
        }
        out.dissipative_force.zeroed(out.force.len());
        let mut batch = MatrixBatch::default();
        let active = self.active(&x)?;
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
                let lagged = &self.lagged;
                while next_lagged < lagged.len() && lagged[next_lagged].key() < kp {
                    let lg = &lagged[next_lagged];
                    if let Some(h) = self.lagged_matrix(lg, &v, co) {
                        self.scatter_matrix(&lg.ids, &h, &mut batch);
                    }
                    next_lagged += 1;
                }
                let mut h = match (co.k == 0.0, self.project) {
                    (true, _) => None,
                    (false, true) => Some(co.k * project_psd(&e.h, points)),
                    (false, false) => Some(co.k * e.h),
                };
                while next_lagged < lagged.len() && lagged[next_lagged].key() == kp {
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
            for lg in &self.lagged[next_lagged..] {
                if let Some(h) = self.lagged_matrix(lg, &v, co) {
                    self.scatter_matrix(&lg.ids, &h, &mut batch);
                }
            }
        }
        self.crease_stops(asm, st, out, matrix.as_ref().map(|(_, co)| *co), &mut batch)?;
        // Dashpots on the gap rates along the lagged normals, with the
        // lagged coefficients and closest-point weights (the pair's own
        // distance gradient would turn tangential once a sample slides off
        // its triangle within the step, and damp the slide).
        for lg in self.lagged.iter().filter(|lg| lg.c > 0.0) {
            let vr: Vector3<f64> = (0..4).map(|k| lg.w[k] * v[lg.ids[k]]).sum();
            let rate = lg.normal.dot(&vr);
            out.contact_damping_power += lg.c * rate * rate;
            let mut g = SVector::<f64, 12>::zeros();
            for k in 0..4 {
                g.fixed_rows_mut::<3>(3 * k)
                    .copy_from(&((lg.c * rate * lg.w[k]) * lg.normal));
            }
            self.scatter_force(&lg.ids, &g, &mut out.force);
            self.scatter_force(&lg.ids, &g, &mut out.dissipative_force.damping);
        }
        // Friction with the lagged normal forces and bases.
        for lg in self.lagged.iter().filter(|_| self.mu > 0.0) {
            let vr: Vector3<f64> = (0..4).map(|k| lg.w[k] * v[lg.ids[k]]).sum();
            let u = Vector2::new(lg.basis[0].dot(&vr), lg.basis[1].dot(&vr));
            let y = u.norm();
            let (phi, _) = slip_factor(y, self.eps_v);
            let ml = self.mu * lg.lambda;
            let ut = lg.basis[0] * u.x + lg.basis[1] * u.y;
            let fr = ml * phi * ut;
            out.friction_power += fr.dot(&vr);
            let mut g = SVector::<f64, 12>::zeros();
            for k in 0..4 {
                g.fixed_rows_mut::<3>(3 * k).copy_from(&(lg.w[k] * fr));
            }
            self.scatter_force(&lg.ids, &g, &mut out.force);
            self.scatter_force(&lg.ids, &g, &mut out.dissipative_force.friction);
        }
        if let Some((vals, _)) = matrix.as_mut() {
            let mut known = self.positions.lock().unwrap_or_else(|e| e.into_inner());
            batch.flush(asm, vals, &mut known);
        }
        Ok(())
    }
}
