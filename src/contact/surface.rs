//! The contact surface: points of the shell's own curved surface, sampled
//! on a lattice of `n` subdivisions per facet side, each an exact linear
//! map of the slots (`r = S(xi) e`, so a force at a sample maps to the
//! nodal coordinates through `S^T`), with the sub-triangles and edges
//! between them. Samples on a shared side or corner are one vertex (the
//! side traces of neighbouring facets coincide, creases included).
//!
//! Two families of primitives: the fine ones (sub-triangles and their
//! edges) between facets that share no side (samples against sub-triangles
//! across a crease too, once folded past a right angle), and the coarse
//! ones (each facet's corner triangle and the mesh edges) between facets
//! that share a vertex.
//! A midsurface model has no hinge radius: two panels that meet at a crease
//! folded flat close to a wedge, and between neighbours only the corners
//! keep the thickness apart (the open end of the wedge is one thickness).

use crate::dofs::DofLayout;
use crate::element::ShellElement;
use crate::ids::VertexId;
use crate::mesh::Mesh;
use nalgebra::Vector3;
use std::collections::HashMap;

mod kerf;

/// One contact vertex as a linear map of the slots: `x = sum c_k q[slot_k]`.
pub type VertexMap = Vec<(usize, f64)>;

/// The sampled surface of a mesh (built once; positions come from `q`).
#[derive(Clone, Debug)]
pub struct ContactSurface {
    /// Subdivisions per facet side.
    pub n: usize,
    /// Slot map of each contact vertex.
    pub maps: Vec<VertexMap>,
    /// Position of each contact vertex in the flat reference (z = 0).
    pub rest: Vec<Vector3<f64>>,
    /// Facets each contact vertex lies on (sorted).
    pub vertex_facets: Vec<Vec<usize>>,
    /// Contact vertex at each mesh vertex.
    pub corner: Vec<usize>,
    /// Fine triangles (contact vertices) and their facet.
    pub fine_tris: Vec<([usize; 3], usize)>,
    /// Fine edges and the facets they lie on (one or two, sorted).
    pub fine_edges: Vec<([usize; 2], Vec<usize>)>,
    /// Coarse edges (mesh edges as contact vertices) and their facets.
    pub coarse_edges: Vec<([usize; 2], Vec<usize>)>,
    /// Facets that share a mesh vertex with each facet, itself included
    /// (sorted).
    pub neighbours: Vec<Vec<usize>>,
    /// Contact vertices of each facet (its samples, sorted).
    pub facet_vertices: Vec<Vec<usize>>,
    /// Fine triangles of each facet (indices into `fine_tris`).
    pub facet_fine_tris: Vec<Vec<usize>>,
    /// Contact vertices along each mesh edge, from its first vertex to its
    /// second (`n + 1` of them).
    pub edge_samples: Vec<Vec<usize>>,
    /// Fine edges of each facet (indices into `fine_edges`).
    pub facet_fine_edges: Vec<Vec<usize>>,
    /// Chord probes: at the centroid and the side midpoints of each fine
    /// triangle, the curved surface's point there minus the sampled
    /// surface's (a linear map of the slots, zero where the facet is flat),
    /// and the probe's facet.
    pub chord_probes: Vec<(VertexMap, usize)>,
    /// How far (m) the samples on a cut's lips stand back from the drawn
    /// line into their facets (0: none); see [`ContactSurface::new`].
    pub kerf: f64,
}

/// Where a lattice sample sits: a mesh corner, a point of a mesh edge
/// (lower vertex, upper vertex, steps from the lower), or inside a facet.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Site {
    Corner(VertexId),
    Side(VertexId, VertexId, usize),
    Inside(usize, usize, usize),
}

/// Each sub-triangle side once, with the facets it lies on.
#[allow(clippy::type_complexity)]
fn fine_edges(fine_tris: &[([usize; 3], usize)]) -> Vec<([usize; 2], Vec<usize>)> {
    let mut edge_of: HashMap<(usize, usize), usize> = HashMap::new();
    let mut fine_edges: Vec<([usize; 2], Vec<usize>)> = Vec::new();
    for &(t, f) in fine_tris {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let key = (a.min(b), a.max(b));
            let e = *edge_of.entry(key).or_insert_with(|| {
                fine_edges.push(([key.0, key.1], Vec::new()));
                fine_edges.len() - 1
            });
            if !fine_edges[e].1.contains(&f) {
                fine_edges[e].1.push(f);
                fine_edges[e].1.sort_unstable();
            }
        }
    }
    fine_edges
}

/// For each facet, the facets that share a vertex with it (itself too).
fn facet_neighbours(mesh: &Mesh) -> Vec<Vec<usize>> {
    let mut vertex_faces = vec![Vec::new(); mesh.n_vertices()];
    for (f, tri) in mesh.triangles().iter().enumerate() {
        for &v in tri {
            vertex_faces[v.index()].push(f);
        }
    }
    mesh.triangles()
        .iter()
        .map(|tri| {
            let mut nb: Vec<usize> = tri
                .iter()
                .flat_map(|&v| vertex_faces[v.index()].iter().copied())
                .collect();
            nb.sort_unstable();
            nb.dedup();
            nb
        })
        .collect()
}

impl ContactSurface {
    /// Sample every facet of `mesh` with `n >= 1` subdivisions per side;
    /// with `chord`, also the [`ContactSurface::chord_probes`] (the contact
    /// term's surface; a checker's or the obstacles' need none). Where two
    /// boundary lines of the flat sheet lie on each other (a cut's lips, a
    /// vertex where sheets only touch), the samples on them stand back into
    /// their own facets by `kerf` (m): the lips start `2 kerf` apart, and
    /// the chord probes still measure from the drawn surface.
    #[allow(clippy::needless_range_loop)] // i, j are lattice coordinates
    pub fn new(
        mesh: &Mesh,
        layout: &DofLayout,
        elements: &[ShellElement],
        n: usize,
        chord: bool,
        kerf: f64,
    ) -> Self {
        let n = n.max(1);
        let q_ref = layout.reference_state(mesh);
        let mut index: HashMap<Site, usize> = HashMap::new();
        let mut maps: Vec<VertexMap> = Vec::new();
        let mut vertex_facets: Vec<Vec<usize>> = Vec::new();
        let mut fine_tris = Vec::new();
        let mut chord_probes = Vec::new();
        // The surface point of facet `f` at area coordinates `l` as a slot
        // map, less the given maps with their weights.
        let facet_map = |f: usize, l: [f64; 3], less: &[(&VertexMap, f64)]| -> VertexMap {
            let s = elements[f].shape().values(l);
            let mut terms: HashMap<usize, f64> = HashMap::new();
            for (node, combo) in layout.local[f].iter().enumerate() {
                for (slot, c) in combo.terms() {
                    *terms.entry(slot).or_insert(0.0) += s[node] * c;
                }
            }
            for (m, w) in less {
                for &(slot, c) in m.iter() {
                    *terms.entry(slot).or_insert(0.0) -= w * c;
                }
            }
            let mut m: VertexMap = terms.into_iter().filter(|&(_, c)| c != 0.0).collect();
            m.sort_unstable_by_key(|&(s, _)| s);
            m
        };
        // The kerf's sites first, at their recessed points; the drawn
        // points' maps kept for the chord probes.
        let mut drawn: HashMap<usize, VertexMap> = HashMap::new();
        for r in kerf::recessed_sites(mesh, n, kerf) {
            if index.contains_key(&r.site) {
                continue;
            }
            index.insert(r.site, maps.len());
            drawn.insert(maps.len(), facet_map(r.facet, r.drawn, &[]));
            maps.push(facet_map(r.facet, r.at, &[]));
            vertex_facets.push(Vec::new());
        }
        for (f, tri) in mesh.triangles().iter().enumerate() {
            let map_at = |l: [f64; 3], less: &[(&VertexMap, f64)]| facet_map(f, l, less);
            // Lattice (i, j): area coordinates ((n-i-j), i, j) / n.
            let mut id = vec![vec![0usize; n + 1]; n + 1];
            for i in 0..=n {
                for j in 0..=(n - i) {
                    let k = n - i - j;
                    let counts = [k, i, j];
                    let nonzero: Vec<usize> = (0..3).filter(|&c| counts[c] > 0).collect();
                    let site = match nonzero.len() {
                        1 => Site::Corner(tri[nonzero[0]]),
                        2 => {
                            let (a, b) = (nonzero[0], nonzero[1]);
                            let (va, vb) = (tri[a], tri[b]);
                            if va < vb {
                                Site::Side(va, vb, counts[b])
                            } else {
                                Site::Side(vb, va, counts[a])
                            }
                        }
                        _ => Site::Inside(f, i, j),
                    };
                    let v = *index.entry(site).or_insert_with(|| {
                        let l = [
                            k as f64 / n as f64,
                            i as f64 / n as f64,
                            j as f64 / n as f64,
                        ];
                        maps.push(map_at(l, &[]));
                        vertex_facets.push(Vec::new());
                        maps.len() - 1
                    });
                    if !vertex_facets[v].contains(&f) {
                        vertex_facets[v].push(f);
                    }
                    id[i][j] = v;
                }
            }
            let area = |(i, j): (usize, usize)| {
                let nf = n as f64;
                [(n - i - j) as f64 / nf, i as f64 / nf, j as f64 / nf]
            };
            for t in lattice_triangles(n) {
                let ids = t.map(|(i, j)| id[i][j]);
                fine_tris.push((ids, f));
                if !chord {
                    continue;
                }
                let l = t.map(area);
                let centre = std::array::from_fn(|c| (l[0][c] + l[1][c] + l[2][c]) / 3.0);
                let m = |v: usize| drawn.get(&v).unwrap_or(&maps[v]);
                let less: Vec<(&VertexMap, f64)> = ids.iter().map(|&v| (m(v), 1.0 / 3.0)).collect();
                let mut probes = vec![map_at(centre, &less)];
                for (a, b) in [(0, 1), (1, 2), (2, 0)] {
                    let mid = std::array::from_fn(|c| 0.5 * (l[a][c] + l[b][c]));
                    probes.push(map_at(mid, &[(m(ids[a]), 0.5), (m(ids[b]), 0.5)]));
                }
                chord_probes.extend(probes.into_iter().map(|m| (m, f)));
            }
        }
        for vf in vertex_facets.iter_mut() {
            vf.sort_unstable();
        }
        let mut facet_vertices = vec![Vec::new(); mesh.triangles().len()];
        for (v, fs) in vertex_facets.iter().enumerate() {
            for &f in fs {
                facet_vertices[f].push(v);
            }
        }
        let rest: Vec<Vector3<f64>> = maps.iter().map(|m| eval_map(m, &q_ref)).collect();
        let corner: Vec<usize> = mesh
            .vertex_ids()
            .map(|v| index.get(&Site::Corner(v)).copied().unwrap_or(usize::MAX))
            .collect();
        let fine_edges = fine_edges(&fine_tris);
        let coarse_edges = mesh
            .edges()
            .iter()
            .zip(mesh.edge_faces())
            .map(|(e, faces)| {
                let mut fs: Vec<usize> = faces.iter().map(|f| f.index()).collect();
                fs.sort_unstable();
                ([corner[e.v[0].index()], corner[e.v[1].index()]], fs)
            })
            .collect();
        let edge_samples = mesh
            .edges()
            .iter()
            .map(|e| {
                let [a, b] = e.v;
                let (lo, hi) = (a.min(b), a.max(b));
                let mut along: Vec<usize> = (0..=n)
                    .map(|k| match k {
                        0 => corner[lo.index()],
                        k if k == n => corner[hi.index()],
                        k => index[&Site::Side(lo, hi, k)],
                    })
                    .collect();
                if a != lo {
                    along.reverse();
                }
                along
            })
            .collect();
        let neighbours = facet_neighbours(mesh);
        let mut facet_fine_tris = vec![Vec::new(); mesh.triangles().len()];
        for (k, &(_, f)) in fine_tris.iter().enumerate() {
            facet_fine_tris[f].push(k);
        }
        let mut facet_fine_edges = vec![Vec::new(); mesh.triangles().len()];
        for (k, (_, fs)) in fine_edges.iter().enumerate() {
            for &f in fs {
                facet_fine_edges[f].push(k);
            }
        }
        ContactSurface {
            n,
            facet_fine_tris,
            edge_samples,
            facet_fine_edges,
            chord_probes,
            maps,
            rest,
            vertex_facets,
            corner,
            fine_tris,
            fine_edges,
            coarse_edges,
            neighbours,
            facet_vertices,
            kerf,
        }
    }

    /// The largest distance (m) between the curved facets and the sampled
    /// surface at slot vector `q` (over [`ContactSurface::chord_probes`]),
    /// and the facets where it passes `limit`, in order.
    pub fn chord_error(&self, q: &[f64], limit: f64) -> (f64, Vec<usize>) {
        let each = self.facet_chord_errors(q);
        let worst = each.iter().fold(0.0f64, |a, &b| a.max(b));
        let over = (0..each.len()).filter(|&f| each[f] > limit).collect();
        (worst, over)
    }

    /// The chord error (m) of each facet at slot vector `q`: the largest of
    /// its [`ContactSurface::chord_probes`] (0 without probes).
    pub fn facet_chord_errors(&self, q: &[f64]) -> Vec<f64> {
        let mut each = vec![0.0f64; self.facet_fine_tris.len()];
        for (m, f) in &self.chord_probes {
            each[*f] = each[*f].max(eval_map(m, q).norm());
        }
        each
    }

    /// Number of contact vertices.
    pub fn n_vertices(&self) -> usize {
        self.maps.len()
    }

    /// Positions (or velocities) of every contact vertex from a slot vector.
    pub fn positions(&self, q: &[f64], out: &mut Vec<Vector3<f64>>) {
        out.clear();
        out.extend(self.maps.iter().map(|m| eval_map(m, q)));
    }

    /// Whether facets `f` and `g` share a mesh vertex (or are the same).
    pub fn are_neighbours(&self, f: usize, g: usize) -> bool {
        self.neighbours[f].binary_search(&g).is_ok()
    }

    /// Whether any facet of `a` is a neighbour of any facet of `b`.
    pub fn any_neighbours(&self, a: &[usize], b: &[usize]) -> bool {
        a.iter()
            .any(|&f| b.iter().any(|&g| self.are_neighbours(f, g)))
    }

    /// The corner triangle of facet `f` (contact vertices).
    pub fn coarse_tri(&self, mesh: &Mesh, f: usize) -> [usize; 3] {
        let t = mesh.triangles()[f];
        [
            self.corner[t[0].index()],
            self.corner[t[1].index()],
            self.corner[t[2].index()],
        ]
    }
}

/// Add the 3-vector `f` at a vertex to the slots it maps to (`c_k f` to
/// slot `k`): the transpose of [`eval_map`].
pub fn scatter_map(m: &VertexMap, f: &Vector3<f64>, force: &mut [f64]) {
    for &(slot, c) in m {
        for a in 0..3 {
            force[3 * slot + a] += c * f[a];
        }
    }
}

/// Add a vector over `N` points' coordinates (`f[3 k..3 k + 3]` at point
/// `k`) to the slots the points map to ([`scatter_map`] per point).
pub fn scatter_points<const N: usize>(maps: [&VertexMap; N], f: &[f64], force: &mut [f64]) {
    assert_eq!(f.len(), 3 * N, "a vector over the points' coordinates");
    for (m, fk) in maps.into_iter().zip(f.chunks_exact(3)) {
        scatter_map(m, &Vector3::new(fk[0], fk[1], fk[2]), force);
    }
}

/// The slots `maps` map to, sorted and once each, written to the front of
/// `out` (at least the maps' total length); returns how many.
pub fn slot_union(maps: &[&VertexMap], out: &mut [usize]) -> usize {
    let mut total = 0;
    for &(s, _) in maps.iter().flat_map(|m| m.iter()) {
        out[total] = s;
        total += 1;
    }
    let slots = &mut out[..total];
    slots.sort_unstable();
    let mut n = 0;
    for a in 0..total {
        if n == 0 || slots[a] != slots[n - 1] {
            slots[n] = slots[a];
            n += 1;
        }
    }
    n
}

/// `sum c_k q[slot_k]` for one vertex map.
pub fn eval_map(m: &VertexMap, q: &[f64]) -> Vector3<f64> {
    let mut x = Vector3::zeros();
    for &(s, c) in m {
        x += c * Vector3::new(q[3 * s], q[3 * s + 1], q[3 * s + 2]);
    }
    x
}

/// The sub-triangles of a facet's lattice of `n` subdivisions, as lattice
/// points `(i, j)` (area coordinates `((n - i - j) / n, i / n, j / n)`),
/// counter-clockwise like the facet: `n^2` of them.
pub fn lattice_triangles(n: usize) -> impl Iterator<Item = [(usize, usize); 3]> {
    (0..n).flat_map(move |i| {
        (0..n - i).flat_map(move |j| {
            let up = [(i, j), (i + 1, j), (i, j + 1)];
            let down = [(i + 1, j), (i + 1, j + 1), (i, j + 1)];
            std::iter::once(up).chain((i + j + 1 < n).then_some(down))
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slot_union_lists_each_slot_once_in_order() {
        let a: VertexMap = vec![(7, 0.5), (2, 0.25), (4, 0.25)];
        let b: VertexMap = vec![(4, 1.0), (9, -0.5), (2, 0.5)];
        let mut out = [0usize; 6];
        let n = slot_union(&[&a, &b], &mut out);
        assert_eq!(&out[..n], &[2, 4, 7, 9]);
    }
}
