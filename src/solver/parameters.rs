//! [`IntegrationParameters`]: every constant of the implicit stepper's
//! Newton iteration, predictor and step-size control in one documented
//! struct (as rapier's `IntegrationParameters`). The user-facing settings
//! (tolerance, step bounds, rho_inf, Newton mode) are the scene's
//! [`crate::scene::SolverSettings`]; these are the numerics behind them,
//! changed from the Rust API only (`scene.solver.integration`).
//!
//! `docs/performance.md` tabulates each rule on and off on the bench suite
//! (`cargo bench --bench suite -- --rules all`); a rule stays only where
//! the suite as a whole gains from it.

/// The stepper's numerical constants, with their defaults in [`Default`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IntegrationParameters {
    // Step-size control (Hairer, Norsett & Wanner I, II.4).
    /// Safety factor on the step size the error estimate proposes.
    pub safety: f64,
    /// Smallest factor from one step to the next after an error estimate.
    pub min_factor: f64,
    /// Largest growth from one accepted step to the next.
    pub max_growth: f64,
    /// Largest factor after a step rejected for its error (it must shrink).
    pub max_factor_rejected: f64,
    /// Lowest order of the local error in h that a second rejection reads
    /// off two attempts; `None`: every rejection assumes the scheme's order.
    pub observed_order: Option<f64>,
    /// Factor after a step whose Newton iteration failed.
    pub factor_failed: f64,
    /// Land on the communication point with the last two steps equal halves
    /// of what is left, so they share one step size and iteration matrix.
    pub equal_last_steps: bool,
    /// A rest of the advance shorter than this fraction of the step joins it.
    pub join_fraction: f64,
    /// A step within this factor of `min_step` is accepted whatever its error.
    pub at_min_step: f64,

    // Newton's stopping test.
    /// Newton's tolerance as a fraction of the error tolerance (the
    /// iteration error stays below what the step control accepts).
    pub newton_tolerance_ratio: f64,
    /// Newton's tolerance as a fraction of the thickness ratio h / L: a
    /// correction small against the sheet may be large against its
    /// thickness, and then carries membrane force far above the bending.
    pub newton_thickness_ratio: f64,
    /// Smallest Newton tolerance (near the round-off of a scaled correction).
    pub newton_tolerance_floor: f64,
    /// Newton's velocity error against friction's stick velocity: scaled
    /// corrections stay below this fraction of the stick velocity's
    /// position equivalent, so a sticking contact does not creep.
    pub stick_fraction: f64,
    /// A fresh matrix that contracts slower than this within
    /// `floor_factor` times the tolerance has reached the round-off floor
    /// of an ill-conditioned system: the iterate counts as converged.
    pub floor_rate: f64,
    /// See `floor_rate`.
    pub floor_factor: f64,
    /// The iteration diverges when the correction grows by more than this
    /// twice in a row (one growth alone happens in a converging zig-zag).
    pub divergence_rate: f64,

    // Modified Newton's iteration matrix.
    /// A kept matrix serves steps within this factor of the size it was
    /// formed for (and its inverse).
    pub kept_matrix_ratio: f64,
    /// A kept matrix is formed anew when the iteration contracts slower than this.
    pub max_rate: f64,
    /// Within this factor of Newton's tolerance a slow contraction of the
    /// kept matrix does not at once form the matrix anew, ...
    pub near_factor: f64,
    /// ... for up to this many iterations in a row (0: the rule is off):
    /// the rate of two tiny corrections says little.
    pub near_chances: u32,
    /// Modified Newton's matrix takes the membrane's geometric stiffness
    /// from the step start (it changes fast as facets turn, and an exact
    /// one would need forming at every iterate).
    pub lag_membrane_stiffness: bool,
    /// Broyden secant updates of a kept matrix within a step.
    pub secant_updates: bool,

    // Predictor.
    /// Start Newton from the better of two guesses (positions held, or
    /// extrapolated with constant acceleration); off: held only.
    pub two_guess_predictor: bool,
    /// After this many steps in a row won by one guess the other is skipped
    /// (one force evaluation less per step) ...
    pub skip_loser_after: u32,
    /// ... except on every this-many-th step of the streak, where both compete again.
    pub recheck_every: u32,

    // Line search near contact.
    /// Sufficient-decrease constant of the line search on the incremental potential.
    pub armijo: f64,
    /// Most halvings of one correction in the line search.
    pub line_search_halvings: usize,
}

impl Default for IntegrationParameters {
    fn default() -> Self {
        IntegrationParameters {
            safety: 0.9,
            min_factor: 0.2,
            max_growth: 2.0,
            max_factor_rejected: 0.9,
            observed_order: Some(0.5),
            factor_failed: 0.25,
            equal_last_steps: true,
            join_fraction: 1e-3,
            at_min_step: 1.000001,
            newton_tolerance_ratio: 1e-3,
            newton_thickness_ratio: 1e-2,
            newton_tolerance_floor: 1e-13,
            stick_fraction: 1.0,
            floor_rate: 0.5,
            floor_factor: 100.0,
            divergence_rate: 2.0,
            kept_matrix_ratio: 1.25,
            max_rate: 0.25,
            near_factor: 10.0,
            near_chances: 3,
            lag_membrane_stiffness: true,
            secant_updates: true,
            two_guess_predictor: true,
            skip_loser_after: 4,
            recheck_every: 8,
            armijo: 0.1,
            line_search_halvings: 8,
        }
    }
}

/// One speed rule of the stepper that can be switched off, for the suite
/// that decides whether it stays.
#[derive(Clone, Copy, Debug)]
pub struct Rule {
    /// Its name on the suite bench's command line.
    pub name: &'static str,
    /// What it does, in a line.
    pub what: &'static str,
    /// The parameters with the rule off.
    pub off: fn(IntegrationParameters) -> IntegrationParameters,
}

impl IntegrationParameters {
    /// The speed rule named `name` (see [`IntegrationParameters::rules`]).
    pub fn rule(name: &str) -> Option<&'static Rule> {
        Self::rules().iter().find(|r| r.name == name)
    }

    /// The speed rules that can be switched off one at a time.
    pub fn rules() -> &'static [Rule] {
        &[
            Rule {
                name: "observed-order",
                what: "a second rejection reads the error's order off two attempts",
                off: |p| IntegrationParameters {
                    observed_order: None,
                    ..p
                },
            },
            Rule {
                name: "equal-last-steps",
                what: "the last two steps of an advance are equal halves",
                off: |p| IntegrationParameters {
                    equal_last_steps: false,
                    ..p
                },
            },
            Rule {
                name: "near-chances",
                what: "slow contractions near the tolerance keep the matrix",
                off: |p| IntegrationParameters {
                    near_chances: 0,
                    ..p
                },
            },
            Rule {
                name: "lagged-membrane",
                what: "the kept matrix's membrane stiffness from the step start",
                off: |p| IntegrationParameters {
                    lag_membrane_stiffness: false,
                    ..p
                },
            },
            Rule {
                name: "secant",
                what: "Broyden updates of the kept matrix",
                off: |p| IntegrationParameters {
                    secant_updates: false,
                    ..p
                },
            },
            Rule {
                name: "two-guesses",
                what: "the predictor picks the better of two guesses",
                off: |p| IntegrationParameters {
                    two_guess_predictor: false,
                    ..p
                },
            },
            Rule {
                name: "skip-loser",
                what: "the predictor skips a guess that keeps losing",
                off: |p| IntegrationParameters {
                    skip_loser_after: u32::MAX,
                    ..p
                },
            },
        ]
    }

    /// Newton stops when every scaled correction is below this: a fraction
    /// of the error `tolerance` and of the sheet's `thickness_ratio` (h /
    /// L), whichever is smaller, at least the floor.
    pub fn newton_tolerance(&self, tolerance: f64, thickness_ratio: f64) -> f64 {
        (self.newton_tolerance_ratio * tolerance)
            .min(self.newton_thickness_ratio * thickness_ratio)
            .max(self.newton_tolerance_floor)
    }
}
