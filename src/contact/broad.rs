//! Broad phase: axis-aligned boxes on a uniform hash grid. Every box goes
//! into the cells it overlaps; two boxes are a candidate pair when they
//! share a cell and overlap. With cells about the size of the largest box
//! each box meets a bounded number of others, so the cost grows linearly
//! with the number of primitives.

use nalgebra::Vector3;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A multiply-rotate hasher for cell keys (the standard SipHash is made
/// for untrusted keys and was a fifth of the search's time).
#[derive(Default)]
struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_i64(&mut self, x: i64) {
        self.write_u64(x as u64);
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub lo: Vector3<f64>,
    /// Upper corner.
    pub hi: Vector3<f64>,
}

impl Aabb {
    /// The box around `points`, grown by `pad` on every side.
    pub fn around(points: &[Vector3<f64>], pad: f64) -> Aabb {
        let mut lo = points[0];
        let mut hi = points[0];
        for p in &points[1..] {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        let d = Vector3::repeat(pad);
        Aabb {
            lo: lo - d,
            hi: hi + d,
        }
    }

    /// The smallest box holding every box of `boxes` (at least one): the
    /// same box as [`Aabb::around`] of all their points with the same pad.
    pub fn around_boxes<'a>(mut boxes: impl Iterator<Item = &'a Aabb>) -> Aabb {
        let first = *boxes.next().expect("at least one box");
        boxes.fold(first, |a, b| Aabb {
            lo: a.lo.inf(&b.lo),
            hi: a.hi.sup(&b.hi),
        })
    }

    /// Whether two boxes overlap.
    pub fn overlaps(&self, o: &Aabb) -> bool {
        (0..3).all(|c| self.lo[c] <= o.hi[c] && o.lo[c] <= self.hi[c])
    }
}

/// Pairs `(i, j)` with box `a[i]` overlapping box `b[j]`, sorted and
/// without repeats. With `same` (the two lists are one), only `i < j`.
pub fn overlapping(a: &[Aabb], b: &[Aabb], same: bool) -> Vec<(usize, usize)> {
    if a.is_empty() || b.is_empty() {
        return Vec::new();
    }
    let mut size: f64 = 0.0;
    for bx in a.iter().chain(b) {
        size = size.max((bx.hi - bx.lo).max());
    }
    let cell = if size > 0.0 && size.is_finite() {
        size
    } else {
        1.0
    };
    let key = |x: f64| (x / cell).floor() as i64;
    let mut grid: HashMap<(i64, i64, i64), Vec<usize>, BuildHasherDefault<CellHasher>> =
        HashMap::default();
    for (j, bx) in b.iter().enumerate() {
        for x in key(bx.lo.x)..=key(bx.hi.x) {
            for y in key(bx.lo.y)..=key(bx.hi.y) {
                for z in key(bx.lo.z)..=key(bx.hi.z) {
                    grid.entry((x, y, z)).or_default().push(j);
                }
            }
        }
    }
    // Each overlapping pair is taken in one cell only: the one holding the
    // lower corner of the two boxes' intersection (both boxes cover it), so
    // there are no repeats to sort out; each box's partners are sorted.
    let mut out = Vec::new();
    for (i, bx) in a.iter().enumerate() {
        let first = out.len();
        for x in key(bx.lo.x)..=key(bx.hi.x) {
            for y in key(bx.lo.y)..=key(bx.hi.y) {
                for z in key(bx.lo.z)..=key(bx.hi.z) {
                    if let Some(js) = grid.get(&(x, y, z)) {
                        for &j in js {
                            let o = &b[j];
                            if (!same || i < j)
                                && bx.overlaps(o)
                                && key(bx.lo.x.max(o.lo.x)) == x
                                && key(bx.lo.y.max(o.lo.y)) == y
                                && key(bx.lo.z.max(o.lo.z)) == z
                            {
                                out.push((i, j));
                            }
                        }
                    }
                }
            }
        }
        out[first..].sort_unstable();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::XorShift;

    #[test]
    fn grid_finds_exactly_the_overlapping_pairs() {
        let mut rng = XorShift(7);
        let boxes: Vec<Aabb> = (0..300)
            .map(|_| {
                let c = Vector3::new(rng.uniform(), rng.uniform(), 0.1 * rng.uniform());
                let r = 0.02 + 0.03 * rng.uniform();
                Aabb::around(&[c], r)
            })
            .collect();
        let got = overlapping(&boxes, &boxes, true);
        let mut want = Vec::new();
        for i in 0..boxes.len() {
            for j in i + 1..boxes.len() {
                if boxes[i].overlaps(&boxes[j]) {
                    want.push((i, j));
                }
            }
        }
        assert_eq!(got, want);
        assert!(!want.is_empty());
    }
}
