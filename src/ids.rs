//! Typed indices for the kinds of index that get mixed up: a mesh vertex, a
//! facet (mesh triangle), a mesh edge and a FOLD edge. Each is a `usize`
//! in a newtype; [`VertexId::index`] (and the like) gives the number back
//! to index a slice. Serialized as the bare number (`#[serde(transparent)]`),
//! so saved scenes and states read and write the same JSON as before.
//!
//! A FOLD edge and a mesh edge are different things: the loader puts FOLD
//! edge `e` at mesh edge `e` ([`EdgeId::of_fold_edge`]) before refinement,
//! which splits every mesh edge in two; after that, only the tag
//! [`crate::mesh::Edge::fold_edge`] says which FOLD edge a mesh edge lies on.

use serde::{Deserialize, Serialize};
use std::fmt;

macro_rules! id {
    ($(#[$doc:meta])* $name:ident) => {
        $(#[$doc])*
        #[derive(
            Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize,
            Deserialize,
        )]
        #[serde(transparent)]
        pub struct $name(pub usize);

        impl $name {
            /// The number, to index a slice.
            #[inline]
            pub const fn index(self) -> usize {
                self.0
            }
        }

        impl From<usize> for $name {
            fn from(i: usize) -> Self {
                $name(i)
            }
        }

        // Debug as the bare number too, so that messages listing ids
        // (`{:?}` of a list) read as they did with plain numbers.
        impl fmt::Debug for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                self.0.fmt(f)
            }
        }

        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                self.0.fmt(f)
            }
        }
    };
}

id!(
    /// A mesh vertex: FOLD vertex `i` is mesh vertex `i`; copies of split
    /// vertices and refinement midpoints come after the FOLD vertices.
    VertexId
);
id!(
    /// A facet: one triangle of the mesh.
    FacetId
);
id!(
    /// A mesh edge (after triangulation, splitting and refinement).
    EdgeId
);
id!(
    /// An edge of the FOLD file (`edges_vertices[i]`).
    FoldEdgeId
);

impl VertexId {
    /// The mesh vertex of FOLD vertex `i` (`vertices_coords[i]`): the same
    /// number, in every mesh the loader builds (copies of split vertices
    /// and refinement midpoints come after the FOLD vertices).
    pub const fn of_fold_vertex(i: usize) -> VertexId {
        VertexId(i)
    }
}

impl EdgeId {
    /// The mesh edge of FOLD edge `f` in a mesh as the loader builds it,
    /// before refinement: the FOLD edges come first, in order (see
    /// [`crate::scene::build`]). After refinement this no longer holds.
    pub const fn of_fold_edge(f: FoldEdgeId) -> EdgeId {
        EdgeId(f.0)
    }
}

impl FoldEdgeId {
    /// The FOLD edge of mesh edge `e` of a mesh built in code, with no FOLD
    /// file behind it: its edge indices are the FOLD edge indices.
    pub const fn of_mesh_edge(e: EdgeId) -> FoldEdgeId {
        FoldEdgeId(e.0)
    }
}

#[doc(hidden)]
/// Vertex ids from numbers: `vertex_ids([0, 1, 2])` is a triangle.
pub fn vertex_ids<const N: usize>(v: [usize; N]) -> [VertexId; N] {
    v.map(VertexId)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Edge, builders::square_with_diagonal};

    #[test]
    fn serialized_and_printed_as_bare_numbers() {
        assert_eq!(serde_json::to_string(&VertexId(3)).unwrap(), "3");
        let e: FoldEdgeId = serde_json::from_str("7").unwrap();
        assert_eq!(e, FoldEdgeId(7));
        let mut edge = Edge::crease(VertexId(0), VertexId(2), 1.5);
        edge.fold_edge = Some(FoldEdgeId(4));
        assert_eq!(
            serde_json::to_string(&edge).unwrap(),
            r#"{"v":[0,2],"kind":"Crease","fold_target":1.5,"fold_edge":4}"#
        );
        // A mesh (and so a saved scene) reads and writes plain index arrays.
        let json = serde_json::to_value(square_with_diagonal(1.0, true, 1.0)).unwrap();
        assert_eq!(json["triangles"], serde_json::json!([[0, 1, 2], [0, 2, 3]]));
        assert_eq!(json["edge_faces"][0], serde_json::json!([0, 1]));
        assert_eq!(json["face_edges"][0], serde_json::json!([1, 2, 0]));
        assert_eq!(format!("{:?}", vec![EdgeId(1), EdgeId(2)]), "[1, 2]");
        assert_eq!(format!("{}", FacetId(5)), "5");
    }

    #[test]
    fn fold_edge_and_mesh_edge_are_the_same_number_before_refinement() {
        assert_eq!(EdgeId::of_fold_edge(FoldEdgeId(6)), EdgeId(6));
        assert_eq!(FoldEdgeId::of_mesh_edge(EdgeId(6)), FoldEdgeId(6));
        assert_eq!(VertexId::of_fold_vertex(2), VertexId(2));
    }
}
