//! The intersection checker the tests run after every output: each curved
//! facet sampled on a lattice (`m` subdivisions per side, on the shell's
//! own interpolation; samples on a shared side or corner computed once, so
//! neighbouring facets meet exactly there), exact triangle-triangle tests
//! between every two facets, neighbours included (sub-triangles that share
//! samples are tested beyond what they share), and the smallest distance
//! between facets that share no vertex. At contact's own sampling
//! ([`check_surface`] on self-contact's surface) it checks the guarantee;
//! finer, it shows where the curved facets cross between the samples.

use super::broad::{Aabb, overlapping};
use super::distance::{V3, edge_edge_distance_sq, point_triangle_distance_sq};
use super::intersect::{orient3d, segment_triangle_intersect, triangles_intersect};
use super::surface::ContactSurface;
use crate::assembly::Assembler;
use crate::mesh::Mesh;
use nalgebra::Vector3;
use std::cmp::Ordering;

/// What the checker found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IntersectionReport {
    /// Facet pairs whose sampled surfaces cross (neighbours: beyond the
    /// samples they share).
    pub intersecting: Vec<(usize, usize)>,
    /// Smallest distance between the sampled surfaces of two facets that
    /// share no vertex, among those within `search` (else `search`).
    pub min_distance: f64,
    /// Crease edges folded past flat (a fold angle beyond +-180 degrees:
    /// the facets across them have passed through each other), where the
    /// caller knows the fold angles ([`crate::model::Model::check_intersections`]).
    pub past_flat: Vec<crate::ids::EdgeId>,
}

impl IntersectionReport {
    /// Whether nothing crosses.
    pub fn is_clear(&self) -> bool {
        self.intersecting.is_empty() && self.past_flat.is_empty()
    }
}

/// The sheet at `q` sampled with `m` subdivisions per facet side: the
/// sample points and each facet's sub-triangles (indices into them).
pub struct Sampled {
    /// Sample points (one per lattice site; shared sides and corners once).
    pub points: Vec<Vector3<f64>>,
    /// Each facet's `m^2` sub-triangles.
    pub tris: Vec<Vec<[usize; 3]>>,
}

/// Every facet of `surf` at `q`: its samples and sub-triangles.
pub fn sample_surface(surf: &ContactSurface, q: &[f64]) -> Sampled {
    let mut points = Vec::new();
    surf.positions(q, &mut points);
    let tris = surf
        .facet_fine_tris
        .iter()
        .map(|ks| ks.iter().map(|&k| surf.fine_tris[k].0).collect())
        .collect();
    Sampled { points, tris }
}

/// Check the sheet at slot vector `q` (facets sampled with `m`
/// subdivisions); distances between facets that share no vertex are looked
/// for up to `search` (none with 0: only crossings, which is much cheaper).
/// A cut's lips stand back by self-contact's kerf, as on its own surface.
pub fn check(asm: &Assembler, mesh: &Mesh, q: &[f64], m: usize, search: f64) -> IntersectionReport {
    let kerf = asm.contact().map_or(0.0, |c| c.surface().kerf);
    let surf = ContactSurface::new(mesh, &asm.layout, &asm.elements, m, false, kerf);
    check_surface(&surf, mesh, q, search)
}

/// [`check`] on a sampled surface already built (self-contact's own, so
/// that what is checked is what contact keeps apart).
pub fn check_surface(
    surf: &ContactSurface,
    mesh: &Mesh,
    q: &[f64],
    search: f64,
) -> IntersectionReport {
    let s = sample_surface(surf, q);
    let p = &s.points;
    let corners = |t: &[usize; 3]| [p[t[0]], p[t[1]], p[t[2]]];
    // Each facet's sub-triangles' boxes, tight (crossings) and padded
    // (distances), and the facet's box around them.
    let tight: Vec<Vec<Aabb>> = s
        .tris
        .iter()
        .map(|ts| ts.iter().map(|t| Aabb::around(&corners(t), 0.0)).collect())
        .collect();
    let padded: Vec<Vec<Aabb>> = if search > 0.0 {
        s.tris
            .iter()
            .map(|ts| {
                ts.iter()
                    .map(|t| Aabb::around(&corners(t), 0.5 * search))
                    .collect()
            })
            .collect()
    } else {
        tight.clone()
    };
    let boxes: Vec<Aabb> = padded
        .iter()
        .map(|bs| {
            bs.iter().skip(1).fold(bs[0], |a, b| Aabb {
                lo: a.lo.inf(&b.lo),
                hi: a.hi.sup(&b.hi),
            })
        })
        .collect();
    let mut rep = IntersectionReport {
        min_distance: search,
        ..Default::default()
    };
    for (f, g) in overlapping(&boxes, &boxes, true) {
        let (tf, tg) = (mesh.triangles()[f], mesh.triangles()[g]);
        let neighbours = tf.iter().any(|v| tg.contains(v));
        let distances = !neighbours && search > 0.0;
        let (bf, bg) = if distances {
            (&padded[f], &padded[g])
        } else {
            (&tight[f], &tight[g])
        };
        let mut hit = false;
        for (i, j) in overlapping(bf, bg, false) {
            let (a, b) = (&s.tris[f][i], &s.tris[g][j]);
            if !hit && cross(p, a, b) {
                hit = true;
            }
            if distances {
                rep.min_distance = rep
                    .min_distance
                    .min(triangle_distance(&corners(a), &corners(b)));
            }
        }
        if hit {
            rep.intersecting.push((f, g));
            if !neighbours {
                rep.min_distance = 0.0;
            }
        }
    }
    rep
}

/// Whether sub-triangles `a` and `b` (indices into `p`) cross beyond the
/// samples they share. Sharing none: any common point. Sharing one, `s`:
/// two triangles meet beyond a common vertex only if the side of one
/// opposite it meets the other (their intersection is convex, and away
/// from `s` its boundary runs along those sides). Sharing a side: only when
/// they lie in one plane on the same side of it (otherwise the planes meet
/// in that side's line alone).
fn cross(p: &[Vector3<f64>], a: &[usize; 3], b: &[usize; 3]) -> bool {
    let shared: Vec<usize> = a.iter().copied().filter(|v| b.contains(v)).collect();
    let pa = [p[a[0]], p[a[1]], p[a[2]]];
    let pb = [p[b[0]], p[b[1]], p[b[2]]];
    let others = |t: &[usize; 3]| -> Vec<Vector3<f64>> {
        t.iter()
            .filter(|v| !shared.contains(v))
            .map(|&v| p[v])
            .collect()
    };
    match shared.len() {
        0 => triangles_intersect(pa, pb),
        1 => {
            let (oa, ob) = (others(a), others(b));
            segment_triangle_intersect(&oa[0], &oa[1], &pb)
                || segment_triangle_intersect(&ob[0], &ob[1], &pa)
        }
        2 => {
            let (s0, s1) = (p[shared[0]], p[shared[1]]);
            let (oa, ob) = (others(a)[0], others(b)[0]);
            if orient3d(&s0, &s1, &oa, &ob) != Ordering::Equal {
                return false;
            }
            // In their plane: on the same side of the shared side when the
            // triangle of the side and `oa` contains points beyond it
            // towards `ob`, i.e. `ob` and `oa` turn alike about it; the
            // plane's normal picks the turning sense.
            let n = (s1 - s0).cross(&(oa - s0));
            let far = s0 + n;
            orient3d(&s0, &s1, &far, &oa) == orient3d(&s0, &s1, &far, &ob)
        }
        _ => false,
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    /// Sub-triangles sharing samples cross only beyond them.
    #[test]
    fn shared_samples_are_no_crossing() {
        // 0 shared at the origin; a fan of triangles about the z axis.
        let p = vec![
            v(0.0, 0.0, 0.0),  // 0: shared vertex
            v(1.0, 0.0, 0.0),  // 1
            v(0.0, 1.0, 0.0),  // 2
            v(1.0, 0.0, 1.0),  // 3
            v(-1.0, 0.0, 1.0), // 4
            v(0.3, 0.3, -1.0), // 5
            v(0.3, 0.3, 1.0),  // 6
            v(0.5, 0.5, 0.0),  // 7: in the plane z = 0
            v(-1.0, -1.0, 0.0),
        ];
        // Sharing vertex 0 only, apart: no crossing.
        assert!(!cross(&p, &[0, 1, 2], &[0, 3, 4]));
        // Sharing vertex 0, the other's far side pierces: crossing.
        assert!(cross(&p, &[0, 1, 2], &[0, 5, 6]));
        // Sharing the side 0-1, hinged out of the plane: none.
        assert!(!cross(&p, &[0, 1, 2], &[0, 1, 3]));
        // Sharing the side 0-1, folded flat onto each other: crossing.
        assert!(cross(&p, &[0, 1, 2], &[1, 0, 7]));
        // Sharing the side 0-1, flat but on opposite sides: none.
        assert!(!cross(&p, &[0, 1, 2], &[0, 1, 8]));
        // Sharing nothing: the exact test.
        assert!(
            cross(&p, &[1, 2, 5], &[3, 4, 6])
                == triangles_intersect([p[1], p[2], p[5]], [p[3], p[4], p[6]])
        );
    }
}
