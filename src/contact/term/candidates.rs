//! The candidate pairs: the search, the step start's cache of it, the matrix blocks they need.

use super::ContactTerm;
use super::pairs::{Kind, Pair, PairKey, distance_sq, key, lift};
use crate::assembly::Assembler;
use crate::contact::broad::{Aabb, overlapping};
use crate::contact::surface::ContactSurface;
use nalgebra::Vector3;

/// The candidate pairs of the step start, found with boxes padded by
/// `pad + 2 margin`: a superset of the pairs any search with pad up to `pad`
/// finds while every contact vertex (and its swept end) stays within
/// `margin` of its step-start position `x0`. A step's many evaluations and
/// collision checks then filter this list by distance instead of searching
/// again (the pairs' final test is their distance in both cases).
#[derive(Clone, Debug, Default)]
pub(super) struct CandidateCache {
    pub(super) x0: Vec<Vector3<f64>>,
    pub(super) pad: f64,
    pub(super) pairs: Vec<Pair>,
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
}

/// The box of the primitive with samples `ids`: the union of their boxes
/// (the box around all their points).
fn union(samples: &[Aabb], ids: &[usize]) -> Aabb {
    Aabb::around_boxes(ids.iter().map(|&i| &samples[i]))
}

/// A facet's slab: the unit normal of its corner triangle and the span of
/// its samples (with their swept ends) along it. Every primitive of the
/// facet lies in the hull of its samples, so points whose span along the
/// normal stays more than `pad` outside the slab are farther than `pad`
/// from every primitive of the facet.
#[derive(Clone, Copy)]
struct Slab {
    axis: Vector3<f64>,
    lo: f64,
    hi: f64,
}

impl Slab {
    /// Whether points `ids` (and their swept ends) may come within `pad` of
    /// the facet.
    fn near(
        &self,
        ids: &[usize],
        x: &[Vector3<f64>],
        dx: Option<&[Vector3<f64>]>,
        pad: f64,
    ) -> bool {
        let (lo, hi) = span(&self.axis, ids, x, dx);
        !(lo - self.hi > pad || self.lo - hi > pad)
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
        let c = s.coarse_tri(&self.mesh, h).map(|i| x[i]);
        let axis = (c[1] - c[0]).cross(&(c[2] - c[0])).try_normalize(0.0)?;
        let (lo, hi) = span(&axis, &s.facet_vertices[h], x, dx);
        Some(Slab { axis, lo, hi })
    }

    /// Whether facets `f` and `g` are more than `pad` apart along the
    /// normal of either one's corner triangle: the samples of each (and
    /// their swept ends) projected on it, every primitive of a facet being
    /// in their hull. Tilted facets' boxes overlap far more often than the
    /// facets come near.
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
            for (a, b) in [(f, g), (g, f)] {
                self.samples_against(a, b, search, &mut keep);
            }
            self.fine_edges_against(f, g, search, &mut keep);
        }
    }

    /// Edge-edge pairs (at the full thickness) of facet `f`'s fine edges
    /// near facet `g` against `g`'s near `f`, sharing no sample and with
    /// overlapping boxes, into `sink`.
    fn fine_edges_against(&self, f: usize, g: usize, search: &Search, sink: &mut dyn FnMut(Pair)) {
        let s = &self.surf;
        let edges_near = |h: usize, other: usize| -> Vec<usize> {
            s.facet_fine_edges[h]
                .iter()
                .copied()
                .filter(|&k| search.near(other, &s.fine_edges[k].0))
                .collect()
        };
        let ef = edges_near(f, g);
        if ef.is_empty() {
            return;
        }
        let eg = edges_near(g, f);
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
    /// facet and their boxes overlapping, into `sink`.
    fn samples_against(&self, a: usize, b: usize, search: &Search, sink: &mut dyn FnMut(Pair)) {
        let s = &self.surf;
        let tris: Vec<usize> = s.facet_fine_tris[b]
            .iter()
            .copied()
            .filter(|&k| search.near(a, &s.fine_tris[k].0))
            .collect();
        if tris.is_empty() {
            return;
        }
        for &p in &s.facet_vertices[a] {
            if s.vertex_facets[p].binary_search(&b).is_ok() || !search.near(b, &[p]) {
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
        let thin = |pair: Pair| {
            let xi = self.wedge_share(&pair).max(NEIGHBOUR_MIN * self.xi);
            Pair { xi, ..pair }
        };
        for &(f, g) in near
            .iter()
            .filter(|&&(f, g)| self.share_a_corner_only(f, g))
        {
            for (a, b) in [(f, g), (g, f)] {
                self.samples_against(a, b, search, &mut |pair| mine.push(thin(pair)));
            }
            self.fine_edges_against(f, g, search, &mut |pair| mine.push(thin(pair)));
        }
        mine.sort_unstable_by_key(key);
        mine.dedup_by_key(|p| key(p));
        let held: std::collections::HashSet<PairKey> = out.iter().map(key).collect();
        out.extend(mine.into_iter().filter(|p| !held.contains(&key(p))));
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
            self.surf.positions(&self.cache_q, &mut x0);
            let origin = CandidateCache {
                x0,
                pad,
                pairs: Vec::new(),
            };
            origin
                .covers(x, None, pad, 0.5 * margin)
                .then(|| self.search_cache(&origin.x0))
        } else if self.cache.covers(x, None, pad, 0.5 * margin) {
            return None;
        } else {
            None
        };
        let cache = restored.unwrap_or_else(|| {
            self.cache_q = q.to_vec();
            let spare = self.spare.get_mut().ok().and_then(Option::take);
            match spare.filter(|c| c.pad == pad && c.x0 == x) {
                Some(c) => c,
                None => self.search_cache(x),
            }
        });
        let old = std::mem::replace(&mut self.cache, cache);
        self.blocks = self.cache_blocks();
        Some(old)
    }

    /// A new cache at `x`: every pair within the barrier's reach plus
    /// twice the cache margin.
    pub(super) fn search_cache(&self, x: &[Vector3<f64>]) -> CandidateCache {
        let pad = self.xi + self.s_hat;
        CandidateCache {
            pairs: self.candidates(x, None, pad + 2.0 * self.cache_margin),
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
