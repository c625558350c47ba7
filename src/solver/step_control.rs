//! Step-size control, apart from the schemes' formulas: which step to try
//! next within one advance, and what an attempt's error or failure means
//! for the step after it (Hairer, Norsett & Wanner I, II.4).

use crate::solver::IntegrationParameters;

/// The step sizes of one advance (one communication step).
pub struct StepController {
    params: IntegrationParameters,
    min_step: f64,
    max_step: f64,
    /// The step to try next.
    h: f64,
    /// The last attempt, where it was rejected for its error: size, error.
    last_rejected: Option<(f64, f64)>,
    /// Whether the step proposed before fitting it to the rest was at the minimum.
    proposal_at_min: bool,
}

/// What the controller makes of a step that converged with its error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Verdict {
    /// Keep it; the step after it and the proposal for the next advance.
    Accept {
        /// The next step within this advance.
        next: f64,
    },
    /// Try again with the (shorter) step the controller now holds.
    Reject,
}

/// The local error estimate's order in h (generalized-alpha: h^3).
const ERROR_ORDER: f64 = 3.0;

impl StepController {
    /// Start an advance at the proposed step `h_start`, within `[min_step, max_step]`.
    pub fn new(params: IntegrationParameters, min_step: f64, max_step: f64, h_start: f64) -> Self {
        StepController {
            params,
            min_step,
            max_step,
            h: h_start.min(max_step),
            last_rejected: None,
            proposal_at_min: false,
        }
    }

    /// Keep a step within [min_step, max_step] (max wins, so a bad pair of
    /// settings cannot panic here).
    fn bounded(&self, x: f64) -> f64 {
        x.max(self.min_step).min(self.max_step)
    }

    /// The step to try with `remaining` seconds left in the advance: the
    /// proposal, or all that is left when it is within the join fraction,
    /// or half of it when less than two proposals remain (the last two
    /// steps then share one size, and modified Newton one matrix; earlier
    /// steps keep the proposed size, so a last-bit difference in the
    /// master's step reaches only these two).
    pub fn next_step(&mut self, remaining: f64) -> f64 {
        let p = &self.params;
        self.proposal_at_min = self.h <= self.min_step * p.at_min_step;
        let ratio = remaining / self.h;
        if ratio <= 1.0 + p.join_fraction {
            self.h = remaining;
        } else if p.equal_last_steps && ratio <= 2.0 {
            self.h = 0.5 * remaining;
        }
        self.h
    }

    /// The step factor the error estimate `error` (1 = the tolerance) proposes.
    fn proposed_factor(&self, error: f64) -> f64 {
        self.params.safety * error.powf(-1.0 / ERROR_ORDER)
    }

    /// Accept or reject the step `h` that converged with `error`. A step at
    /// the minimum (also after a join stretched it) is accepted whatever
    /// its error, where it would otherwise be rejected for ever.
    pub fn judge(&mut self, h: f64, error: f64) -> Verdict {
        let p = self.params;
        let at_min = self.proposal_at_min || h <= self.min_step * p.at_min_step;
        if error <= 1.0 || at_min {
            let grow = if error > 0.0 {
                self.proposed_factor(error)
            } else {
                p.max_growth
            };
            self.last_rejected = None;
            self.h = self.bounded(h * grow.clamp(p.min_factor, p.max_growth));
            Verdict::Accept { next: self.h }
        } else {
            let factor = self.rejected_factor(h, error);
            self.last_rejected = Some((h, error));
            self.h = self.bounded(h * factor);
            Verdict::Reject
        }
    }

    /// After the step `h` failed to converge: false where the retry would
    /// fall below the minimum step.
    pub fn failed(&mut self, h: f64) -> bool {
        self.last_rejected = None;
        self.h = h * self.params.factor_failed;
        self.h >= self.min_step
    }

    /// The step factor after a step of size `h` rejected with `error`,
    /// where the attempt before it was rejected too: the error of two
    /// attempts gives its observed order in h. Right after an input's kink
    /// or at the start, where the acceleration jumps, it falls as h^1-1.5,
    /// not h^3, and the h^3 rule takes four or five rejections to get there.
    fn rejected_factor(&self, h: f64, error: f64) -> f64 {
        let p = &self.params;
        let order = match (self.last_rejected, p.observed_order) {
            (Some((h0, e0)), Some(min_order)) if h0 > h && e0 > error => {
                let k = (e0 / error).ln() / (h0 / h).ln();
                k.clamp(min_order, ERROR_ORDER)
            }
            _ => ERROR_ORDER,
        };
        (p.safety * error.powf(-1.0 / order)).clamp(p.min_factor, p.max_factor_rejected)
    }
}

/// Equal substeps of an advance `big_h` none longer than `h_max`: their
/// number and size.
pub fn equal_substeps(big_h: f64, h_max: f64) -> (usize, f64) {
    let n = (big_h / h_max).ceil().max(1.0);
    (n as usize, big_h / n)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn controller() -> StepController {
        StepController::new(IntegrationParameters::default(), 1e-12, 1.0, 0.01)
    }

    /// Where the error falls as h (not h^3), the second rejection reads the
    /// order off the two attempts and proposes the step that meets the
    /// tolerance: here one more attempt instead of four.
    #[test]
    fn a_second_rejection_uses_the_observed_order() {
        let error = |h: f64| 1000.0 * h; // 10 at 10 ms
        let mut c = controller();
        let h0 = c.next_step(1.0);
        assert_eq!(h0, 0.01);
        // First rejection: the h^3 rule (limited to 0.2 .. 0.9).
        assert_eq!(c.judge(h0, error(h0)), Verdict::Reject);
        let h1 = c.next_step(1.0);
        assert!(
            (h1 / h0 - 0.9 * 10f64.powf(-1.0 / 3.0)).abs() < 1e-12,
            "{h1}"
        );
        assert_eq!(c.judge(h1, error(h1)), Verdict::Reject);
        let h2 = c.next_step(1.0);
        assert!(
            (error(h2) - 0.9).abs() < 1e-9,
            "error {} at {h2}",
            error(h2)
        );
        // An error that falls as h^3 keeps the h^3 rule; one that does not
        // fall trusts no order below 0.5 (and the factor stays >= 0.2).
        let cubic = |h: f64| 1e7 * h * h * h;
        let mut c = controller();
        c.last_rejected = Some((0.01, cubic(0.01)));
        let g = c.rejected_factor(0.005, cubic(0.005));
        assert!((g - c.proposed_factor(cubic(0.005))).abs() < 1e-12);
        c.last_rejected = Some((0.01, 3.0));
        let flat = c.rejected_factor(0.005, 3.0);
        assert!((flat - c.proposed_factor(3.0).clamp(0.2, 0.9)).abs() < 1e-12);
    }

    /// The last two steps of an advance are equal halves of what is left;
    /// a rest within the join fraction joins the step before.
    #[test]
    fn the_last_two_steps_are_equal() {
        let mut c = controller();
        assert_eq!(c.next_step(0.015), 0.0075);
        let mut c = controller();
        assert_eq!(c.next_step(0.01 * (1.0 + 1e-4)), 0.01 * (1.0 + 1e-4));
        let mut c = controller();
        assert_eq!(c.next_step(0.05), 0.01);
    }

    /// A first rejection shrinks the step by the error's h^3 rule within
    /// its bounds, an accepted step grows by at most the largest growth
    /// (right after a rejection too); a failure cuts the step by the
    /// failure factor and reports when the retry would be below the minimum.
    #[test]
    fn rejections_and_failures() {
        let mut c = controller();
        let h0 = c.next_step(1.0);
        assert_eq!(c.judge(h0, 2.0), Verdict::Reject);
        let h = c.next_step(1.0);
        assert!((h / h0 - 0.9 * 2f64.powf(-1.0 / 3.0)).abs() < 1e-12, "{h}");
        assert_eq!(c.judge(h, 1e-9), Verdict::Accept { next: 2.0 * h });
        assert_eq!(c.judge(h, 1e3), Verdict::Reject);
        assert_eq!(c.next_step(1.0), 0.2 * h);
        let mut c = StepController::new(IntegrationParameters::default(), 1e-3, 1.0, 2e-3);
        assert!(!c.failed(2e-3));
    }

    #[test]
    fn equal_substeps_cover_the_advance() {
        assert_eq!(equal_substeps(1.0, 0.3), (4, 0.25));
        assert_eq!(equal_substeps(1e-3, 1.0), (1, 1e-3));
    }
}
