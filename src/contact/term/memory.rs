//! Self-contact's memory in a saved state: the pair stiffnesses, listed by key and read back.

use super::ContactTerm;
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

impl ContactTerm {
    /// The pairs' and crease stops' barrier stiffnesses as a saved state
    /// lists them (the term's memory): six numbers an entry, the pairs'
    /// (edge-edge or not, its four contact vertices, the stiffness) in key
    /// order, then the stop points' with a positive stiffness (2, the point's
    /// index, three zeros, the stiffness) in point order.
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
        out
    }

    /// The stiffnesses of a list as [`ContactTerm::memory_list`] writes it
    /// (untrusted: a restored state's): sixes of kind (0 point-triangle, 1
    /// edge-edge, 2 crease stop point), four contact-vertex ids (a stop
    /// point's index and three zeros) and a positive stiffness up to
    /// MAX_MAGNITUDE. Returns the pairs' by key and the stop points'
    /// ([`super::stops::UNSET`] where none is listed).
    pub(super) fn parse_memory(
        &self,
        memory: &[f64],
    ) -> Result<(HashMap<PairKey, f64>, Vec<f64>), MemoryError> {
        if !memory.len().is_multiple_of(6) {
            return Err(MemoryError::PairLength {
                values: memory.len(),
            });
        }
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
        Ok((pairs, stops))
    }
}
