//! Cuts and vertices where sheets only touch: the vertices there are split
//! into copies, and a cut edge gets its second side.

use super::edges::{FoldEdges, Sides, key};
use super::invalid;
use crate::ids::{FoldEdgeId, vertex_ids};
use crate::mesh::{Edge, EdgeKind};
use crate::scene::error::SceneError;
use crate::scene::fold::Assignment;
use crate::scene::planar::{self, SideAt};
use nalgebra::Vector2;
use std::collections::HashMap;

/// Split vertices along cut edges and where sheets only touch at a vertex
/// ([`planar::split_vertices`]); renumber the mesh edges on split vertices
/// and add the second side of every cut. Returns, for each copy (mesh
/// vertex `nv + j`), the FOLD vertex it copies.
pub(super) fn split(
    faces: &mut [Vec<usize>],
    coords: &mut Vec<Vector2<f64>>,
    sides: &Sides,
    edges: &FoldEdges,
    mesh_edges: &mut Vec<Edge>,
    warnings: &mut Vec<String>,
    notes: &mut Vec<String>,
) -> Result<Vec<usize>, SceneError> {
    let cut: HashMap<(usize, usize), usize> = (0..edges.v.len())
        .filter(|&e| edges.assignment[e] == Assignment::Cut)
        .map(|e| (key(edges.v[e][0], edges.v[e][1]), e))
        .collect();
    let shared: Vec<(SideAt, SideAt, bool)> = sides
        .order
        .iter()
        .filter_map(|k| {
            let l = &sides.map[k];
            (l.len() == 2).then(|| ((l[0].0, l[0].1), (l[1].0, l[1].1), cut.contains_key(k)))
        })
        .collect();
    let original: Vec<Vec<usize>> = faces.to_vec();
    let nv = coords.len();
    let copies = planar::split_vertices(faces, coords, &shared);
    if copies.is_empty() {
        let closed = (0..edges.v.len()).find(|&e| {
            edges.assignment[e] == Assignment::Cut && sides.count(edges.v[e][0], edges.v[e][1]) == 2
        });
        if let Some(e) = closed {
            let [a, b] = edges.v[e];
            return Err(invalid(
                format!("edges_vertices[{e}]"),
                format!(
                    "the cut {a}-{b} cannot open: both of its ends stay joined to the sheet (a \
                     cut inside the sheet must run along at least two edges, or reach the \
                     boundary)"
                ),
            ));
        }
        return Ok(copies);
    }
    // Where a side of an original face now runs.
    let now = |(f, k): SideAt, a: usize| -> [usize; 2] {
        let n = faces[f].len();
        let (p, q) = (faces[f][k], faces[f][(k + 1) % n]);
        if original[f][k] == a { [p, q] } else { [q, p] }
    };
    for (e, edge) in mesh_edges.iter_mut().enumerate() {
        let [a, _] = edges.v[e];
        let at = sides.at(edges.v[e][0], edges.v[e][1]);
        let v = now(at[0], a);
        edge.v = vertex_ids(v);
        if edges.assignment[e] == Assignment::Cut && at.len() == 2 {
            let other = now(at[1], a);
            if key(other[0], other[1]) == key(v[0], v[1]) {
                let [a, b] = edges.v[e];
                return Err(invalid(
                    format!("edges_vertices[{e}]"),
                    format!(
                        "the cut {a}-{b} cannot open: both of its ends stay joined to the sheet \
                         (a cut inside the sheet must run along at least two edges, or reach the \
                         boundary)"
                    ),
                ));
            }
        }
    }
    for (e, &[a, b]) in edges.v.iter().enumerate() {
        if edges.assignment[e] == Assignment::Cut {
            let at = sides.at(a, b);
            if at.len() == 2 {
                let v = now(at[1], a);
                mesh_edges.push(Edge {
                    v: vertex_ids(v),
                    kind: EdgeKind::Boundary,
                    fold_target: 0.0,
                    fold_edge: Some(FoldEdgeId(e)),
                });
            }
        }
    }
    // Which copies come from cuts, which from sheets touching at a point.
    let mut on_cut = vec![false; nv];
    for k in cut.keys() {
        on_cut[k.0] = true;
        on_cut[k.1] = true;
    }
    let (by_cut, touching): (Vec<usize>, Vec<usize>) = copies.iter().partition(|&&v| on_cut[v]);
    if !by_cut.is_empty() {
        notes.push(format!(
            "cuts: {} cut edge(s) (C) open the sheet; {} vertex copies were made along them \
             (mesh vertices {} on); outputs vertex[i] follow the first copy, supports hold all",
            cut.len(),
            by_cut.len(),
            nv
        ));
    }
    if let Some(&v) = touching.first() {
        warnings.push(format!(
            "vertices_coords[{v}]: at {} vertex(es) (first: {v}) the faces form separate fans \
             (sheets touching only at a point); each is split into one vertex per fan, so the \
             sheets are free to move apart there",
            touching.len()
        ));
    }
    Ok(copies)
}

#[cfg(test)]
mod tests {
    use super::super::fixtures::{base, err, load, with};
    use crate::ids::{FoldEdgeId, VertexId};
    use crate::mesh::{Edge, EdgeKind};
    use crate::scene::LoadOptions;
    use crate::scene::build::from_fold_with;
    use serde_json::json;

    #[test]
    fn cuts() {
        // a cut across the sheet: two separate panels, vertices 1 and 4 split
        let v = with(
            base(),
            "edges_assignment",
            json!(["B", "B", "B", "B", "B", "B", "C"]),
        );
        let l = from_fold_with(
            &crate::scene::fold::parse(&v.to_string(), None).unwrap().0,
            &LoadOptions::default(),
        )
        .unwrap();
        let s = &l.scene;
        assert_eq!(s.mesh.n_vertices(), 8);
        assert_eq!(s.fold_vertex_count, 6);
        assert_eq!(s.mesh.coords()[6], s.mesh.coords()[1]);
        assert_eq!(s.mesh.coords()[7], s.mesh.coords()[4]);
        assert!(
            l.notes.iter().any(|n| n.starts_with("cuts: 1 cut edge")),
            "{:?}",
            l.notes
        );
        assert!(
            l.warnings[0].contains("angle 90 of the C edge 1-4 is ignored"),
            "{:?}",
            l.warnings
        );
        // both sides of the cut are boundary edges on FOLD edge 6
        let cut: Vec<&Edge> = s
            .mesh
            .edges()
            .iter()
            .filter(|e| e.fold_edge == Some(FoldEdgeId(6)))
            .collect();
        assert_eq!(cut.len(), 2);
        assert!(cut.iter().all(|e| e.kind == EdgeKind::Boundary));
        assert!(s.actuators[0].edges.is_empty());
        // a support on a split vertex holds both copies
        let (s, _) = load(&with(
            v.clone(),
            "ancf:supports",
            json!([{"vertices": [1]}]),
        ))
        .unwrap();
        assert_eq!(s.supports[0].vertices, vec![VertexId(1), VertexId(6)]);
        crate::model::Model::new(s).unwrap();
        // a cut of one edge inside the sheet cannot open
        let v = json!({
            "frame_unit": "m",
            "vertices_coords": [[0,0],[3,0],[3,3],[0,3],[1,1],[2,2]],
            "edges_vertices": [[0,1],[1,2],[2,3],[3,0],[4,5],[0,4],[4,3],[1,5],[5,2],[1,4],[3,5]],
            "edges_assignment": ["B","B","B","B","C","F","F","F","F","F","F"],
            "faces_vertices": [[0,1,4],[1,5,4],[1,2,5],[2,3,5],[3,4,5],[3,0,4]]
        });
        let e = err(&v, "edges_vertices[4]");
        assert!(e.contains("cannot open"), "{e}");
    }
}
