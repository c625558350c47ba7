//! Uniform refinement: every triangle into four through its edge midpoints.
//!
//! One level puts a new vertex at the midpoint of every mesh edge, appended
//! after the existing vertices in edge order (so FOLD vertex indices stay
//! valid); edge `e` becomes edges `2e` and `2e + 1`, keeping its kind, fold
//! target and `fold_edge` tag; the three edges inside each old triangle
//! follow as smooth edges. Actuator edge lists are mapped onto the halves;
//! supports and vertex inputs keep their vertices; the FOLD counts are
//! unchanged.

use super::Scene;
use super::error::SceneError;
use crate::ids::{EdgeId, VertexId};
use crate::mesh::{Edge, EdgeKind, Mesh, MeshError};

/// Most triangles a refinement may produce: the size budget
/// [`super::build::MAX_FACETS`].
pub const MAX_TRIANGLES: usize = super::build::MAX_FACETS;

/// The two halves of mesh edge `e` after one level of refinement: new
/// edges `2e` and `2e + 1` (from its first vertex to the midpoint, and on).
pub fn halves(e: EdgeId) -> [EdgeId; 2] {
    [EdgeId(2 * e.index()), EdgeId(2 * e.index() + 1)]
}

/// One level of refinement of a mesh; returns the new mesh (old edge `e`
/// is new edges [`halves`]`(e)`).
pub fn refine_mesh(mesh: &Mesh) -> Result<Mesh, MeshError> {
    let nv = mesh.n_vertices();
    let mut coords = mesh.coords().to_vec();
    for e in mesh.edges() {
        coords.push(0.5 * (mesh.coord(e.v[0]) + mesh.coord(e.v[1])));
    }
    // The midpoint of edge e: new vertex nv + e.
    let mid = |e: EdgeId| VertexId(nv + e.index());
    let mut edges = Vec::with_capacity(2 * mesh.edges().len() + 3 * mesh.triangles().len());
    // Pushed in edge order, two per edge: edge e becomes halves(e).
    for (e, old) in mesh.edge_ids().zip(mesh.edges()) {
        for half in [[old.v[0], mid(e)], [mid(e), old.v[1]]] {
            edges.push(Edge {
                v: half,
                kind: old.kind,
                fold_target: old.fold_target,
                fold_edge: old.fold_edge,
            });
        }
    }
    let mut triangles = Vec::with_capacity(4 * mesh.triangles().len());
    for (t, &[a, b, c]) in mesh.facet_ids().zip(mesh.triangles()) {
        let [eab, ebc, eca] = mesh.sides_of(t);
        let (mab, mbc, mca) = (mid(eab), mid(ebc), mid(eca));
        triangles.push([a, mab, mca]);
        triangles.push([mab, b, mbc]);
        triangles.push([mca, mbc, c]);
        triangles.push([mab, mbc, mca]);
        for (p, q) in [(mab, mbc), (mbc, mca), (mca, mab)] {
            edges.push(Edge::smooth(p, q));
        }
    }
    Mesh::new(coords, triangles, edges)
}

/// `levels` levels of refinement of a scene (see the module docs).
pub fn refine(scene: &Scene, levels: usize) -> Result<Scene, SceneError> {
    let tris = scene.mesh.triangles().len();
    let grown = (0..levels).try_fold(tris, |n, _| {
        n.checked_mul(4).filter(|&m| m <= MAX_TRIANGLES)
    });
    if grown.is_none() {
        return Err(SceneError::invalid(
            "ancf:refine",
            format!(
                "{levels} level(s) would turn {tris} triangles into more than {MAX_TRIANGLES}, \
                 the size budget; use fewer levels"
            ),
        ));
    }
    let mut out = scene.clone();
    for _ in 0..levels {
        out.mesh = refine_mesh(&out.mesh)
            .map_err(|e| SceneError::invalid("ancf:refine", format!("refinement failed: {e}")))?;
        for a in &mut out.actuators {
            a.edges = a.edges.iter().flat_map(|&e| halves(e)).collect();
        }
    }
    debug_assert!(out.mesh.edges().iter().all(|e| e.kind != EdgeKind::Crease
        || e.fold_edge.is_some_and(|f| f.index() < out.fold_edge_count)));
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ids::FoldEdgeId;
    use crate::mesh::builders::square_with_diagonal;

    #[test]
    fn square_refines_into_four_times_the_triangles() {
        let mut m = square_with_diagonal(1.0, true, 1.0);
        m.tag_creases_as_fold_edges();
        assert_eq!(m.edges()[0].fold_edge, Some(FoldEdgeId(0)));
        let r = refine_mesh(&m).unwrap();
        assert_eq!(r.triangles().len(), 8);
        assert_eq!(r.n_vertices(), 4 + 5);
        let area: f64 = r.facet_ids().map(|t| r.area(t)).sum();
        assert!((area - 1.0).abs() < 1e-14);
        // The crease 0-2 became two creases through the centre, same target and tag.
        for e in [EdgeId(0), EdgeId(1)] {
            assert_eq!(r.edge(e).kind, EdgeKind::Crease);
            assert_eq!(r.edge(e).fold_target, 1.0);
            assert_eq!(r.edge(e).fold_edge, Some(FoldEdgeId(0)));
            assert!((r.edge_length(e) - 0.5 * 2f64.sqrt()).abs() < 1e-14);
        }
        let creases = r.creases().count();
        assert_eq!(creases, 2);
        let boundary = r
            .edges()
            .iter()
            .filter(|e| e.kind == EdgeKind::Boundary)
            .count();
        assert_eq!(boundary, 8);
    }
}
