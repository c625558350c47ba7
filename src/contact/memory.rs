//! The pair stiffnesses self-contact and the obstacles carry from step to step: kept, listed, read.

use crate::assembly::MemoryError;
use std::collections::HashMap;
use std::hash::Hash;

/// A pair's barrier stiffness at a step start: `last`, the one it had,
/// while `inside` says the pair is in the barrier (its energy is not zero:
/// a new stiffness would change it); else `anew` (set while its barrier
/// energy is zero, it changes none).
pub(crate) fn kept_stiffness(
    last: Option<f64>,
    inside: impl FnOnce() -> bool,
    anew: impl FnOnce() -> f64,
) -> f64 {
    match last {
        Some(k) if inside() => k,
        _ => anew(),
    }
}

/// Append to `out` the list a saved state carries of `pairs`' stiffnesses:
/// each pair's key as `values` writes it, then its stiffness, in key
/// order, one pair a key.
pub(crate) fn list_pairs<K: Ord, const N: usize>(
    mut pairs: Vec<(K, f64)>,
    values: impl Fn(&K) -> [f64; N],
    out: &mut Vec<f64>,
) {
    pairs.sort_unstable_by(|a, b| a.0.cmp(&b.0));
    pairs.dedup_by(|a, b| a.0 == b.0);
    out.reserve((N + 1) * pairs.len());
    for (key, k) in &pairs {
        out.extend(values(key));
        out.push(*k);
    }
}

/// A value of a saved list read as an index into `n` things: a whole
/// number in `0..n`, or None.
pub(crate) fn list_index(x: f64, n: usize) -> Option<usize> {
    (x >= 0.0 && x < n as f64 && x.fract() == 0.0).then_some(x as usize)
}

/// The pair stiffnesses of a saved list (untrusted), `width` values a
/// pair: its key, which `key` reads from all its values but the last
/// (given the pair's place in the list), then its stiffness, a positive
/// number up to MAX_MAGNITUDE. The list's length is the caller's to check
/// (its error names the caller's layout).
pub(crate) fn parse_pairs<K: Eq + Hash>(
    list: &[f64],
    width: usize,
    key: impl Fn(usize, &[f64]) -> Result<K, MemoryError>,
) -> Result<HashMap<K, f64>, MemoryError> {
    let max = crate::scene::limits::MAX_MAGNITUDE;
    let mut map = HashMap::with_capacity(list.len() / width);
    for (pair, m) in list.chunks_exact(width).enumerate() {
        let (values, stiffness) = (&m[..width - 1], m[width - 1]);
        let k = key(pair, values)?;
        if !(stiffness > 0.0 && stiffness <= max) {
            return Err(MemoryError::PairStiffness {
                pair,
                stiffness,
                max,
            });
        }
        map.insert(k, stiffness);
    }
    Ok(map)
}
