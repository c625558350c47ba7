//! The planar-graph steps of FOLD import: faces traced from the edges when
//! a file has no `faces_vertices`, the crossing check that tracing needs,
//! and vertex splitting along cut edges and at vertices where sheets touch.
//!
//! All three are linear (or near it) in the size of the pattern: the
//! crossing check buckets edges in a uniform grid, tracing sorts the edges
//! around each vertex once, and splitting is a union-find over face corners.

use super::error::SceneError;
use nalgebra::Vector2;
use std::collections::HashMap;

fn invalid(key: impl Into<String>, message: impl Into<String>) -> SceneError {
    SceneError::invalid(key, message)
}

fn cross(a: Vector2<f64>, b: Vector2<f64>) -> f64 {
    a.perp(&b)
}

/// Signed area of a polygon (counter-clockwise positive).
pub(crate) fn shoelace(face: &[usize], c: &[Vector2<f64>]) -> f64 {
    let mut a = 0.0;
    for k in 0..face.len() {
        let (p, q) = (c[face[k]], c[face[(k + 1) % face.len()]]);
        a += p.perp(&q);
    }
    0.5 * a
}

fn bbox_of(points: impl Iterator<Item = Vector2<f64>>) -> (Vector2<f64>, Vector2<f64>) {
    let mut lo = Vector2::repeat(f64::INFINITY);
    let mut hi = Vector2::repeat(f64::NEG_INFINITY);
    for p in points {
        lo = lo.inf(&p);
        hi = hi.sup(&p);
    }
    (lo, hi)
}

/// Refuse edge graphs whose faces cannot be traced: edges of zero length,
/// edges that cross without a common vertex, a vertex in the middle of an
/// edge, and collinear edges that overlap. Edges are bucketed in a grid of
/// about one edge per cell, so typical patterns cost linear time.
pub(crate) fn check_crossings(
    coords: &[Vector2<f64>],
    edges: &[[usize; 2]],
) -> Result<(), SceneError> {
    let n = edges.len();
    if n < 2 {
        return Ok(());
    }
    let (lo, hi) = bbox_of(edges.iter().flat_map(|e| [coords[e[0]], coords[e[1]]]));
    let size = (hi - lo).norm();
    let tol = 1e-9 * size;
    for (e, &[a, b]) in edges.iter().enumerate() {
        if (coords[b] - coords[a]).norm() <= tol {
            return Err(invalid(
                format!("edges_vertices[{e}]"),
                format!(
                    "vertices {a} and {b} are at the same point (an edge of zero length); merge them"
                ),
            ));
        }
    }
    // Distinct vertices at one point: the edges do not share their ends.
    let mut ends: Vec<usize> = edges.iter().flat_map(|e| [e[0], e[1]]).collect();
    ends.sort_unstable();
    ends.dedup();
    ends.sort_by(|&p, &q| coords[p].x.total_cmp(&coords[q].x));
    for (k, &p) in ends.iter().enumerate() {
        for &q in &ends[k + 1..] {
            if coords[q].x - coords[p].x > tol {
                break;
            }
            if (coords[q] - coords[p]).norm() <= tol {
                return Err(invalid(
                    format!("vertices_coords[{}]", p.max(q)),
                    format!(
                        "vertices {} and {} are at the same point, so the edges there do not \
                         share their ends and no face can be traced; merge the vertices (one \
                         index per point; Rabbit Ear's removeDuplicateVertices does this)",
                        p.min(q),
                        p.max(q)
                    ),
                ));
            }
        }
    }
    let g = ((n as f64).sqrt().ceil() as usize).clamp(1, 2048);
    let cell = |p: Vector2<f64>| -> (usize, usize) {
        let f = |x: f64, l: f64, h: f64| {
            if h > l {
                (((x - l) / (h - l) * g as f64) as usize).min(g - 1)
            } else {
                0
            }
        };
        (f(p.x, lo.x, hi.x), f(p.y, lo.y, hi.y))
    };
    let ebox = |e: usize| {
        let [a, b] = edges[e];
        (coords[a].inf(&coords[b]), coords[a].sup(&coords[b]))
    };
    let mut grid: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
    for e in 0..n {
        let (l, h) = ebox(e);
        let ((i0, j0), (i1, j1)) = (cell(l), cell(h));
        for i in i0..=i1 {
            for j in j0..=j1 {
                grid.entry((i, j)).or_default().push(e);
            }
        }
    }
    let mut keys: Vec<&(usize, usize)> = grid.keys().collect();
    keys.sort_unstable();
    for key in keys {
        let list = &grid[key];
        for (x, &i) in list.iter().enumerate() {
            let (li, hi_) = ebox(i);
            for &j in &list[x + 1..] {
                let (lj, hj) = ebox(j);
                let (ol, oh) = (li.sup(&lj), hi_.inf(&hj));
                if ol.x > oh.x + tol || ol.y > oh.y + tol {
                    continue;
                }
                // Test each pair once: in the cell of the overlap's low corner.
                if cell(ol) != *key {
                    continue;
                }
                segment_pair(coords, edges, i, j, tol)?;
            }
        }
    }
    Ok(())
}

fn segment_pair(
    c: &[Vector2<f64>],
    edges: &[[usize; 2]],
    i: usize,
    j: usize,
    tol: f64,
) -> Result<(), SceneError> {
    let (i, j) = (i.min(j), i.max(j));
    let [a, b] = edges[i];
    let [p, q] = edges[j];
    let (ca, cb, cp, cq) = (c[a], c[b], c[p], c[q]);
    let key = format!("edges_vertices[{j}]");
    let shared = [a, b].iter().filter(|v| **v == p || **v == q).count();
    if shared == 1 {
        // Collinear and pointing the same way from the shared vertex: overlap.
        let s = if a == p || a == q { a } else { b };
        let u = if s == a { cb - ca } else { ca - cb };
        let w = if s == p { cq - cp } else { cp - cq };
        if cross(u.normalize(), w.normalize()).abs() * u.norm().min(w.norm()) <= tol
            && u.dot(&w) > 0.0
        {
            return Err(invalid(
                key,
                format!(
                    "edges {i} ({a}-{b}) and {j} ({p}-{q}) overlap along a line from vertex {s}: \
                     the edge graph is not planar; keep one edge per piece of line (split the \
                     longer one at the other's end)"
                ),
            ));
        }
        return Ok(());
    }
    if shared == 2 {
        return Ok(()); // a repeated edge is reported by the edge reader
    }
    // Signed distances of each end from the other segment's line.
    let dist = |o: Vector2<f64>, d: Vector2<f64>, x: Vector2<f64>| cross(d, x - o) / d.norm();
    let (d1, d2) = (cb - ca, cq - cp);
    let (op, oq) = (dist(ca, d1, cp), dist(ca, d1, cq));
    let (oa, ob) = (dist(cp, d2, ca), dist(cp, d2, cb));
    let sgn = |x: f64| {
        if x > tol {
            1
        } else if x < -tol {
            -1
        } else {
            0
        }
    };
    let on_segment = |o: Vector2<f64>, d: Vector2<f64>, x: Vector2<f64>| {
        let t = (x - o).dot(&d) / d.norm_squared();
        t * d.norm() > tol && (1.0 - t) * d.norm() > tol
    };
    // A vertex in the middle of the other edge.
    for (v, x, o, d, e, [e0, e1]) in [
        (p, cp, ca, d1, i, [a, b]),
        (q, cq, ca, d1, i, [a, b]),
        (a, ca, cp, d2, j, [p, q]),
        (b, cb, cp, d2, j, [p, q]),
    ] {
        if sgn(dist(o, d, x)) == 0 && on_segment(o, d, x) {
            let other = if e == i { j } else { i };
            if sgn(op) == 0 && sgn(oq) == 0 {
                return Err(invalid(
                    key,
                    format!(
                        "edges {i} ({a}-{b}) and {j} ({p}-{q}) overlap on one line: the edge graph \
                         is not planar; split them where they meet so that no two edges overlap"
                    ),
                ));
            }
            return Err(invalid(
                format!("edges_vertices[{other}]"),
                format!(
                    "vertex {v} of edge {other} lies in the middle of edge {e} ({e0}-{e1}) without \
                     being one of its ends: split edge {e} at vertex {v} (the faces cannot be traced \
                     otherwise)"
                ),
            ));
        }
    }
    if sgn(op) * sgn(oq) < 0 && sgn(oa) * sgn(ob) < 0 {
        let t = oa / (oa - ob);
        let x = ca + t * d1;
        return Err(invalid(
            key,
            format!(
                "edges {i} ({a}-{b}) and {j} ({p}-{q}) cross at ({:.6}, {:.6}) without a common \
                 vertex: the faces of a graph whose edges cross cannot be traced; split both edges \
                 at their crossings (add a vertex there; Rabbit Ear's planarize does this), or give \
                 faces_vertices",
                x.x, x.y
            ),
        ));
    }
    Ok(())
}

/// The faces of a planar straight-line graph: the counter-clockwise
/// boundary cycles of its bounded regions, found by walking each half-edge
/// to the next one clockwise around its end vertex. Outer boundaries
/// (clockwise cycles) are dropped, and so are holes: regions bounded only
/// by edges marked `boundary` that are also sides of other faces. A crease
/// that ends inside a region makes its face run along it and back (a slit:
/// the crease stops in the paper), which the triangulation handles.
/// Refused: crossing edges (see [`check_crossings`]), a face that touches
/// itself at a vertex without a slit, and a piece of the pattern lying
/// inside a face of another piece with no edge between them (an island).
pub(crate) fn trace_faces(
    coords: &[Vector2<f64>],
    edges: &[[usize; 2]],
    boundary: &[bool],
) -> Result<Vec<Vec<usize>>, SceneError> {
    check_crossings(coords, edges)?;
    let he = HalfEdges::new(coords, edges);
    let (lo, hi) = bbox_of(coords.iter().copied());
    let eps = 1e-12 * (hi - lo).norm_squared();
    let (cycles, cycle_of) = he.cycles(coords);
    // Bounded regions; holes (all sides boundary edges shared with another
    // region) are not paper.
    let is_hole = |id: usize| {
        cycles[id].0.iter().all(|&h| {
            let other = cycle_of[h ^ 1];
            boundary[h / 2] && other != id && cycles[other].1 > eps
        })
    };
    let mut faces = Vec::new();
    for id in (0..cycles.len()).filter(|&id| cycles[id].1 > eps) {
        if is_hole(id) {
            continue;
        }
        let hs = &cycles[id].0;
        let verts: Vec<usize> = hs.iter().map(|&h| he.origin(h)).collect();
        let mut sorted = verts.clone();
        sorted.sort_unstable();
        if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1])
            && !hs.iter().any(|&h| cycle_of[h ^ 1] == id)
        {
            return Err(invalid(
                format!("vertices_coords[{}]", w[0]),
                format!(
                    "a face traced from the edges touches itself at vertex {}: add an edge \
                         that splits it there",
                    w[0]
                ),
            ));
        }
        faces.push(verts);
    }
    let outer: Vec<usize> = (0..cycles.len())
        .filter(|&id| cycles[id].1 < -eps)
        .collect();
    if outer.len() > 1 {
        let starts: Vec<usize> = outer.iter().map(|&id| cycles[id].0[0]).collect();
        check_islands(coords, edges, &faces, &he, &starts)?;
    }
    Ok(faces)
}

/// Where half-edge `h` starts: h = 2e runs a -> b, 2e + 1 runs b -> a.
fn half_edge_origin(edges: &[[usize; 2]], h: usize) -> usize {
    if h.is_multiple_of(2) {
        edges[h / 2][0]
    } else {
        edges[h / 2][1]
    }
}

/// The half-edges of a planar graph: h = 2e runs a -> b, 2e + 1 runs b -> a;
/// around each vertex its outgoing half-edges sorted by angle.
struct HalfEdges<'a> {
    edges: &'a [[usize; 2]],
    /// Outgoing half-edges of each vertex, counter-clockwise.
    out: Vec<Vec<usize>>,
    /// Position of each half-edge in its origin's list.
    pos: Vec<usize>,
}

impl<'a> HalfEdges<'a> {
    fn new(coords: &[Vector2<f64>], edges: &'a [[usize; 2]]) -> Self {
        let ne = edges.len();
        let origin = |h: usize| half_edge_origin(edges, h);
        let mut out: Vec<Vec<usize>> = vec![Vec::new(); coords.len()];
        for h in 0..2 * ne {
            out[origin(h)].push(h);
        }
        let angle = |h: usize| {
            let d = coords[origin(h ^ 1)] - coords[origin(h)];
            d.y.atan2(d.x)
        };
        let mut pos = vec![0usize; 2 * ne];
        for list in &mut out {
            list.sort_by(|&x, &y| angle(x).total_cmp(&angle(y)).then(x.cmp(&y)));
            for (k, &h) in list.iter().enumerate() {
                pos[h] = k;
            }
        }
        HalfEdges { edges, out, pos }
    }

    fn origin(&self, h: usize) -> usize {
        half_edge_origin(self.edges, h)
    }

    /// The half-edge after `h` in its cycle: the next one clockwise around
    /// `h`'s end.
    fn next(&self, h: usize) -> usize {
        let twin = h ^ 1;
        let list = &self.out[self.origin(twin)];
        list[(self.pos[twin] + list.len() - 1) % list.len()]
    }

    /// Every cycle (its half-edges and signed area) and the cycle of each
    /// half-edge.
    fn cycles(&self, coords: &[Vector2<f64>]) -> (Vec<(Vec<usize>, f64)>, Vec<usize>) {
        let nh = self.pos.len();
        let mut cycle_of = vec![usize::MAX; nh];
        let mut cycles = Vec::new();
        for start in 0..nh {
            if cycle_of[start] != usize::MAX {
                continue;
            }
            let id = cycles.len();
            let mut hs = Vec::new();
            let mut h = start;
            while cycle_of[h] == usize::MAX {
                cycle_of[h] = id;
                hs.push(h);
                h = self.next(h);
            }
            let verts: Vec<usize> = hs.iter().map(|&h| self.origin(h)).collect();
            let area = shoelace(&verts, coords);
            cycles.push((hs, area));
        }
        (cycles, cycle_of)
    }
}

/// Refuse a piece (connected component) of the pattern lying inside a face
/// of another piece: `starts` holds a half-edge of each outer boundary.
fn check_islands(
    coords: &[Vector2<f64>],
    edges: &[[usize; 2]],
    faces: &[Vec<usize>],
    he: &HalfEdges,
    starts: &[usize],
) -> Result<(), SceneError> {
    let mut parent: Vec<usize> = (0..coords.len()).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for &[a, b] in edges {
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        if ra != rb {
            parent[ra] = rb;
        }
    }
    let boxes: Vec<_> = faces
        .iter()
        .map(|f| bbox_of(f.iter().map(|&v| coords[v])))
        .collect();
    let piece: Vec<usize> = faces.iter().map(|f| find(&mut parent, f[0])).collect();
    for &h in starts {
        let v = he.origin(h);
        let pv = find(&mut parent, v);
        let x = coords[v];
        for (f, face) in faces.iter().enumerate() {
            let (l, hi) = boxes[f];
            if piece[f] == pv || x.x < l.x || x.x > hi.x || x.y < l.y || x.y > hi.y {
                continue;
            }
            if inside(x, face, coords) {
                return Err(invalid(
                    format!("edges_vertices[{}]", h / 2),
                    format!(
                        "the edges around vertex {v} form a piece that lies inside a face of \
                         the rest of the pattern, with no edge joining them (an island): join \
                         it to the surrounding pattern with an edge (a J edge joins without \
                         folding), or mark the edges around it B if it is a hole"
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Point strictly inside a simple polygon (crossing number).
fn inside(x: Vector2<f64>, face: &[usize], c: &[Vector2<f64>]) -> bool {
    let mut odd = false;
    for k in 0..face.len() {
        let (p, q) = (c[face[k]], c[face[(k + 1) % face.len()]]);
        if (p.y > x.y) != (q.y > x.y) {
            let t = (x.y - p.y) / (q.y - p.y);
            if p.x + t * (q.x - p.x) > x.x {
                odd = !odd;
            }
        }
    }
    odd
}

/// One occurrence of a face side: face `f`, position `k` (the side runs
/// from `faces[f][k]` to `faces[f][k + 1]`).
pub(crate) type SideAt = (usize, usize);

/// Split vertices so that the faces around every vertex form one fan: along
/// cut edges (sides for which `is_cut` is true, which then separate their
/// two faces) and where sheets only touch at a vertex. `sides` lists, per
/// side shared by two faces, its two occurrences. The corners of each
/// vertex are grouped by union-find across shared sides; every group after
/// the first gets a new vertex (appended to `coords`, same position), and
/// the faces are renumbered. Returns, for each new vertex, the vertex it
/// copies.
pub(crate) fn split_vertices(
    faces: &mut [Vec<usize>],
    coords: &mut Vec<Vector2<f64>>,
    shared_sides: &[(SideAt, SideAt, bool)],
) -> Vec<usize> {
    let mut offset = Vec::with_capacity(faces.len() + 1);
    let mut total = 0usize;
    for f in faces.iter() {
        offset.push(total);
        total += f.len();
    }
    let corner = |f: usize, k: usize| offset[f] + k % faces[f].len();
    let mut parent: Vec<usize> = (0..total).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    let union = |p: &mut Vec<usize>, x: usize, y: usize| {
        let (rx, ry) = (find(p, x), find(p, y));
        if rx != ry {
            p[rx] = ry;
        }
    };
    for &((f1, k1), (f2, k2), cut) in shared_sides {
        if cut {
            continue;
        }
        // f1 runs a -> b at k1, f2 runs b -> a at k2.
        union(&mut parent, corner(f1, k1), corner(f2, k2 + 1));
        union(&mut parent, corner(f1, k1 + 1), corner(f2, k2));
    }
    let mut label: HashMap<usize, usize> = HashMap::new();
    let mut taken = vec![false; coords.len()];
    let mut copies = Vec::new();
    for f in 0..faces.len() {
        for k in 0..faces[f].len() {
            let v = faces[f][k];
            let r = find(&mut parent, offset[f] + k);
            let id = *label.entry(r).or_insert_with(|| {
                if !taken[v] {
                    taken[v] = true;
                    v
                } else {
                    coords.push(coords[v]);
                    copies.push(v);
                    coords.len() - 1
                }
            });
            faces[f][k] = id;
        }
    }
    copies
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64) -> Vector2<f64> {
        Vector2::new(x, y)
    }

    #[test]
    fn square_with_diagonal_traces_two_faces() {
        let c = vec![v(0., 0.), v(1., 0.), v(1., 1.), v(0., 1.)];
        let e = vec![[0, 1], [1, 2], [2, 3], [3, 0], [0, 2]];
        let f = trace_faces(&c, &e, &[false; 5]).unwrap();
        assert_eq!(f.len(), 2);
        for face in &f {
            assert_eq!(face.len(), 3);
            assert!(shoelace(face, &c) > 0.0);
        }
    }

    #[test]
    fn crossings_slits_holes_and_islands() {
        let no = [false; 16];
        // both diagonals, no centre vertex
        let c = vec![v(0., 0.), v(1., 0.), v(1., 1.), v(0., 1.)];
        let e = vec![[0, 1], [1, 2], [2, 3], [3, 0], [0, 2], [1, 3]];
        let err = trace_faces(&c, &e, &no).unwrap_err().to_string();
        assert!(err.contains("cross at (0.500000, 0.500000)"), "{err}");
        // a crease from a corner to the centre: a slit face
        let c = vec![v(0., 0.), v(1., 0.), v(1., 1.), v(0., 1.), v(0.5, 0.5)];
        let e = vec![[0, 1], [1, 2], [2, 3], [3, 0], [0, 4]];
        let f = trace_faces(&c, &e, &no).unwrap();
        assert_eq!(f.len(), 1);
        assert_eq!(f[0].len(), 6);
        // a vertex on an edge
        let c = vec![v(0., 0.), v(2., 0.), v(2., 1.), v(0., 1.), v(1., 0.)];
        let e = vec![[0, 1], [1, 2], [2, 3], [3, 0], [4, 2]];
        let err = trace_faces(&c, &e, &no).unwrap_err().to_string();
        assert!(err.contains("in the middle of edge 0"), "{err}");
        // a square inside a square, not joined: an island
        let c = vec![
            v(0., 0.),
            v(3., 0.),
            v(3., 3.),
            v(0., 3.),
            v(1., 1.),
            v(2., 1.),
            v(2., 2.),
            v(1., 2.),
        ];
        let e = vec![
            [0, 1],
            [1, 2],
            [2, 3],
            [3, 0],
            [4, 5],
            [5, 6],
            [6, 7],
            [7, 4],
        ];
        let err = trace_faces(&c, &e, &no).unwrap_err().to_string();
        assert!(err.contains("island"), "{err}");
        // joined by one edge: the ring face runs along it both ways
        let mut e2 = e.clone();
        e2.push([0, 4]);
        let f = trace_faces(&c, &e2, &no).unwrap();
        assert_eq!(f.len(), 2);
        // the inner square marked B and joined twice: a hole
        let mut e3 = e2.clone();
        e3.push([2, 6]);
        let mut b = vec![true, true, true, true, true, true, true, true, false, false];
        let f = trace_faces(&c, &e3, &b).unwrap();
        assert_eq!(f.len(), 2);
        b[4] = false; // not all B: a face
        assert_eq!(trace_faces(&c, &e3, &b).unwrap().len(), 3);
        // two separate squares side by side are fine
        let c = vec![
            v(0., 0.),
            v(1., 0.),
            v(1., 1.),
            v(0., 1.),
            v(2., 0.),
            v(3., 0.),
            v(3., 1.),
            v(2., 1.),
        ];
        let f = trace_faces(&c, &e, &no).unwrap();
        assert_eq!(f.len(), 2);
        // disjoint edges with ends at one point
        let c = vec![v(0., 0.), v(1., 0.), v(1., 0.), v(0., 1.)];
        let e = vec![[0, 1], [2, 3], [3, 0]];
        let err = trace_faces(&c, &e, &no).unwrap_err().to_string();
        assert!(
            err.contains("vertices 1 and 2 are at the same point"),
            "{err}"
        );
    }

    #[test]
    fn splitting_along_a_cut() {
        // Three squares in a row, 0-1-2-3 bottom, 4-5-6-7 top; cut 1-5.
        let mut c = vec![
            v(0., 0.),
            v(1., 0.),
            v(2., 0.),
            v(3., 0.),
            v(0., 1.),
            v(1., 1.),
            v(2., 1.),
            v(3., 1.),
        ];
        let mut faces = vec![vec![0, 1, 5, 4], vec![1, 2, 6, 5], vec![2, 3, 7, 6]];
        // side 1-5: face 0 at k = 1 (1 -> 5), face 1 at k = 3 (5 -> 1); side 2-6 likewise.
        let shared = vec![((0, 1), (1, 3), true), ((1, 1), (2, 3), false)];
        let copies = split_vertices(&mut faces, &mut c, &shared);
        assert_eq!(copies, vec![1, 5]);
        assert_eq!(faces[0], vec![0, 1, 5, 4]);
        assert_eq!(faces[1], vec![8, 2, 6, 9]);
        assert_eq!(c.len(), 10);
        assert_eq!(c[8], c[1]);
    }
}
