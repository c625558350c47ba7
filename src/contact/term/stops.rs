//! Crease stops: a crease cannot fold past flat (see
//! [`ContactTerm::crease_stops`]).

use super::ContactTerm;
use super::batch::MatrixBatch;
use crate::assembly::{Assembler, EvalError, Evaluation, MatrixCoeffs, State};
use crate::contact::potentials::{barrier, db, ddb, speed_stiffness};
use crate::dofs::DofLayout;
use crate::mesh::Mesh;
use nalgebra::{SMatrix, Vector3};
use std::collections::HashMap;

/// A point of a crease where its stop acts: the crease's `[a, b, t]` there
/// (into the facet on the right of `t`, into the left one, along the
/// crease) as linear maps of the slots.
#[derive(Clone, Debug)]
pub(super) struct StopPoint {
    edge: crate::ids::EdgeId,
    /// Share of the crease's length (m) the point stands for.
    length: f64,
    maps: [crate::contact::surface::VertexMap; 3],
    /// Each map's sums of |coefficient| over its position slots and over
    /// its gradient slots: `|x(q) - x(r)| <= l1[0] max_p |q_p - r_p| +
    /// l1[1] max_g |q_g - r_g|` (p position slots, g gradient slots).
    l1: [[f64; 2]; 3],
}

/// The crease stops' points, by crease edge, and for each edge the state
/// where its points were last evaluated with how far its slots may move
/// from there before one of them can come within the stop's width or turn
/// by a radian: edges within that are skipped (their points would act on
/// nothing), the same result for a fraction of the work. Each point's
/// barrier stiffness is set for a step from the step start (see
/// [`ContactTerm::stop_stiffness`]) and kept while the point is inside.
pub(super) struct Stops {
    pub(super) points: Vec<StopPoint>,
    edges: Vec<StopEdge>,
    refs: std::sync::Mutex<Vec<EdgeRef>>,
    /// Each point's stiffness (N m/rad), [`UNSET`] where none is: set when
    /// a point first enters its barrier in a step, kept while it is inside.
    kappas: std::sync::Mutex<Vec<f64>>,
    /// The slots' positions and rates at the step start.
    start_q: Vec<f64>,
    start_v: Vec<f64>,
}

impl StopPoint {
    /// The crease spring's stiffness of the point's share of its crease
    /// (N m/rad): its stop's stiffness without a fast approach.
    fn spring(&self, asm: &Assembler) -> f64 {
        asm.physics.crease_k_per_length * self.length
    }
}

/// One crease edge's points, the slots their maps read and each slot's
/// kind (0 position, 1 gradient).
struct StopEdge {
    points: std::ops::Range<usize>,
    slots: Vec<usize>,
    kinds: Vec<usize>,
}

/// An edge's reference: its slots' values where its points were last
/// evaluated, and the rates `[A, B]` at which the largest moves of its
/// position slots (m) and gradient slots use up the room of its points:
/// moves with `A dp + B dg < 1` keep every point clear (see
/// [`allowance`]); None where no move does.
#[derive(Clone, Default)]
struct EdgeRef {
    q: Vec<Vector3<f64>>,
    rates: Option<[f64; 2]>,
}

/// Slot `s`'s vector in `q`.
pub(super) fn slot(q: &[f64], s: usize) -> Vector3<f64> {
    Vector3::new(q[3 * s], q[3 * s + 1], q[3 * s + 2])
}

/// How far slots `(slot, kind, reference)` (kind 0 position, 1 gradient)
/// can be from their references along `q + alpha dq`, alpha in [0, 1]: by
/// kind, the largest distance at `q` plus the largest step.
pub(super) fn reach_by_kind(
    slots: impl Iterator<Item = (usize, usize, Vector3<f64>)>,
    q: &[f64],
    dq: Option<&[f64]>,
) -> [f64; 2] {
    let (mut moved, mut step) = ([0.0f64; 2], [0.0f64; 2]);
    for (s, kind, r) in slots {
        moved[kind] = moved[kind].max((slot(q, s) - r).norm_squared());
        if let Some(d) = dq {
            step[kind] = step[kind].max(slot(d, s).norm_squared());
        }
    }
    [0, 1].map(|k| moved[k].sqrt() + step[k].sqrt())
}

impl EdgeRef {
    /// Take `q` as the reference of `edge`, with its allowance's rates.
    fn set(&mut self, edge: &StopEdge, q: &[f64], rates: Option<[f64; 2]>) {
        self.q.clear();
        self.q.extend(edge.slots.iter().map(|&s| slot(q, s)));
        self.rates = rates;
    }

    /// Whether every slot of `edge` at `q` (and along `q + alpha dq`,
    /// alpha in [0, 1]) is within the reference's allowance.
    fn covers(&self, edge: &StopEdge, q: &[f64], dq: Option<&[f64]>) -> bool {
        let Some(rates) = self.rates else {
            return false;
        };
        if self.q.len() != edge.slots.len() {
            return false;
        }
        let slots =
            (edge.slots.iter().zip(&edge.kinds).zip(&self.q)).map(|((&s, &k), r)| (s, k, *r));
        let reach = reach_by_kind(slots, q, dq);
        rates[0] * reach[0] + rates[1] * reach[1] < 1.0
    }
}

/// A stop point's stiffness where none is set for the step (a crease
/// without a spring keeps a stiffness of 0).
pub(super) const UNSET: f64 = -1.0;

/// Points per crease edge where the crease stops act, ends included: a
/// flat-folded crease's facets bend between its ends, and crossed each
/// other along it (at a sixteenth of a facet from the crease) with only
/// the ends stopped.
const STOP_POINTS: usize = 9;

/// Slot `s`'s kind as an index: 0 position, 1 gradient.
pub(super) fn slot_kind(layout: &DofLayout, s: usize) -> usize {
    usize::from(layout.slot_kind[s] != crate::dofs::SlotKind::Position)
}

/// The crease stops' points: [`STOP_POINTS`] along every crease edge.
pub(super) fn stop_points(
    mesh: &Mesh,
    layout: &DofLayout,
    elements: &[crate::element::ShellElement],
) -> Vec<StopPoint> {
    let mut out = Vec::new();
    for (e, edge) in mesh.edge_ids().zip(mesh.edges()) {
        if edge.kind != crate::mesh::EdgeKind::Crease || mesh.faces_of(e).len() != 2 {
            continue;
        }
        let (v, w) = (edge.v[0], edge.v[1]);
        let chord = mesh.coord(w) - mesh.coord(v);
        let length = mesh.edge_length(e) / STOP_POINTS as f64;
        for k in 0..STOP_POINTS {
            let s = k as f64 / (STOP_POINTS - 1) as f64;
            let mut right = None;
            let mut left = None;
            let mut tangent = None;
            for &f in mesh.faces_of(e) {
                let tri = mesh.triangle(f);
                let at = |x| tri.iter().position(|&y| y == x).expect("on the facet");
                let (iv, iw) = (at(v), at(w));
                let ik = 3 - iv - iw;
                let mut l = [0.0; 3];
                l[iv] = 1.0 - s;
                l[iw] = s;
                // Into the facet: towards its third corner; along the crease.
                let mut into = [0.0; 3];
                into[ik] = 1.0;
                for i in 0..3 {
                    into[i] -= l[i];
                }
                let mut along = [0.0; 3];
                along[iw] = 1.0;
                along[iv] = -1.0;
                let shape = elements[f.index()].shape();
                let map = |dir: [f64; 3]| {
                    let d = shape.d_along(l, dir);
                    let mut terms: HashMap<usize, f64> = HashMap::new();
                    for (node, combo) in layout.local[f.index()].iter().enumerate() {
                        for (slot, c) in combo.terms() {
                            *terms.entry(slot).or_insert(0.0) += d[node] * c;
                        }
                    }
                    let mut m: crate::contact::surface::VertexMap =
                        terms.into_iter().filter(|&(_, c)| c != 0.0).collect();
                    m.sort_unstable_by_key(|&(s, _)| s);
                    m
                };
                let x = mesh.coord(tri[ik]) - mesh.coord(v);
                if chord.x * x.y - chord.y * x.x < 0.0 {
                    right = Some(map(into));
                } else {
                    left = Some(map(into));
                }
                tangent.get_or_insert_with(|| map(along));
            }
            if let (Some(a), Some(b), Some(t)) = (right, left, tangent) {
                let l1 = |m: &crate::contact::surface::VertexMap| {
                    let mut sums = [0.0; 2];
                    for &(s, c) in m {
                        sums[slot_kind(layout, s)] += c.abs();
                    }
                    sums
                };
                out.push(StopPoint {
                    edge: e,
                    length,
                    l1: [l1(&a), l1(&b), l1(&t)],
                    maps: [a, b, t],
                });
            }
        }
    }
    out
}

impl Stops {
    /// The points' stiffnesses ([`UNSET`] where none is).
    pub(super) fn kappas(&self) -> Vec<f64> {
        self.kappas
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clone()
    }

    /// Set the points' stiffnesses (a restored state's; [`UNSET`] where none is).
    pub(super) fn set_kappas(&mut self, kappas: Vec<f64>) {
        *self.kappas.get_mut().unwrap_or_else(|e| e.into_inner()) = kappas;
    }

    /// The stops at `points`, grouped by crease edge (each edge's points
    /// are consecutive), none with a reference yet.
    pub(super) fn new(points: Vec<StopPoint>, layout: &DofLayout) -> Stops {
        let mut edges: Vec<StopEdge> = Vec::new();
        for (i, sp) in points.iter().enumerate() {
            match edges.last_mut() {
                Some(last) if points[last.points.start].edge == sp.edge => last.points.end = i + 1,
                _ => edges.push(StopEdge {
                    points: i..i + 1,
                    slots: Vec::new(),
                    kinds: Vec::new(),
                }),
            }
        }
        for edge in &mut edges {
            let mut slots: Vec<usize> = points[edge.points.clone()]
                .iter()
                .flat_map(|sp| sp.maps.iter().flatten().map(|&(s, _)| s))
                .collect();
            slots.sort_unstable();
            slots.dedup();
            edge.kinds = slots.iter().map(|&s| slot_kind(layout, s)).collect();
            edge.slots = slots;
        }
        let refs = std::sync::Mutex::new(vec![EdgeRef::default(); edges.len()]);
        let kappas = std::sync::Mutex::new(vec![UNSET; points.len()]);
        Stops {
            points,
            edges,
            refs,
            kappas,
            start_q: Vec::new(),
            start_v: Vec::new(),
        }
    }
}

/// The rates `[A, B]` at which moves of the position slots (by up to `dp`,
/// m) and the gradient slots (by up to `dg`) of a stop point's maps use up
/// its room from where its vectors are `[a, b, t]` (gap to flat `gap`):
/// moves with `A dp + B dg < 1` keep the point at least `width` from flat
/// and turning by less than a radian (so the collision check's wrap test
/// holds too). With `|dx| <= d_x = l1_x[0] dp + l1_x[1] dg`,
/// [`stop_turn_bound`] is at most `pi/2 (K_a / |a x t| + K_b / |b x t|)`,
/// `K_x = 2 d_x |t| + |x| d_t`, for `d_t <= |t|`: both linear in `(dp,
/// dg)`. Bounding position and gradient slots apart keeps a fold's
/// turning gradients (a hundredth of a radian, against millimetres of
/// motion) from setting the bound of the positions. None where no move is
/// allowed.
fn allowance(
    [a, b, t]: &[Vector3<f64>; 3],
    l1: &[[f64; 2]; 3],
    gap: f64,
    width: f64,
) -> Option<[f64; 2]> {
    let room = (gap - width).min(1.0) - 1e-9;
    let nt = t.norm();
    let (na, nb) = (a.cross(t).norm(), b.cross(t).norm());
    if room <= 0.0 || na <= 0.0 || nb <= 0.0 || l1[2][0] + l1[2][1] <= 0.0 {
        return None;
    }
    let rate = |k: usize| {
        let ka = 2.0 * l1[0][k] * nt + a.norm() * l1[2][k];
        let kb = 2.0 * l1[1][k] * nt + b.norm() * l1[2][k];
        let turn = std::f64::consts::FRAC_PI_2 * (ka / na + kb / nb) / room;
        // A margin for rounding: the skip must never drop a point that acts.
        turn.max(l1[2][k] / nt) / 0.999
    };
    Some([rate(0), rate(1)])
}

/// The rates of an edge's points together ([`allowance`]): the largest of
/// each, None where a point has none.
fn both(x: Option<[f64; 2]>, y: Option<[f64; 2]>) -> Option<[f64; 2]> {
    let (x, y) = (x?, y?);
    Some([x[0].max(y[0]), x[1].max(y[1])])
}

/// A bound on how far the angle between the crease normals `a x t` and
/// `b x t` (the gap to flat of [`flat_gap`]) can change along the move
/// `(a, b, t) + alpha (da, db, dt)`, `alpha` in [0, 1]: each normal turns by
/// at most `asin(|change| / |normal|) <= pi/2 |change| / |normal|`.
fn stop_turn_bound([a, b, t]: [Vector3<f64>; 3], [da, db, dt]: [Vector3<f64>; 3]) -> f64 {
    let (nt, ndt) = (t.norm(), dt.norm());
    let turn = |x: &Vector3<f64>, dx: &Vector3<f64>| {
        let normal = x.cross(&t).norm();
        let change = dx.norm() * (nt + ndt) + x.norm() * ndt;
        if change < normal {
            std::f64::consts::FRAC_PI_2 * change / normal
        } else {
            std::f64::consts::PI
        }
    };
    turn(&a, &da) + turn(&b, &db)
}

/// The largest fraction, `limit` or a halving of it, of the move `(a, b, t)
/// + alpha (da, db, dt)` from raw angle `raw0` (gap to flat `gap`) whose end
/// keeps the point on its side of flat with a gap of at least `keep`, and
/// so do the halvings of that fraction a line search may step back to; 0 if
/// none. Passing flat wraps the raw angle across 0 = 2 pi; the angle need not
/// change monotonically along the move, so an end on the right side says
/// nothing of the points before it. Halvings are tested down to where
/// [`stop_turn_bound`] alone keeps the point clear.
fn stop_fraction(
    x: [Vector3<f64>; 3],
    dx: [Vector3<f64>; 3],
    raw0: f64,
    gap: f64,
    keep: f64,
    limit: f64,
) -> f64 {
    let room = (gap - keep).min(1.0);
    if room.is_nan() || room <= 0.0 || dx.iter().any(|d| !d.iter().all(|c| c.is_finite())) {
        return 0.0;
    }
    let bounded = |alpha: f64| stop_turn_bound(x, dx.map(|d| d * alpha)) < room;
    let clear = |alpha: f64| {
        let [a, b, t] = [0, 1, 2].map(|i| x[i] + dx[i] * alpha);
        // The raw angle once: its gap to flat is flat_gap's.
        let theta = crate::crease::theta(&a, &b, &t);
        (theta - raw0).abs() < std::f64::consts::PI
            && theta.min(std::f64::consts::TAU - theta) >= keep
    };
    let mut fraction = limit;
    let mut halvings = 0;
    loop {
        // The first of fraction, fraction / 2, ... (down to the bound) that
        // is not clear: the fraction falls below it.
        let mut alpha = fraction;
        let mut blocked = None;
        while alpha > 0.0 && !bounded(alpha) {
            if !clear(alpha) {
                blocked = Some(alpha);
                break;
            }
            alpha *= 0.5;
        }
        match blocked {
            None => return fraction,
            Some(b) => {
                fraction = 0.5 * b;
                halvings += 1;
                if halvings >= 60 {
                    return 0.0;
                }
            }
        }
    }
}

/// A crease angle's gap to flat (rad) and `d gap / d theta`: `2 pi -
/// theta` on the valley side (-1), `theta` on the mountain side (+1).
fn flat_gap(a: &Vector3<f64>, b: &Vector3<f64>, t: &Vector3<f64>) -> (f64, f64) {
    let theta = crate::crease::theta(a, b, t);
    if theta > std::f64::consts::PI {
        (std::f64::consts::TAU - theta, -1.0)
    } else {
        (theta, 1.0)
    }
}

impl ContactTerm {
    /// Crease stops: a crease cannot fold past flat, where the facets across
    /// it would pass through each other. Its facets share a vertex, so no
    /// contact pair between them acts near the crease (a midsurface crease
    /// folded flat closes to a wedge, only its open end a thickness wide),
    /// and a crease pressed past flat (by a moment, or by layers above it)
    /// crossed its facets there. At [`STOP_POINTS`] points along every
    /// crease, the angle between the facets' surfaces (as the crease
    /// springs read it at the ends) that comes within `flat_width` (the
    /// thickness over the mean facet side: the wedge's angle) of flat, on
    /// either side, meets the barrier `k b(g)` in its gap to flat `g`
    /// (rad), `k` the crease spring stiffness of the point's share of the
    /// crease (a spring driven to exactly flat then rests about half-way
    /// into the stop). The iteration matrix takes the Gauss-Newton part
    /// `k b'' grad grad^T` (positive semi-definite) unless exact Hessians
    /// are asked for. The stops keep every accepted angle within (0, 2 pi),
    /// so the raw angle is the unwrapped one.
    pub(super) fn crease_stops(
        &self,
        asm: &Assembler,
        st: &State,
        out: &mut Evaluation,
        matrix: Option<MatrixCoeffs>,
        batch: &mut MatrixBatch,
    ) -> Result<(), EvalError> {
        let w = self.flat_width;
        let stops = &self.stops;
        let mut refs = stops.refs.lock().unwrap_or_else(|e| e.into_inner());
        for (edge, r) in stops.edges.iter().zip(refs.iter_mut()) {
            if r.covers(edge, st.q, None) {
                continue;
            }
            let mut rates = Some([0.0; 2]);
            for i in edge.points.clone() {
                let sp = &stops.points[i];
                let [a, b, t] = sp
                    .maps
                    .each_ref()
                    .map(|m| crate::contact::surface::eval_map(m, st.q));
                let (g, sign) = flat_gap(&a, &b, &t);
                rates = both(rates, allowance(&[a, b, t], &sp.l1, g, w));
                if g >= w {
                    continue;
                }
                if g <= 0.0 {
                    return Err(EvalError::PastFlat { edge: sp.edge });
                }
                let k = {
                    let mut kappas = stops.kappas.lock().unwrap_or_else(|e| e.into_inner());
                    if kappas[i] == UNSET {
                        kappas[i] = self.stop_stiffness(asm, sp);
                    }
                    kappas[i]
                };
                let d =
                    crate::crease::theta_derivatives(&a, &b, &t, matrix.is_some() && !self.project);
                out.term_energy += k * barrier(g, w);
                out.barrier_pairs += 1;
                let grad = d.grad9() * sign;
                let f = grad * (k * db(g, w));
                crate::contact::surface::scatter_points(
                    sp.maps.each_ref(),
                    f.as_slice(),
                    &mut out.force,
                );
                if let Some(co) = matrix.filter(|co| co.k != 0.0) {
                    let mut h = grad * grad.transpose() * (k * ddb(g, w));
                    if let Some(hess) = d.hess9() {
                        h += hess * (sign * k * db(g, w));
                    }
                    self.scatter_maps_matrix(&sp.maps, &(co.k * h), batch);
                }
            }
            r.set(edge, st.q, rates);
        }
        Ok(())
    }

    /// The largest fraction of the move `q -> q + dq` that keeps every
    /// crease stop's point from passing flat: on the same side, its gap to
    /// flat not below the collision checks' share of the gap it had
    /// (halving the fraction until it holds).
    pub(super) fn crease_fraction(&self, q: &[f64], dq: &[f64]) -> f64 {
        let mut fraction: f64 = 1.0;
        let stops = &self.stops;
        let mut refs = stops.refs.lock().unwrap_or_else(|e| e.into_inner());
        for (edge, r) in stops.edges.iter().zip(refs.iter_mut()) {
            if r.covers(edge, q, Some(dq)) {
                continue;
            }
            let mut rates = Some([0.0; 2]);
            for sp in &stops.points[edge.points.clone()] {
                let vecs = |x: &[f64]| {
                    sp.maps
                        .each_ref()
                        .map(|m| crate::contact::surface::eval_map(m, x))
                };
                let [a, b, t] = vecs(q);
                let [da, db_, dt] = vecs(dq);
                let raw0 = crate::crease::theta(&a, &b, &t);
                let gap = if raw0 > std::f64::consts::PI {
                    std::f64::consts::TAU - raw0
                } else {
                    raw0
                };
                rates = both(rates, allowance(&[a, b, t], &sp.l1, gap, self.flat_width));
                let keep = (super::ccd::MIN_SEPARATION * gap).min(self.flat_width);
                fraction = stop_fraction([a, b, t], [da, db_, dt], raw0, gap, keep, fraction);
                if fraction == 0.0 {
                    return 0.0;
                }
            }
            r.set(edge, q, rates);
        }
        fraction
    }

    /// The crease stops at a step start (slots `q`, rates `v`): keep the
    /// stiffness of each point inside its barrier (the crease spring's
    /// where it has none), clear the others'; returns whether a point is
    /// within twice the stop's width of flat.
    pub(super) fn stops_at_step_start(&mut self, asm: &Assembler, q: &[f64], v: &[f64]) -> bool {
        let w = self.flat_width;
        let stops = &mut self.stops;
        stops.start_q.clear();
        stops.start_q.extend_from_slice(q);
        stops.start_v.clear();
        stops.start_v.extend_from_slice(v);
        let kappas = stops.kappas.get_mut().unwrap_or_else(|e| e.into_inner());
        kappas.resize(stops.points.len(), UNSET);
        let mut near = false;
        for (sp, kappa) in stops.points.iter().zip(kappas.iter_mut()) {
            let [a, b, t] = sp
                .maps
                .each_ref()
                .map(|m| crate::contact::surface::eval_map(m, q));
            let g = flat_gap(&a, &b, &t).0;
            near |= g < 2.0 * w;
            if g >= w {
                *kappa = UNSET;
            } else if *kappa == UNSET {
                *kappa = sp.spring(asm);
            }
        }
        near
    }

    /// The barrier stiffness (N m/rad) a stop point outside its barrier at
    /// the step start takes for the step: the crease spring's share `k`,
    /// or enough to stop its approach at the step start within the width
    /// as a pair's is ([`speed_stiffness`]: the kinetic energy `I g_dot^2 /
    /// 2` stopped at `b(g) = PAIR_SPEED_DIVISOR w^2 / 2`, about 4 % of the
    /// width), `g_dot` its gap's rate and `I = 1 / sum_s |dg/dx_s|^2 / m_s`
    /// its inertia with the mass matrix's diagonal `m_s` over the free
    /// slots `s` its vectors read. A crease's facets bend and ring along it
    /// (a held input's jump sets them ringing): a point between the crease
    /// ends can reach flat at hundreds of radians a second, which the crease
    /// spring's stiffness would stop only at a gap crushed to round-off.
    /// Set while the point's barrier energy is zero and kept while it is
    /// inside, the stiffness changes no energy.
    fn stop_stiffness(&self, asm: &Assembler, sp: &StopPoint) -> f64 {
        let k = sp.spring(asm);
        let (q, v) = (&self.stops.start_q, &self.stops.start_v);
        if q.len() != asm.n_dofs() || v.len() != q.len() {
            return k;
        }
        let eval = |x: &[f64]| {
            sp.maps
                .each_ref()
                .map(|m| crate::contact::surface::eval_map(m, x))
        };
        let [a, b, t] = eval(q);
        let (_, sign) = flat_gap(&a, &b, &t);
        let d = crate::crease::theta_derivatives(&a, &b, &t, false);
        let rates = eval(v);
        let g_dot: f64 = sign * (0..3).map(|i| d.grad[i].dot(&rates[i])).sum::<f64>();
        let approach = (-g_dot).max(0.0);
        if approach == 0.0 {
            return k;
        }
        // dg/dx_s, summed over the three maps by slot.
        let mut by_slot: Vec<(usize, Vector3<f64>)> = sp
            .maps
            .iter()
            .zip(&d.grad)
            .flat_map(|(m, gr)| m.iter().map(move |&(s, c)| (s, gr * (sign * c))))
            .collect();
        by_slot.sort_by_key(|&(s, _)| s);
        let mut inverse = 0.0;
        let mut i = 0;
        while i < by_slot.len() {
            let s = by_slot[i].0;
            let mut j = Vector3::zeros();
            while i < by_slot.len() && by_slot[i].0 == s {
                j += by_slot[i].1;
                i += 1;
            }
            let m = asm.slot_mass(s);
            if asm.free[3 * s] != crate::assembly::FIXED && m > 0.0 {
                inverse += j.norm_squared() / m;
            }
        }
        if inverse > 0.0 {
            speed_stiffness(k, 1.0 / inverse, approach, self.flat_width)
        } else {
            k
        }
    }

    /// Add a 9x9 matrix over the crease vectors `(a, b, t)` to `batch`.
    fn scatter_maps_matrix(
        &self,
        maps: &[crate::contact::surface::VertexMap; 3],
        h: &SMatrix<f64, 9, 9>,
        batch: &mut MatrixBatch,
    ) {
        batch.add_mapped(&maps.each_ref(), h.as_slice());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::XorShift;

    /// A stop's fraction of a move keeps the point on its side of flat at its
    /// end and at every halving of it down to the turn bound, where a line
    /// search may step back to: near flat, moves whose end is on the right
    /// side but whose middle is past flat (the angle is not monotone along
    /// them) are cut. The endpoint test alone, as it was, let flat-folder's
    /// Squirrel fold two creases past flat in the middle of a correction.
    #[test]
    fn stop_fraction_keeps_its_halvings_on_the_side() {
        let mut rng = XorShift(53);
        let mut v = |s: f64| Vector3::new(rng.range(-s, s), rng.range(-s, s), rng.range(-s, s));
        let (mut cut, mut endpoint_only_wrong) = (0, 0);
        for i in 0..20000 {
            let x = [v(1.0), v(1.0), v(1.0)];
            let scale = [0.3, 1.0, 3.0][i % 3];
            let dx = [v(scale), v(scale), v(scale)];
            let raw0 = crate::crease::theta(&x[0], &x[1], &x[2]);
            let gap = flat_gap(&x[0], &x[1], &x[2]).0;
            let keep = (0.1 * gap).min(0.01);
            let room = (gap - keep).min(1.0);
            let at = |alpha: f64| [0, 1, 2].map(|k| x[k] + dx[k] * alpha);
            let clear = |alpha: f64| {
                let [a, b, t] = at(alpha);
                (crate::crease::theta(&a, &b, &t) - raw0).abs() < std::f64::consts::PI
                    && flat_gap(&a, &b, &t).0 >= keep
            };
            let bounded = |alpha: f64| stop_turn_bound(x, dx.map(|d| d * alpha)) < room;
            let f = stop_fraction(x, dx, raw0, gap, keep, 1.0);
            let mut alpha = f;
            while alpha > 0.0 && !bounded(alpha) {
                assert!(clear(alpha), "case {i}: {alpha} of {f} past flat");
                alpha *= 0.5;
            }
            if f < 1.0 {
                cut += 1;
            }
            // The endpoint-only rule: halve until the end is clear.
            let mut g = 1.0;
            while !bounded(g) && !clear(g) && g > 1e-18 {
                g *= 0.5;
            }
            let mut alpha = g;
            while alpha > 1e-18 && !bounded(alpha) {
                if !clear(alpha) {
                    endpoint_only_wrong += 1;
                    break;
                }
                alpha *= 0.5;
            }
        }
        assert!(cut > 1000, "moves were cut ({cut})");
        // A move that is not finite is no move.
        let x = [Vector3::x(), Vector3::y(), Vector3::z()];
        let mut dx = [Vector3::zeros(); 3];
        dx[1].x = f64::NAN;
        assert_eq!(stop_fraction(x, dx, 1.0, 0.5, 0.05, 1.0), 0.0);
        assert!(
            endpoint_only_wrong > 0,
            "some moves pass flat in the middle only ({endpoint_only_wrong})"
        );
    }

    /// Moves of the slots within an allowance's rates keep the point at
    /// least the width from flat all along them: each vector moved by the
    /// most its map lets it (`l1` position and gradient sums times the
    /// moves), in random directions.
    #[test]
    fn moves_within_the_allowance_keep_the_point_clear() {
        let mut rng = XorShift(29);
        let mut checked = 0;
        for i in 0..4000 {
            let mut v = |s: f64| Vector3::new(rng.range(-s, s), rng.range(-s, s), rng.range(-s, s));
            let x = [v(1.0), v(1.0), v(1.0)];
            let mut l1 = [[0.0; 2]; 3];
            for sums in &mut l1 {
                *sums = [rng.range(0.0, 6.0), rng.range(0.0, 0.1)];
            }
            let gap = flat_gap(&x[0], &x[1], &x[2]).0;
            let width = [1e-3, 0.05, 0.3][i % 3];
            let Some(rates) = allowance(&x, &l1, gap, width) else {
                continue;
            };
            // Moves using up a random share of the allowance, split at random.
            let share = rng.range(0.0, 1.0);
            let split = rng.uniform();
            let (dp, dg) = (share * split / rates[0], share * (1.0 - split) / rates[1]);
            let dx: [Vector3<f64>; 3] = std::array::from_fn(|k| {
                let dir = Vector3::new(
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                );
                dir.normalize() * (l1[k][0] * dp + l1[k][1] * dg)
            });
            let raw0 = crate::crease::theta(&x[0], &x[1], &x[2]);
            for k in 1..=20 {
                let alpha = k as f64 / 20.0;
                let [a, b, t] = [0, 1, 2].map(|j| x[j] + dx[j] * alpha);
                let raw = crate::crease::theta(&a, &b, &t);
                assert!(
                    (raw - raw0).abs() < 1.0 + 1e-12,
                    "case {i}: turned {raw0} -> {raw}"
                );
                assert!(
                    flat_gap(&a, &b, &t).0 >= width,
                    "case {i}: within the width at {alpha}"
                );
            }
            checked += 1;
        }
        assert!(checked > 2000, "{checked} cases had an allowance");
    }

    /// The bound on a crease stop's turn holds along the whole move: the
    /// gap to flat never changes by more than it, at any fraction.
    #[test]
    fn stop_turn_bound_holds_along_the_move() {
        let mut rng = XorShift(11);
        let mut v = |s: f64| Vector3::new(rng.range(-s, s), rng.range(-s, s), rng.range(-s, s));
        let mut tight = 0;
        for i in 0..2000 {
            let x = [v(1.0), v(1.0), v(1.0)];
            let scale = [1e-3, 1e-2, 0.1, 0.5][i % 4];
            let dx = [v(scale), v(scale), v(scale)];
            let bound = stop_turn_bound(x, dx);
            let g0 = flat_gap(&x[0], &x[1], &x[2]).0;
            for k in 1..=50 {
                let alpha = k as f64 / 50.0;
                let [a, b, t] = [0, 1, 2].map(|i| x[i] + dx[i] * alpha);
                let g = flat_gap(&a, &b, &t).0;
                assert!(
                    (g - g0).abs() <= bound + 1e-12,
                    "gap {g0} -> {g} at {alpha}, bound {bound}"
                );
            }
            if bound < 0.5 {
                tight += 1;
            }
        }
        assert!(
            tight > 500,
            "the bound is informative ({tight} of 2000 below 0.5)"
        );
    }
}
