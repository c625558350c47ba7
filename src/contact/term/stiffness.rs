//! Each pair's barrier stiffness: the default or more for a fast approach, kept while inside.

use super::ContactTerm;
use super::candidates::CandidateCache;
use super::pairs::{Kind, Pair, distance_sq, find_key, key, lift};
use crate::contact::memory::kept_stiffness;
use crate::contact::potentials::speed_stiffness;
use nalgebra::Vector3;

impl ContactTerm {
    /// Set the pair stiffnesses (`kappas`, by index of the cache's pairs)
    /// at a step start with contact-vertex positions `x` and velocities
    /// `v`: kept for pairs inside the barrier (their energy is not zero),
    /// set anew for the others. The last ones are by index while the cache
    /// is the same, else by key (a restored state's by key, used up here).
    /// `old` is the candidate cache the step start replaced, if it did.
    pub(super) fn set_stiffnesses(
        &mut self,
        x: &[Vector3<f64>],
        v: &[Vector3<f64>],
        old: Option<&CandidateCache>,
    ) {
        let restored = self.restored.take();
        let old_kappas = std::mem::take(&mut self.kappas);
        let last = |i: usize, p: &Pair| -> Option<f64> {
            match (&restored, old) {
                (Some(map), _) => map.get(&key(p)).copied(),
                (None, Some(c)) => find_key(&c.pairs, p).and_then(|j| old_kappas.get(j).copied()),
                (None, None) => old_kappas.get(i).copied(),
            }
        };
        let mut kappas = Vec::with_capacity(self.cache.pairs.len());
        for (i, p) in self.cache.pairs.iter().enumerate() {
            let xs = self.points(x, p);
            let s_hat = self.s_hat_of(p);
            let inside = || {
                !p.apart(&xs, p.xi + s_hat)
                    && distance_sq::<f64>(&p.kind, &lift(&xs)).sqrt() - p.xi < s_hat
            };
            kappas.push(kept_stiffness(last(i, p), inside, || {
                self.pair_stiffness(p, x, v)
            }));
        }
        // Pairs with one key (adjacent in the canonical order) take the
        // last one's value, as a map by key keeps it.
        for i in (1..kappas.len()).rev() {
            if key(&self.cache.pairs[i - 1]) == key(&self.cache.pairs[i]) {
                kappas[i - 1] = kappas[i];
            }
        }
        self.kappas = kappas;
    }

    /// The barrier stiffness a pair outside the barrier takes at a step
    /// start with contact-vertex positions `x` and velocities `v`: its
    /// [`ContactTerm::base_stiffness`], or more where the pair approaches so fast that the default
    /// barrier's energy scale `kappa s_hat^2` would let it come much
    /// closer than a few hundredths of the barrier width:
    /// `m v_n^2 / (PAIR_SPEED_DIVISOR s_hat^2)` for its sample mass `m` and
    /// normal approach `v_n` (IPC raises one global stiffness where the
    /// smallest gap falls, which changes the energy of every pair in the
    /// barrier). Set while the pair's barrier energy is zero and kept while
    /// it is inside, the stiffness changes no energy. A panel's corner
    /// whipping onto the layer below (a flat stack released in one held
    /// step) reaches the default barrier's energy scale many times over and
    /// would be stopped at a gap of 1e-13 m, where Newton cannot move it.
    pub(super) fn pair_stiffness(&self, p: &Pair, x: &[Vector3<f64>], v: &[Vector3<f64>]) -> f64 {
        let base = self.base_stiffness(p);
        if v.len() != x.len() || x.is_empty() {
            return base;
        }
        let xs = self.points(x, p);
        let (w, n) = self.closest(p, &xs);
        let ids = p.ids();
        let vr: Vector3<f64> = (0..4).map(|k| w[k] * v[ids[k]]).sum();
        // Along the normal of the second primitive's surface (the
        // triangle's; for two edges, a facet of the second), not the
        // closest points' direction: a sample sliding onto the next
        // sub-triangle, or an edge sliding sideways onto a parallel one,
        // comes closer to it at the sliding speed, but it does not
        // approach the surface.
        let surface = match p.kind {
            Kind::PointTriangle { .. } => (xs[2] - xs[1]).cross(&(xs[3] - xs[1])),
            Kind::EdgeEdge { b, .. } => {
                let fb = &self.surf.vertex_facets;
                match fb[b[0]].iter().find(|f| fb[b[1]].contains(f)) {
                    Some(&f) => {
                        let c = self.surf.coarse_tri(&self.mesh, f).map(|i| x[i]);
                        (c[1] - c[0]).cross(&(c[2] - c[0]))
                    }
                    None => n,
                }
            }
        };
        let normal = match surface.try_normalize(0.0) {
            Some(u) if u.dot(&n) < 0.0 => -u,
            Some(u) => u,
            None => n,
        };
        let approach = (-normal.dot(&vr)).max(0.0);
        speed_stiffness(base, p.mass, approach, self.s_hat_of(p))
    }

    /// The stiffness a pair takes without an approach: the default `kappa`
    /// times `(xi / xi_p)^2` for a pair whose thickness `xi_p` is tapered
    /// (beside a crease or a shared corner), so that its barrier's energy
    /// scale `kappa s_hat^2` is a full pair's though its width shrinks with
    /// its thickness. Its force at a share of its width then grows as its
    /// thickness falls, as a moment about the crease presses a point nearer
    /// it harder: a panel held closed by a crease moment crushed a tapered
    /// pair beside the crease to 5e-10 m with the default stiffness.
    pub(super) fn base_stiffness(&self, p: &Pair) -> f64 {
        self.kappa * (self.xi / p.xi).powi(2)
    }

    /// A pair's barrier stiffness: the one set at the last step start, or
    /// (a pair found since) the one it would have been given there (a
    /// pair the next step start finds inside the barrier and not in the
    /// map, having come closer than the candidate search's margin in one
    /// step, takes the stiffness of that step start).
    pub(super) fn kappa_of(&self, p: &Pair) -> f64 {
        let set = match &self.restored {
            Some(map) => map.get(&key(p)).copied(),
            None => find_key(&self.cache.pairs, p).and_then(|i| self.kappas.get(i).copied()),
        };
        set.unwrap_or_else(|| self.pair_stiffness(p, &self.at_start.x, &self.at_start.v))
    }

    /// The stiffness of the `i`th pair of `pairs`, which are the cache's
    /// when `cached`.
    pub(super) fn kappa_at(&self, pairs: &[Pair], i: usize, cached: bool) -> f64 {
        match self.kappas.get(i) {
            Some(&k) if cached && self.restored.is_none() => k,
            _ => self.kappa_of(&pairs[i]),
        }
    }
}
