//! Why an assembler could not be built, a configuration not evaluated, or
//! a force term's saved memory not taken back.

use crate::element::ElementError;
use crate::ids::{EdgeId, FacetId};
use std::fmt;

/// Why [`super::Assembler::new`] refused a mesh or a force term.
#[derive(Clone, Debug, PartialEq)]
pub enum BuildError {
    /// A facet's shell element could not be built (degenerate facet).
    Element {
        /// The facet.
        face: FacetId,
        /// Why.
        source: ElementError,
    },
    /// A force term declared a slot pair outside the layout.
    Pattern {
        /// The term's name.
        term: String,
        /// The pair.
        pair: (usize, usize),
        /// How many slots there are.
        slots: usize,
    },
}

impl fmt::Display for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BuildError::Element { face, source } => write!(f, "face {face}: {source}"),
            BuildError::Pattern {
                term,
                pair: (a, b),
                slots,
            } => write!(
                f,
                "force term {term}: slot pair ({a}, {b}) outside the {slots} slots"
            ),
        }
    }
}

impl std::error::Error for BuildError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            BuildError::Element { source, .. } => Some(source),
            BuildError::Pattern { .. } => None,
        }
    }
}

/// Why forces could not be evaluated at a configuration.
#[derive(Clone, Debug, PartialEq)]
pub enum EvalError {
    /// A crease's fold angle is undefined there (a facet gradient along
    /// the crease, or no tangent).
    UndefinedAngle {
        /// The crease's edge.
        edge: EdgeId,
    },
    /// Two surfaces are closer than the contact thickness.
    Penetration {
        /// The facets of the pair's first contact vertex.
        facets_a: Vec<usize>,
        /// The facets of the pair's last contact vertex.
        facets_b: Vec<usize>,
        /// The thickness kept (m).
        thickness: f64,
        /// The gap found (m, not positive).
        gap: f64,
    },
    /// A crease is folded past flat through its layers (contact's stops).
    PastFlat {
        /// The crease's edge.
        edge: EdgeId,
    },
    /// A force or an energy is not finite.
    NotFinite {
        /// The first term whose own forces or energy are not, if one is.
        term: Option<String>,
    },
    /// A term refused the configuration for a reason of its own.
    Term {
        /// The term's name.
        term: String,
        /// Why.
        reason: String,
    },
}

impl fmt::Display for EvalError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EvalError::UndefinedAngle { edge } => {
                write!(f, "crease on edge {edge} has an undefined fold angle")
            }
            EvalError::Penetration {
                facets_a,
                facets_b,
                thickness,
                gap,
            } => write!(
                f,
                "contact: surfaces at facets {facets_a:?} and {facets_b:?} are closer than the \
                 contact thickness {thickness} m (gap {gap:.3e} m)"
            ),
            EvalError::PastFlat { edge } => {
                write!(f, "contact: the crease on edge {edge} is folded past flat")
            }
            EvalError::NotFinite { term: Some(name) } => {
                write!(f, "internal forces are not finite (those of the {name})")
            }
            EvalError::NotFinite { term: None } => write!(f, "internal forces are not finite"),
            EvalError::Term { term, reason } => write!(f, "{term}: {reason}"),
        }
    }
}

impl std::error::Error for EvalError {}

/// Why a force term's memory (untrusted: a restored state's) was refused.
#[derive(Clone, Debug, PartialEq)]
pub enum MemoryError {
    /// Values given to a term that carries nothing from step to step.
    CarriesNothing {
        /// How many.
        values: usize,
    },
    /// Not one list per force term.
    Count {
        /// Lists given.
        lists: usize,
        /// Force terms.
        terms: usize,
    },
    /// One term's list refused.
    Term {
        /// The term's place in evaluation order.
        index: usize,
        /// The term's name.
        name: String,
        /// Why.
        reason: Box<MemoryError>,
    },
    /// A list of pairs whose length is not a multiple of a pair's values.
    PairLength {
        /// Values given.
        values: usize,
    },
    /// A pair's kind is neither point-triangle (0) nor edge-edge (1).
    PairKind {
        /// The pair's place in the list.
        pair: usize,
        /// The value given.
        kind: f64,
    },
    /// A pair names a vertex the surface does not have.
    PairVertex {
        /// The pair's place in the list.
        pair: usize,
        /// The value given.
        vertex: f64,
        /// How many contact vertices there are.
        vertices: usize,
    },
    /// An obstacle memory shorter than the moving obstacles' motions, or
    /// whose pair list after them is not a multiple of three (obstacle,
    /// sample, stiffness).
    ObstaclePairLength {
        /// Values given.
        values: usize,
        /// Values the moving obstacles' motions take first.
        motions: usize,
    },
    /// A moving obstacle's motion value that is not finite or too large.
    ObstacleMotion {
        /// Its place in the list.
        index: usize,
        /// The value given.
        value: f64,
        /// The largest magnitude taken.
        max: f64,
    },
    /// An obstacle pair names an obstacle or a contact sample there is not.
    ObstaclePairIndex {
        /// The pair's place in the list.
        pair: usize,
        /// What the index is of ("obstacle", "contact sample").
        what: &'static str,
        /// The value given.
        value: f64,
        /// How many there are.
        count: usize,
    },
    /// A crease stop entry (kind 2) that is not a stop point's index
    /// followed by three zeros.
    StopEntry {
        /// The entry's place in the list.
        pair: usize,
        /// The four values after its kind.
        values: [f64; 4],
        /// How many crease stop points there are.
        points: usize,
    },
    /// The candidate cache's origin entries (kind 3, at the list's end)
    /// are not the slot vector's values in order.
    OriginEntry {
        /// The entry's place in the list.
        entry: usize,
        /// What is wrong.
        reason: String,
    },
    /// A pair's stiffness is not a positive number up to `max`.
    PairStiffness {
        /// The pair's place in the list.
        pair: usize,
        /// The value given.
        stiffness: f64,
        /// The largest accepted.
        max: f64,
    },
}

impl fmt::Display for MemoryError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MemoryError::CarriesNothing { values } => write!(
                f,
                "{values} values for a term that carries nothing from step to step"
            ),
            MemoryError::Count { lists, terms } => {
                write!(f, "{lists} force terms' memory for {terms} terms")
            }
            MemoryError::Term {
                index,
                name,
                reason,
            } => write!(f, "term {index} ({name}): {reason}"),
            MemoryError::PairLength { values } => write!(
                f,
                "{values} values; the pair stiffnesses come in sixes (kind, four vertices, \
                 stiffness)"
            ),
            MemoryError::ObstaclePairLength { values, motions } => write!(
                f,
                "{values} values; the moving obstacles' motions take the first {motions}, then \
                 the obstacle pairs' stiffnesses come in threes (obstacle, sample, stiffness)"
            ),
            MemoryError::ObstacleMotion { index, value, max } => write!(
                f,
                "moving obstacle value {index}: {value} is not a finite number up to {max:e} in \
                 magnitude"
            ),
            MemoryError::ObstaclePairIndex {
                pair,
                what,
                value,
                count,
            } => write!(f, "pair {pair}: {value} is not a {what} (0..{count})"),
            MemoryError::PairKind { pair, kind } => write!(
                f,
                "pair {pair}: kind {kind} is not 0 (point-triangle), 1 (edge-edge) or 2 \
                 (crease stop point)"
            ),
            MemoryError::StopEntry {
                pair,
                values,
                points,
            } => write!(
                f,
                "pair {pair}: a crease stop entry is (2, a point in 0..{points}, 0, 0, 0, \
                 stiffness), not (2, {}, {}, {}, {}, ...)",
                values[0], values[1], values[2], values[3]
            ),
            MemoryError::PairVertex {
                pair,
                vertex,
                vertices,
            } => write!(
                f,
                "pair {pair}: {vertex} is not a contact vertex (0..{vertices})"
            ),
            MemoryError::OriginEntry { entry, reason } => {
                write!(f, "entry {entry} (the candidate cache's origin): {reason}")
            }
            MemoryError::PairStiffness {
                pair,
                stiffness,
                max,
            } => write!(
                f,
                "pair {pair}: stiffness {stiffness} is not a positive number up to {max:e}"
            ),
        }
    }
}

impl std::error::Error for MemoryError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            MemoryError::Term { reason, .. } => Some(reason.as_ref()),
            _ => None,
        }
    }
}
