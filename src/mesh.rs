//! The crease pattern as data: flat reference vertices, counter-clockwise
//! triangles and labelled edges, plus the topology (edge-to-face incidence,
//! vertex fans) that the DOF layout and the creases need.
//!
//! A [`Mesh`] is built with [`Mesh::new`], which validates it: indices in
//! range, no degenerate or clockwise triangle, no edge shared by more than two
//! triangles, every crease between exactly two triangles. Triangle edges that
//! are not listed become smooth (interior) or boundary edges.

use crate::ids::{EdgeId, FacetId, FoldEdgeId, VertexId, vertex_ids};
use nalgebra::Vector2;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::fmt;

/// What an edge does mechanically.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum EdgeKind {
    /// A fold line (FOLD `M`, `V` or `U`): facets may kink across it and a
    /// rotational spring acts on the kink.
    Crease,
    /// A smooth edge (FOLD `F`, `J`, or a triangulation diagonal): the
    /// surface stays C1 across it.
    Smooth,
    /// A free edge of the sheet (FOLD `B`): exactly one facet.
    Boundary,
}

/// One edge of the mesh.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Edge {
    /// The two end vertices.
    pub v: [VertexId; 2],
    /// Crease, smooth or boundary.
    pub kind: EdgeKind,
    /// Target fold angle at full actuation in radians, FOLD sign (valley
    /// positive). Only meaningful for creases.
    pub fold_target: f64,
    /// The FOLD edge this mesh edge lies on; `None` for diagonals added by
    /// triangulation. Refinement keeps the tag on both halves.
    pub fold_edge: Option<FoldEdgeId>,
}

impl Edge {
    /// A crease between `a` and `b` folding to `fold_target` radians.
    pub fn crease(a: VertexId, b: VertexId, fold_target: f64) -> Self {
        Edge {
            v: [a, b],
            kind: EdgeKind::Crease,
            fold_target,
            fold_edge: None,
        }
    }
    /// A smooth edge between `a` and `b`.
    pub fn smooth(a: VertexId, b: VertexId) -> Self {
        Edge {
            v: [a, b],
            kind: EdgeKind::Smooth,
            fold_target: 0.0,
            fold_edge: None,
        }
    }
    /// A boundary edge between `a` and `b`.
    pub fn boundary(a: VertexId, b: VertexId) -> Self {
        Edge {
            v: [a, b],
            kind: EdgeKind::Boundary,
            fold_target: 0.0,
            fold_edge: None,
        }
    }
}

/// A validated crease pattern with its topology.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Mesh {
    coords: Vec<Vector2<f64>>,
    triangles: Vec<[VertexId; 3]>,
    edges: Vec<Edge>,
    edge_faces: Vec<Vec<FacetId>>,
    face_edges: Vec<[EdgeId; 3]>,
}

/// What is wrong with a mesh, naming the index.
#[derive(Clone, Debug, PartialEq)]
#[allow(missing_docs)] // variant fields are named for what they hold
pub enum MeshError {
    /// A triangle or edge refers to a vertex that does not exist.
    VertexOutOfRange {
        what: String,
        index: usize,
        vertex: VertexId,
        count: usize,
    },
    /// A triangle names the same vertex twice.
    RepeatedVertex { triangle: FacetId },
    /// A triangle has (nearly) zero area.
    Degenerate { triangle: FacetId, area: f64 },
    /// A triangle is clockwise in the reference plane.
    Inverted { triangle: FacetId },
    /// More than two triangles share an edge.
    NonManifold {
        vertices: [VertexId; 2],
        faces: Vec<FacetId>,
    },
    /// A listed edge is not a side of any triangle.
    DanglingEdge { edge: EdgeId },
    /// An edge is listed twice.
    DuplicateEdge { first: EdgeId, second: EdgeId },
    /// A crease does not lie between exactly two triangles.
    CreaseNotInterior { edge: EdgeId, faces: usize },
    /// An edge marked boundary has two triangles.
    BoundaryNotOnBoundary { edge: EdgeId },
    /// A non-finite coordinate or fold angle.
    NotFinite { what: String, index: usize },
    /// The vertex fan around a vertex is not a single disc or half-disc
    /// (e.g. two sheets touching at a point).
    NonManifoldVertex { vertex: VertexId },
}

impl fmt::Display for MeshError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use MeshError::*;
        match self {
            VertexOutOfRange {
                what,
                index,
                vertex,
                count,
            } => write!(
                f,
                "{what} {index} refers to vertex {vertex}, but there are only {count} vertices"
            ),
            RepeatedVertex { triangle } => write!(f, "face {triangle} repeats a vertex"),
            Degenerate { triangle, area } => {
                write!(f, "face {triangle} is degenerate (area {area:.3e})")
            }
            Inverted { triangle } => write!(
                f,
                "face {triangle} is clockwise (inverted); faces must be counter-clockwise"
            ),
            NonManifold { vertices, faces } => write!(
                f,
                "edge {}-{} is shared by {} faces {:?}; at most two are allowed (non-manifold)",
                vertices[0],
                vertices[1],
                faces.len(),
                faces
            ),
            DanglingEdge { edge } => write!(f, "edge {edge} is not a side of any face"),
            DuplicateEdge { first, second } => {
                write!(f, "edge {second} repeats edge {first} (same two vertices)")
            }
            CreaseNotInterior { edge, faces } => write!(
                f,
                "edge {edge} is a crease but borders {faces} face(s); a crease needs exactly two"
            ),
            BoundaryNotOnBoundary { edge } => {
                write!(f, "edge {edge} is marked boundary but borders two faces")
            }
            NotFinite { what, index } => write!(f, "{what} {index} is not a finite number"),
            NonManifoldVertex { vertex } => write!(
                f,
                "the faces around vertex {vertex} do not form one fan (sheets touching at a point)"
            ),
        }
    }
}

impl std::error::Error for MeshError {}

/// Relative area below which a triangle counts as degenerate (against the
/// square of the mean edge length of the whole mesh). The FOLD loader tests
/// its polygons against the same threshold ([`is_degenerate`]) before they
/// are triangulated, so that such a face is named in the file's terms.
const DEGENERATE_AREA: f64 = 1e-12;

/// The mean squared side length of `polygons` (closed, by vertex index into
/// `coords`), 1 when there is no side: the scale of [`is_degenerate`].
pub(crate) fn mean_side_length2<'a>(
    polygons: impl IntoIterator<Item = &'a [usize]>,
    coords: &[Vector2<f64>],
) -> f64 {
    let mut sum = 0.0;
    let mut count = 0usize;
    for p in polygons {
        for k in 0..p.len() {
            sum += (coords[p[(k + 1) % p.len()]] - coords[p[k]]).norm_squared();
            count += 1;
        }
    }
    if count > 0 { sum / count as f64 } else { 1.0 }
}

/// True for a triangle or polygon of (signed) `area` that is degenerate
/// against `mean_len2` ([`mean_side_length2`] of the whole mesh or pattern).
pub(crate) fn is_degenerate(area: f64, mean_len2: f64) -> bool {
    area.abs() <= DEGENERATE_AREA * mean_len2
}

/// Edges by their vertex pair ([`edge_key`]).
type EdgeIndex = HashMap<(VertexId, VertexId), EdgeId>;

/// The key of the edge between `a` and `b` (either order).
fn edge_key(a: VertexId, b: VertexId) -> (VertexId, VertexId) {
    if a < b { (a, b) } else { (b, a) }
}

/// Finite coordinates; triangles of three distinct vertices in range,
/// neither degenerate nor inverted.
fn check_triangles(coords: &[Vector2<f64>], triangles: &[[VertexId; 3]]) -> Result<(), MeshError> {
    let nv = coords.len();
    for (i, c) in coords.iter().enumerate() {
        if !(c.x.is_finite() && c.y.is_finite()) {
            return Err(MeshError::NotFinite {
                what: "vertex".into(),
                index: i,
            });
        }
    }
    for (t, tri) in triangles.iter().enumerate() {
        for &v in tri {
            if v.index() >= nv {
                return Err(MeshError::VertexOutOfRange {
                    what: "face".into(),
                    index: t,
                    vertex: v,
                    count: nv,
                });
            }
        }
        if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
            return Err(MeshError::RepeatedVertex {
                triangle: FacetId(t),
            });
        }
    }
    let corners: Vec<[usize; 3]> = triangles.iter().map(|t| t.map(VertexId::index)).collect();
    let mean_len2 = mean_side_length2(corners.iter().map(|t| &t[..]), coords);
    for (t, &[a, b, c]) in corners.iter().enumerate() {
        let u = coords[b] - coords[a];
        let w = coords[c] - coords[a];
        let area = 0.5 * (u.x * w.y - u.y * w.x);
        if is_degenerate(area, mean_len2) {
            return Err(MeshError::Degenerate {
                triangle: FacetId(t),
                area,
            });
        }
        if area < 0.0 {
            return Err(MeshError::Inverted {
                triangle: FacetId(t),
            });
        }
    }
    Ok(())
}

/// The listed edges, checked (vertices in range, finite targets, no
/// duplicates), and their index by vertex pair.
fn listed_edges(edges: Vec<Edge>, nv: usize) -> Result<(Vec<Edge>, EdgeIndex), MeshError> {
    let mut index = EdgeIndex::new();
    let mut all = Vec::with_capacity(edges.len());
    for (e, edge) in edges.into_iter().enumerate() {
        for &v in &edge.v {
            if v.index() >= nv {
                return Err(MeshError::VertexOutOfRange {
                    what: "edge".into(),
                    index: e,
                    vertex: v,
                    count: nv,
                });
            }
        }
        if !edge.fold_target.is_finite() {
            return Err(MeshError::NotFinite {
                what: "fold angle of edge".into(),
                index: e,
            });
        }
        if let Some(&first) = index.get(&edge_key(edge.v[0], edge.v[1])) {
            return Err(MeshError::DuplicateEdge {
                first,
                second: EdgeId(e),
            });
        }
        index.insert(edge_key(edge.v[0], edge.v[1]), EdgeId(e));
        all.push(edge);
    }
    Ok((all, index))
}

/// Every edge in one or two faces, creases interior and boundary edges on
/// the boundary; edges in one face become boundary edges.
fn check_edge_faces(all: &mut [Edge], edge_faces: &[Vec<FacetId>]) -> Result<(), MeshError> {
    for (e, faces) in edge_faces.iter().enumerate() {
        if faces.len() > 2 {
            return Err(MeshError::NonManifold {
                vertices: all[e].v,
                faces: faces.clone(),
            });
        }
        if faces.is_empty() {
            return Err(MeshError::DanglingEdge { edge: EdgeId(e) });
        }
        match all[e].kind {
            EdgeKind::Crease if faces.len() != 2 => {
                return Err(MeshError::CreaseNotInterior {
                    edge: EdgeId(e),
                    faces: faces.len(),
                });
            }
            EdgeKind::Boundary if faces.len() == 2 => {
                return Err(MeshError::BoundaryNotOnBoundary { edge: EdgeId(e) });
            }
            _ => {}
        }
        if faces.len() == 1 {
            all[e].kind = EdgeKind::Boundary;
        }
    }
    Ok(())
}

/// Two triangles across an edge traverse it in opposite directions
/// (consistent orientation); with all faces counter-clockwise in the plane
/// this holds unless faces overlap.
fn check_orientation(
    all: &[Edge],
    edge_faces: &[Vec<FacetId>],
    triangles: &[[VertexId; 3]],
) -> Result<(), MeshError> {
    for (e, faces) in edge_faces.iter().enumerate() {
        if faces.len() == 2 {
            let [a, b] = all[e].v;
            let dir = |t: FacetId| {
                let tri = triangles[t.index()];
                (0..3).any(|k| tri[k] == a && tri[(k + 1) % 3] == b)
            };
            if dir(faces[0]) == dir(faces[1]) {
                return Err(MeshError::Inverted { triangle: faces[1] });
            }
        }
    }
    Ok(())
}

impl Mesh {
    /// Validate the pattern and build its topology. `edges` lists labelled
    /// edges; unlisted triangle sides become smooth or boundary edges.
    pub fn new(
        coords: Vec<Vector2<f64>>,
        triangles: Vec<[VertexId; 3]>,
        edges: Vec<Edge>,
    ) -> Result<Mesh, MeshError> {
        check_triangles(&coords, &triangles)?;
        let nv = coords.len();
        // Listed edges first, then the sides no edge lists.
        let (mut all, mut index) = listed_edges(edges, nv)?;
        let n_listed = all.len();
        let mut edge_faces: Vec<Vec<FacetId>> = vec![Vec::new(); n_listed];
        let mut face_edges = Vec::with_capacity(triangles.len());
        for (t, tri) in triangles.iter().enumerate() {
            let mut fe = [EdgeId(0); 3];
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let e = *index.entry(edge_key(a, b)).or_insert_with(|| {
                    all.push(Edge::smooth(a, b));
                    edge_faces.push(Vec::new());
                    EdgeId(all.len() - 1)
                });
                edge_faces[e.index()].push(FacetId(t));
                fe[k] = e;
            }
            face_edges.push(fe);
        }
        check_edge_faces(&mut all, &edge_faces)?;
        check_orientation(&all, &edge_faces, &triangles)?;
        let mesh = Mesh {
            coords,
            triangles,
            edges: all,
            edge_faces,
            face_edges,
        };
        // One pass over the triangles (calling `fan` per vertex would be
        // quadratic in the mesh size).
        mesh.fans()?;
        Ok(mesh)
    }

    /// Reference (stress-free, flat) vertex coordinates in metres, by
    /// [`VertexId::index`].
    pub fn coords(&self) -> &[Vector2<f64>] {
        &self.coords
    }

    /// The reference coordinates of vertex `v`.
    pub fn coord(&self, v: VertexId) -> Vector2<f64> {
        self.coords[v.index()]
    }

    /// Triangles, counter-clockwise in the reference coordinates, by
    /// [`FacetId::index`].
    pub fn triangles(&self) -> &[[VertexId; 3]] {
        &self.triangles
    }

    /// The corners of facet `t`, counter-clockwise.
    pub fn triangle(&self, t: FacetId) -> [VertexId; 3] {
        self.triangles[t.index()]
    }

    /// All edges, by [`EdgeId::index`]: the listed ones first, in the given
    /// order, then the unlisted triangle edges.
    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    /// Edge `e`.
    pub fn edge(&self, e: EdgeId) -> &Edge {
        &self.edges[e.index()]
    }

    /// The creases, in edge order.
    pub fn creases(&self) -> impl Iterator<Item = &Edge> {
        self.edges.iter().filter(|e| e.kind == EdgeKind::Crease)
    }

    /// For each edge, the one or two triangles that contain it.
    pub fn edge_faces(&self) -> &[Vec<FacetId>] {
        &self.edge_faces
    }

    /// The one or two triangles that contain edge `e`.
    pub fn faces_of(&self, e: EdgeId) -> &[FacetId] {
        &self.edge_faces[e.index()]
    }

    /// For each triangle, the edges of its sides (v0v1, v1v2, v2v0).
    pub fn face_edges(&self) -> &[[EdgeId; 3]] {
        &self.face_edges
    }

    /// The edges of the sides of facet `t` (v0v1, v1v2, v2v0).
    pub fn sides_of(&self, t: FacetId) -> [EdgeId; 3] {
        self.face_edges[t.index()]
    }

    /// The vertices, in order.
    pub fn vertex_ids(&self) -> impl ExactSizeIterator<Item = VertexId> + use<> {
        (0..self.coords.len()).map(VertexId)
    }

    /// The facets, in order.
    pub fn facet_ids(&self) -> impl ExactSizeIterator<Item = FacetId> + use<> {
        (0..self.triangles.len()).map(FacetId)
    }

    /// The edges, in order.
    pub fn edge_ids(&self) -> impl ExactSizeIterator<Item = EdgeId> + use<> {
        (0..self.edges.len()).map(EdgeId)
    }

    /// Tag edge `e` with the FOLD edge it lies on (`None`: none).
    pub fn set_fold_edge(&mut self, e: EdgeId, fold_edge: Option<FoldEdgeId>) {
        self.edges[e.index()].fold_edge = fold_edge;
    }

    /// Tag every crease without a FOLD edge with the FOLD edge of its own
    /// index ([`FoldEdgeId::of_mesh_edge`]): for a mesh built in code, with
    /// no FOLD file behind it, whose edge indices are the FOLD edge indices.
    /// (The tag is not checked by [`Mesh::new`]: this changes nothing that
    /// it validated.)
    pub fn tag_creases_as_fold_edges(&mut self) {
        for (e, edge) in self.edges.iter_mut().enumerate() {
            if edge.fold_edge.is_none() && edge.kind == EdgeKind::Crease {
                edge.fold_edge = Some(FoldEdgeId::of_mesh_edge(EdgeId(e)));
            }
        }
    }

    /// Set the target fold angle (radians, FOLD sign) of edge `e`; an error
    /// (and no change) for a number that is not finite, as in [`Mesh::new`].
    pub fn set_fold_target(&mut self, e: EdgeId, fold_target: f64) -> Result<(), MeshError> {
        if !fold_target.is_finite() {
            return Err(MeshError::NotFinite {
                what: "fold angle of edge".into(),
                index: e.index(),
            });
        }
        self.edges[e.index()].fold_target = fold_target;
        Ok(())
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.coords.len()
    }

    /// Diagonal of the reference bounding box (m): the sheet's size, the
    /// length scale of position errors.
    pub fn size(&self) -> f64 {
        let Some(&first) = self.coords.first() else {
            return 0.0;
        };
        let (mut lo, mut hi) = (first, first);
        for c in &self.coords {
            lo = lo.inf(c);
            hi = hi.sup(c);
        }
        (hi - lo).norm()
    }

    /// Reference area of triangle `t`.
    pub fn area(&self, t: FacetId) -> f64 {
        let [a, b, c] = self.triangle(t);
        let u = self.coord(b) - self.coord(a);
        let w = self.coord(c) - self.coord(a);
        0.5 * (u.x * w.y - u.y * w.x)
    }

    /// Reference length of edge `e`.
    pub fn edge_length(&self, e: EdgeId) -> f64 {
        let [a, b] = self.edge(e).v;
        (self.coord(b) - self.coord(a)).norm()
    }

    /// The edge between vertices `a` and `b`, if any (a linear search: for
    /// tests and small meshes).
    pub fn find_edge(&self, a: VertexId, b: VertexId) -> Option<EdgeId> {
        self.edges
            .iter()
            .position(|e| (e.v[0] == a && e.v[1] == b) || (e.v[0] == b && e.v[1] == a))
            .map(EdgeId)
    }

    #[doc(hidden)]
    /// The triangles around vertex `v`, ordered counter-clockwise, with the
    /// edges between them: `edges[i]` precedes `faces[i]` and `edges[i+1]`
    /// follows it. For an interior vertex the fan is closed
    /// (`edges.len() == faces.len()`, the last face followed by `edges[0]`);
    /// for a boundary vertex it is open, starts and ends on a boundary edge
    /// (`edges.len() == faces.len() + 1`). A vertex used by no face has an
    /// empty fan. Scans all triangles: use [`Mesh::fans`] for all vertices.
    pub fn fan(&self, v: VertexId) -> Result<Fan, MeshError> {
        let faces: Vec<FacetId> = self
            .facet_ids()
            .filter(|&t| self.triangle(t).contains(&v))
            .collect();
        self.fan_of(v, &faces)
    }

    #[doc(hidden)]
    /// The fans of all vertices, in vertex order (linear in the mesh size,
    /// where calling [`Mesh::fan`] for every vertex is quadratic).
    pub fn fans(&self) -> Result<Vec<Fan>, MeshError> {
        let mut around = vec![Vec::new(); self.n_vertices()];
        for (t, tri) in self.triangles.iter().enumerate() {
            for &v in tri {
                around[v.index()].push(FacetId(t));
            }
        }
        around
            .iter()
            .enumerate()
            .map(|(v, faces)| self.fan_of(VertexId(v), faces))
            .collect()
    }

    fn fan_of(&self, v: VertexId, faces_at_v: &[FacetId]) -> Result<Fan, MeshError> {
        // For each incident face: the edge entering (v -> prev-ccw) and leaving.
        // In a CCW triangle (v, p, q): going CCW around v we pass edge v-p,
        // then the face, then edge v-q.
        let mut incident: Vec<(FacetId, EdgeId, EdgeId)> = Vec::new(); // (face, in_edge, out_edge)
        for &t in faces_at_v {
            let tri = self.triangle(t);
            if let Some(k) = tri.iter().position(|&x| x == v) {
                let fe = self.sides_of(t);
                // side k is (tri[k], tri[k+1]); side k+2 is (tri[k+2], tri[k]).
                incident.push((t, fe[k], fe[(k + 2) % 3]));
            }
        }
        if incident.is_empty() {
            return Ok(Fan {
                vertex: v,
                faces: vec![],
                edges: vec![],
                closed: false,
            });
        }
        // Find a start: a face whose in-edge is a boundary edge (open fan).
        let start = incident
            .iter()
            .position(|&(_, ein, _)| self.faces_of(ein).len() == 1)
            .unwrap_or(0);
        let closed = self.faces_of(incident[start].1).len() == 2;
        let mut faces = Vec::with_capacity(incident.len());
        let mut edges = vec![incident[start].1];
        let mut cur = start;
        let mut used = vec![false; incident.len()];
        loop {
            used[cur] = true;
            let (t, _, eout) = incident[cur];
            faces.push(t);
            if self.faces_of(eout).len() == 1 {
                edges.push(eout);
                break;
            }
            let next = incident
                .iter()
                .position(|&(t2, ein, _)| ein == eout && t2 != t);
            match next {
                Some(n) if !used[n] => {
                    edges.push(eout);
                    cur = n;
                }
                Some(n) if n == start && closed => break,
                _ => return Err(MeshError::NonManifoldVertex { vertex: v }),
            }
        }
        if faces.len() != incident.len() {
            return Err(MeshError::NonManifoldVertex { vertex: v });
        }
        Ok(Fan {
            vertex: v,
            faces,
            edges,
            closed,
        })
    }
}

#[doc(hidden)]
/// The counter-clockwise fan of triangles around one vertex (see [`Mesh::fan`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Fan {
    /// The centre vertex.
    pub vertex: VertexId,
    /// Faces in counter-clockwise order.
    pub faces: Vec<FacetId>,
    /// Edges in counter-clockwise order; `edges[i]` precedes `faces[i]`.
    pub edges: Vec<EdgeId>,
    /// True for an interior vertex (the fan closes on itself).
    pub closed: bool,
}

/// Small builders for test and example meshes.
pub mod builders {
    use super::*;

    /// Unit square (side `a`) split along the 0-2 diagonal into two triangles.
    /// Vertices 0 (0,0), 1 (a,0), 2 (a,a), 3 (0,a); the diagonal is a crease
    /// folding to `fold_target` when `crease` is true, smooth otherwise.
    pub fn square_with_diagonal(a: f64, crease: bool, fold_target: f64) -> Mesh {
        let coords = vec![
            Vector2::new(0.0, 0.0),
            Vector2::new(a, 0.0),
            Vector2::new(a, a),
            Vector2::new(0.0, a),
        ];
        let tris = vec![vertex_ids([0, 1, 2]), vertex_ids([0, 2, 3])];
        let diag = if crease {
            Edge::crease(VertexId(0), VertexId(2), fold_target)
        } else {
            Edge::smooth(VertexId(0), VertexId(2))
        };
        Mesh::new(coords, tris, vec![diag]).expect("valid square")
    }

    /// A rectangular strip `[0, lx] x [0, ly]` with `nx` x `ny` cells, each
    /// split into two triangles along alternating diagonals; all interior
    /// edges smooth.
    pub fn strip(lx: f64, ly: f64, nx: usize, ny: usize) -> Mesh {
        grid(lx, ly, nx, ny, &[])
    }

    /// Like [`strip`], with the vertical grid lines at the listed column
    /// indices (1..nx) made creases folding to `fold_target`.
    pub fn grid(lx: f64, ly: f64, nx: usize, ny: usize, crease_cols: &[(usize, f64)]) -> Mesh {
        grid_with(lx, ly, nx, ny, crease_cols, true)
    }

    /// Like [`grid`]; with `alternate` false every cell is split along the
    /// same diagonal (a three-direction mesh).
    pub fn grid_with(
        lx: f64,
        ly: f64,
        nx: usize,
        ny: usize,
        crease_cols: &[(usize, f64)],
        alternate: bool,
    ) -> Mesh {
        let diagonals = if alternate {
            Diagonals::Alternating
        } else {
            Diagonals::Same
        };
        grid_family(lx, ly, nx, ny, crease_cols, diagonals, 0.0)
    }

    /// How the cells of a structured grid are split into two triangles.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum Diagonals {
        /// Every cell along the same diagonal (a three-direction mesh).
        Same,
        /// Alternating like a chessboard ("union-jack").
        Alternating,
        /// Each cell's diagonal drawn at random (the seed).
        Random(u64),
    }

    /// The general structured grid: `nx` x `ny` cells on `[0, lx] x [0, ly]`
    /// split by `diagonals`, the vertical lines at `crease_cols` creases.
    /// With `jitter > 0` every vertex moves by up to `jitter` cell sizes
    /// (seeded like the diagonals): interior vertices in both directions,
    /// vertices on the boundary, a crease line or the middle grid lines only
    /// along their line (so the centre vertex stays put), corners not.
    pub fn grid_family(
        lx: f64,
        ly: f64,
        nx: usize,
        ny: usize,
        crease_cols: &[(usize, f64)],
        diagonals: Diagonals,
        jitter: f64,
    ) -> Mesh {
        let id = |i: usize, j: usize| VertexId(j * (nx + 1) + i);
        let seed = match diagonals {
            Diagonals::Random(s) => s,
            _ => 0x9E37_79B9_7F4A_7C15,
        };
        let mut rng = crate::rng::XorShift(seed | 1);
        let (dx, dy) = (lx / nx as f64, ly / ny as f64);
        let mut coords = Vec::new();
        for j in 0..=ny {
            for i in 0..=nx {
                let mut p = Vector2::new(lx * i as f64 / nx as f64, ly * j as f64 / ny as f64);
                if jitter > 0.0 {
                    let (sx, sy) = (rng.uniform() - 0.5, rng.uniform() - 0.5);
                    let on_x_line =
                        i == 0 || i == nx || 2 * i == nx || crease_cols.iter().any(|c| c.0 == i);
                    let on_y_line = j == 0 || j == ny || 2 * j == ny;
                    if !on_x_line {
                        p.x += 2.0 * jitter * dx * sx;
                    }
                    if !on_y_line {
                        p.y += 2.0 * jitter * dy * sy;
                    }
                }
                coords.push(p);
            }
        }
        let mut tris = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                let along_ac = match diagonals {
                    Diagonals::Same => true,
                    Diagonals::Alternating => (i + j) % 2 == 0,
                    Diagonals::Random(_) => rng.uniform() < 0.5,
                };
                if along_ac {
                    tris.push([a, b, c]);
                    tris.push([a, c, d]);
                } else {
                    tris.push([a, b, d]);
                    tris.push([b, c, d]);
                }
            }
        }
        let mut edges = Vec::new();
        for &(i, target) in crease_cols {
            for j in 0..ny {
                edges.push(Edge::crease(id(i, j), id(i, j + 1), target));
            }
        }
        Mesh::new(coords, tris, edges).expect("valid grid")
    }
}

#[cfg(test)]
mod tests {
    use super::builders::*;
    use super::*;

    fn v(x: f64, y: f64) -> Vector2<f64> {
        Vector2::new(x, y)
    }

    #[test]
    fn square_topology() {
        let m = square_with_diagonal(1.0, true, 1.0);
        assert_eq!(m.edges.len(), 5);
        assert_eq!(m.edges[0].kind, EdgeKind::Crease);
        assert_eq!(
            m.edges
                .iter()
                .filter(|e| e.kind == EdgeKind::Boundary)
                .count(),
            4
        );
        let fan0 = m.fan(VertexId(0)).unwrap();
        assert!(!fan0.closed);
        assert_eq!(fan0.faces, vec![FacetId(0), FacetId(1)]);
        assert_eq!(fan0.edges.len(), 3);
        assert_eq!(fan0.edges[1], EdgeId(0));
    }

    #[test]
    fn interior_fan_is_closed() {
        let m = grid(2.0, 2.0, 2, 2, &[]);
        let centre = VertexId(4);
        let fan = m.fan(centre).unwrap();
        assert!(fan.closed);
        assert_eq!(fan.faces.len(), fan.edges.len());
        assert!(fan.faces.len() >= 4);
    }

    #[test]
    fn bad_meshes_are_errors() {
        let sq = || vec![v(0., 0.), v(1., 0.), v(1., 1.), v(0., 1.)];
        assert!(matches!(
            Mesh::new(sq(), vec![vertex_ids([0, 1, 7])], vec![]),
            Err(MeshError::VertexOutOfRange {
                vertex: VertexId(7),
                ..
            })
        ));
        assert!(matches!(
            Mesh::new(sq(), vec![vertex_ids([0, 2, 1])], vec![]),
            Err(MeshError::Inverted {
                triangle: FacetId(0)
            })
        ));
        let line = vec![v(0., 0.), v(1., 0.), v(2., 0.)];
        assert!(matches!(
            Mesh::new(line, vec![vertex_ids([0, 1, 2])], vec![]),
            Err(MeshError::Degenerate {
                triangle: FacetId(0),
                ..
            })
        ));
        // crease with one facet
        assert!(matches!(
            Mesh::new(
                sq(),
                vec![vertex_ids([0, 1, 2])],
                vec![Edge::crease(VertexId(0), VertexId(1), 1.0)]
            ),
            Err(MeshError::CreaseNotInterior {
                edge: EdgeId(0),
                faces: 1
            })
        ));
        // three triangles on edge 0-1 (non-manifold)
        let c = vec![v(0., 0.), v(1., 0.), v(0.5, 1.), v(0.5, 2.), v(0.5, -1.)];
        let tris = vec![
            vertex_ids([0, 1, 2]),
            vertex_ids([0, 1, 3]),
            vertex_ids([1, 0, 4]),
        ];
        let err = Mesh::new(c, tris, vec![]).unwrap_err();
        assert!(matches!(err, MeshError::NonManifold { .. }), "{err}");
        assert!(err.to_string().contains("non-manifold"));
    }
}
