//! Global assembly: the sparsity pattern and scatter maps built once, then
//! residual forces, energies and the combined matrix
//! `k K + m M + c C` (exactly what an implicit integrator's Newton step
//! needs) assembled without allocation per call.
//!
//! Forces come from force terms ([`ForceTerm`], in `assembly/terms.rs`):
//! shell elements and crease springs always; damping (Rayleigh
//! `alpha M + beta K`, crease dashpots) only when its coefficients are
//! non-zero; terms from outside through [`Assembler::with_terms`], and
//! barrier terms (contact) through [`Assembler::add_barrier`]. Gravity is a constant force computed once.

mod errors;
mod terms;

pub use errors::{BuildError, EvalError, MemoryError};
pub use terms::{BarrierTerm, ForceTerm};

use crate::dofs::{Combo, DofLayout, SlotKind};
use crate::element::{ElemVec, ElementOptions, ShellElement};
use crate::ids::{EdgeId, VertexId};
use crate::material::Material;
use crate::mesh::{EdgeKind, Mesh};
use crate::rigid::RigidModes;
use crate::solver::LowRank;
use nalgebra::{SMatrix, Vector2, Vector3};

/// Marker for "not a free scalar".
pub const FIXED: usize = usize::MAX;

/// One rotational spring at one end of a crease edge (MATH.md section 5).
#[derive(Clone, Debug)]
pub struct CreaseEnd {
    /// Mesh edge.
    pub edge: EdgeId,
    /// Crease length share of this end (half the edge length), m.
    pub length: f64,
    /// Gradient into the facet to the right of `t`, into the left facet, and
    /// the crease tangent: `[a, b, t]`.
    pub combos: [Combo; 3],
}

impl CreaseEnd {
    /// The crease's `[a, b, t]` at positions `q`.
    pub fn vectors(&self, q: &[f64]) -> [Vector3<f64>; 3] {
        [
            self.combos[0].eval(q),
            self.combos[1].eval(q),
            self.combos[2].eval(q),
        ]
    }

    /// `raw` (the angle of `[a, b, t]`) unwrapped nearest `previous`, or an
    /// error naming the crease where the angle is undefined (a facet
    /// gradient along the crease, or no tangent).
    pub fn checked_angle(
        &self,
        raw: f64,
        [a, b, t]: &[Vector3<f64>; 3],
        previous: f64,
    ) -> Result<f64, EvalError> {
        if !raw.is_finite() || a.cross(t).norm() == 0.0 || b.cross(t).norm() == 0.0 {
            return Err(EvalError::UndefinedAngle { edge: self.edge });
        }
        Ok(crate::crease::unwrap(raw, previous))
    }
}

/// Scatter map of one term (element or spring): its distinct slots and,
/// for each ordered pair of them, the offsets of the 3 columns of the 3x3
/// block in the matrix values (`FIXED` when either slot is not free).
#[derive(Clone, Debug, Default)]
struct BlockMap {
    slots: Vec<usize>,
    /// For each local vector: terms as (index into `slots`, coefficient).
    terms: Vec<[(usize, f64); 2]>,
    nterms: Vec<u8>,
    offsets: Vec<[usize; 3]>,
}

/// Physical coefficients the assembly needs (may change between
/// initializations, so kept apart from the topology).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Physics {
    /// Sheet material.
    pub material: Material,
    /// Rotational stiffness per unit crease length of each crease, N/rad
    /// (the rule `k = (L/L*) D` is per unit length too).
    pub crease_k_per_length: f64,
    /// Crease dashpot per unit length, N s/rad.
    pub crease_c_per_length: f64,
    /// Mass-proportional damping (1/s) of the deformation rate: it acts on
    /// the velocity less its rigid-body part, so rigid motion is undamped.
    pub alpha: f64,
    /// Rayleigh beta (s).
    pub beta: f64,
}

/// Inputs of one evaluation.
pub struct State<'a> {
    /// Positions/gradients (all slots).
    pub q: &'a [f64],
    /// Velocities (all slots); only read when damping is on.
    pub v: &'a [f64],
    /// Rest angle theta0 (rad, pi = flat) of each crease end.
    pub theta0: &'a [f64],
    /// Applied moment of each crease end (N m), folding positive.
    pub moment: &'a [f64],
    /// Unwrapped angle of each end at the last accepted state.
    pub theta_prev: &'a [f64],
}

/// Results of one evaluation.
#[derive(Clone, Debug, Default)]
pub struct Evaluation {
    /// Internal force: dU/dq plus damping forces, all slots.
    pub force: Vec<f64>,
    /// Membrane + bending energy.
    pub strain_energy: f64,
    /// Crease spring energy.
    pub crease_energy: f64,
    /// Unwrapped angle theta of every crease end.
    pub theta: Vec<f64>,
    /// Energy of the terms given to [`Assembler::with_terms`] (contact, ...).
    pub term_energy: f64,
    /// Power dissipated by friction (W).
    pub friction_power: f64,
    /// Power dissipated by the contact's normal dashpots (W).
    pub contact_damping_power: f64,
    /// Friction's and the contact dashpots' parts of `force`, all slots
    /// (left empty without contact): their work over a step is the
    /// trapezoidal force times the displacement, as the integrator's own
    /// energy balance has it.
    pub dissipative_force: DissipativeForce,
    /// Pairs within a barrier's reach (contact): Newton's line search
    /// watches iterates with any.
    pub barrier_pairs: usize,
    /// The wrench the sheet exerts on each rigid obstacle (force, then
    /// moment about the obstacle's origin; N, N m, world axes), from the
    /// obstacle term (empty without obstacles).
    pub obstacle_wrenches: Vec<[f64; 6]>,
}

/// Dissipative parts of an evaluation's internal force (N, all slots),
/// and what the contact forces do on moving obstacles.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DissipativeForce {
    /// Friction.
    pub friction: Vec<f64>,
    /// Normal dashpots.
    pub damping: Vec<f64>,
    /// The power of the sheet's contact forces on moving obstacles.
    #[serde(default)]
    pub obstacles: ObstaclePower,
}

/// What the contact forces on moving obstacles do on them (W): all of
/// them, and friction and the dashpots alone (zero for fixed obstacles).
/// The sheet gets minus the first; the friction and dashpot forces
/// dissipate their power on the sheet less these.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ObstaclePower {
    /// All forces'.
    pub total: f64,
    /// Friction's.
    pub friction: f64,
    /// The normal dashpots'.
    pub damping: f64,
}

impl DissipativeForce {
    /// Zeroed vectors of `n` slots' values.
    pub fn zeroed(&mut self, n: usize) {
        for v in [&mut self.friction, &mut self.damping] {
            v.clear();
            v.resize(n, 0.0);
        }
    }

    /// Work of these forces (at the step start) and `end`'s (at its end)
    /// over the displacement `q1 - q0`, by the trapezoidal rule:
    /// (friction, dashpots). An empty side counts as zero.
    pub fn work_to(&self, end: &DissipativeForce, q0: &[f64], q1: &[f64]) -> (f64, f64) {
        let w = |a: &[f64], b: &[f64]| -> f64 {
            (0..q0.len())
                .map(|i| {
                    0.5 * (a.get(i).copied().unwrap_or(0.0) + b.get(i).copied().unwrap_or(0.0))
                        * (q1[i] - q0[i])
                })
                .sum()
        };
        (
            w(&self.friction, &end.friction),
            w(&self.damping, &end.damping),
        )
    }

    /// The work of the contact forces on moving obstacles over a step of
    /// `h` seconds from these (at its start) to `end`'s, by the
    /// trapezoidal rule.
    pub fn obstacle_work_to(&self, end: &DissipativeForce, h: f64) -> ObstaclePower {
        let (a, b) = (&self.obstacles, &end.obstacles);
        ObstaclePower {
            total: 0.5 * (a.total + b.total) * h,
            friction: 0.5 * (a.friction + b.friction) * h,
            damping: 0.5 * (a.damping + b.damping) * h,
        }
    }
}

/// Coefficients of the requested matrix `k K + m M + c C`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatrixCoeffs {
    /// Stiffness coefficient.
    pub k: f64,
    /// Mass coefficient.
    pub m: f64,
    /// Damping coefficient.
    pub c: f64,
}

/// The assembled system of one mesh.
pub struct Assembler {
    /// DOF layout.
    pub layout: DofLayout,
    /// One shell element per facet.
    pub elements: Vec<ShellElement>,
    /// Crease springs.
    pub creases: Vec<CreaseEnd>,
    /// Free index of each scalar DOF, or [`FIXED`].
    pub free: Vec<usize>,
    /// Number of free scalars.
    pub n_free: usize,
    /// CSC column pointers of the free-DOF matrix pattern.
    pub col_ptr: Vec<usize>,
    /// CSC row indices (sorted per column; both triangles).
    pub row_idx: Vec<usize>,
    face_maps: Vec<BlockMap>,
    crease_maps: Vec<BlockMap>,
    /// Slot-level pattern (all slots, CSR, sorted rows): which slots couple.
    slot_ptr: Vec<usize>,
    slot_idx: Vec<usize>,
    /// Which slots are supported or prescribed.
    is_fixed: Vec<bool>,
    /// Slot pairs force terms asked for (sorted, a <= b).
    extra_pairs: Vec<(usize, usize)>,
    /// Mass matrix by slots, compressed rows: slot `a`'s entries (other
    /// slot, coefficient of I3) are `mass_entries[mass_ptr[a]..mass_ptr[a + 1]]`.
    mass_ptr: Vec<usize>,
    mass_entries: Vec<(usize, f64)>,
    mass_values: Vec<f64>,
    /// The sheet's rigid-body modes (what mass damping leaves alone).
    pub rigid: RigidModes,
    /// Physics in force.
    pub physics: Physics,
    /// The force terms, in evaluation order.
    terms: Vec<Box<dyn ForceTerm>>,
    /// The barrier terms (contact), evaluated after `terms`.
    barriers: Vec<Box<dyn BarrierTerm>>,
    /// Whether the iteration matrix takes the shell's membrane geometric
    /// stiffness from the step start ([`Assembler::lag_membrane_stiffness`]).
    lag_membrane: bool,
    /// Identifies the matrix pattern (see [`Assembler::pattern_id`]).
    pattern_id: u64,
}

/// Where a slot block sits in the iteration matrix's values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlockPosition {
    /// A slot is fixed: the block is not in the matrix.
    Fixed,
    /// The pattern lacks the block.
    Missing,
    /// Rows from `offset` in the free columns `column..column + 3`.
    At { column: usize, offset: usize },
}

/// The last pattern id given out (ids are unique in the process).
static PATTERN_IDS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

impl Assembler {
    /// Build layout, elements, springs and the pattern. `fixed_slots` are
    /// supported or prescribed slots (not unknowns).
    pub fn new(
        mesh: &Mesh,
        physics: Physics,
        element: ElementOptions,
        fixed_slots: &[usize],
    ) -> Result<Assembler, BuildError> {
        Self::with_terms(mesh, physics, element, fixed_slots, Vec::new())
    }

    /// Like [`Assembler::new`], with more force terms after the built-in
    /// ones; the slot pairs each declares ([`ForceTerm::pattern`]) join the
    /// matrix pattern.
    pub fn with_terms(
        mesh: &Mesh,
        physics: Physics,
        element: ElementOptions,
        fixed_slots: &[usize],
        extra: Vec<Box<dyn ForceTerm>>,
    ) -> Result<Assembler, BuildError> {
        let layout = DofLayout::new(mesh);
        let elements = mesh
            .facet_ids()
            .zip(mesh.triangles())
            .map(|(f, &[a, b, c])| {
                ShellElement::with_sides(
                    [mesh.coord(a), mesh.coord(b), mesh.coord(c)],
                    layout.side_vectors(mesh, f),
                    element,
                )
                .map_err(|source| BuildError::Element { face: f, source })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let creases = crease_ends(mesh, &layout);

        let n_slots = layout.n_slots();
        let mut is_fixed = vec![false; n_slots];
        for &s in fixed_slots {
            is_fixed[s] = true;
        }
        let mut free = vec![FIXED; 3 * n_slots];
        let mut n_free = 0;
        for s in 0..n_slots {
            if !is_fixed[s] {
                for c in 0..3 {
                    free[3 * s + c] = n_free;
                    n_free += 1;
                }
            }
        }
        let block_map_of = |combos: &[Combo]| {
            let mut slots: Vec<usize> = Vec::new();
            let mut terms = Vec::new();
            let mut nterms = Vec::new();
            for cb in combos {
                let mut t = [(0usize, 0.0); 2];
                for (k, (s, c)) in cb.terms().enumerate() {
                    let i = slots.iter().position(|&x| x == s).unwrap_or_else(|| {
                        slots.push(s);
                        slots.len() - 1
                    });
                    t[k] = (i, c);
                }
                terms.push(t);
                nterms.push(cb.len);
            }
            BlockMap {
                slots,
                terms,
                nterms,
                offsets: Vec::new(),
            }
        };
        let face_maps: Vec<BlockMap> = layout.local.iter().map(|l| block_map_of(l)).collect();
        let crease_maps: Vec<BlockMap> = creases.iter().map(|c| block_map_of(&c.combos)).collect();
        let mut pairs: Vec<(usize, usize)> = Vec::new();
        for t in &extra {
            for (a, b) in t.pattern(&layout) {
                if a >= n_slots || b >= n_slots {
                    return Err(BuildError::Pattern {
                        term: t.name().to_string(),
                        pair: (a, b),
                        slots: n_slots,
                    });
                }
                pairs.push((a.min(b), a.max(b)));
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        let mut asm = Assembler {
            layout,
            elements,
            creases,
            free,
            n_free,
            col_ptr: Vec::new(),
            row_idx: Vec::new(),
            face_maps,
            crease_maps,
            slot_ptr: Vec::new(),
            slot_idx: Vec::new(),
            is_fixed,
            extra_pairs: pairs,
            mass_ptr: vec![0],
            mass_entries: Vec::new(),
            mass_values: Vec::new(),
            rigid: RigidModes::default(),
            physics,
            terms: terms::built_in().into_iter().chain(extra).collect(),
            barriers: Vec::new(),
            lag_membrane: false,
            pattern_id: 0,
        };
        asm.build_pattern();
        asm.set_physics(physics);
        Ok(asm)
    }

    /// The slot-level and free-DOF patterns and the scatter offsets, from
    /// the facets, the creases and `extra_pairs`.
    fn build_pattern(&mut self) {
        let n_slots = self.layout.n_slots();
        let is_fixed = &self.is_fixed;
        let free = &self.free;
        // Slot-level adjacency (CSR, sorted, all slots) -> scalar pattern
        // over free DOFs. Sorting each slot's neighbour list keeps this
        // O(n log n) in time and O(n) in memory.
        let mut count = vec![0usize; n_slots + 1];
        for bm in self.face_maps.iter().chain(self.crease_maps.iter()) {
            for &a in &bm.slots {
                count[a + 1] += bm.slots.len();
            }
        }
        for &(a, b) in &self.extra_pairs {
            count[a + 1] += 2;
            count[b + 1] += 2;
        }
        for s in 0..n_slots {
            count[s + 1] += count[s];
        }
        let mut fill = count.clone();
        let mut raw = vec![0usize; count[n_slots]];
        for bm in self.face_maps.iter().chain(self.crease_maps.iter()) {
            for &a in &bm.slots {
                for &b in &bm.slots {
                    raw[fill[a]] = b;
                    fill[a] += 1;
                }
            }
        }
        for &(a, b) in &self.extra_pairs {
            for (x, y) in [(a, b), (b, a), (a, a), (b, b)] {
                raw[fill[x]] = y;
                fill[x] += 1;
            }
        }
        let mut slot_ptr = Vec::with_capacity(n_slots + 1);
        slot_ptr.push(0);
        let mut slot_idx = Vec::new();
        for s in 0..n_slots {
            let row = &mut raw[count[s]..count[s + 1]];
            row.sort_unstable();
            let mut last = usize::MAX;
            for &b in row.iter() {
                if b != last {
                    slot_idx.push(b);
                    last = b;
                }
            }
            slot_ptr.push(slot_idx.len());
        }
        drop(raw);
        let mut col_ptr = vec![0usize];
        let mut row_idx = Vec::new();
        for sb in 0..n_slots {
            if is_fixed[sb] {
                continue;
            }
            for _cb in 0..3 {
                for &sa in &slot_idx[slot_ptr[sb]..slot_ptr[sb + 1]] {
                    if !is_fixed[sa] {
                        for ca in 0..3 {
                            row_idx.push(free[3 * sa + ca]);
                        }
                    }
                }
                col_ptr.push(row_idx.len());
            }
        }
        let offset = |sa: usize, sb: usize| -> [usize; 3] {
            if is_fixed[sa] || is_fixed[sb] {
                return [FIXED; 3];
            }
            let r0 = free[3 * sa];
            let mut o = [0; 3];
            for (cb, oc) in o.iter_mut().enumerate() {
                let col = free[3 * sb + cb];
                let rows = &row_idx[col_ptr[col]..col_ptr[col + 1]];
                *oc = col_ptr[col] + rows.binary_search(&r0).expect("pattern has the block");
            }
            o
        };
        for bm in self.face_maps.iter_mut().chain(self.crease_maps.iter_mut()) {
            let ns = bm.slots.len();
            bm.offsets = Vec::with_capacity(ns * ns);
            for i in 0..ns {
                for j in 0..ns {
                    bm.offsets.push(offset(bm.slots[i], bm.slots[j]));
                }
            }
        }
        self.col_ptr = col_ptr;
        self.row_idx = row_idx;
        self.slot_ptr = slot_ptr;
        self.slot_idx = slot_idx;
        self.pattern_id = PATTERN_IDS.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
    }

    /// An id of the matrix pattern and the free DOFs' numbering, unique in
    /// the process: positions in the matrix values found under one id hold
    /// while the id is the same (a copy of the assembler keeps it).
    pub fn pattern_id(&self) -> u64 {
        self.pattern_id
    }

    /// Whether slots `a` and `b` couple in the pattern.
    pub fn has_pair(&self, a: usize, b: usize) -> bool {
        self.slot_idx[self.slot_ptr[a]..self.slot_ptr[a + 1]]
            .binary_search(&b)
            .is_ok()
    }

    /// Slot pairs beyond the facets' and creases' own (sorted, `a <= b`):
    /// what force terms asked for. Part of a saved state, so that a
    /// restore factors with the very pattern the run had.
    pub fn extra_pairs(&self) -> &[(usize, usize)] {
        &self.extra_pairs
    }

    /// Make the pattern exactly the built-in one plus `pairs` (rebuilds the
    /// pattern and the mass values; the solver must be rebuilt after).
    pub fn set_extra_pairs(&mut self, mut pairs: Vec<(usize, usize)>) {
        for p in pairs.iter_mut() {
            *p = (p.0.min(p.1), p.0.max(p.1));
        }
        pairs.sort_unstable();
        pairs.dedup();
        if pairs == self.extra_pairs {
            return;
        }
        self.extra_pairs = pairs;
        self.build_pattern();
        self.set_physics(self.physics);
    }

    /// Change the physical coefficients (rebuilds the mass matrix).
    pub fn set_physics(&mut self, physics: Physics) {
        self.physics = physics;
        for el in &mut self.elements {
            el.prepare(&physics.material);
        }
        let n_slots = self.layout.n_slots();
        let rho_h = physics.material.density * physics.material.thickness;
        // Accumulate on the slot pattern, element by element in the order
        // of the terms (each entry sums its contributions in that order).
        let mut mass = vec![0.0; self.slot_idx.len()];
        let mut touched = vec![false; self.slot_idx.len()];
        let mut vals = vec![0.0; self.row_idx.len()];
        let mut pos: Vec<usize> = Vec::new();
        for (f, el) in self.elements.iter().enumerate() {
            let scale = rho_h * el.area();
            let mass_hat = el.mass_hat();
            let bm = &self.face_maps[f];
            let ns = bm.slots.len();
            pos.clear();
            for &sa in &bm.slots {
                let row = &self.slot_idx[self.slot_ptr[sa]..self.slot_ptr[sa + 1]];
                for &sb in &bm.slots {
                    let k = row.binary_search(&sb).expect("slot pattern has the pair");
                    pos.push(self.slot_ptr[sa] + k);
                }
            }
            // i and j index the mass block and both term lists alike.
            #[allow(clippy::needless_range_loop)]
            for i in 0..9 {
                for j in 0..9 {
                    let mij = scale * mass_hat[i][j];
                    for ti in 0..bm.nterms[i] as usize {
                        for tj in 0..bm.nterms[j] as usize {
                            let (a, ca) = bm.terms[i][ti];
                            let (b, cb) = bm.terms[j][tj];
                            let p = pos[a * ns + b];
                            let m = ca * cb * mij;
                            mass[p] += m;
                            touched[p] = true;
                            // The free-DOF matrix: the same sums, in the same order.
                            let off = bm.offsets[a * ns + b];
                            if off[0] != FIXED {
                                for c in 0..3 {
                                    vals[off[c] + c] += m;
                                }
                            }
                        }
                    }
                }
            }
        }
        self.mass_ptr = Vec::with_capacity(n_slots + 1);
        self.mass_ptr.push(0);
        self.mass_entries.clear();
        for a in 0..n_slots {
            for p in self.slot_ptr[a]..self.slot_ptr[a + 1] {
                if touched[p] {
                    self.mass_entries.push((self.slot_idx[p], mass[p]));
                }
            }
            self.mass_ptr.push(self.mass_entries.len());
        }
        self.mass_values = vals;
        let positions: Vec<usize> = self.layout.position_slot.clone();
        let old = std::mem::take(&mut self.rigid);
        self.rigid = RigidModes::new(n_slots, positions, |x, y| self.mass_mul(x, y));
        // The supports (and frames) stay declared: the pattern grows with
        // contact pairs and a restore sets it, the supports do not change.
        self.rigid.keep_constraints(old);
    }

    /// Number of scalar DOFs (free and fixed).
    pub fn n_dofs(&self) -> usize {
        self.layout.n_dofs()
    }

    /// Number of stored matrix entries.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Where each free slot is (its vertex in the reference sheet, `z = 0`),
    /// by block of 3 free scalars: what nested dissection cuts by.
    pub fn free_block_coords(&self, mesh: &Mesh) -> Vec<[f64; 3]> {
        let mut out = vec![[0.0; 3]; self.n_free / 3];
        for (s, &v) in self.layout.slot_vertex.iter().enumerate() {
            let fi = self.free[3 * s];
            if fi != FIXED {
                let x = mesh.coord(v);
                out[fi / 3] = [x.x, x.y, 0.0];
            }
        }
        out
    }

    /// `y = M x` over all slots.
    pub fn mass_mul(&self, x: &[f64], y: &mut [f64]) {
        self.mass_mul_n([x], [y]);
    }

    /// `y_i = M x_i` for `N` vectors in one pass over the mass entries
    /// (mass damping needs `M v` and `M q` at every evaluation).
    pub fn mass_mul_n<const N: usize>(&self, x: [&[f64]; N], mut y: [&mut [f64]; N]) {
        for (a, w) in self.mass_ptr.windows(2).enumerate() {
            let mut acc = [[0.0; 3]; N];
            for &(b, m) in &self.mass_entries[w[0]..w[1]] {
                for (acc, x) in acc.iter_mut().zip(&x) {
                    for c in 0..3 {
                        acc[c] += m * x[3 * b + c];
                    }
                }
            }
            for (acc, y) in acc.iter().zip(y.iter_mut()) {
                y[3 * a..3 * a + 3].copy_from_slice(acc);
            }
        }
    }

    /// Slot `s`'s diagonal mass coefficient (kg, or kg m^2 for a gradient
    /// slot: the coefficient of I3 in the mass matrix).
    pub fn slot_mass(&self, s: usize) -> f64 {
        let row = &self.mass_entries[self.mass_ptr[s]..self.mass_ptr[s + 1]];
        row.iter().find(|&&(b, _)| b == s).map_or(0.0, |&(_, m)| m)
    }

    /// The mass matrix restricted to the free DOFs, in pattern order.
    pub fn mass_values(&self) -> &[f64] {
        &self.mass_values
    }

    /// Whether damping terms are active.
    pub fn has_damping(&self) -> bool {
        let p = &self.physics;
        p.alpha != 0.0 || p.beta != 0.0 || p.crease_c_per_length != 0.0
    }

    /// Evaluate internal forces and energies, and, if `matrix` is given,
    /// write `k K + m M + c C` (free DOFs, pattern order) into it: the
    /// inertia `m M`, then every force term in order (shell, crease springs,
    /// mass damping, then the terms given to [`Assembler::with_terms`]).
    /// Fails (without panicking) on a configuration where a crease angle
    /// is undefined or a value is not finite.
    pub fn evaluate(
        &self,
        st: &State,
        out: &mut Evaluation,
        mut matrix: Option<(&mut [f64], MatrixCoeffs)>,
    ) -> Result<(), EvalError> {
        let n = self.n_dofs();
        out.force.clear();
        out.force.resize(n, 0.0);
        out.theta.clear();
        out.strain_energy = 0.0;
        out.crease_energy = 0.0;
        out.term_energy = 0.0;
        out.friction_power = 0.0;
        out.contact_damping_power = 0.0;
        out.dissipative_force.friction.clear();
        out.dissipative_force.damping.clear();
        out.dissipative_force.obstacles = ObstaclePower::default();
        out.barrier_pairs = 0;
        out.obstacle_wrenches.clear();
        if let Some((vals, co)) = matrix.as_mut() {
            for (v, m) in vals.iter_mut().zip(&self.mass_values) {
                *v = co.m * m;
            }
        }
        for term in self.all_terms() {
            term.add(
                self,
                st,
                out,
                matrix.as_mut().map(|(v, co)| (&mut **v, *co)),
            )?;
        }
        if out.force.iter().any(|x| !x.is_finite())
            || !out.strain_energy.is_finite()
            || !out.term_energy.is_finite()
        {
            return Err(EvalError::NotFinite {
                term: self.non_finite_term(st).map(str::to_string),
            });
        }
        Ok(())
    }

    /// The name of the first force term whose forces or energy at `st` are
    /// not finite, evaluated on its own (for the message of a failed
    /// evaluation: which term, hence which parameters, to look at).
    pub fn non_finite_term(&self, st: &State) -> Option<&str> {
        let mut ev = Evaluation::default();
        for term in self.all_terms() {
            ev.force.clear();
            ev.force.resize(self.n_dofs(), 0.0);
            ev.theta.clear();
            ev.strain_energy = 0.0;
            ev.crease_energy = 0.0;
            ev.term_energy = 0.0;
            let bad = term.add(self, st, &mut ev, None).is_err()
                || ev.force.iter().any(|x| !x.is_finite())
                || !(ev.strain_energy + ev.crease_energy + ev.term_energy).is_finite();
            if bad {
                return Some(term.name());
            }
        }
        None
    }

    /// The dense low-rank part of the iteration matrix at `q` (free DOFs):
    /// what force terms add to `k df/dq + c df/dv` beyond the sparse values
    /// [`Assembler::evaluate`] writes (mass damping's rigid-body
    /// projection). The solver takes it with
    /// [`crate::solver::SparseSolver::set_low_rank`].
    pub fn matrix_low_rank(&self, q: &[f64], co: MatrixCoeffs) -> Option<LowRank> {
        let n = self.n_dofs();
        self.all_terms()
            .filter_map(|t| t.low_rank(self, q, co))
            .map(|lr| {
                let mut u = vec![0.0; self.n_free * lr.rank()];
                for (col, all) in u.chunks_mut(self.n_free).zip(lr.u.chunks(n)) {
                    for (&fi, &x) in self.free.iter().zip(all) {
                        if fi != FIXED {
                            col[fi] = x;
                        }
                    }
                }
                LowRank { u, s: lr.s }
            })
            .reduce(LowRank::join)
    }

    /// The unwrapped angle of every crease end at `q` (each nearest its
    /// `theta_prev`), into `theta`: what [`Assembler::evaluate`] gives as
    /// `theta`, without forces or energies.
    pub fn crease_angles(
        &self,
        q: &[f64],
        theta_prev: &[f64],
        theta: &mut Vec<f64>,
    ) -> Result<(), EvalError> {
        theta.clear();
        for (ce, &prev) in self.creases.iter().zip(theta_prev) {
            let v = ce.vectors(q);
            theta.push(ce.checked_angle(crate::crease::theta(&v[0], &v[1], &v[2]), &v, prev)?);
        }
        Ok(())
    }

    /// Every force term in evaluation order: the plain ones, then the
    /// barriers.
    fn all_terms(&self) -> impl Iterator<Item = &dyn ForceTerm> {
        let barriers = self.barriers.iter().map(|b| &**b as &dyn ForceTerm);
        self.terms.iter().map(|t| &**t).chain(barriers)
    }

    /// The barrier terms' energy at `st` (J), evaluating them alone: the
    /// `term_energy` of [`Assembler::evaluate`], summed in the same order.
    pub fn barrier_energy(&self, st: &State) -> Result<f64, EvalError> {
        let mut out = Evaluation {
            force: vec![0.0; self.n_dofs()],
            ..Default::default()
        };
        for term in &self.barriers {
            term.add(self, st, &mut out, None)?;
        }
        Ok(out.term_energy)
    }

    /// Whether a barrier term reports powers the stepper integrates
    /// ([`BarrierTerm::reports_power`]).
    pub fn reports_power(&self) -> bool {
        self.barriers.iter().any(|t| t.reports_power())
    }

    /// Whether a barrier term's dissipative forces may be nonzero in this
    /// step ([`BarrierTerm::dissipates_this_step`]): the step's end is then
    /// evaluated in full, else they are zero there.
    pub fn dissipates_this_step(&self) -> bool {
        self.barriers
            .iter()
            .any(|t| t.reports_power() && t.dissipates_this_step())
    }

    /// Give every force term the accepted state before a time step (its
    /// per-step hook: a broad phase, caches).
    /// Returns whether the pattern grew (the solver's symbolic analysis
    /// must then be redone).
    pub fn before_step(&mut self, q: &[f64], v: &[f64]) -> bool {
        let mut terms = std::mem::take(&mut self.terms);
        let mut barriers = std::mem::take(&mut self.barriers);
        let mut wanted = Vec::new();
        for t in terms.iter_mut() {
            wanted.extend(t.before_step(self, q, v));
        }
        for t in barriers.iter_mut() {
            wanted.extend(t.before_step(self, q, v));
        }
        self.terms = terms;
        self.barriers = barriers;
        wanted.retain(|&(a, b)| !(self.has_pair(a, b) || self.is_fixed[a] || self.is_fixed[b]));
        if wanted.is_empty() {
            return false;
        }
        let mut pairs = self.extra_pairs.clone();
        pairs.extend(wanted);
        self.set_extra_pairs(pairs);
        true
    }

    /// Take the iteration matrix's membrane geometric stiffness from the
    /// state at each step start (see [`crate::element::ShellElement::eval_lagged`])
    /// instead of from the iterate: the implicit stepper's modified Newton
    /// sets it; without it (the default: statics, explicit stepping, full
    /// Newton) the matrix is the exact tangent.
    pub fn lag_membrane_stiffness(&mut self, on: bool) {
        self.lag_membrane = on;
    }

    /// Whether [`Assembler::lag_membrane_stiffness`] is on.
    pub fn lags_membrane_stiffness(&self) -> bool {
        self.lag_membrane
    }

    /// Let every term take its lagged data from the step start `(q, v)`
    /// (as in [`Assembler::before_step`], without growing the pattern).
    pub fn lag(&mut self, q: &[f64], v: &[f64]) {
        let mut terms = std::mem::take(&mut self.terms);
        let mut barriers = std::mem::take(&mut self.barriers);
        for t in terms.iter_mut() {
            t.lag(self, q, v);
        }
        for t in barriers.iter_mut() {
            t.lag(self, q, v);
        }
        self.terms = terms;
        self.barriers = barriers;
    }

    /// The largest fraction in (0, 1] of the move `q -> q + dq` every
    /// barrier term admits (contact: free of collisions).
    pub fn max_step_fraction(&self, q: &[f64], dq: &[f64]) -> f64 {
        self.barriers
            .iter()
            .map(|t| t.max_step_fraction(self, q, dq))
            .fold(1.0, f64::min)
    }

    /// [`Assembler::max_step_fraction`] of a move from the step start (see
    /// [`BarrierTerm::max_motion_fraction`]): the predictors'.
    pub fn max_motion_fraction(&self, q: &[f64], dq: &[f64]) -> f64 {
        self.barriers
            .iter()
            .map(|t| t.max_motion_fraction(self, q, dq))
            .fold(1.0, f64::min)
    }

    /// Place the moving bodies of the barrier terms (moving obstacles):
    /// at the step start and at its end ([`BarrierTerm::place`]).
    pub fn place_bodies(&mut self, start: &[crate::frame::Motion], end: &[crate::frame::Motion]) {
        for t in self.barriers.iter_mut() {
            t.place(start, end);
        }
    }

    /// Whether any barrier term has moving bodies.
    pub fn moves_bodies(&self) -> bool {
        self.barriers.iter().any(|t| t.moves())
    }

    /// The largest fraction in (0, 1] of a Newton correction `q -> q + dq`
    /// (velocities moving by `dv_dq dq` from `v`) every barrier term admits
    /// by [`BarrierTerm::max_correction_fraction`]: where a term's stiffness
    /// changes along the correction (the iteration matrix is then formed
    /// anew where it stops).
    pub fn max_correction_fraction(&self, q: &[f64], v: &[f64], dq: &[f64], dv_dq: f64) -> f64 {
        self.barriers
            .iter()
            .map(|t| t.max_correction_fraction(self, q, v, dq, dv_dq))
            .fold(1.0, f64::min)
    }

    /// Whether a barrier term limits this step (contact in touch): the
    /// stepper then backtracks corrections that raise the residual.
    pub fn limits_steps(&self) -> bool {
        self.barriers.iter().any(|t| t.limits_steps())
    }

    /// The rigid obstacles' term, if the assembler has one.
    pub fn obstacles(&self) -> Option<&crate::contact::ObstacleTerm> {
        self.barriers.iter().find_map(|t| t.as_obstacles())
    }

    /// The self-contact term, if the assembler has one.
    pub fn contact(&self) -> Option<&crate::contact::ContactTerm> {
        self.barriers.iter().find_map(|t| t.as_contact())
    }

    /// The viscous force at `(q, v)` (all DOFs; [`ForceTerm::viscous_force`]
    /// of every term): mass and stiffness damping, crease dashpots.
    pub fn viscous_force(&self, q: &[f64], v: &[f64], out: &mut Vec<f64>) {
        out.clear();
        out.resize(self.n_dofs(), 0.0);
        for t in self.all_terms() {
            t.viscous_force(self, q, v, out);
        }
    }

    /// What each force term carries from step to step, in evaluation
    /// order: nothing for a plain term, [`BarrierTerm::memory`] for a
    /// barrier.
    pub fn term_memory(&self) -> Vec<Vec<f64>> {
        let plain = self.terms.iter().map(|_| Vec::new());
        plain
            .chain(self.barriers.iter().map(|t| t.memory()))
            .collect()
    }

    /// Whether `memory` (untrusted) fits the force terms: one list per
    /// term, each one the term could have given (empty for a plain term,
    /// [`BarrierTerm::check_memory`] for a barrier); empty: every term as
    /// built.
    pub fn check_term_memory(&self, memory: &[Vec<f64>]) -> Result<(), MemoryError> {
        let n = self.terms.len() + self.barriers.len();
        if !memory.is_empty() && memory.len() != n {
            return Err(MemoryError::Count {
                lists: memory.len(),
                terms: n,
            });
        }
        let (plain, barrier) = memory.split_at(memory.len().min(self.terms.len()));
        let checks = self
            .terms
            .iter()
            .zip(plain)
            .map(|(t, m)| (t.name(), terms::no_memory(m)));
        let checks = checks.chain(
            self.barriers
                .iter()
                .zip(barrier)
                .map(|(t, m)| (t.name(), t.check_memory(m))),
        );
        for (index, (name, check)) in checks.enumerate() {
            check.map_err(|e| MemoryError::Term {
                index,
                name: name.to_string(),
                reason: Box::new(e),
            })?;
        }
        Ok(())
    }

    /// Hand each barrier term back its memory (`memory` as from
    /// [`Assembler::term_memory`]; empty: every term as built); checked
    /// first, so that a refused memory changes nothing.
    pub fn restore_term_memory(&mut self, memory: &[Vec<f64>]) -> Result<(), MemoryError> {
        self.check_term_memory(memory)?;
        let offset = self.terms.len();
        for (k, t) in self.barriers.iter_mut().enumerate() {
            t.restore_memory(memory.get(offset + k).map_or(&[][..], |m| &m[..]))?;
        }
        Ok(())
    }

    /// Append a barrier term built after the assembler (it needs the
    /// layout and elements, as contact does); its declared pattern joins.
    pub fn add_barrier(&mut self, term: Box<dyn BarrierTerm>) {
        let mut pairs = self.extra_pairs.clone();
        pairs.extend(term.pattern(&self.layout));
        self.barriers.push(term);
        self.set_extra_pairs(pairs);
    }

    /// Names of the force terms, in evaluation order.
    pub fn term_names(&self) -> Vec<&str> {
        self.all_terms().map(|t| t.name()).collect()
    }

    /// Add the 3x3 block `k` at slots (a, b) of the free-DOF matrix values
    /// (nothing when either slot is fixed). For loads outside the elements.
    /// Panics when the pair is not in the pattern.
    pub fn add_block(&self, a: usize, b: usize, k: &nalgebra::Matrix3<f64>, vals: &mut [f64]) {
        assert!(self.try_add_block(a, b, k, vals), "block in pattern");
    }

    /// [`Assembler::add_block`] that leaves out a block not in the pattern
    /// and says so (false): an iteration matrix may lack couplings that
    /// appeared within a step (the pattern grows before the next one).
    pub fn try_add_block(
        &self,
        a: usize,
        b: usize,
        k: &nalgebra::Matrix3<f64>,
        vals: &mut [f64],
    ) -> bool {
        match self.block_position(a, b) {
            BlockPosition::Fixed => true,
            BlockPosition::Missing => false,
            at => {
                self.add_block_at(at, |x, y| k[(x, y)], vals);
                true
            }
        }
    }

    /// Where the block of slots `a` (rows) and `b` (columns) sits in the
    /// matrix values (valid while [`Assembler::pattern_id`] is the same).
    pub fn block_position(&self, a: usize, b: usize) -> BlockPosition {
        if self.free[3 * a] == FIXED || self.free[3 * b] == FIXED {
            return BlockPosition::Fixed;
        }
        let r0 = self.free[3 * a];
        // The three columns of a slot hold the same rows: one search.
        let c0 = self.free[3 * b];
        let rows = &self.row_idx[self.col_ptr[c0]..self.col_ptr[c0 + 1]];
        match rows.binary_search(&r0) {
            Ok(k0) => BlockPosition::At {
                column: c0,
                offset: k0,
            },
            Err(_) => BlockPosition::Missing,
        }
    }

    /// Add the block `k(x, y)` at a position [`Assembler::block_position`]
    /// found (nothing where it is fixed or missing).
    pub fn add_block_at(
        &self,
        at: BlockPosition,
        k: impl Fn(usize, usize) -> f64,
        vals: &mut [f64],
    ) {
        if let BlockPosition::At { column, offset } = at {
            for y in 0..3 {
                let start = self.col_ptr[column + y] + offset;
                for x in 0..3 {
                    vals[start + x] += k(x, y);
                }
            }
        }
    }

    /// Strain energy (membrane + bending) and crease spring energy at `q`,
    /// the crease ends at the angles `theta` with rest angles `theta0`: the
    /// energies of [`Assembler::evaluate`] without its forces.
    pub fn energies(&self, q: &[f64], theta: &[f64], theta0: &[f64]) -> (f64, f64) {
        let strain = self.facet_strain_energies(q).iter().sum();
        let k = self.physics.crease_k_per_length;
        let crease = self
            .creases
            .iter()
            .zip(theta.iter().zip(theta0))
            .map(|(ce, (&th, &th0))| 0.5 * k * ce.length * (th - th0).powi(2))
            .sum();
        (strain, crease)
    }

    /// Membrane + bending energy of each facet (J) at slot vector `q`, in
    /// triangle order: the per-facet split of `Evaluation::strain_energy`.
    pub fn facet_strain_energies(&self, q: &[f64]) -> Vec<f64> {
        self.elements
            .iter()
            .zip(&self.layout.local)
            .map(|(el, map)| {
                let e = el.energy(&self.physics.material, &local_vector(map, q));
                e.membrane + e.bending
            })
            .collect()
    }

    /// Position slots and their vertices.
    pub fn position_slot(&self, v: VertexId) -> usize {
        self.layout.position_slot[v.index()]
    }

    /// Characteristic size of each scalar DOF for Newton's norms: `length`
    /// for positions, 1 for gradients.
    pub fn scales(&self, length: f64) -> Vec<f64> {
        let mut s = vec![1.0; self.n_dofs()];
        for (slot, kind) in self.layout.slot_kind.iter().enumerate() {
            if *kind == SlotKind::Position {
                for c in 0..3 {
                    s[3 * slot + c] = length;
                }
            }
        }
        s
    }
}

/// Characteristic size of each scalar DOF for the local error of a time
/// step: the surface displacement an error in it makes, measured against the
/// sheet size `length`. Positions count as they are (`length`); an error
/// `d` in a gradient moves the surface by about `d w` within the facets
/// around its vertex, so gradients count at `length / w` (at least 1), `w`
/// the mean facet size `sqrt(2 * mean area)` (the one the automatic damping
/// uses; a mean, not each vertex's own, so that a mesh refined in one place
/// is not held looser there). With 1 for gradients, the gradients of a
/// sheet of n x n facets were held about n times tighter than its
/// positions, and the ringing of the panels' unresolved stiff modes in them
/// set the step.
pub fn error_scales(layout: &DofLayout, mesh: &Mesh, length: f64) -> Vec<f64> {
    let nt = mesh.triangles().len().max(1);
    let mean_area = mesh.facet_ids().map(|t| mesh.area(t)).sum::<f64>() / nt as f64;
    let w = (2.0 * mean_area).sqrt();
    let gradient = if w > 0.0 { (length / w).max(1.0) } else { 1.0 };
    layout
        .slot_kind
        .iter()
        .flat_map(|kind| {
            let x = match kind {
                SlotKind::Position => length,
                SlotKind::Gradient => gradient,
            };
            [x; 3]
        })
        .collect()
}

/// The 9 local nodal vectors of a facet from the slot vector.
pub fn local_vector(map: &[Combo; 9], q: &[f64]) -> ElemVec {
    std::array::from_fn(|k| map[k].eval(q))
}

fn scatter_force(bm: &BlockMap, f: &[f64], out: &mut [f64]) {
    for (i, terms) in bm.terms.iter().enumerate() {
        for &(a, c) in &terms[..bm.nterms[i] as usize] {
            let s = bm.slots[a];
            for x in 0..3 {
                out[3 * s + x] += c * f[3 * i + x];
            }
        }
    }
}

fn scatter_matrix<const N: usize>(bm: &BlockMap, k: &SMatrix<f64, N, N>, w: f64, vals: &mut [f64]) {
    let ns = bm.slots.len();
    let nv = N / 3;
    for i in 0..nv {
        for &(a, ca) in &bm.terms[i][..bm.nterms[i] as usize] {
            for j in 0..nv {
                for &(b, cb) in &bm.terms[j][..bm.nterms[j] as usize] {
                    let off = bm.offsets[a * ns + b];
                    if off[0] == FIXED {
                        continue;
                    }
                    let s = w * ca * cb;
                    for y in 0..3 {
                        for x in 0..3 {
                            vals[off[y] + x] += s * k[(3 * i + x, 3 * j + y)];
                        }
                    }
                }
            }
        }
    }
}

/// The springs at both ends of every crease edge, with the right/left
/// facet convention of [`crate::crease`].
fn crease_ends(mesh: &Mesh, layout: &DofLayout) -> Vec<CreaseEnd> {
    let mut out = Vec::new();
    for (e, edge) in mesh.edge_ids().zip(mesh.edges()) {
        if edge.kind != EdgeKind::Crease {
            continue;
        }
        let len = mesh.edge_length(e);
        for (v, w) in [(edge.v[0], edge.v[1]), (edge.v[1], edge.v[0])] {
            // The crease tangent at v: the chord, or the curve's tangent.
            let d: Vector2<f64> = layout.curves.direction(mesh, e, v, w);
            // Which side of the edge a facet is on: by its chord (robust on
            // curved sides).
            let chord = mesh.coord(w) - mesh.coord(v);
            let mut right = None;
            let mut left = None;
            for &f in mesh.faces_of(e) {
                let third = *mesh
                    .triangle(f)
                    .iter()
                    .find(|&&x| x != v && x != w)
                    .expect("triangle");
                let x = mesh.coord(third) - mesh.coord(v);
                let side = chord.x * x.y - chord.y * x.x;
                let g = layout.gradient_along(v, f, x);
                if side < 0.0 {
                    right = Some(g);
                } else {
                    left = Some(g);
                }
            }
            let t = layout.gradient_along(v, mesh.faces_of(e)[0], d);
            out.push(CreaseEnd {
                edge: e,
                length: 0.5 * len,
                combos: [right.expect("right facet"), left.expect("left facet"), t],
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::builders::strip;

    /// One pass over the mass entries for several vectors gives each
    /// product as `mass_mul` does, and `M` is symmetric.
    #[test]
    fn mass_products_of_several_vectors_match_one_at_a_time() {
        let mesh = strip(0.4, 0.1, 4, 2);
        let physics = crate::benchmarks::plate_physics(1e6, 0.3, 1e-3);
        let asm = Assembler::new(&mesh, physics, ElementOptions::default(), &[]).unwrap();
        let n = asm.n_dofs();
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let z: Vec<f64> = (0..n).map(|i| (i as f64 * 0.11).cos()).collect();
        let (mut mx, mut mz) = (vec![0.0; n], vec![0.0; n]);
        asm.mass_mul(&x, &mut mx);
        asm.mass_mul(&z, &mut mz);
        let (mut px, mut pz) = (vec![0.0; n], vec![0.0; n]);
        asm.mass_mul_n([&x, &z], [&mut px, &mut pz]);
        assert_eq!(mx, px);
        assert_eq!(mz, pz);
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(a, b)| a * b).sum::<f64>();
        let (zmx, xmz) = (dot(&z, &mx), dot(&x, &mz));
        assert!(
            zmx.abs() > 0.0 && (zmx - xmz).abs() < 1e-12 * zmx.abs(),
            "{zmx} {xmz}"
        );
    }

    /// The rigid modes the supports allow outlive a change of the pattern
    /// (contact pairs joining it, a restored state's pattern): a clamped
    /// strip has none before and after.
    #[test]
    fn supports_stay_declared_when_the_pattern_grows() {
        let mesh = strip(0.4, 0.1, 4, 2);
        let physics = crate::benchmarks::plate_physics(1e6, 0.3, 1e-3);
        let mut asm = Assembler::new(&mesh, physics, ElementOptions::default(), &[]).unwrap();
        let q = asm.layout.reference_state(&mesh);
        let v0 = crate::ids::VertexId(0);
        let held: Vec<usize> = asm
            .layout
            .vertex_slots(v0)
            .into_iter()
            .chain(asm.layout.vertex_slots(crate::ids::VertexId(5)))
            .flat_map(|s| 3 * s..3 * s + 3)
            .collect();
        asm.rigid.set_supports(&held, &q, 0.4);
        assert_eq!(asm.rigid.n_allowed(), 0);
        let far = asm.layout.n_slots() - 1;
        asm.set_extra_pairs(vec![(0, far)]);
        assert!(asm.has_pair(0, far));
        assert_eq!(asm.rigid.n_allowed(), 0, "the clamp is remembered");
    }

    /// A 0.4 x 0.1 strip of 8 x 2 square cells (two triangles each): positions
    /// count at the sheet size, gradients at the sheet size over the facet
    /// size sqrt(2 x 0.05^2 / 2) = 0.05.
    #[test]
    fn error_scales_measure_gradients_by_the_surface_they_move() {
        let mesh = strip(0.4, 0.1, 8, 2);
        let layout = DofLayout::new(&mesh);
        let length = mesh.size();
        assert!((length - 0.17f64.sqrt()).abs() < 1e-15, "{length}");
        let s = error_scales(&layout, &mesh, length);
        assert_eq!(s.len(), 3 * layout.slot_kind.len());
        let mut seen = [false; 2];
        for (slot, kind) in layout.slot_kind.iter().enumerate() {
            let want = match kind {
                SlotKind::Position => length,
                SlotKind::Gradient => length / 0.05,
            };
            seen[(*kind == SlotKind::Gradient) as usize] = true;
            for c in 0..3 {
                let got = s[3 * slot + c];
                assert!(
                    (got - want).abs() < 1e-12 * want,
                    "{kind:?}: {got} vs {want}"
                );
            }
        }
        assert_eq!(seen, [true, true]);
        // One cell, two facets: gradients count at the diagonal over the
        // side, sqrt(2), positions at the diagonal.
        let one = strip(0.1, 0.1, 1, 1);
        let layout = DofLayout::new(&one);
        let s = error_scales(&layout, &one, one.size());
        for (slot, kind) in layout.slot_kind.iter().enumerate() {
            let want = match kind {
                SlotKind::Position => 0.02f64.sqrt(),
                SlotKind::Gradient => 2f64.sqrt(),
            };
            assert!(
                (s[3 * slot] - want).abs() < 1e-12,
                "{kind:?}: {}",
                s[3 * slot]
            );
        }
    }
}
