//! The intersection checker the tests run after every output: each curved
//! facet sampled finely (`m` subdivisions per side, on the shell's own
//! interpolation), exact triangle-triangle tests between facets that share
//! no vertex, and the smallest distance between such facets.

use super::broad::{Aabb, overlapping};
use super::distance::{V3, edge_edge_distance_sq, point_triangle_distance_sq};
use super::intersect::triangles_intersect;
use crate::assembly::{Assembler, local_vector};
use crate::mesh::Mesh;
use nalgebra::Vector3;

/// What the checker found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IntersectionReport {
    /// Facet pairs (sharing no vertex) whose sampled surfaces intersect.
    pub intersecting: Vec<(usize, usize)>,
    /// Smallest distance between the sampled surfaces of two facets that
    /// share no vertex, among those within `search` (else `search`).
    pub min_distance: f64,
}

/// Sample every facet of `mesh` at `q` with `m` subdivisions per side.
pub fn sample_facets(asm: &Assembler, q: &[f64], m: usize) -> Vec<Vec<[Vector3<f64>; 3]>> {
    let m = m.max(1);
    let mf = m as f64;
    (0..asm.elements.len())
        .map(|f| {
            let e = local_vector(&asm.layout.local[f], q);
            let shape = asm.elements[f].shape();
            let at = |i: usize, j: usize| {
                shape.position(&e, [(m - i - j) as f64 / mf, i as f64 / mf, j as f64 / mf])
            };
            super::surface::lattice_triangles(m)
                .map(|t| t.map(|(i, j)| at(i, j)))
                .collect()
        })
        .collect()
}

/// Check the sheet at slot vector `q` (facets sampled with `m` subdivisions).
pub fn check(asm: &Assembler, mesh: &Mesh, q: &[f64], m: usize, search: f64) -> IntersectionReport {
    let tris = sample_facets(asm, q, m);
    let boxes: Vec<Aabb> = tris
        .iter()
        .map(|ts| {
            let pts: Vec<Vector3<f64>> = ts.iter().flat_map(|t| t.iter().copied()).collect();
            Aabb::around(&pts, 0.5 * search)
        })
        .collect();
    let mut rep = IntersectionReport {
        min_distance: search,
        ..Default::default()
    };
    for (f, g) in overlapping(&boxes, &boxes, true) {
        let (tf, tg) = (mesh.triangles()[f], mesh.triangles()[g]);
        if tf.iter().any(|v| tg.contains(v)) {
            continue;
        }
        let mut hit = false;
        for a in &tris[f] {
            for b in &tris[g] {
                if !hit && triangles_intersect(*a, *b) {
                    hit = true;
                }
                rep.min_distance = rep.min_distance.min(triangle_distance(a, b));
            }
        }
        if hit {
            rep.intersecting.push((f, g));
            rep.min_distance = 0.0;
        }
    }
    rep
}

/// Distance between two (non-intersecting) triangles: the smallest of the
/// point-triangle and edge-edge distances.
pub fn triangle_distance(a: &[Vector3<f64>; 3], b: &[Vector3<f64>; 3]) -> f64 {
    let c = |p: &Vector3<f64>| V3::<f64>::cst(p);
    let mut d2 = f64::INFINITY;
    for (x, y) in [(a, b), (b, a)] {
        for p in x {
            d2 = d2.min(point_triangle_distance_sq(
                &c(p),
                &c(&y[0]),
                &c(&y[1]),
                &c(&y[2]),
            ));
        }
    }
    for i in 0..3 {
        for j in 0..3 {
            d2 = d2.min(edge_edge_distance_sq(
                &c(&a[i]),
                &c(&a[(i + 1) % 3]),
                &c(&b[j]),
                &c(&b[(j + 1) % 3]),
            ));
        }
    }
    d2.sqrt()
}
