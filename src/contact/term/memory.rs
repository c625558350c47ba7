//! Self-contact's memory in a saved state: the pair stiffnesses, listed by key, and where the
//! candidate cache was searched; listed and read back.

use super::ContactTerm;
use super::candidates::CandidateCache;
use super::pairs::{PairKey, key};
use crate::assembly::MemoryError;
use crate::contact::memory::{list_index, list_pairs, parse_pairs};
use std::collections::HashMap;

/// What one entry of the memory list is the stiffness of.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub(super) enum Entry {
    /// A pair of primitives, by key.
    Pair(PairKey),
    /// A crease stop point, by index.
    Stop(usize),
}

/// The entry kind of a crease stop point in the memory list.
const STOP_KIND: f64 = 2.0;

/// The entry kind of the candidate cache's origin in the memory list: the
/// slot vector where it was searched, four values an entry.
const ORIGIN_KIND: f64 = 3.0;

/// What a restored memory list holds: the pairs' stiffnesses by key, the
/// stop points' ([`super::stops::UNSET`] where none is listed), and the
/// slot vector the candidate cache was searched at (None: no search yet).
type Parsed = (HashMap<PairKey, f64>, Vec<f64>, Option<Vec<f64>>);

impl ContactTerm {
    /// The pairs' and crease stops' barrier stiffnesses as a saved state
    /// lists them (the term's memory): six numbers an entry, the pairs'
    /// (edge-edge or not, its four contact vertices, the stiffness) in key
    /// order, then the stop points' with a positive stiffness (2, the point's
    /// index, three zeros, the stiffness) in point order, then the slot
    /// vector the candidate cache was searched at (3, the entry's index,
    /// four of its values, the last entry padded with zeros).
    pub(super) fn memory_list(&self) -> Vec<f64> {
        let pairs: Vec<(PairKey, f64)> = match &self.restored {
            Some(map) => map.iter().map(|(k, &v)| (*k, v)).collect(),
            None => self
                .cache
                .pairs
                .iter()
                .map(key)
                .zip(self.kappas.iter().copied())
                .collect(),
        };
        let mut out = Vec::new();
        list_pairs(
            pairs,
            |&(edge, ids)| {
                let [a, b, c, d] = ids.map(|i| i as f64);
                [if edge { 1.0 } else { 0.0 }, a, b, c, d]
            },
            &mut out,
        );
        for (i, k) in self.stops.kappas().into_iter().enumerate() {
            if k > 0.0 {
                out.extend([STOP_KIND, i as f64, 0.0, 0.0, 0.0, k]);
            }
        }
        for (i, q) in self.cache.q0.chunks(4).enumerate() {
            let mut entry = [ORIGIN_KIND, i as f64, 0.0, 0.0, 0.0, 0.0];
            entry[2..2 + q.len()].copy_from_slice(q);
            out.extend(entry);
        }
        out
    }

    /// Drop the candidate cache; with `origin` (a restored state's: the
    /// slot vector where the saved cache was searched), the next step start
    /// searches it there where it covers that step start as the saved one
    /// did (so a forged origin is searched only within the cache's margin
    /// of the state's own positions), else at the step start.
    pub(super) fn restore_cache(&mut self, origin: Option<Vec<f64>>) {
        self.cache_pending = origin.is_some();
        self.cache = CandidateCache {
            q0: origin.unwrap_or_default(),
            ..Default::default()
        };
        self.forget_near();
        self.blocks.clear();
        self.kappas.clear();
        if let Ok(mut spare) = self.spare.lock() {
            *spare = None;
        }
    }

    /// The stiffnesses of a list as [`ContactTerm::memory_list`] writes it
    /// (untrusted: a restored state's): sixes of kind (0 point-triangle, 1
    /// edge-edge, 2 crease stop point), four contact-vertex ids (a stop
    /// point's index and three zeros) and a positive stiffness up to
    /// MAX_MAGNITUDE; then, where a search was made, the candidate cache's
    /// origin: sixes of kind 3, the entry's index and four values of the
    /// slot vector (the last padded with zeros), each value finite up to
    /// MAX_MAGNITUDE.
    pub(super) fn parse_memory(&self, memory: &[f64]) -> Result<Parsed, MemoryError> {
        if !memory.len().is_multiple_of(6) {
            return Err(MemoryError::PairLength {
                values: memory.len(),
            });
        }
        let first = memory
            .chunks_exact(6)
            .position(|m| m[0] == ORIGIN_KIND)
            .unwrap_or(memory.len() / 6);
        let origin = self.parse_origin(&memory[6 * first..], first)?;
        let memory = &memory[..6 * first];
        let n = self.surf.n_vertices();
        let points = self.stops.points.len();
        let entries = parse_pairs(memory, 6, |pair, m| {
            if m[0] == STOP_KIND {
                return match list_index(m[1], points) {
                    Some(i) if m[2..5].iter().all(|&x| x == 0.0) => Ok(Entry::Stop(i)),
                    _ => Err(MemoryError::StopEntry {
                        pair,
                        values: [m[1], m[2], m[3], m[4]],
                        points,
                    }),
                };
            }
            let id = |x: f64| {
                list_index(x, n).ok_or(MemoryError::PairVertex {
                    pair,
                    vertex: x,
                    vertices: n,
                })
            };
            if m[0] != 0.0 && m[0] != 1.0 {
                return Err(MemoryError::PairKind { pair, kind: m[0] });
            }
            Ok(Entry::Pair((
                m[0] == 1.0,
                [id(m[1])?, id(m[2])?, id(m[3])?, id(m[4])?],
            )))
        })?;
        let mut pairs = HashMap::new();
        let mut stops = vec![super::stops::UNSET; points];
        for (entry, k) in entries {
            match entry {
                Entry::Pair(key) => {
                    pairs.insert(key, k);
                }
                Entry::Stop(i) => stops[i] = k,
            }
        }
        Ok((pairs, stops, origin))
    }

    /// The cache's origin from the origin entries that end a memory list
    /// (`list` from entry `first` on; see [`ContactTerm::parse_memory`]).
    fn parse_origin(&self, list: &[f64], first: usize) -> Result<Option<Vec<f64>>, MemoryError> {
        if list.is_empty() {
            return Ok(None);
        }
        let n = self.n_dofs;
        let entries = n.div_ceil(4);
        let max = crate::scene::limits::MAX_MAGNITUDE;
        let bad = |entry: usize, reason: String| MemoryError::OriginEntry {
            entry: first + entry,
            reason,
        };
        if list.len() != 6 * entries {
            return Err(bad(
                0,
                format!(
                    "{} entries of kind 3; the candidate cache's origin takes {entries} (four of \
                     the {n} DOFs each), the last ones of the list",
                    list.len() / 6
                ),
            ));
        }
        let mut q = Vec::with_capacity(n);
        for (i, m) in list.chunks_exact(6).enumerate() {
            if m[0] != ORIGIN_KIND || m[1] != i as f64 {
                return Err(bad(
                    i,
                    format!("({}, {}, ...) is not (3, {i}, ...)", m[0], m[1]),
                ));
            }
            for (j, &x) in m[2..].iter().enumerate() {
                let dof = 4 * i + j;
                if dof >= n && x != 0.0 {
                    return Err(bad(i, format!("{x} past the {n} DOFs is not 0")));
                }
                if !(x.is_finite() && x.abs() <= max) {
                    return Err(bad(i, format!("{x} is not a finite number up to {max:e}")));
                }
                if dof < n {
                    q.push(x);
                }
            }
        }
        Ok(Some(q))
    }
}
