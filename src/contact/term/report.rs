//! What contact looks like at a state (outputs, tests): the smallest gap, pairs, normal force.

use super::ContactTerm;
use super::pairs::{Pair, distance_sq, lift};
use nalgebra::Vector3;

/// What contact looks like at one state (for outputs and tests).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactReport {
    /// Smallest surface distance minus the thickness (m) over the pairs
    /// searched (within `search` of each other).
    pub min_gap: f64,
    /// Pairs within the barrier width.
    pub pairs: usize,
    /// Sum of the pairs' normal forces (N).
    pub normal_force: f64,
}

impl ContactTerm {
    /// How far beyond the thickness [`ContactTerm::report_near`] looks for
    /// the smallest gap (m): the candidate search's margin, a tenth of a
    /// facet side or the barrier's reach if more.
    pub fn report_reach(&self) -> f64 {
        self.cache_margin
    }

    /// [`ContactTerm::report`] with the search up to
    /// [`ContactTerm::report_reach`], from the step's candidate pairs where
    /// they hold every pair that close (the contact vertices have moved
    /// less than the slack their search left): what the contact outputs
    /// read after each step, with no search of their own.
    pub fn report_near(&self, q: &[f64]) -> ContactReport {
        let mut x = Vec::new();
        self.surf.positions(q, &mut x);
        let reach = self.report_reach();
        // The cache holds every pair within `pad + 2 margin` of its search
        // positions; a pair within `xi + reach` now was within that of
        // them while no vertex moved more than `slack`.
        let slack = 0.5 * (self.cache.pad + 2.0 * self.cache_margin - self.xi - reach);
        if slack >= 0.0 && self.cache.covers(&x, None, self.cache.pad, slack) {
            return self.report_over(&x, &self.cache.pairs, true, reach);
        }
        // The next step starts here and would search again: search once,
        // as it would (a wider search than the report needs), and leave it.
        let searched = self.search_cache(q, &x);
        let r = self.report_over(&searched.x0, &searched.pairs, false, reach);
        if let Ok(mut spare) = self.spare.lock() {
            *spare = Some(searched);
        }
        r
    }

    /// Gap, pair count and normal force at slot vector `q`; the smallest
    /// gap is searched up to `search` (m) apart (`search` if none is closer).
    pub fn report(&self, q: &[f64], search: f64) -> ContactReport {
        let mut x = Vec::new();
        self.surf.positions(q, &mut x);
        self.report_over(
            &x,
            &self.candidates(&x, None, search + self.xi),
            false,
            search,
        )
    }

    /// The report over `pairs` at contact-vertex positions `x`, the
    /// smallest gap capped at `search`.
    /// `cached`: `pairs` are the candidate cache's.
    fn report_over(
        &self,
        x: &[Vector3<f64>],
        pairs: &[Pair],
        cached: bool,
        search: f64,
    ) -> ContactReport {
        let mut r = ContactReport {
            min_gap: search,
            ..Default::default()
        };
        for (i, p) in pairs.iter().enumerate() {
            let xs = self.points(x, p);
            let d = distance_sq::<f64>(&p.kind, &lift(&xs)).sqrt();
            let s = d - p.xi;
            r.min_gap = r.min_gap.min(s);
            if s < self.s_hat_of(p) {
                r.pairs += 1;
                if s > 0.0 {
                    r.normal_force += self.normal_force(p, &xs, s, self.kappa_at(pairs, i, cached));
                }
            }
        }
        r
    }
}
