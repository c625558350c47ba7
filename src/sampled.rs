//! The sheet as the pictures and ParaView draw it: the sampled surface that
//! self-contact keeps apart (each facet's sub-triangles at contact's
//! subdivisions, every sample an exact map of the state), so that what the
//! user sees is what contact computes with. Without contact, the curved
//! facets are sampled the same way at the default subdivisions: the shell's
//! bending shows, and the picture is the surface contact would keep apart
//! if it were turned on with its defaults.

use crate::contact::surface::ContactSurface;
use crate::model::Model;
use nalgebra::Vector3;

/// The sampled surface of a model, its points numbered for drawing.
#[derive(Clone, Debug)]
pub struct SampledSheet {
    surf: ContactSurface,
    /// Contact vertex of each point: the mesh vertices first (in mesh
    /// order, so point `v` is mesh vertex `v`), then the other samples.
    vertex: Vec<usize>,
    /// Sub-triangles (points, counter-clockwise like their facet) and
    /// their facet (mesh triangle).
    pub triangles: Vec<([usize; 3], usize)>,
    /// Each mesh edge's samples (points), from its first vertex to its
    /// second.
    pub edges: Vec<Vec<usize>>,
}

impl SampledSheet {
    /// The sampled surface of `model` ([`Model::sampled_surface`]).
    pub fn new(model: &Model) -> SampledSheet {
        let mesh = &model.scene().mesh;
        let surf = model.sampled_surface().expect("a model is built");
        let mut point = vec![usize::MAX; surf.n_vertices()];
        let mut vertex = Vec::with_capacity(surf.n_vertices());
        let corners = mesh.vertex_ids().map(|v| surf.corner[v.index()]);
        for v in corners.chain(0..surf.n_vertices()) {
            if point[v] == usize::MAX {
                point[v] = vertex.len();
                vertex.push(v);
            }
        }
        let triangles = surf
            .fine_tris
            .iter()
            .map(|&(t, f)| (t.map(|v| point[v]), f))
            .collect();
        let edges = surf
            .edge_samples
            .iter()
            .map(|s| s.iter().map(|&v| point[v]).collect())
            .collect();
        SampledSheet {
            surf,
            vertex,
            triangles,
            edges,
        }
    }

    /// Subdivisions per facet side.
    pub fn subdivisions(&self) -> usize {
        self.surf.n
    }

    /// Number of points.
    pub fn n_points(&self) -> usize {
        self.vertex.len()
    }

    /// Every point of `model` now (m).
    pub fn points(&self, model: &Model) -> Vec<[f64; 3]> {
        let mut x = Vec::new();
        model.sampled_positions(&self.surf, &mut x);
        self.in_order(&x)
    }

    /// Every point in the flat reference (m).
    pub fn reference(&self) -> Vec<[f64; 3]> {
        self.in_order(&self.surf.rest)
    }

    /// Contact vertex positions `x` in the points' order.
    fn in_order(&self, x: &[Vector3<f64>]) -> Vec<[f64; 3]> {
        self.vertex.iter().map(|&v| x[v].into()).collect()
    }
}
