//! Self-contact's memory in a saved state: the pair stiffnesses, listed by key and read back.

use super::ContactTerm;
use super::pairs::{PairKey, key};
use crate::assembly::MemoryError;
use std::collections::HashMap;

impl ContactTerm {
    /// The pairs' barrier stiffnesses as a saved state lists them (the
    /// term's memory): six numbers a pair (edge-edge or not, its four
    /// contact vertices, the stiffness), in key order.
    pub(super) fn memory_list(&self) -> Vec<f64> {
        let mut pairs: Vec<(PairKey, f64)> = match &self.restored {
            Some(map) => map.iter().map(|(k, &v)| (*k, v)).collect(),
            None => self
                .cache
                .pairs
                .iter()
                .map(key)
                .zip(self.kappas.iter().copied())
                .collect(),
        };
        pairs.sort_unstable_by_key(|a| a.0);
        pairs.dedup_by(|a, b| a.0 == b.0);
        let mut out = Vec::with_capacity(6 * pairs.len());
        for ((edge, ids), k) in pairs {
            out.push(if edge { 1.0 } else { 0.0 });
            out.extend(ids.iter().map(|&i| i as f64));
            out.push(k);
        }
        out
    }

    /// The pair stiffnesses of a list as [`ContactTerm::memory_list`]
    /// writes it (untrusted: a restored state's): sixes of edge flag (0 or
    /// 1), four contact-vertex ids and a positive stiffness up to
    /// MAX_MAGNITUDE.
    pub(super) fn parse_memory(
        &self,
        memory: &[f64],
    ) -> Result<HashMap<PairKey, f64>, MemoryError> {
        if !memory.len().is_multiple_of(6) {
            return Err(MemoryError::PairLength {
                values: memory.len(),
            });
        }
        let n = self.surf.n_vertices();
        let max = crate::scene::limits::MAX_MAGNITUDE;
        let mut map = HashMap::with_capacity(memory.len() / 6);
        for (k, m) in memory.chunks_exact(6).enumerate() {
            let id = |x: f64| {
                (x >= 0.0 && x < n as f64 && x.fract() == 0.0)
                    .then_some(x as usize)
                    .ok_or(MemoryError::PairVertex {
                        pair: k,
                        vertex: x,
                        vertices: n,
                    })
            };
            if m[0] != 0.0 && m[0] != 1.0 {
                return Err(MemoryError::PairKind {
                    pair: k,
                    kind: m[0],
                });
            }
            let ids = [id(m[1])?, id(m[2])?, id(m[3])?, id(m[4])?];
            if !(m[5] > 0.0 && m[5] <= max) {
                return Err(MemoryError::PairStiffness {
                    pair: k,
                    stiffness: m[5],
                    max,
                });
            }
            map.insert((m[0] == 1.0, ids), m[5]);
        }
        Ok(map)
    }
}
