//! The one set of rules for every physical value of a scene and every FMU
//! parameter: the scene reader, the FMU's scene check and
//! [`crate::model::Model::set_parameter`] all ask [`check`], so a value is
//! accepted or refused with the same words wherever it comes from.
//!
//! Names are the FMU parameter names (`material.thickness`,
//! `solver.max_step`, ...); the scene keys map onto them one to one.
//! [`LIMITS`] is the one table of them: name, range, unit, description,
//! whether the model chooses it automatically, and where a scene holds it.
//! The FMU's parameters take their unit and description from it.

use super::{CreaseStiffness, InputTiming, RampShape, Scene, SolverSettings};
use crate::text::num;

/// Largest magnitude of a physical number: beyond it, products of a few
/// parameters would overflow.
pub const MAX_MAGNITUDE: f64 = 1e30;

/// Smallest value of a quantity that must be positive (a density, a
/// thickness, a length scale): below it, products of a few parameters
/// underflow (a mass of 0, a crease stiffness of infinity).
pub const MIN_POSITIVE: f64 = 1e-30;

/// The admissible set of one value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Range {
    /// Any finite number.
    Any,
    /// x >= [`MIN_POSITIVE`] (positive, and not vanishingly small).
    Positive,
    /// x >= 0.
    NonNegative,
    /// lo < x < hi.
    Open(f64, f64),
    /// lo <= x <= hi.
    Closed(f64, f64),
    /// lo < x <= hi.
    OpenClosed(f64, f64),
    /// A whole number in lo..=hi.
    Whole(u64, u64),
}

impl Range {
    fn contains(self, x: f64) -> bool {
        match self {
            Range::Any => true,
            Range::Positive => x >= MIN_POSITIVE,
            Range::NonNegative => x >= 0.0,
            Range::Open(lo, hi) => x > lo && x < hi,
            Range::Closed(lo, hi) => (lo..=hi).contains(&x),
            Range::OpenClosed(lo, hi) => x > lo && x <= hi,
            Range::Whole(lo, hi) => x.fract() == 0.0 && x >= lo as f64 && x <= hi as f64,
        }
    }

    fn describe(self) -> String {
        match self {
            Range::Any => "a finite number".into(),
            Range::Positive => format!("positive (at least {MIN_POSITIVE:e})"),
            Range::NonNegative => "zero or positive".into(),
            Range::Open(lo, hi) => format!("in the open interval ({}, {})", num(lo), num(hi)),
            Range::Closed(lo, hi) => format!("in [{}, {}]", num(lo), num(hi)),
            Range::OpenClosed(lo, hi) => format!("in ({}, {}]", num(lo), num(hi)),
            Range::Whole(lo, hi) => format!("a whole number in {lo}..={hi}"),
        }
    }
}

/// A named value: its range, unit and description, whether the model
/// chooses it automatically, and where a scene holds it. The one table of
/// these ([`LIMITS`]) serves the scene reader, the scene check, the FMU
/// parameters (`crate::model`, which reads name, unit, description and the
/// automatic flag from it) and the model description.
#[derive(Clone, Copy, Debug)]
pub struct Limit {
    /// FMU parameter name (the scene keys map onto it one to one).
    pub name: &'static str,
    /// Admissible values.
    pub range: Range,
    /// Unit, as the model description names it ("" when dimensionless).
    pub unit: &'static str,
    /// What it is, in a line.
    pub description: &'static str,
    /// Chosen by the model from the scene until it is set (the damping).
    pub automatic: bool,
    /// Its value in a scene, where the scene has one.
    pub value: fn(&Scene) -> Option<f64>,
}

const fn lim(
    name: &'static str,
    range: Range,
    unit: &'static str,
    description: &'static str,
    value: fn(&Scene) -> Option<f64>,
) -> Limit {
    Limit {
        name,
        range,
        unit,
        description,
        automatic: false,
        value,
    }
}

/// A [`lim`] the model chooses until it is set.
const fn automatic(
    name: &'static str,
    range: Range,
    unit: &'static str,
    description: &'static str,
    value: fn(&Scene) -> Option<f64>,
) -> Limit {
    Limit {
        automatic: true,
        ..lim(name, range, unit, description, value)
    }
}

/// Largest `solver.max_internal_steps`: with at most [`MAX_NEWTON`] Newton
/// iterations per internal step it bounds the work of one communication
/// step (an `fmi2DoStep`). A small scene takes about 80 us per internal
/// step, so a call that hits the limit returns within minutes, not hours.
pub const MAX_INTERNAL_STEPS: u64 = 1_000_000;

/// Largest `solver.max_newton`.
pub const MAX_NEWTON: u64 = 100;

/// Smallest `solver.tolerance`: below it the local error estimate is
/// round-off (Newton's tolerance floors at 1e-13) and every step falls to
/// `solver.min_step`.
pub const MIN_TOLERANCE: f64 = 1e-12;

/// Largest `solver.tolerance`: an error control that accepts more is none.
pub const MAX_TOLERANCE: f64 = 0.5;

/// Smallest `solver.min_step` and `solver.max_step` (s).
pub const MIN_STEP: f64 = 1e-15;

/// Every named value of a scene, in the FMU's parameter order.
pub const LIMITS: &[Limit] = &[
    lim(
        "material.youngs_modulus",
        Range::Positive,
        "Pa",
        "Young's modulus",
        |s| Some(s.material.youngs_modulus),
    ),
    lim(
        "material.poisson_ratio",
        Range::Open(-1.0, 0.5),
        "",
        "Poisson's ratio",
        |s| Some(s.material.poisson_ratio),
    ),
    lim(
        "material.thickness",
        Range::Positive,
        "m",
        "sheet thickness",
        |s| Some(s.material.thickness),
    ),
    lim(
        "material.density",
        Range::Positive,
        "kg/m3",
        "mass density",
        |s| Some(s.material.density),
    ),
    lim(
        "crease.length_scale",
        Range::Positive,
        "m",
        "crease stiffness = (crease length / length_scale) * bending stiffness",
        |s| match s.crease {
            CreaseStiffness::LengthScale(l) => Some(l),
            CreaseStiffness::PerLength(_) => None,
        },
    ),
    lim(
        "crease.stiffness_per_length",
        Range::NonNegative,
        "N/rad",
        "rotational crease stiffness per unit crease length",
        |s| match s.crease {
            CreaseStiffness::PerLength(k) => Some(k),
            CreaseStiffness::LengthScale(_) => None,
        },
    ),
    automatic(
        "damping.alpha",
        Range::NonNegative,
        "1/s",
        "Rayleigh mass-proportional damping",
        |s| Some(s.damping.alpha),
    ),
    automatic(
        "damping.beta",
        Range::NonNegative,
        "s",
        "Rayleigh stiffness-proportional damping",
        |s| Some(s.damping.beta),
    ),
    automatic(
        "damping.crease",
        Range::NonNegative,
        "N.s/rad",
        "crease damping per unit length",
        |s| Some(s.damping.crease),
    ),
    lim(
        "gravity.x",
        Range::Any,
        "m/s2",
        "gravity, x component",
        |s| s.gravity.map(|g| g[0]),
    ),
    lim(
        "gravity.y",
        Range::Any,
        "m/s2",
        "gravity, y component",
        |s| s.gravity.map(|g| g[1]),
    ),
    lim(
        "gravity.z",
        Range::Any,
        "m/s2",
        "gravity, z component",
        |s| s.gravity.map(|g| g[2]),
    ),
    lim(
        "solver.rho_inf",
        Range::Closed(0.0, 1.0),
        "",
        "generalized-alpha spectral radius",
        |s| Some(s.solver.rho_inf),
    ),
    lim(
        "solver.max_step",
        Range::Closed(MIN_STEP, MAX_MAGNITUDE),
        "s",
        "largest internal step",
        |s| Some(s.solver.max_step),
    ),
    lim(
        "solver.min_step",
        Range::Closed(MIN_STEP, MAX_MAGNITUDE),
        "s",
        "smallest internal step before an advance fails",
        |s| Some(s.solver.min_step),
    ),
    lim(
        "solver.tolerance",
        Range::Closed(MIN_TOLERANCE, MAX_TOLERANCE),
        "",
        "relative solver tolerance",
        |s| Some(s.solver.tolerance),
    ),
    lim(
        "solver.max_newton",
        Range::Whole(1, MAX_NEWTON),
        "",
        "most Newton iterations of one internal step",
        |s| Some(s.solver.max_newton as f64),
    ),
    lim(
        "solver.max_internal_steps",
        Range::Whole(1, MAX_INTERNAL_STEPS),
        "",
        "most internal steps one communication step may take before it fails",
        |s| Some(s.solver.max_internal_steps as f64),
    ),
    lim(
        "solver.max_step_cpu",
        Range::Positive,
        "s",
        "most CPU time one communication step may take before it is discarded with the state from before it",
        |s| Some(s.solver.max_step_cpu),
    ),
    lim(
        "solver.stop_time",
        Range::Positive,
        "s",
        "default experiment stop time",
        |s| Some(s.solver.stop_time),
    ),
    lim(
        "solver.error_filter",
        Range::Whole(0, 1),
        "",
        "1: the local error estimate filtered through the iteration matrix (ringing far above the step's frequency counts by its displacement and is damped by the scheme: cheaper under held inputs, loses that ringing's energy); 0 (default): the plain estimate",
        |s| Some(if s.solver.error_filter { 1.0 } else { 0.0 }),
    ),
    lim(
        "input.first_order_hold",
        Range::Whole(0, 1),
        "",
        "0 (default): an input set before a step is held over it (FMI 2.0); 1: first-order hold, each step ramps from the previous value to the one set, so a sample acts one step late (no input derivatives then)",
        |s| {
            Some(match s.solver.input_timing {
                InputTiming::Hold => 0.0,
                InputTiming::FirstOrderHold => 1.0,
            })
        },
    ),
    lim(
        "contact.friction",
        Range::NonNegative,
        "",
        "Coulomb friction coefficient of self-contact",
        |s| s.contact.map(|c| c.friction),
    ),
    lim(
        "actuator.time_constant",
        Range::NonNegative,
        "s",
        "time constant of the actuators' servo, a critically damped response to their inputs; 0 (the default): ideal, the input acts at once",
        |s| s.actuator_time_constant,
    ),
    lim(
        "ramp.time",
        Range::Closed(0.0, 1e9),
        "s",
        "built-in signal: when > 0, every rest-angle actuator (fold) goes from 0 to 1 over this time and holds 1, and values set on those inputs are not used; 0 = off, the master drives them",
        |s| Some(s.ramp.time),
    ),
    lim(
        "ramp.shape",
        Range::Whole(0, 1),
        "",
        "shape of the built-in signal: 0 linear, 1 smooth (zero slope at both ends)",
        |s| {
            Some(match s.ramp.shape {
                RampShape::Linear => 0.0,
                RampShape::Smooth => 1.0,
            })
        },
    ),
    lim(
        "contact.stiffness",
        Range::Positive,
        "N/m",
        "barrier stiffness (automatic when absent)",
        |s| s.contact.and_then(|c| c.stiffness),
    ),
    lim(
        "contact.thickness",
        Range::Positive,
        "m",
        "distance contact keeps between the mid-surfaces",
        |s| s.contact.map(|c| c.thickness),
    ),
    lim(
        "contact.barrier_width",
        Range::OpenClosed(0.0, 1.0),
        "",
        "width of the barrier, a fraction of the thickness",
        |s| s.contact.map(|c| c.width),
    ),
    lim(
        "contact.stick_velocity",
        Range::Positive,
        "m/s",
        "slip velocity below which friction sticks",
        |s| s.contact.map(|c| c.stick_velocity),
    ),
    lim(
        "contact.damping_ratio",
        Range::NonNegative,
        "",
        "damping ratio of the barrier's dashpots",
        |s| s.contact.map(|c| c.damping_ratio),
    ),
    lim(
        "contact.subdivisions",
        Range::Whole(1, 8),
        "",
        "contact samples per facet side",
        |s| s.contact.map(|c| c.subdivisions as f64),
    ),
];

/// The limit of `name`, if it has one.
pub fn limit(name: &str) -> Option<&'static Limit> {
    LIMITS.iter().find(|l| l.name == name)
}

/// Why a value was refused.
#[derive(Clone, Debug, PartialEq)]
pub enum LimitError {
    /// NaN or infinite.
    NotFinite(f64),
    /// Larger than [`MAX_MAGNITUDE`] in magnitude.
    TooLarge(f64),
    /// Outside the range of its [`Limit`].
    OutOfRange {
        /// The value.
        value: f64,
        /// What the value must be.
        range: Range,
        /// Its unit ("" when dimensionless).
        unit: &'static str,
    },
    /// `solver.min_step` above `solver.max_step`.
    MinStepAboveMaxStep {
        /// `solver.min_step`.
        min_step: f64,
        /// `solver.max_step`.
        max_step: f64,
    },
    /// A value of a scene, by its parameter name.
    Named {
        /// The parameter name (`material.thickness`, ...).
        name: &'static str,
        /// Why it was refused.
        error: Box<LimitError>,
    },
}

impl LimitError {
    /// The parameter name of a [`LimitError::Named`] or of a relation
    /// between values, if the error carries one.
    pub fn name(&self) -> Option<&'static str> {
        match self {
            LimitError::Named { name, .. } => Some(name),
            LimitError::MinStepAboveMaxStep { .. } => Some("solver.min_step"),
            _ => None,
        }
    }
}

impl std::fmt::Display for LimitError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LimitError::NotFinite(x) => write!(f, "{} is not a finite number", num(*x)),
            LimitError::TooLarge(x) => write!(
                f,
                "{} is too large (at most {MAX_MAGNITUDE:e} in magnitude)",
                num(*x)
            ),
            LimitError::OutOfRange { value, range, unit } => {
                write!(
                    f,
                    "{} is out of range; it must be {}",
                    num(*value),
                    range.describe()
                )?;
                if !unit.is_empty() {
                    write!(f, " ({unit})")?;
                }
                Ok(())
            }
            LimitError::MinStepAboveMaxStep { min_step, max_step } => write!(
                f,
                "min_step {} is larger than max_step {}; an internal step must fit between them",
                num(*min_step),
                num(*max_step)
            ),
            LimitError::Named { name, error } => write!(f, "{name}: {error}"),
        }
    }
}

impl std::error::Error for LimitError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            LimitError::Named { error, .. } => Some(error.as_ref()),
            _ => None,
        }
    }
}

/// Check one value: finite, of sensible magnitude, and in the range of
/// `name` (names without a limit only need to be finite). The error says
/// what the value must be, e.g. "0 is out of range; it must be positive (at
/// least 1e-30) (m)".
pub fn check(name: &str, x: f64) -> Result<(), LimitError> {
    if !x.is_finite() {
        return Err(LimitError::NotFinite(x));
    }
    if x.abs() > MAX_MAGNITUDE {
        return Err(LimitError::TooLarge(x));
    }
    if let Some(l) = limit(name)
        && !l.range.contains(x)
    {
        return Err(LimitError::OutOfRange {
            value: x,
            range: l.range,
            unit: l.unit,
        });
    }
    Ok(())
}

/// Check a number without a limit of its own (an input, a stored value):
/// finite and at most [`MAX_MAGNITUDE`] in magnitude.
pub fn check_number(x: f64) -> Result<(), LimitError> {
    check("", x)
}

/// Rules between solver settings: `min_step <= max_step`. The error's
/// [`LimitError::name`] is the offending value.
pub fn check_solver_relations(s: &SolverSettings) -> Result<(), LimitError> {
    if s.min_step > s.max_step {
        return Err(LimitError::MinStepAboveMaxStep {
            min_step: s.min_step,
            max_step: s.max_step,
        });
    }
    Ok(())
}

/// Every value of a scene that has a limit, by name (what the FMU's scene
/// check and a parameter rebuild run).
pub fn check_scene(s: &Scene) -> Result<(), LimitError> {
    for l in LIMITS {
        if let Some(x) = (l.value)(s) {
            check(l.name, x).map_err(|e| LimitError::Named {
                name: l.name,
                error: Box::new(e),
            })?;
        }
    }
    check_solver_relations(&s.solver).map_err(|e| LimitError::Named {
        name: "solver.min_step",
        error: Box::new(e),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_and_messages() {
        assert!(check("material.thickness", 1e-4).is_ok());
        let e = check("material.thickness", 0.0).unwrap_err();
        assert_eq!(
            e.to_string(),
            "0 is out of range; it must be positive (at least 1e-30) (m)"
        );
        assert!(check("material.density", 1e-300).is_err());
        assert!(check("solver.tolerance", 50.0).is_err());
        assert!(check("solver.tolerance", 1e-6).is_ok());
        assert!(check("material.poisson_ratio", 0.5).is_err());
        assert!(check("solver.rho_inf", 1.0).is_ok());
        assert!(check("solver.max_newton", 2.5).is_err());
        assert!(check("solver.max_internal_steps", 0.0).is_err());
        assert!(check("gravity.z", -9.81).is_ok());
        assert!(
            check("gravity.z", f64::NAN)
                .unwrap_err()
                .to_string()
                .contains("finite")
        );
        assert!(
            check("anything", 1e31)
                .unwrap_err()
                .to_string()
                .contains("too large")
        );
        assert!(
            check("damping.alpha", -1.0)
                .unwrap_err()
                .to_string()
                .contains("zero or positive")
        );
    }

    #[test]
    fn min_step_above_max_step_is_refused() {
        let s = SolverSettings {
            max_step: 1e-10,
            ..SolverSettings::default()
        };
        let e = check_solver_relations(&s).unwrap_err();
        assert_eq!(e.name(), Some("solver.min_step"));
        let why = e.to_string();
        assert!(why.contains("larger than max_step"), "{why}");
    }
}
