//! Self-contact's memory in a saved state: the pair stiffnesses, listed by key and read back.

use super::ContactTerm;
use super::pairs::{PairKey, key};
use crate::assembly::MemoryError;
use crate::contact::memory::{list_index, list_pairs, parse_pairs};
use std::collections::HashMap;

impl ContactTerm {
    /// The pairs' barrier stiffnesses as a saved state lists them (the
    /// term's memory): six numbers a pair (edge-edge or not, its four
    /// contact vertices, the stiffness), in key order.
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
        parse_pairs(memory, 6, |pair, m| {
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
            Ok((m[0] == 1.0, [id(m[1])?, id(m[2])?, id(m[3])?, id(m[4])?]))
        })
    }
}
