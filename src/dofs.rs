//! Global degrees of freedom: the layout that lets creases kink while smooth
//! edges stay smooth (MATH.md section 4).
//!
//! The unknowns are *vector slots* (3 scalars each). Every vertex has a
//! position slot. Around a vertex, the incident facets split into *sectors*
//! at crease and boundary edges; each sector s has a surface gradient
//! `G_s` (3x2, with respect to the flat pattern coordinates), written as
//! `G_s = sum_k q_k c_{s,k}^T` over a few slots `q_k` of the vertex:
//!
//! 1. interior vertex without creases: `G = [q_x q_y]` (two slots);
//! 2. sector between two non-parallel creases a, b: `G [d_a d_b] = [t_a t_b]`,
//!    so the crease tangent slots `t` are shared by the sectors on both
//!    sides of a crease (the surface stays continuous along it);
//! 3. sector between two anti-parallel creases (a straight crease through the
//!    vertex) or between a crease and the boundary: the crease tangent plus
//!    one extra in-sector slot along the perpendicular;
//! 4. sector between two boundary edges (no crease): two free slots.
//!
//! A facet's gradient DOF at v towards w is `G_s (X_w - X_v)`, so each facet's
//! 27 local DOFs are a constant linear map of the slots: [`LocalMap`].

use crate::curves::CreaseCurves;
use crate::ids::{EdgeId, FacetId, VertexId};
use crate::mesh::{EdgeKind, Mesh};
use nalgebra::{Matrix2, Matrix3x2, Vector2, Vector3};

/// A linear combination of at most two slots: `sum coeff * q[slot]`.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Combo {
    /// Number of terms used (1 or 2).
    pub len: u8,
    /// Slot indices.
    pub slot: [u32; 2],
    /// Coefficients.
    pub coeff: [f64; 2],
}

impl Combo {
    fn one(slot: usize, coeff: f64) -> Combo {
        Combo {
            len: 1,
            slot: [slot as u32, 0],
            coeff: [coeff, 0.0],
        }
    }
    fn two(s0: usize, c0: f64, s1: usize, c1: f64) -> Combo {
        Combo {
            len: 2,
            slot: [s0 as u32, s1 as u32],
            coeff: [c0, c1],
        }
    }
    /// The terms as (slot, coefficient) pairs.
    pub fn terms(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        (0..self.len as usize).map(move |k| (self.slot[k] as usize, self.coeff[k]))
    }
    /// Evaluate on a slot vector `q` (3 scalars per slot).
    pub fn eval(&self, q: &[f64]) -> nalgebra::Vector3<f64> {
        let mut r = nalgebra::Vector3::zeros();
        for (s, c) in self.terms() {
            r += c * nalgebra::Vector3::new(q[3 * s], q[3 * s + 1], q[3 * s + 2]);
        }
        r
    }
}

/// How one facet's 9 local nodal vectors (MATH.md order
/// `[r1, r1_eta, r1_zeta, r2, r2_zeta, r2_xi, r3, r3_xi, r3_eta]`) follow
/// from the slots.
pub type LocalMap = [Combo; 9];

/// What a slot stands for (for scaling and for supports).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SlotKind {
    /// Position of a vertex (m).
    Position,
    /// A surface gradient vector (dimensionless).
    Gradient,
}

/// A sector of the fan around a vertex: its facets and gradient.
#[derive(Clone, Debug, PartialEq)]
pub struct Sector {
    /// Facets in the sector.
    pub faces: Vec<FacetId>,
    /// Coefficients: `G = sum_k q[slot_k] c_k^T`.
    pub terms: Vec<(usize, Vector2<f64>)>,
}

/// The slot layout of a whole mesh.
#[derive(Clone, Debug)]
pub struct DofLayout {
    /// Vertex that owns each slot.
    pub slot_vertex: Vec<VertexId>,
    /// Kind of each slot.
    pub slot_kind: Vec<SlotKind>,
    /// Position slot of each vertex.
    pub position_slot: Vec<usize>,
    /// Sectors around each vertex.
    pub sectors: Vec<Vec<Sector>>,
    /// For each facet, its local map.
    pub local: Vec<LocalMap>,
    /// Crease curve tangents (curved crease sides).
    pub curves: CreaseCurves,
}

/// The gradient of the sector (among a vertex's `sectors`) holding `face`,
/// applied to the reference vector `x`.
fn gradient_in(sectors: &[Sector], face: FacetId, x: Vector2<f64>) -> Combo {
    let s = sectors
        .iter()
        .find(|s| s.faces.contains(&face))
        .expect("every face is in a sector at its corners");
    let (s0, c0) = s.terms[0];
    let (s1, c1) = s.terms[1];
    Combo::two(s0, c0.dot(&x), s1, c1.dot(&x))
}

/// The six sides of facet `f` in element order `[1->2, 1->3, 2->3, 2->1,
/// 3->1, 3->2]`: (corner, towards, reference side vector).
fn facet_sides(
    mesh: &Mesh,
    curves: &CreaseCurves,
    f: FacetId,
) -> [(VertexId, VertexId, Vector2<f64>); 6] {
    let [a, b, c] = mesh.triangle(f);
    [(a, b), (a, c), (b, c), (b, a), (c, a), (c, b)]
        .map(|(v, w)| (v, w, curves.side(mesh, side_edge(mesh, f, v, w), v, w)))
}

/// The edge of facet `f` between its corners `v` and `w`.
fn side_edge(mesh: &Mesh, f: FacetId, v: VertexId, w: VertexId) -> EdgeId {
    let t = mesh.triangle(f);
    (0..3)
        .find(|&k| {
            let (p, q) = (t[k], t[(k + 1) % 3]);
            (p == v && q == w) || (p == w && q == v)
        })
        .map(|k| mesh.sides_of(f)[k])
        .expect("v and w are corners of f")
}

/// Two unit directions closer than this (1 - |cos|) count as parallel.
const PARALLEL_TOL: f64 = 1e-9;

/// The sectors of vertex `v` (fan `fan`), making their gradient slots:
/// one tangent slot per crease, shared (with sign) across anti-parallel
/// creases that bound one sector, and a second slot where a sector needs one.
fn vertex_sectors(
    mesh: &Mesh,
    curves: &CreaseCurves,
    v: VertexId,
    fan: &crate::mesh::Fan,
    slots: &mut Slots,
) -> Vec<Sector> {
    // Unit tangent at v along edge e: the chord, or the crease curve's
    // tangent where two non-collinear creases meet.
    let dir = |e: EdgeId| {
        let [a, b] = mesh.edge(e).v;
        let w = if a == v { b } else { a };
        curves.direction(mesh, e, v, w)
    };
    let is_crease = |e: EdgeId| mesh.edge(e).kind == EdgeKind::Crease;
    let raw = split_fan(fan, is_crease);
    let mut tangent: Tangents = Vec::new();
    for (first, _, last) in &raw {
        if let (Some(a), Some(b)) = (*first, *last)
            && a != b
            && 1.0 + dir(a).dot(&dir(b)) < PARALLEL_TOL
        {
            match (tangent_of(&tangent, a), tangent_of(&tangent, b)) {
                (Some((s, sg)), None) => tangent.push((b, s, -sg)),
                (None, Some((s, sg))) => tangent.push((a, s, -sg)),
                (None, None) => {
                    let s = slots.add(v, SlotKind::Gradient);
                    tangent.push((a, s, 1.0));
                    tangent.push((b, s, -1.0));
                }
                (Some(_), Some(_)) => {}
            }
        }
    }
    for &e in fan.edges.iter().filter(|&&e| is_crease(e)) {
        if tangent_of(&tangent, e).is_none() {
            let s = slots.add(v, SlotKind::Gradient);
            tangent.push((e, s, 1.0));
        }
    }
    let mut sectors = Vec::with_capacity(raw.len());
    for (first, faces, last) in raw {
        let perp = |d: Vector2<f64>| Vector2::new(-d.y, d.x);
        // Columns: G [d0 d1] = [u0 u1] with u_k = sign * q[slot].
        let (d0, u0, d1, u1) = match (first, last) {
            (None, None) => {
                let sx = slots.add(v, SlotKind::Gradient);
                let sy = slots.add(v, SlotKind::Gradient);
                (Vector2::x(), (sx, 1.0), Vector2::y(), (sy, 1.0))
            }
            (Some(a), Some(b)) if a != b && (1.0 - dir(a).dot(&dir(b)).abs()) >= PARALLEL_TOL => (
                dir(a),
                tangent_of(&tangent, a).unwrap(),
                dir(b),
                tangent_of(&tangent, b).unwrap(),
            ),
            (Some(a), _) | (None, Some(a)) => {
                let extra = slots.add(v, SlotKind::Gradient);
                (
                    dir(a),
                    tangent_of(&tangent, a).unwrap(),
                    perp(dir(a)),
                    (extra, 1.0),
                )
            }
        };
        let dinv = Matrix2::from_columns(&[d0, d1])
            .try_inverse()
            .expect("sector directions span the plane");
        // G = [u0 u1] D^-1 = u0 row0(D^-1) + u1 row1(D^-1)
        let terms = vec![
            (u0.0, u0.1 * dinv.row(0).transpose()),
            (u1.0, u1.1 * dinv.row(1).transpose()),
        ];
        sectors.push(Sector { faces, terms });
    }
    sectors
}

/// Slots made so far: the vertex and kind of each.
#[derive(Default)]
struct Slots {
    vertex: Vec<VertexId>,
    kind: Vec<SlotKind>,
}

impl Slots {
    /// A new slot at vertex `v`.
    fn add(&mut self, v: VertexId, kind: SlotKind) -> usize {
        self.vertex.push(v);
        self.kind.push(kind);
        self.vertex.len() - 1
    }
}

/// A sector of a vertex's fan before its slots are chosen: the crease or
/// boundary it starts at (None: the fan's boundary or a closed fan without
/// creases), its faces, the crease it ends at.
type RawSector = (Option<EdgeId>, Vec<FacetId>, Option<EdgeId>);

/// A crease's tangent slot at a vertex, with the sign it enters with.
type Tangents = Vec<(EdgeId, usize, f64)>;

/// The tangent slot and sign of crease `e` at the vertex, if made.
fn tangent_of(tangents: &Tangents, e: EdgeId) -> Option<(usize, f64)> {
    tangents.iter().find(|t| t.0 == e).map(|t| (t.1, t.2))
}

/// Split a vertex's fan into sectors at its creases (`is_crease`).
fn split_fan(fan: &crate::mesh::Fan, is_crease: impl Fn(EdgeId) -> bool) -> Vec<RawSector> {
    let nf = fan.faces.len();
    let crease_pos: Vec<usize> = (0..fan.edges.len())
        .filter(|&i| is_crease(fan.edges[i]))
        .collect();
    let mut raw = Vec::new();
    if fan.closed {
        if crease_pos.is_empty() {
            raw.push((None, fan.faces.clone(), None));
        } else {
            let nc = crease_pos.len();
            for k in 0..nc {
                let start = crease_pos[k];
                let end = crease_pos[(k + 1) % nc];
                let mut faces = Vec::new();
                let mut i = start;
                loop {
                    faces.push(fan.faces[i]);
                    i = (i + 1) % nf;
                    if i == end {
                        break;
                    }
                }
                raw.push((Some(fan.edges[start]), faces, Some(fan.edges[end])));
            }
        }
    } else {
        // Open fan: edges[0] and edges[nf] are boundary edges.
        let mut cuts = vec![0usize];
        cuts.extend(crease_pos.iter().copied().filter(|&i| i > 0 && i < nf));
        cuts.push(nf);
        for w in cuts.windows(2) {
            let (s, e) = (w[0], w[1]);
            let first = if s == 0 { None } else { Some(fan.edges[s]) };
            let last = if e == nf { None } else { Some(fan.edges[e]) };
            raw.push((first, fan.faces[s..e].to_vec(), last));
        }
    }
    raw
}

impl DofLayout {
    /// Build the layout of a validated mesh.
    pub fn new(mesh: &Mesh) -> DofLayout {
        let curves = CreaseCurves::new(mesh);
        let nv = mesh.n_vertices();
        let mut slots = Slots::default();
        let mut position_slot = vec![0; nv];
        let mut sectors = vec![Vec::new(); nv];
        let fans = mesh.fans().expect("mesh validated its fans");
        for v in mesh.vertex_ids() {
            position_slot[v.index()] = slots.add(v, SlotKind::Position);
            let fan = &fans[v.index()];
            if !fan.faces.is_empty() {
                sectors[v.index()] = vertex_sectors(mesh, &curves, v, fan, &mut slots);
            }
        }
        let local = mesh
            .facet_ids()
            .map(|f| {
                let [a, b, c] = mesh.triangle(f);
                let sides = facet_sides(mesh, &curves, f);
                let grad = |k: usize| {
                    let (v, _, x) = sides[k];
                    gradient_in(&sectors[v.index()], f, x)
                };
                [
                    Combo::one(position_slot[a.index()], 1.0),
                    grad(0),
                    grad(1),
                    Combo::one(position_slot[b.index()], 1.0),
                    grad(2),
                    grad(3),
                    Combo::one(position_slot[c.index()], 1.0),
                    grad(4),
                    grad(5),
                ]
            })
            .collect();
        DofLayout {
            slot_vertex: slots.vertex,
            slot_kind: slots.kind,
            position_slot,
            sectors,
            local,
            curves,
        }
    }

    /// The reference side vectors of facet `f` in element order `[1->2,
    /// 1->3, 2->3, 2->1, 3->1, 3->2]`: chords, or Hermite tangents on curved
    /// crease sides (what the facet's gradient DOFs mean).
    pub fn side_vectors(&self, mesh: &Mesh, f: FacetId) -> [Vector2<f64>; 6] {
        facet_sides(mesh, &self.curves, f).map(|(_, _, x)| x)
    }

    /// Number of vector slots.
    pub fn n_slots(&self) -> usize {
        self.slot_vertex.len()
    }

    /// Number of scalar DOFs (3 per slot).
    pub fn n_dofs(&self) -> usize {
        3 * self.n_slots()
    }

    /// The gradient of `face` at vertex `v` applied to the reference vector
    /// `x` (a combination of slots).
    pub fn gradient_along(&self, v: VertexId, face: FacetId, x: Vector2<f64>) -> Combo {
        gradient_in(&self.sectors[v.index()], face, x)
    }

    /// Slots owned by vertex `v` (its position first).
    pub fn vertex_slots(&self, v: VertexId) -> Vec<usize> {
        (0..self.n_slots())
            .filter(|&s| self.slot_vertex[s] == v)
            .collect()
    }

    /// The flat reference configuration: positions `(X, Y, 0)` and every
    /// sector gradient the identity `G_s = [e_x e_y]`.
    pub fn reference_state(&self, mesh: &Mesh) -> Vec<f64> {
        self.state_of_field(mesh, |x| {
            (
                Vector3::new(x.x, x.y, 0.0),
                Matrix3x2::new(1.0, 0.0, 0.0, 1.0, 0.0, 0.0),
            )
        })
    }

    /// The slots of a smooth map `X -> (r(X), dr/dX(X))` of the crease
    /// pattern: every position `r(X_v)` and every sector gradient
    /// `G_s = dr/dX(X_v)` (the same in all sectors at a vertex).
    pub fn state_of_field<F>(&self, mesh: &Mesh, field: F) -> Vec<f64>
    where
        F: Fn(Vector2<f64>) -> (Vector3<f64>, Matrix3x2<f64>),
    {
        let mut q = vec![0.0; self.n_dofs()];
        for (v, x) in mesh.coords().iter().enumerate() {
            let (r, g) = field(*x);
            let s = self.position_slot[v];
            q[3 * s..3 * s + 3].copy_from_slice(r.as_slice());
            // G = sum_k q_k c_k^T over the sector's two independent slots, so
            // [q0 q1] = G C^-1 with C = [c0 c1]^T (rows c0, c1).
            for sec in &self.sectors[v] {
                let (s0, c0) = sec.terms[0];
                let (s1, c1) = sec.terms[1];
                let cm = Matrix2::from_rows(&[c0.transpose(), c1.transpose()]);
                let slots = g * cm.try_inverse().expect("sector map invertible");
                for (k, s) in [s0, s1].into_iter().enumerate() {
                    q[3 * s..3 * s + 3].copy_from_slice(slots.column(k).as_slice());
                }
            }
        }
        q
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ids::vertex_ids;
    use crate::mesh::builders::{grid, square_with_diagonal};
    use crate::mesh::{Edge, Mesh};

    #[test]
    fn counts_from_math_md() {
        assert_eq!(
            DofLayout::new(&square_with_diagonal(1.0, true, 1.0)).n_dofs(),
            42
        );
        assert_eq!(
            DofLayout::new(&square_with_diagonal(1.0, false, 0.0)).n_dofs(),
            36
        );
    }

    /// A vertex with 4 creases (generic directions, like a Miura vertex where
    /// no sector spans 180 degrees): 15 DOF.
    #[test]
    fn interior_vertex_with_four_creases_has_15() {
        let c = |x: f64, y: f64| Vector2::new(x, y);
        // centre 0, ring 1..6; creases to 1, 3, 4, 6 (1 and 4 collinear).
        let coords = vec![
            c(0.0, 0.0),
            c(1.0, 0.0),
            c(0.6, 1.0),
            c(-0.5, 0.9),
            c(-1.0, 0.0),
            c(-0.4, -1.0),
            c(0.5, -0.9),
        ];
        let tris = (1..=6).map(|i| vertex_ids([0, i, i % 6 + 1])).collect();
        let v = VertexId;
        let edges = vec![
            Edge::crease(v(0), v(1), 1.0),
            Edge::crease(v(0), v(3), -1.0),
            Edge::crease(v(0), v(4), 1.0),
            Edge::crease(v(0), v(6), -1.0),
        ];
        let mesh = Mesh::new(coords, tris, edges).unwrap();
        let layout = DofLayout::new(&mesh);
        assert_eq!(layout.vertex_slots(v(0)).len() * 3, 15);
    }

    /// A straight crease line through a vertex with no other crease: the
    /// tangent is shared, each side gets one extra vector: 12 DOF.
    #[test]
    fn straight_crease_through_vertex_shares_tangent() {
        let m = grid(2.0, 2.0, 2, 2, &[(1, 0.5)]);
        let layout = DofLayout::new(&m);
        let centre = VertexId(4);
        assert_eq!(layout.vertex_slots(centre).len(), 4);
        // The reference state is consistent: every facet gradient is the edge vector.
        let q = layout.reference_state(&m);
        check_reference(&m, &layout, &q);
    }

    fn check_reference(m: &Mesh, layout: &DofLayout, q: &[f64]) {
        for (f, &[a, b, c]) in m.triangles().iter().enumerate() {
            let x = |v: VertexId| nalgebra::Vector3::new(m.coord(v).x, m.coord(v).y, 0.0);
            let expect = [
                x(a),
                x(b) - x(a),
                x(c) - x(a),
                x(b),
                x(c) - x(b),
                x(a) - x(b),
                x(c),
                x(a) - x(c),
                x(b) - x(c),
            ];
            for (k, want) in expect.iter().enumerate() {
                let got = layout.local[f][k].eval(q);
                assert!(
                    (got - want).norm() < 1e-12,
                    "face {f} vector {k}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn reference_state_reproduces_every_facet() {
        for mesh in [
            square_with_diagonal(1.0, true, 1.0),
            square_with_diagonal(0.3, false, 0.0),
            grid(3.0, 1.0, 3, 2, &[(1, 1.0), (2, -1.0)]),
        ] {
            let layout = DofLayout::new(&mesh);
            let q = layout.reference_state(&mesh);
            check_reference(&mesh, &layout, &q);
        }
    }

    /// A rigid fold of the creased square is represented exactly: rotate
    /// facet 1 about the diagonal and find slots reproducing both facets.
    #[test]
    fn rigid_fold_is_representable_only_across_a_crease() {
        use nalgebra::{Rotation3, Unit, Vector3};
        for crease in [true, false] {
            let mesh = square_with_diagonal(1.0, crease, 1.0);
            let layout = DofLayout::new(&mesh);
            let axis = Unit::new_normalize(Vector3::new(1.0, 1.0, 0.0));
            let rot = Rotation3::from_axis_angle(&axis, 0.7);
            let x3 = |v: VertexId| Vector3::new(mesh.coord(v).x, mesh.coord(v).y, 0.0);
            // facet 0 = (0,1,2) stays, facet 1 = (0,2,3) rotates about the 0-2 line
            let pos = |f: usize, v: VertexId| if f == 1 { rot * x3(v) } else { x3(v) };
            // Least squares: find q with local[f][k](q) = target for all f, k.
            let n = layout.n_dofs();
            let mut rows: Vec<(Vec<(usize, f64)>, f64)> = Vec::new();
            for (f, &[a, b, c]) in mesh.triangles().iter().enumerate() {
                let t = [
                    pos(f, a),
                    pos(f, b) - pos(f, a),
                    pos(f, c) - pos(f, a),
                    pos(f, b),
                    pos(f, c) - pos(f, b),
                    pos(f, a) - pos(f, b),
                    pos(f, c),
                    pos(f, a) - pos(f, c),
                    pos(f, b) - pos(f, c),
                ];
                for (k, tk) in t.iter().enumerate() {
                    for (comp, &tc) in tk.iter().enumerate() {
                        let r: Vec<(usize, f64)> = layout.local[f][k]
                            .terms()
                            .map(|(s, cf)| (3 * s + comp, cf))
                            .collect();
                        rows.push((r, tc));
                    }
                }
            }
            let mut a = nalgebra::DMatrix::zeros(rows.len(), n);
            let mut rhs = nalgebra::DVector::zeros(rows.len());
            for (i, (r, t)) in rows.iter().enumerate() {
                for &(j, cf) in r {
                    a[(i, j)] += cf;
                }
                rhs[i] = *t;
            }
            let sol = a.clone().svd(true, true).solve(&rhs, 1e-12).unwrap();
            let resid = (a * sol - rhs).norm();
            if crease {
                assert!(
                    resid < 1e-10,
                    "creased square must fold rigidly, residual {resid}"
                );
            } else {
                assert!(
                    resid > 1e-3,
                    "smooth square must not fold, residual {resid}"
                );
            }
        }
    }
}
