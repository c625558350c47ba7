//! The iteration matrix's contact part: matrices over a few contact points
//! mapped to the slots through the points' weights, summed per set of slots
//! and added to the sparse matrix at block positions kept while the
//! pattern is the same.

use crate::assembly::{Assembler, BlockPosition};
use std::collections::HashMap;

/// Slots of a pair's four points kept on the stack (each point maps to
/// its facet's 12 slots or fewer).
const MAX_PAIR_SLOTS: usize = 48;

/// Pair matrices summed per set of slots before they reach the sparse
/// matrix: the many pairs between two facets (stacked layers) share their
/// slots, so each slot block is looked up in the pattern once per facet
/// pair instead of once per pair.
/// Groups are written in the order they were met (the pairs' canonical
/// order), so the sums do not depend on hashing.
#[derive(Default)]
pub(super) struct MatrixBatch {
    /// Sorted slots -> index in `groups`.
    index: HashMap<Vec<usize>, usize>,
    /// Sorted slots and the dense column-major matrix over their coordinates.
    groups: Vec<(Vec<usize>, Vec<f64>)>,
    /// The group used last (pairs in canonical order often share it).
    last: Option<usize>,
}

impl MatrixBatch {
    /// The (zeroed when new) dense matrix of the group of `slots`.
    fn group(&mut self, slots: &[usize]) -> &mut [f64] {
        let k = match self.last.filter(|&k| self.groups[k].0 == slots) {
            Some(k) => k,
            None => match self.index.get(slots) {
                Some(&k) => k,
                None => {
                    let n3 = 3 * slots.len();
                    self.index.insert(slots.to_vec(), self.groups.len());
                    self.groups.push((slots.to_vec(), vec![0.0; n3 * n3]));
                    self.groups.len() - 1
                }
            },
        };
        self.last = Some(k);
        &mut self.groups[k].1
    }

    /// Add `W^T h W`: `h` (column-major) over the coordinates of the `N`
    /// points `maps`, `W` their weights on the slots.
    pub(super) fn add_mapped<const N: usize>(
        &mut self,
        maps: &[&crate::contact::surface::VertexMap; N],
        h: &[f64],
    ) {
        let nh = 3 * N;
        assert_eq!(h.len(), nh * nh, "a matrix over the points' coordinates");
        // The points' slots (sorted, once each) and each point's weight on
        // them, on the stack unless they are many.
        let total: usize = maps.iter().map(|m| m.len()).sum();
        let (mut slot_stack, mut w_stack) = ([0usize; MAX_PAIR_SLOTS], [[0.0; N]; MAX_PAIR_SLOTS]);
        let (mut slot_heap, mut w_heap) = (Vec::new(), Vec::new());
        let (slots, w): (&mut [usize], &mut [[f64; N]]) = if total <= MAX_PAIR_SLOTS {
            (&mut slot_stack[..total], &mut w_stack[..total])
        } else {
            slot_heap.resize(total, 0);
            w_heap.resize(total, [0.0; N]);
            (&mut slot_heap, &mut w_heap)
        };
        let ns = crate::contact::surface::slot_union(maps, slots);
        let slots = &slots[..ns];
        let w = &mut w[..ns];
        for (k, m) in maps.iter().enumerate() {
            for &(s, c) in m.iter() {
                let a = slots.binary_search(&s).expect("slot listed");
                w[a][k] += c;
            }
        }
        let dense = self.group(slots);
        let n3 = 3 * ns;
        // Column (b, y) in two stages: the points' column
        // `t = sum_l w[b][l] h[.., (l, y)]`, then `sum_k w[a][k] t[k]` into
        // each slot a.
        for (b, wb) in w.iter().enumerate() {
            for y in 0..3 {
                let mut t = [[0.0; 3]; N];
                for (l, &c) in wb.iter().enumerate() {
                    if c != 0.0 {
                        let hc = &h[(3 * l + y) * nh..][..nh];
                        for (tk, hk) in t.iter_mut().zip(hc.chunks_exact(3)) {
                            for x in 0..3 {
                                tk[x] += c * hk[x];
                            }
                        }
                    }
                }
                let col = &mut dense[(3 * b + y) * n3..][..n3];
                for (ca, wa) in col.chunks_exact_mut(3).zip(w.iter()) {
                    for (&c, tk) in wa.iter().zip(&t) {
                        if c != 0.0 {
                            for x in 0..3 {
                                ca[x] += c * tk[x];
                            }
                        }
                    }
                }
            }
        }
    }

    /// Add every group to the matrix values `vals` (blocks the pattern
    /// lacks are left out: the pattern holds every facet pair in reach),
    /// at the blocks' positions kept in `known` (found where new).
    pub(super) fn flush(self, asm: &Assembler, vals: &mut [f64], known: &mut BlockPositions) {
        if known.pattern != asm.pattern_id() || known.count > MAX_KEPT_POSITIONS {
            *known = BlockPositions {
                pattern: asm.pattern_id(),
                ..Default::default()
            };
        }
        for (slots, dense) in self.groups {
            let ns = slots.len();
            let n3 = 3 * ns;
            let at = match known.groups.get(&slots) {
                Some(at) => at,
                None => {
                    let at: Vec<BlockPosition> = (0..ns * ns)
                        .map(|k| asm.block_position(slots[k % ns], slots[k / ns]))
                        .collect();
                    known.count += at.len();
                    known.groups.entry(slots).or_insert(at)
                }
            };
            for b in 0..ns {
                for a in 0..ns {
                    let col = |y: usize| 3 * b + y;
                    asm.add_block_at(at[b * ns + a], |x, y| dense[col(y) * n3 + 3 * a + x], vals);
                }
            }
        }
    }
}

/// The matrix positions of slot groups' blocks (column-major over each
/// group's slots), kept across evaluations while the pattern is the same:
/// a stack's pairs meet the same groups at every evaluation.
#[derive(Debug, Default)]
pub(super) struct BlockPositions {
    /// The pattern they were found in ([`Assembler::pattern_id`]).
    pattern: u64,
    groups: HashMap<Vec<usize>, Vec<BlockPosition>>,
    /// Positions kept in all.
    count: usize,
}

/// Block positions kept at most (then found anew): 24 bytes each, so
/// about 25 MB (the flat 4x4 Miura keeps about 0.4 M).
const MAX_KEPT_POSITIONS: usize = 1 << 20;

#[cfg(test)]
mod tests {
    use super::*;

    /// The cap's memory note holds.
    #[test]
    fn a_kept_position_is_24_bytes() {
        assert_eq!(std::mem::size_of::<BlockPosition>(), 24);
    }
}
