//! A cut's kerf in the sampled surface. Where two boundary lines of the
//! flat sheet lie on each other (the lips of a cut, the copies of a vertex
//! where sheets only touch), the samples on them stand back into their own
//! facets by `delta`: the lips start `2 delta` apart, beyond the contact
//! thickness and the barrier's width, so contact keeps them apart from the
//! first step instead of leaving out every pair that touches in the flat
//! sheet. The shell keeps the drawn line; only the sampled surface has the
//! kerf.

use super::Site;
use crate::ids::VertexId;
use crate::mesh::Mesh;
use nalgebra::Vector2;
use std::collections::HashMap;

/// A lattice site that stands back: the facet it is sampled on, its area
/// coordinates there, and those of the drawn site (for the chord probes).
pub(super) struct Recessed {
    pub(super) site: Site,
    pub(super) facet: usize,
    pub(super) at: [f64; 3],
    pub(super) drawn: [f64; 3],
}

/// The sites of the lattice with `n` subdivisions a side that stand back by
/// `delta` (m), in a fixed order: the samples inside the lips' sides, then
/// the copied corners. Empty where no two boundary lines lie on each other.
pub(super) fn recessed_sites(mesh: &Mesh, n: usize, delta: f64) -> Vec<Recessed> {
    let mut out = Vec::new();
    if delta.is_nan() || delta <= 0.0 {
        return out;
    }
    let group = coincident(mesh.coords(), 1e-9 * mesh.size());
    let copied: Vec<bool> = {
        let mut count = vec![0usize; group.len()];
        group.iter().for_each(|&g| count[g] += 1);
        group.iter().map(|&g| count[g] > 1).collect()
    };
    if !copied.iter().any(|&c| c) {
        return out;
    }
    let x = |v: VertexId| mesh.coord(v);
    // Lips: boundary edges whose ends lie where another boundary edge's do.
    let boundary: Vec<usize> = (0..mesh.edges().len())
        .filter(|&e| mesh.edge_faces()[e].len() == 1)
        .collect();
    let ends = |e: usize| {
        let [a, b] = mesh.edges()[e].v.map(|v| group[v.index()]);
        (a.min(b), a.max(b))
    };
    let mut on_line: HashMap<(usize, usize), usize> = HashMap::new();
    for &e in &boundary {
        *on_line.entry(ends(e)).or_insert(0) += 1;
    }
    for &e in boundary.iter().filter(|&&e| on_line[&ends(e)] > 1) {
        let f = mesh.edge_faces()[e][0].index();
        let tri = mesh.triangles()[f];
        let [a, b] = mesh.edges()[e].v;
        let (lo, hi) = (a.min(b), a.max(b));
        let third = tri.iter().copied().find(|&v| v != a && v != b).unwrap_or(a);
        let along = x(hi) - x(lo);
        let mut inward = Vector2::new(-along.y, along.x).normalize();
        if inward.dot(&(x(third) - x(lo))) < 0.0 {
            inward = -inward;
        }
        for k in 1..n {
            let drawn = x(lo) + along * (k as f64 / n as f64);
            if let Some((at, d)) = inside(mesh, f, drawn, inward * delta) {
                out.push(Recessed {
                    site: Site::Side(lo, hi, k),
                    facet: f,
                    at,
                    drawn: d,
                });
            }
        }
    }
    let Ok(fans) = mesh.fans() else {
        return out;
    };
    for v in mesh.vertex_ids().filter(|v| copied[v.index()]) {
        let fan = &fans[v.index()];
        if fan.closed || fan.faces.is_empty() {
            continue;
        }
        // The bisector of the open fan, swept from its first boundary edge
        // through its faces, and the distance along it that stands `delta`
        // off both boundary lines.
        let other = |e: crate::ids::EdgeId| {
            let [a, b] = mesh.edge(e).v;
            if a == v { b } else { a }
        };
        let angle_at = |f: crate::ids::FacetId| {
            let tri = mesh.triangle(f);
            let k = tri.iter().position(|&w| w == v).unwrap_or(0);
            let (p, q) = (x(tri[(k + 1) % 3]) - x(v), x(tri[(k + 2) % 3]) - x(v));
            p.angle(&q)
        };
        let sweep: f64 = fan.faces.iter().map(|&f| angle_at(f)).sum();
        let u = (x(other(fan.edges[0])) - x(v)).normalize();
        let next = x(other(fan.edges[1])) - x(v);
        let half = 0.5 * sweep * u.perp(&next).signum();
        let dir = Vector2::new(
            u.x * half.cos() - u.y * half.sin(),
            u.x * half.sin() + u.y * half.cos(),
        );
        let reach = delta / half.abs().min(std::f64::consts::FRAC_PI_2).sin();
        let best = fan
            .faces
            .iter()
            .filter_map(|&f| {
                let (at, d) = inside(mesh, f.index(), x(v), dir * reach)?;
                let worst = at.iter().fold(f64::INFINITY, |m, &c| m.min(c));
                Some((worst, f.index(), at, d))
            })
            .max_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((_, f, at, drawn)) = best {
            out.push(Recessed {
                site: Site::Corner(v),
                facet: f,
                at,
                drawn,
            });
        }
    }
    out
}

/// Area coordinates in facet `f` of `p + step` and of `p`, the step halved
/// (up to 20 times) until the point is in the facet; None where even the
/// shortest step leaves it (`p + step` on the wrong side of the facet).
fn inside(
    mesh: &Mesh,
    f: usize,
    p: Vector2<f64>,
    step: Vector2<f64>,
) -> Option<([f64; 3], [f64; 3])> {
    let c = mesh.triangles()[f].map(|v| mesh.coord(v));
    let area = |p: Vector2<f64>| -> [f64; 3] {
        let d = (c[1] - c[0]).perp(&(c[2] - c[0]));
        let l1 = (p - c[0]).perp(&(c[2] - c[0])) / d;
        let l2 = (c[1] - c[0]).perp(&(p - c[0])) / d;
        [1.0 - l1 - l2, l1, l2]
    };
    let drawn = area(p);
    let mut s = step;
    for _ in 0..20 {
        let at = area(p + s);
        if at.iter().all(|&l| l >= 0.0) {
            return Some((at, drawn));
        }
        s *= 0.5;
    }
    None
}

/// For each point, the smallest index of a point within `tol` of it
/// (through a chain of such points): the groups of points that coincide.
fn coincident(points: &[Vector2<f64>], tol: f64) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| points[a].x.total_cmp(&points[b].x));
    let mut group: Vec<usize> = (0..points.len()).collect();
    fn root(group: &mut [usize], mut i: usize) -> usize {
        while group[i] != i {
            group[i] = group[group[i]];
            i = group[i];
        }
        i
    }
    for (k, &a) in order.iter().enumerate() {
        for &b in order[k + 1..].iter() {
            if points[b].x - points[a].x > tol {
                break;
            }
            if (points[b] - points[a]).norm() <= tol {
                let (ra, rb) = (root(&mut group, a), root(&mut group, b));
                group[ra.max(rb)] = ra.min(rb);
            }
        }
    }
    (0..points.len()).map(|i| root(&mut group, i)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coincident_points_are_grouped() {
        let p = [
            Vector2::new(0.0, 0.0),
            Vector2::new(1.0, 0.0),
            Vector2::new(0.0, 1e-12),
            Vector2::new(1.0, 1.0),
            Vector2::new(1.0, 0.0),
        ];
        assert_eq!(coincident(&p, 1e-9), vec![0, 1, 0, 3, 1]);
    }
}
