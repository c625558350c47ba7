//! The candidate pairs: the search, the step start's cache of it, the matrix blocks they need.

use super::ContactTerm;
use super::pairs::{Kind, Pair, PairKey, distance_sq, key, lift};
use super::stops::{reach_by_kind, slot, slot_kind};
use crate::assembly::Assembler;
use crate::contact::broad::{Aabb, overlapping};
use crate::contact::surface::ContactSurface;
use nalgebra::Vector3;

/// The candidate pairs of the step start, found with boxes padded by
/// `pad + 2 margin`: a superset of the pairs any search with pad up to `pad`
/// finds while every contact vertex (and its swept end) stays within
/// `margin` of its step-start position `x0` (the positions of slot vector
/// `q0`). A step's many evaluations and collision checks then filter this
/// list by distance instead of searching again (the pairs' final test is
/// their distance in both cases).
#[derive(Clone, Debug, Default)]
pub(super) struct CandidateCache {
    /// The slot vector the cache was searched at (empty before the first
    /// search; a restored state's origin, with no pairs, until the next
    /// step start searches there): a saved state lists it, so that a
    /// restored one searches the same cache and continues bit for bit
    /// (what a step does depends on the cache it keeps).
    pub(super) q0: Vec<f64>,
    pub(super) x0: Vec<Vector3<f64>>,
    pub(super) pad: f64,
    pub(super) pairs: Vec<Pair>,
}

/// The cache's pairs an evaluation (or a collision check) can act on while
/// every contact vertex (and its swept end) stays within `margin` of `x0`:
/// the indices (ascending) of those not apart along an axis at `x0` by a
/// reach that covers the margin (see [`ContactTerm::near_indices`]). In a
/// jam a step's evaluations move the sheet by far less than the cache's
/// margin, and the cache holds the layers around the touching ones too.
#[derive(Clone, Debug, Default)]
pub(super) struct NearList {
    x0: Vec<Vector3<f64>>,
    margin: f64,
    idx: Vec<usize>,
}

/// A pair left out of an evaluation's [`NearList`] is apart along an axis
/// at its origin by its reach plus this many margins: still apart by its
/// reach anywhere within the margin (a little over two: no rounding of the
/// moved spans brings it back).
pub(super) const NEAR_REACH_MARGINS: f64 = 2.5;

/// A pair left out of a collision check's [`NearList`] is apart along an
/// axis at its origin by the thickness plus this many margins (`g`). With
/// every point within the margin `m` of the origin all along the move, its
/// gap stays above `g - 2 m`, and starts below `g + 2 m`: above a tenth of
/// where it starts for `g` over 2.45 margins, where the advancement finds
/// no time of impact.
pub(super) const NEAR_MOVE_MARGINS: f64 = 3.0;

/// How far the contact vertices can have moved, bounded from the slots'
/// moves alone: a vertex `x = sum c_k q[slot_k]` moves by at most `l1[0]
/// dp + l1[1] dg`, `dp` and `dg` the largest moves of any position and any
/// gradient slot, `l1` the largest sums of `|c|` over a vertex's position
/// and gradient slots. Cheaper than the positions when nothing is near.
#[derive(Clone, Debug)]
pub(super) struct SlotBound {
    /// Each slot's kind: 0 position, 1 gradient.
    kinds: Vec<usize>,
    l1: [f64; 2],
}

impl SlotBound {
    pub(super) fn new(surf: &ContactSurface, layout: &crate::dofs::DofLayout) -> SlotBound {
        let kinds: Vec<usize> = (0..layout.n_slots())
            .map(|s| slot_kind(layout, s))
            .collect();
        let mut l1 = [0.0f64; 2];
        for map in &surf.maps {
            let mut sums = [0.0; 2];
            for &(s, c) in map {
                sums[kinds[s]] += c.abs();
            }
            l1 = [l1[0].max(sums[0]), l1[1].max(sums[1])];
        }
        SlotBound { kinds, l1 }
    }

    /// A bound on how far any vertex is at slot vector `q` (and at `q +
    /// dq`) from where it is at `q0`.
    fn moved(&self, q: &[f64], q0: &[f64], dq: Option<&[f64]>) -> f64 {
        let slots = (self.kinds.iter().enumerate()).map(|(s, &k)| (s, k, slot(q0, s)));
        let reach = reach_by_kind(slots, q, dq);
        self.l1[0] * reach[0] + self.l1[1] * reach[1]
    }
}

impl CandidateCache {
    /// Whether positions `x` (and `x + dx`) are within `margin` of `x0`
    /// (the margin the cache was searched with, or less).
    pub(super) fn covers(
        &self,
        x: &[Vector3<f64>],
        dx: Option<&[Vector3<f64>]>,
        pad: f64,
        margin: f64,
    ) -> bool {
        let m2 = margin * margin;
        pad <= self.pad
            && x.len() == self.x0.len()
            && x.iter().zip(&self.x0).enumerate().all(|(i, (y, y0))| {
                (y - y0).norm_squared() <= m2
                    && dx.is_none_or(|d| (y + d[i] - y0).norm_squared() <= m2)
            })
    }
}

/// Share of the wedge's opening that neighbouring facets keep (see
/// [`ContactTerm::neighbour_pairs`]): room for the facets to bend.
const NEIGHBOUR_SHARE: f64 = 0.5;

/// Neighbour pairs keeping less than this share of the thickness are left
/// out (near the shared vertex or crease, where the crease stops act).
const NEIGHBOUR_MIN: f64 = 0.02;

/// One search's boxes and slabs, each computed once: every sample's box
/// (swept over its move), every fine triangle's and fine edge's (the union
/// of its samples', the box around all their points), every facet's
/// [`Slab`].
struct Search<'a> {
    x: &'a [Vector3<f64>],
    dx: Option<&'a [Vector3<f64>]>,
    pad: f64,
    samples: Vec<Aabb>,
    tris: Vec<Aabb>,
    edges: Vec<Aabb>,
    slabs: Vec<Option<Slab>>,
}

impl<'a> Search<'a> {
    /// The boxes at `x` (swept by `dx`) padded by `pad`, with the facets'
    /// `slabs`.
    fn new(
        surf: &ContactSurface,
        x: &'a [Vector3<f64>],
        dx: Option<&'a [Vector3<f64>]>,
        pad: f64,
        slabs: Vec<Option<Slab>>,
    ) -> Search<'a> {
        let samples: Vec<Aabb> = (0..surf.n_vertices())
            .map(|i| match dx {
                Some(d) => Aabb::around(&[x[i], x[i] + d[i]], 0.5 * pad),
                None => Aabb::around(&[x[i]], 0.5 * pad),
            })
            .collect();
        let tris = surf
            .fine_tris
            .iter()
            .map(|(t, _)| union(&samples, t))
            .collect();
        let edges = surf
            .fine_edges
            .iter()
            .map(|(e, _)| union(&samples, e))
            .collect();
        Search {
            x,
            dx,
            pad,
            samples,
            tris,
            edges,
            slabs,
        }
    }

    /// The box of the primitive with samples `ids`.
    fn bx(&self, ids: &[usize]) -> Aabb {
        union(&self.samples, ids)
    }

    /// Whether the primitive with samples `ids` may come within the pad of
    /// facet `h`.
    fn near(&self, h: usize, ids: &[usize]) -> bool {
        self.slabs[h].is_none_or(|sl| sl.near(ids, self.x, self.dx, self.pad))
    }

    /// Codes of facet `a`'s samples `ids` against facet `b`'s slab, into
    /// `codes`.
    fn fill(&self, codes: &mut Codes, ids: &[usize], b: usize) {
        for &i in ids {
            codes.0[i] = self.slabs[b].map_or(0, |sl| sl.code(i, self.x, self.dx, self.pad));
        }
    }
}

/// The box of the primitive with samples `ids`: the union of their boxes
/// (the box around all their points).
fn union(samples: &[Aabb], ids: &[usize]) -> Aabb {
    Aabb::around_boxes(ids.iter().map(|&i| &samples[i]))
}

/// A facet's slab: the unit normal of its corner triangle and the unit
/// normals of that triangle's sides within its plane, with the span of the
/// facet's samples (and their swept ends) along each. Every primitive of
/// the facet lies in the hull of its samples, so points whose span along
/// any of these axes stays more than `pad` outside the facet's are farther
/// than `pad` from every primitive of the facet. The in-plane axes
/// separate facets side by side in a sheet lying flat, which the normal
/// alone cannot.
#[derive(Clone, Copy)]
struct Slab {
    axes: [Vector3<f64>; 4],
    lo: [f64; 4],
    hi: [f64; 4],
}

impl Slab {
    /// The slab of a facet with corner triangle `c` and samples `ids` at `x`
    /// (swept by `dx`); None where the triangle has no normal.
    fn new(
        c: [Vector3<f64>; 3],
        ids: &[usize],
        x: &[Vector3<f64>],
        dx: Option<&[Vector3<f64>]>,
    ) -> Option<Slab> {
        let normal = (c[1] - c[0]).cross(&(c[2] - c[0])).try_normalize(0.0)?;
        let side = |k: usize| {
            (c[(k + 1) % 3] - c[k])
                .cross(&normal)
                .try_normalize(0.0)
                .unwrap_or(normal)
        };
        let axes = [normal, side(0), side(1), side(2)];
        let spans = axes.map(|axis| span(&axis, ids, x, dx));
        Some(Slab {
            axes,
            lo: spans.map(|(lo, _)| lo),
            hi: spans.map(|(_, hi)| hi),
        })
    }

    /// Whether points `ids` (and their swept ends) may come within `pad` of
    /// the facet.
    fn near(
        &self,
        ids: &[usize],
        x: &[Vector3<f64>],
        dx: Option<&[Vector3<f64>]>,
        pad: f64,
    ) -> bool {
        (0..4).all(|k| {
            let (lo, hi) = span(&self.axes[k], ids, x, dx);
            !(lo - self.hi[k] > pad || self.lo[k] - hi > pad)
        })
    }

    /// Where point `i` (and its swept end) lies against the slab: bit `2k`
    /// set where it is more than `pad` below the span along axis `k`, bit
    /// `2k + 1` where more than `pad` above. Points whose codes share a
    /// bit are all on one side of one axis, out of reach of the facet (the
    /// test of [`Slab::near`], point by point).
    fn code(&self, i: usize, x: &[Vector3<f64>], dx: Option<&[Vector3<f64>]>, pad: f64) -> u8 {
        let mut code = 0;
        for k in 0..4 {
            let a = self.axes[k].dot(&x[i]);
            let b = dx.map_or(a, |d| self.axes[k].dot(&(x[i] + d[i])));
            // The spans' own subtractions: rounding keeps their order, so
            // the codes decide as the spans do.
            if self.lo[k] - a.max(b) > pad {
                code |= 1 << (2 * k);
            } else if a.min(b) - self.hi[k] > pad {
                code |= 2 << (2 * k);
            }
        }
        code
    }
}

/// Samples against a facet's [`Slab`]: their codes, by sample (only the
/// samples of the facet they were last filled for hold theirs).
struct Codes(Vec<u8>);

impl Codes {
    /// Whether the primitive with samples `ids` (all of the filled facet's)
    /// may come within the pad of the other facet.
    fn near(&self, ids: &[usize]) -> bool {
        ids.iter().fold(u8::MAX, |c, &i| c & self.0[i]) == 0
    }
}

/// The span of points `ids` at `x` (and at `x + dx`) along `axis`.
fn span(
    axis: &Vector3<f64>,
    ids: &[usize],
    x: &[Vector3<f64>],
    dx: Option<&[Vector3<f64>]>,
) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for &i in ids {
        let a = axis.dot(&x[i]);
        let b = dx.map_or(a, |d| axis.dot(&(x[i] + d[i])));
        lo = lo.min(a.min(b));
        hi = hi.max(a.max(b));
    }
    (lo, hi)
}

impl ContactTerm {
    /// Candidate pairs with boxes padded by `pad` at positions `x` (and,
    /// with `dx`, swept over the motion `x -> x + dx`).
    pub(super) fn candidates(
        &self,
        x: &[Vector3<f64>],
        dx: Option<&[Vector3<f64>]>,
        pad: f64,
    ) -> Vec<Pair> {
        let s = &self.surf;
        let slabs = (0..s.facet_vertices.len())
            .map(|h| self.slab(x, dx, h))
            .collect();
        let search = Search::new(s, x, dx, pad, slabs);
        let bx = |ids: &[usize]| search.bx(ids);
        let mut out = Vec::new();
        // Facets first: only facets near a facet they share no vertex with
        // take part in the fine search (most of a sheet, most of the time,
        // takes part in none).
        let facet_boxes_all: Vec<Aabb> = s.facet_vertices.iter().map(|vs| bx(vs)).collect();
        let mut fine_active = vec![false; facet_boxes_all.len()];
        let mut near_neighbours = Vec::new();
        for (f, g) in overlapping(&facet_boxes_all, &facet_boxes_all, true) {
            if s.are_neighbours(f, g) {
                near_neighbours.push((f, g));
            } else if !self.facets_apart(&search, (f, g)) {
                fine_active[f] = true;
                fine_active[g] = true;
            }
        }
        let active = |fs: &[usize]| fs.iter().any(|&f| fine_active[f]);
        // Fine: points against sub-triangles, edges against edges, between
        // facets that share no vertex.
        let pts: Vec<usize> = (0..s.n_vertices())
            .filter(|&i| active(&s.vertex_facets[i]))
            .collect();
        let tris: Vec<usize> = (0..s.fine_tris.len())
            .filter(|&k| fine_active[s.fine_tris[k].1])
            .collect();
        let pt_boxes: Vec<Aabb> = pts.iter().map(|&i| search.samples[i]).collect();
        let tri_boxes: Vec<Aabb> = tris.iter().map(|&k| search.tris[k]).collect();
        for (pi, ti) in overlapping(&pt_boxes, &tri_boxes, false) {
            let p = pts[pi];
            let (t, g) = s.fine_tris[tris[ti]];
            let fp = &s.vertex_facets[p];
            if s.any_neighbours(fp, &[g]) {
                continue;
            }
            out.push(Pair {
                kind: Kind::PointTriangle { p, t },
                mass: self.mass_fine,
                xi: self.xi,
            });
        }
        let edges: Vec<usize> = (0..s.fine_edges.len())
            .filter(|&k| active(&s.fine_edges[k].1))
            .collect();
        let edge_boxes: Vec<Aabb> = edges.iter().map(|&k| search.edges[k]).collect();
        for (i, j) in overlapping(&edge_boxes, &edge_boxes, true) {
            let (a, fa) = &s.fine_edges[edges[i]];
            let (b, fb) = &s.fine_edges[edges[j]];
            if s.any_neighbours(fa, fb) {
                continue;
            }
            out.push(self.edge_pair(*a, *b, self.mass_fine));
        }
        // Coarse: corners against corner triangles and mesh edges against
        // mesh edges, between neighbours (sharing no vertex themselves),
        // straight from the neighbouring facet pairs that are near.
        let mut corner_pairs: Vec<(usize, usize)> = Vec::new();
        let mut edge_pairs: Vec<(usize, usize)> = Vec::new();
        // Each corner's, corner triangle's and mesh edge's box once.
        let corner_boxes: Vec<Aabb> = s.corner.iter().map(|&c| search.samples[c]).collect();
        let tri_boxes: Vec<Aabb> = (0..facet_boxes_all.len())
            .map(|f| bx(&s.coarse_tri(&self.mesh, f)))
            .collect();
        let edge_boxes: Vec<Aabb> = s.coarse_edges.iter().map(|(e, _)| bx(e)).collect();
        for &(f, g) in &near_neighbours {
            for (a, b) in [(f, g), (g, f)] {
                for &v in &self.mesh.triangles()[a] {
                    if !self.mesh.triangles()[b].contains(&v)
                        && corner_boxes[v.index()].overlaps(&tri_boxes[b])
                    {
                        corner_pairs.push((v.index(), b));
                    }
                }
            }
            for &i in &self.mesh.face_edges()[f] {
                for &j in &self.mesh.face_edges()[g] {
                    let (ea, eb) = (s.coarse_edges[i.index()].0, s.coarse_edges[j.index()].0);
                    if i != j
                        && !ea.iter().any(|v| eb.contains(v))
                        && edge_boxes[i.index()].overlaps(&edge_boxes[j.index()])
                    {
                        edge_pairs.push((i.min(j).index(), i.max(j).index()));
                    }
                }
            }
        }
        corner_pairs.sort_unstable();
        corner_pairs.dedup();
        edge_pairs.sort_unstable();
        edge_pairs.dedup();
        for (v, g) in corner_pairs {
            out.push(Pair {
                kind: Kind::PointTriangle {
                    p: s.corner[v],
                    t: s.coarse_tri(&self.mesh, g),
                },
                mass: self.mass_coarse,
                xi: self.xi,
            });
        }
        for (i, j) in edge_pairs {
            out.push(self.edge_pair(s.coarse_edges[i].0, s.coarse_edges[j].0, self.mass_coarse));
        }
        self.neighbour_pairs(&search, &near_neighbours, &mut out);
        self.corner_pairs(&search, &near_neighbours, &mut out);
        // Pairs that are (nearly) in contact in the flat sheet are the
        // sheet itself, not contact.
        out.retain(|p| self.rest_distance(p) >= p.xi + self.s_hat_of(p));
        // Boxes overlap where primitives may be within `pad`; without a
        // sweep, keep the pairs that are (the boxes of tilted facets
        // overlap far more often than the facets come near).
        if dx.is_none() {
            out.retain(|p| {
                let xs = self.points(x, p);
                !p.apart(&xs, pad) && distance_sq::<f64>(&p.kind, &lift(&xs)) <= pad * pad
            });
        }
        // A canonical order: sums over pairs do not depend on the search.
        out.sort_unstable_by_key(|p| (matches!(p.kind, Kind::EdgeEdge { .. }), p.ids()));
        out
    }

    /// Facet `h`'s [`Slab`] at `x` (swept by `dx`); None where its corner
    /// triangle has no normal.
    fn slab(&self, x: &[Vector3<f64>], dx: Option<&[Vector3<f64>]>, h: usize) -> Option<Slab> {
        let s = &self.surf;
        let corners = s.coarse_tri(&self.mesh, h).map(|i| x[i]);
        Slab::new(corners, &s.facet_vertices[h], x, dx)
    }

    /// Whether facets `f` and `g` are more than `pad` apart along an axis
    /// of either one's [`Slab`]: the samples of each (and their swept ends)
    /// projected on it, every primitive of a facet being in their hull.
    /// Tilted facets' boxes overlap far more often than the facets come
    /// near.
    fn facets_apart(&self, search: &Search, (f, g): (usize, usize)) -> bool {
        let s = &self.surf;
        !search.near(f, &s.facet_vertices[g]) || !search.near(g, &s.facet_vertices[f])
    }

    /// Fine pairs between neighbouring facets sharing a side (a crease) that
    /// face each other, folded past a right angle (facets sharing only a
    /// corner: [`ContactTerm::corner_pairs`]): each one's samples off the
    /// other against the other's sub-triangles, and their fine edges
    /// against each other's (sharing no sample: a bent facet's sub-triangle
    /// edges crossed the other's beside a crease pressed flat with no
    /// sample through a sub-triangle). A midsurface crease folded
    /// flat closes to a wedge (its facets meet at the crease, their far
    /// corners a thickness apart), so such a pair keeps a thickness that
    /// grows with the two points' distance in the flat pattern `d`:
    /// `NEIGHBOUR_SHARE xi min(1, d / (2 w))` (`w` the mean facet side: the
    /// wedge's own opening at mirror points is `xi d / (2 w)`), and pairs
    /// closer than [`NEIGHBOUR_MIN`] of the thickness are left to the crease
    /// stops. Without them the facets beside a crease folded flat, bent
    /// towards each other, crossed within a sixteenth of a facet of it.
    fn neighbour_pairs(&self, search: &Search, near: &[(usize, usize)], out: &mut Vec<Pair>) {
        let (s, x) = (&self.surf, search.x);
        let normal = |f: usize| {
            let c = s.coarse_tri(&self.mesh, f).map(|i| x[i]);
            (c[1] - c[0]).cross(&(c[2] - c[0]))
        };
        let (mut cf, mut cg) = (self.codes(), self.codes());
        for &(f, g) in near {
            if self.share_a_corner_only(f, g) || normal(f).dot(&normal(g)) >= 0.0 {
                continue;
            }
            let mut keep = |pair: Pair| {
                let xi = self.wedge_share(&pair);
                if xi >= NEIGHBOUR_MIN * self.xi {
                    out.push(Pair { xi, ..pair });
                }
            };
            self.fill_codes(search, (f, &mut cf), (g, &mut cg));
            self.samples_against((f, &cf), (g, &cg), search, &mut keep);
            self.samples_against((g, &cg), (f, &cf), search, &mut keep);
            self.fine_edges_against((f, &cf), (g, &cg), search, &mut keep);
        }
    }

    /// Facet `f`'s samples against `g`'s slab into `cf`, `g`'s against
    /// `f`'s into `cg`.
    fn fill_codes(
        &self,
        search: &Search,
        (f, cf): (usize, &mut Codes),
        (g, cg): (usize, &mut Codes),
    ) {
        let s = &self.surf;
        search.fill(cf, &s.facet_vertices[f], g);
        search.fill(cg, &s.facet_vertices[g], f);
    }

    /// Edge-edge pairs (at the full thickness) of facet `f`'s fine edges
    /// near facet `g` against `g`'s near `f`, sharing no sample and with
    /// overlapping boxes, into `sink`; `cf`, `cg`: each facet's samples
    /// against the other's slab.
    fn fine_edges_against(
        &self,
        (f, cf): (usize, &Codes),
        (g, cg): (usize, &Codes),
        search: &Search,
        sink: &mut dyn FnMut(Pair),
    ) {
        let s = &self.surf;
        let edges_near = |h: usize, codes: &Codes| -> Vec<usize> {
            s.facet_fine_edges[h]
                .iter()
                .copied()
                .filter(|&k| codes.near(&s.fine_edges[k].0))
                .collect()
        };
        let ef = edges_near(f, cf);
        if ef.is_empty() {
            return;
        }
        let eg = edges_near(g, cg);
        for &i in &ef {
            for &j in &eg {
                let (a, b) = (s.fine_edges[i].0, s.fine_edges[j].0);
                if search.edges[i].overlaps(&search.edges[j]) && !a.iter().any(|v| b.contains(v)) {
                    sink(self.edge_pair(a, b, self.mass_fine));
                }
            }
        }
    }

    /// Point-triangle pairs (at the full thickness) of facet `a`'s samples
    /// off facet `b` against `b`'s sub-triangles, each near the other's
    /// facet and their boxes overlapping, into `sink`; `ca`, `cb`: each
    /// facet's samples against the other's slab.
    fn samples_against(
        &self,
        (a, ca): (usize, &Codes),
        (b, cb): (usize, &Codes),
        search: &Search,
        sink: &mut dyn FnMut(Pair),
    ) {
        let s = &self.surf;
        let tris: Vec<usize> = s.facet_fine_tris[b]
            .iter()
            .copied()
            .filter(|&k| cb.near(&s.fine_tris[k].0))
            .collect();
        if tris.is_empty() {
            return;
        }
        for &p in &s.facet_vertices[a] {
            if s.vertex_facets[p].binary_search(&b).is_ok() || ca.0[p] != 0 {
                continue;
            }
            for &k in &tris {
                if search.samples[p].overlaps(&search.tris[k]) {
                    sink(Pair {
                        kind: Kind::PointTriangle {
                            p,
                            t: s.fine_tris[k].0,
                        },
                        mass: self.mass_fine,
                        xi: self.xi,
                    });
                }
            }
        }
    }

    /// Room for every sample's code.
    fn codes(&self) -> Codes {
        Codes(vec![0; self.surf.n_vertices()])
    }

    /// The share of the thickness a pair between neighbouring facets keeps:
    /// [`NEIGHBOUR_SHARE`] of the wedge's opening at its distance `d` in the
    /// flat pattern, `xi min(1, d / (2 w))`.
    fn wedge_share(&self, pair: &Pair) -> f64 {
        NEIGHBOUR_SHARE * self.xi * (self.rest_distance(pair) / (2.0 * self.mean_side)).min(1.0)
    }

    /// Whether facets `f` and `g` share one mesh vertex and no side.
    fn share_a_corner_only(&self, f: usize, g: usize) -> bool {
        let (tf, tg) = (self.mesh.triangles()[f], self.mesh.triangles()[g]);
        tf.iter().filter(|v| tg.contains(v)).count() == 1
    }

    /// Fine pairs between facets that share one vertex and no side,
    /// whichever way they face: each one's samples against the other's
    /// sub-triangles, and their fine edges against each other's (sharing no
    /// sample). No crease stop acts between such facets, and their coarse
    /// pairs (corners against the corner triangle, mesh edges) do not see
    /// the sampled interiors: the Kresling folded flat crossed its sampled
    /// surface in a scissor about a shared vertex, no corner passing
    /// through the other facet. A crossing of two sampled surfaces starts
    /// with a sample through a sub-triangle or a fine edge through a fine
    /// edge, so these pairs and the collision check on them keep the
    /// sampled facets apart. Thickness as across a crease (the layers
    /// between them close to the shared vertex), tapered towards the
    /// vertex but never below [`NEIGHBOUR_MIN`] of the thickness: near the
    /// vertex nothing else keeps them apart. Pairs another family already
    /// holds keep its thickness.
    fn corner_pairs(&self, search: &Search, near: &[(usize, usize)], out: &mut Vec<Pair>) {
        let mut mine = Vec::new();
        let (mut cf, mut cg) = (self.codes(), self.codes());
        let thin = |pair: Pair| {
            let xi = self.wedge_share(&pair).max(NEIGHBOUR_MIN * self.xi);
            Pair { xi, ..pair }
        };
        for &(f, g) in near
            .iter()
            .filter(|&&(f, g)| self.share_a_corner_only(f, g))
        {
            self.fill_codes(search, (f, &mut cf), (g, &mut cg));
            let mut sink = |pair| mine.push(thin(pair));
            self.samples_against((f, &cf), (g, &cg), search, &mut sink);
            self.samples_against((g, &cg), (f, &cf), search, &mut sink);
            self.fine_edges_against((f, &cf), (g, &cg), search, &mut sink);
        }
        mine.sort_unstable_by_key(key);
        mine.dedup_by_key(|p| key(p));
        let held: std::collections::HashSet<PairKey> = out.iter().map(key).collect();
        out.extend(mine.into_iter().filter(|p| !held.contains(&key(p))));
    }

    /// Whether the cache holds no pair and covers the positions at slot
    /// vector `q` (and `q + dq`) for pads up to `pad`, by the slots' moves
    /// alone ([`SlotBound`]): then no pair is near and no position need be
    /// computed; otherwise [`ContactTerm::near_pairs`] decides.
    pub(super) fn nothing_near(&self, q: &[f64], dq: Option<&[f64]>, pad: f64) -> bool {
        let c = &self.cache;
        c.pairs.is_empty()
            && pad <= c.pad
            && c.q0.len() == q.len()
            && c.x0.len() == self.surf.n_vertices()
            // A margin for rounding against the positions' own test.
            && self.slot_bound.moved(q, &c.q0, dq) <= 0.999 * self.cache_margin
    }

    /// Indices into `pairs` (of [`ContactTerm::near_pairs`], `cached` where
    /// the cache's), ascending, of every pair the full list's filters could
    /// keep at `x` (swept by `dx`): all of a search's own; of the cache's,
    /// from `list` where it covers `x` (and `x + dx`), else from a new list
    /// at `x` with a margin of the barrier's width or the move, keeping the
    /// pairs not apart along an axis by `reach(pair, margin)` there.
    pub(super) fn near_indices(
        &self,
        (pairs, cached): (&[Pair], bool),
        list: &std::sync::Mutex<NearList>,
        x: &[Vector3<f64>],
        dx: Option<&[Vector3<f64>]>,
        reach: impl Fn(&Pair, f64) -> f64,
    ) -> Vec<usize> {
        if !cached {
            return (0..pairs.len()).collect();
        }
        let mut near = list.lock().unwrap_or_else(|e| e.into_inner());
        let within = |y: &Vector3<f64>, y0: &Vector3<f64>| (y - y0).norm() <= near.margin;
        let covered = near.x0.len() == x.len()
            && (x.iter().zip(&near.x0).enumerate())
                .all(|(i, (y, y0))| within(y, y0) && dx.is_none_or(|d| within(&(y + d[i]), y0)));
        if !covered {
            // The barrier's width, or the move where it is longer (the
            // cache covers `x + dx`, so at most twice the cache's margin).
            let base = self.s_hat.min(self.cache_margin);
            let margin = dx.map_or(base, |d| d.iter().map(|v| v.norm()).fold(base, f64::max));
            let idx = (self.cache.pairs.iter().enumerate())
                .filter_map(|(i, p)| (!p.apart(&self.points(x, p), reach(p, margin))).then_some(i))
                .collect();
            *near = NearList {
                x0: x.to_vec(),
                margin,
                idx,
            };
        }
        near.idx.clone()
    }

    /// Drop the near lists (the cache they index was replaced).
    pub(super) fn forget_near(&mut self) {
        for list in [&mut self.near, &mut self.near_moves] {
            *list.get_mut().unwrap_or_else(|e| e.into_inner()) = NearList::default();
        }
    }

    /// The candidate pairs at `x` (swept by `dx`) with pad `pad`, or a
    /// superset of them: the step start's cache where it covers them.
    pub(super) fn near_pairs(
        &self,
        x: &[Vector3<f64>],
        dx: Option<&[Vector3<f64>]>,
        pad: f64,
    ) -> std::borrow::Cow<'_, [Pair]> {
        if self.cache.covers(x, dx, pad, self.cache_margin) {
            std::borrow::Cow::Borrowed(&self.cache.pairs)
        } else {
            std::borrow::Cow::Owned(self.candidates(x, dx, pad))
        }
    }

    /// Search at the step start `x` for every pair the step's evaluations
    /// and collision checks may need (pads up to the barrier's reach,
    /// motions up to the margin), unless the last search covers `x`
    /// with half its margin to spare. (Pairs are in a canonical order, so
    /// which search found them does not change a result.)
    /// Returns the cache it replaced, if it searched. `q` is the slot
    /// vector of `x`, kept as where the cache was searched; a restored
    /// state's cache is searched here, at the saved origin, where that
    /// covers `x` as the saved cache did.
    pub(super) fn cache_at(&mut self, q: &[f64], x: &[Vector3<f64>]) -> Option<CandidateCache> {
        let pad = self.xi + self.s_hat;
        let margin = self.cache_margin;
        let restored = if std::mem::take(&mut self.cache_pending) {
            let mut x0 = Vec::new();
            self.surf.positions(&self.cache.q0, &mut x0);
            let origin = CandidateCache {
                x0,
                pad,
                ..Default::default()
            };
            origin
                .covers(x, None, pad, 0.5 * margin)
                .then(|| self.search_cache(&self.cache.q0, &origin.x0))
        } else if self.cache.covers(x, None, pad, 0.5 * margin) {
            return None;
        } else {
            None
        };
        let cache = restored.unwrap_or_else(|| {
            let spare = self.spare.get_mut().ok().and_then(Option::take);
            match spare.filter(|c| c.pad == pad && c.x0 == x) {
                // Searched at the same positions; kept as searched at `q`.
                Some(c) => CandidateCache {
                    q0: q.to_vec(),
                    ..c
                },
                None => self.search_cache(q, x),
            }
        });
        let old = std::mem::replace(&mut self.cache, cache);
        self.forget_near();
        self.blocks = self.cache_blocks();
        Some(old)
    }

    /// A new cache at `x`, the positions of slot vector `q`: every pair
    /// within the barrier's reach plus twice the cache margin.
    pub(super) fn search_cache(&self, q: &[f64], x: &[Vector3<f64>]) -> CandidateCache {
        let pad = self.xi + self.s_hat;
        CandidateCache {
            pairs: self.candidates(x, None, pad + 2.0 * self.cache_margin),
            q0: q.to_vec(),
            x0: x.to_vec(),
            pad,
        }
    }

    /// Slot pairs that the cached candidate pairs' matrices need (the
    /// slots of each pair's four points, among themselves) and the pattern
    /// lacks. The cache holds every pair within the barrier's reach plus
    /// twice the cache margin of the step start, so every pair a step can
    /// activate from it has its blocks (a pair found by a new search
    /// within the step would only leave the iteration matrix; the next
    /// step adds its blocks);
    /// facets that only share a vertex and lie flat get none (they are no
    /// candidates): blocks between every two facets sharing a vertex would
    /// multiply the factorization's work on a large flat sheet.
    pub(super) fn pattern_pairs(&self, asm: &Assembler) -> Vec<(usize, usize)> {
        let mut out = self.blocks.clone();
        out.retain(|&(a, b)| !asm.has_pair(a, b));
        out
    }

    /// Every slot pair `(a, b)`, `a < b`, among the slots of each of
    /// `cache.pairs` (sorted).
    fn cache_blocks(&self) -> Vec<(usize, usize)> {
        // Pairs between the same facets share their slots: each set once.
        let mut sets: Vec<Vec<usize>> = self
            .cache
            .pairs
            .iter()
            .map(|p| {
                let mut slots = Vec::with_capacity(48);
                self.pair_slots(&p.ids(), &mut slots);
                slots
            })
            .collect();
        sets.sort_unstable();
        sets.dedup();
        let mut out = Vec::new();
        for slots in &sets {
            for &a in slots {
                for &b in slots {
                    if a < b {
                        out.push((a, b));
                    }
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::XorShift;

    /// Ten samples about a triangle in the plane z = 0, lifted by up to
    /// `bend` and moved by up to `sweep` (the swept ends), the first three
    /// its corners.
    fn facet(rng: &mut XorShift, bend: f64, sweep: f64) -> (Vec<Vector3<f64>>, Vec<Vector3<f64>>) {
        let c = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(rng.range(0.5, 1.5), rng.range(-0.3, 0.3), 0.0),
            Vector3::new(rng.range(-0.3, 0.8), rng.range(0.5, 1.5), 0.0),
        ];
        let mut x = c.to_vec();
        for _ in 3..10 {
            let (a, b) = (rng.uniform(), rng.uniform());
            let (a, b) = if a + b > 1.0 {
                (1.0 - a, 1.0 - b)
            } else {
                (a, b)
            };
            let mut p = c[0] + (c[1] - c[0]) * a + (c[2] - c[0]) * b;
            p.z += rng.range(-bend, bend);
            x.push(p);
        }
        let dx = (0..10)
            .map(|_| {
                Vector3::new(
                    rng.range(-sweep, sweep),
                    rng.range(-sweep, sweep),
                    rng.range(-sweep, sweep),
                )
            })
            .collect();
        (x, dx)
    }

    /// A random point of the hull of `pts`.
    fn hull_point(rng: &mut XorShift, pts: &[Vector3<f64>]) -> Vector3<f64> {
        let w: Vec<f64> = pts
            .iter()
            .map(|_| -rng.uniform().max(1e-300).ln())
            .collect();
        let sum: f64 = w.iter().sum();
        pts.iter().zip(&w).map(|(p, w)| p * (w / sum)).sum()
    }

    #[test]
    fn a_samples_codes_agree_with_the_slabs_spans() {
        let mut rng = XorShift(0x5eed_51ab);
        for case in 0..200 {
            let (mut x, mut dx) = facet(&mut rng, 0.1, 0.05);
            // Points about the facet, out of and within its reach.
            for _ in 0..30 {
                x.push(Vector3::new(
                    rng.range(-1.0, 2.0),
                    rng.range(-1.0, 2.0),
                    rng.range(-0.6, 0.6),
                ));
                dx.push(Vector3::new(
                    rng.range(-0.1, 0.1),
                    rng.range(-0.1, 0.1),
                    rng.range(-0.1, 0.1),
                ));
            }
            let ids: Vec<usize> = (0..10).collect();
            let swept = (case % 2 == 1).then_some(dx.as_slice());
            let corners = [x[0], x[1], x[2]];
            let slab = Slab::new(corners, &ids, &x, swept).expect("a normal");
            let pad = rng.range(0.0, 0.3);
            let codes = Codes((0..x.len()).map(|i| slab.code(i, &x, swept, pad)).collect());
            for _ in 0..50 {
                let prim: Vec<usize> = (0..1 + rng.below(3)).map(|_| 10 + rng.below(30)).collect();
                assert_eq!(
                    codes.near(&prim),
                    slab.near(&prim, &x, swept, pad),
                    "case {case}, points {prim:?}"
                );
            }
        }
    }

    #[test]
    fn what_a_slab_leaves_out_is_farther_than_the_pad() {
        let mut rng = XorShift(0xfa7_5ab);
        let mut left_out = 0;
        for case in 0..300 {
            let (mut x, _) = facet(&mut rng, 0.1, 0.0);
            for _ in 0..3 {
                x.push(Vector3::new(
                    rng.range(-1.0, 2.0),
                    rng.range(-1.0, 2.0),
                    rng.range(-0.5, 0.5),
                ));
            }
            let ids: Vec<usize> = (0..10).collect();
            let slab = Slab::new([x[0], x[1], x[2]], &ids, &x, None).expect("a normal");
            let pad = rng.range(0.01, 0.3);
            let prim = [10, 11, 12];
            if slab.near(&prim, &x, None, pad) {
                continue;
            }
            left_out += 1;
            let facet: Vec<Vector3<f64>> = x[..10].to_vec();
            let tri: Vec<Vector3<f64>> = x[10..].to_vec();
            for _ in 0..400 {
                let (p, q) = (hull_point(&mut rng, &facet), hull_point(&mut rng, &tri));
                assert!(
                    (p - q).norm() > pad,
                    "case {case}: {} <= pad {pad}",
                    (p - q).norm()
                );
            }
        }
        assert!(
            left_out > 50,
            "{left_out} of 300 cases left out: the test tests little"
        );
    }

    /// The slot bound is never below the largest move of a contact vertex
    /// (to its end, with a step), on a Miura sheet's surface moved at random:
    /// positions by millimetres, gradients by hundredths.
    #[test]
    fn the_slot_bound_holds_every_vertex_move() {
        let scene = crate::benchmarks::miura_scene(2);
        let physics = crate::model::physics(&scene);
        let asm = Assembler::new(&scene.mesh, physics, Default::default(), &[]).unwrap();
        let surf = ContactSurface::new(&scene.mesh, &asm.layout, &asm.elements, 3, true, 0.0);
        let bound = SlotBound::new(&surf, &asm.layout);
        let q0 = asm.layout.reference_state(&scene.mesh);
        let mut rng = XorShift(0xb0b);
        let (mut x0, mut x, mut xd) = (Vec::new(), Vec::new(), Vec::new());
        surf.positions(&q0, &mut x0);
        let mut tightest = 0.0f64;
        for case in 0..200 {
            let (dp, dg) = (rng.range(0.0, 3e-3), rng.range(0.0, 0.03));
            let mut nudge = |q: &[f64], scale: f64| -> Vec<f64> {
                q.iter()
                    .enumerate()
                    .map(|(i, v)| {
                        let size = if bound.kinds[i / 3] == 0 { dp } else { dg };
                        v + scale * rng.range(-size, size)
                    })
                    .collect()
            };
            let q = nudge(&q0, 1.0);
            let dq: Vec<f64> = nudge(&vec![0.0; q0.len()], 0.5);
            let end: Vec<f64> = q.iter().zip(&dq).map(|(a, b)| a + b).collect();
            surf.positions(&q, &mut x);
            surf.positions(&end, &mut xd);
            let moved = x
                .iter()
                .chain(&xd)
                .zip(x0.iter().chain(&x0))
                .map(|(a, b)| (a - b).norm())
                .fold(0.0, f64::max);
            let b = bound.moved(&q, &q0, Some(&dq));
            assert!(moved <= b, "case {case}: moved {moved} past the bound {b}");
            tightest = tightest.max(moved / b);
        }
        assert!(tightest > 0.2, "the bound is informative ({tightest})");
    }

    /// A random stencil (two primitives) about the origin.
    fn stencil(rng: &mut XorShift) -> [Vector3<f64>; 4] {
        std::array::from_fn(|_| {
            Vector3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            )
        })
    }

    /// The unit step along the first axis on which the stencil's first `k`
    /// points and the rest are `d` apart that brings the first primitive
    /// towards the second, if any.
    fn towards(x: &[Vector3<f64>; 4], k: usize, d: f64) -> Option<Vector3<f64>> {
        (0..3).find_map(|c| {
            let (a, b) = x.split_at(k);
            let lo = |s: &[Vector3<f64>]| s.iter().map(|p| p[c]).fold(f64::INFINITY, f64::min);
            let hi = |s: &[Vector3<f64>]| s.iter().map(|p| p[c]).fold(f64::NEG_INFINITY, f64::max);
            let e = Vector3::ith(c, 1.0);
            if lo(b) - hi(a) >= d {
                Some(e)
            } else if lo(a) - hi(b) >= d {
                Some(-e)
            } else {
                None
            }
        })
    }

    /// The stencil with its first `k` points moved by `u` and the rest by
    /// `-u`.
    fn closer(x: &[Vector3<f64>; 4], k: usize, u: Vector3<f64>) -> [Vector3<f64>; 4] {
        std::array::from_fn(|i| if i < k { x[i] + u } else { x[i] - u })
    }

    /// What an evaluation's near list leaves out is apart by its reach
    /// anywhere within the margin of the list's origin: each primitive
    /// moved the whole margin towards the other (the worst case).
    #[test]
    fn left_out_of_an_evaluations_list_stays_apart() {
        let mut rng = XorShift(0x1157);
        let mut left_out = 0;
        for case in 0..20000 {
            let x0 = stencil(&mut rng);
            let (k, reach, m) = (1 + case % 2, rng.range(0.0, 0.3), rng.range(0.01, 0.2));
            let Some(u) = towards(&x0, k, reach + NEAR_REACH_MARGINS * m) else {
                continue;
            };
            left_out += 1;
            let x = closer(&x0, k, u * m);
            assert!(
                crate::contact::distance::axis_apart(&x, k, reach),
                "case {case}"
            );
        }
        assert!(left_out > 2000, "{left_out} cases left out");
    }

    /// What a collision check's near list leaves out has no time of impact
    /// for a move whose start and end are within the margin of the list's
    /// origin: started the margin apart, ended the margin towards each
    /// other (the most the gap can fall against where it starts).
    #[test]
    fn left_out_of_a_checks_list_has_no_time_of_impact() {
        let mut rng = XorShift(0x70e);
        let mut left_out = 0;
        for case in 0..20000 {
            let x0 = stencil(&mut rng);
            let (k, xi, m) = (1 + case % 2, rng.range(0.0, 0.3), rng.range(0.01, 0.2));
            let Some(u) = towards(&x0, k, xi + NEAR_MOVE_MARGINS * m) else {
                continue;
            };
            left_out += 1;
            let x = closer(&x0, k, -u * m);
            let end = closer(&x0, k, u * m);
            let dx = std::array::from_fn(|i| end[i] - x[i]);
            let toi = if k == 1 {
                crate::contact::ccd::point_triangle_toi(x, dx, xi, 1.0)
            } else {
                crate::contact::ccd::edge_edge_toi(x, dx, xi, 1.0)
            };
            assert_eq!(toi, None, "case {case}");
        }
        assert!(left_out > 2000, "{left_out} cases left out");
    }

    #[test]
    fn facets_side_by_side_in_a_flat_sheet_are_apart() {
        // Two triangles in one plane, 0.1 apart across a diagonal gap: the
        // normal alone cannot part them, the sides' normals do.
        let x = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(1.0, 0.1, 0.0),
            Vector3::new(1.0, 1.1, 0.0),
            Vector3::new(0.1, 1.1, 0.0),
        ];
        let slab = Slab::new([x[0], x[1], x[2]], &[0, 1, 2], &x, None).expect("a normal");
        assert!(!slab.near(&[3, 4, 5], &x, None, 0.05));
        assert!(slab.near(&[3, 4, 5], &x, None, 0.08));
        let mut normal_only = slab;
        normal_only.axes = [slab.axes[0]; 4];
        normal_only.lo = [slab.lo[0]; 4];
        normal_only.hi = [slab.hi[0]; 4];
        assert!(normal_only.near(&[3, 4, 5], &x, None, 0.05));
    }
}
