//! Ear-clipping triangulation of a simple counter-clockwise polygon in the
//! reference plane. Convex and non-convex faces both work; vertices lying on
//! a straight side (180 degree corners) are kept. Weakly simple polygons
//! work too: a polygon that runs out along a crease ending inside it and
//! back (visiting the crease's vertices twice, a "slit") is triangulated
//! with the crease as a side of the triangles on both of its sides.
//!
//! Among the available ears the best-shaped one is cut first (largest
//! `4 sqrt(3) A / (a^2 + b^2 + c^2)`), which avoids the slivers of a plain fan;
//! polygons with more than [`QUALITY_LIMIT`] corners take the first ear found
//! to keep the cost quadratic. A strictly convex polygon of more corners
//! (a circle of many segments) is split in halves recursively instead, in
//! linear time; a non-convex one of more than [`MAX_CORNERS`] is refused,
//! since ear clipping may take cubic time on it.
//!
//! Tolerances are lengths, [`TOLERANCE`] times the polygon's size: a corner
//! is straight when it lies that close to the line through its neighbours,
//! whatever the length of its sides, so that a polygon of many short sides
//! (a fine circle) has corners, not 40,000 straight ones.

use nalgebra::Vector2;

/// Polygons larger than this are clipped at the first ear found.
pub const QUALITY_LIMIT: usize = 64;

/// Most corners of a face that is not strictly convex.
pub const MAX_CORNERS: usize = 1000;

/// Distances below this fraction of the polygon's size count as zero.
pub const TOLERANCE: f64 = 1e-12;

/// Why a polygon was not triangulated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Untriangulable {
    /// No ear can be cut: the polygon is not simple (or is clockwise).
    NotSimple,
    /// Not strictly convex and more than [`MAX_CORNERS`] corners.
    TooManyCorners(usize),
}

fn cross(o: Vector2<f64>, a: Vector2<f64>, b: Vector2<f64>) -> f64 {
    (a - o).perp(&(b - o))
}

/// Whether `p` lies left of the line `u -> v` or within `delta` of it.
fn left_or_on(u: Vector2<f64>, v: Vector2<f64>, p: Vector2<f64>, delta: f64) -> bool {
    cross(u, v, p) >= -delta * (v - u).norm()
}

/// Whether `b` is a strictly convex corner between `a` and `c`: left of
/// the line `a -> c` by more than `delta`.
fn convex(a: Vector2<f64>, b: Vector2<f64>, c: Vector2<f64>, delta: f64) -> bool {
    cross(a, b, c) > delta * (c - a).norm()
}

fn quality(a: Vector2<f64>, b: Vector2<f64>, c: Vector2<f64>) -> f64 {
    let area = 0.5 * cross(a, b, c);
    let s = (b - a).norm_squared() + (c - b).norm_squared() + (a - c).norm_squared();
    4.0 * 3f64.sqrt() * area / s
}

/// Triangulate `poly` (vertex indices into `coords`, counter-clockwise, at
/// least 3; a vertex may repeat where the boundary runs along a slit and
/// back). Returns counter-clockwise triangles, or why it cannot.
pub fn ear_clip(
    poly: &[usize],
    coords: &[Vector2<f64>],
) -> Result<Vec<[usize; 3]>, Untriangulable> {
    let n = poly.len();
    if n < 3 {
        return Err(Untriangulable::NotSimple);
    }
    if n == 3 {
        return Ok(vec![[poly[0], poly[1], poly[2]]]);
    }
    let (mut lo, mut hi) = (coords[poly[0]], coords[poly[0]]);
    for &v in poly {
        lo = lo.inf(&coords[v]);
        hi = hi.sup(&coords[v]);
    }
    let delta = TOLERANCE * (hi - lo).norm();
    if n > QUALITY_LIMIT {
        if let Some(tris) = convex_split(poly, coords, delta) {
            return Ok(tris);
        }
        if n > MAX_CORNERS {
            return Err(Untriangulable::TooManyCorners(n));
        }
    }
    let mut rest: Vec<usize> = poly.to_vec();
    let mut out = Vec::with_capacity(n - 2);
    while rest.len() > 3 {
        let m = rest.len();
        let mut best: Option<(usize, f64)> = None;
        for i in 0..m {
            let (ip, inx) = ((i + m - 1) % m, (i + 1) % m);
            let (a, b, c) = (coords[rest[ip]], coords[rest[i]], coords[rest[inx]]);
            if !convex(a, b, c, delta) {
                continue; // reflex or straight corner
            }
            // No other corner inside or on the candidate triangle (the
            // triangle's own vertices, visited again along a slit, aside).
            let own = [rest[ip], rest[i], rest[inx]];
            let blocked = (0..m).filter(|&j| j != ip && j != i && j != inx).any(|j| {
                let p = coords[rest[j]];
                if own.contains(&rest[j]) || p == a || p == b || p == c {
                    return false;
                }
                left_or_on(a, b, p, delta)
                    && left_or_on(b, c, p, delta)
                    && left_or_on(c, a, p, delta)
            });
            if blocked {
                continue;
            }
            // Ties (e.g. the two ears of a parallelogram) go to the first
            // candidate, with a margin so that rounding noise in the
            // coordinates does not change the triangulation.
            let q = quality(a, b, c);
            if best.is_none_or(|(_, bq)| q > bq + 1e-9) {
                best = Some((i, q));
                if n > QUALITY_LIMIT {
                    break;
                }
            }
        }
        let (i, _) = best.ok_or(Untriangulable::NotSimple)?;
        let m = rest.len();
        out.push([rest[(i + m - 1) % m], rest[i], rest[(i + 1) % m]]);
        rest.remove(i);
    }
    let (a, b, c) = (coords[rest[0]], coords[rest[1]], coords[rest[2]]);
    if !convex(a, b, c, delta) {
        return Err(Untriangulable::NotSimple);
    }
    out.push([rest[0], rest[1], rest[2]]);
    Ok(out)
}

/// The triangles of a strictly convex simple polygon (every corner convex
/// by more than `delta`, no vertex twice, turning once around), split in
/// halves recursively: linear time, no slivers of a fan. `None` when the
/// polygon is not such.
fn convex_split(poly: &[usize], coords: &[Vector2<f64>], delta: f64) -> Option<Vec<[usize; 3]>> {
    let n = poly.len();
    let at = |k: usize| coords[poly[k % n]];
    let mut turning = 0.0;
    for k in 0..n {
        let (a, b, c) = (at(k + n - 1), at(k), at(k + 1));
        if !convex(a, b, c, delta) {
            return None;
        }
        turning += (b - a).perp(&(c - b)).atan2((b - a).dot(&(c - b)));
    }
    if (turning - std::f64::consts::TAU).abs() > 1e-6 {
        return None; // winds around more than once
    }
    let mut seen = std::collections::HashSet::with_capacity(n);
    if !poly.iter().all(|v| seen.insert(v)) {
        return None;
    }
    let v = |k: usize| poly[k % n];
    let (t1, t2) = (n / 3, 2 * n / 3);
    let mut out = Vec::with_capacity(n - 2);
    out.push([v(0), v(t1), v(t2)]);
    // Chains i..j of the boundary, closed by the side j -> i.
    let mut chains = vec![(0, t1), (t1, t2), (t2, n)];
    while let Some((i, j)) = chains.pop() {
        if j - i < 2 {
            continue;
        }
        let m = (i + j) / 2;
        out.push([v(i), v(m), v(j)]);
        chains.push((i, m));
        chains.push((m, j));
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64) -> Vector2<f64> {
        Vector2::new(x, y)
    }
    fn area(t: &[usize; 3], c: &[Vector2<f64>]) -> f64 {
        0.5 * cross(c[t[0]], c[t[1]], c[t[2]])
    }

    #[test]
    fn convex_and_non_convex() {
        // L-shape (non-convex): a fan from vertex 0 would cross outside.
        let c = vec![
            v(0., 0.),
            v(2., 0.),
            v(2., 1.),
            v(1., 1.),
            v(1., 2.),
            v(0., 2.),
        ];
        let poly: Vec<usize> = (0..6).collect();
        let tris = ear_clip(&poly, &c).unwrap();
        assert_eq!(tris.len(), 4);
        let total: f64 = tris.iter().map(|t| area(t, &c)).sum();
        assert!((total - 3.0).abs() < 1e-12);
        assert!(tris.iter().all(|t| area(t, &c) > 0.0));
        // A square picks a diagonal; a pentagon with a straight corner keeps it.
        let c = vec![v(0., 0.), v(1., 0.), v(2., 0.), v(2., 1.), v(0., 1.)];
        let tris = ear_clip(&[0, 1, 2, 3, 4], &c).unwrap();
        assert_eq!(tris.len(), 3);
        assert!(tris.iter().all(|t| area(t, &c) > 1e-9));
        assert!(tris.iter().any(|t| t.contains(&1)));
    }

    #[test]
    fn degenerate_and_clockwise_fail() {
        let c = vec![v(0., 0.), v(1., 0.), v(2., 0.), v(3., 0.)];
        assert_eq!(ear_clip(&[0, 1, 2, 3], &c), Err(Untriangulable::NotSimple));
        let c = vec![v(0., 0.), v(1., 0.), v(1., 1.), v(0., 1.)];
        assert_eq!(ear_clip(&[3, 2, 1, 0], &c), Err(Untriangulable::NotSimple));
    }

    #[test]
    fn slit_polygon() {
        // A square 0-1-2-3 with a crease from corner 0 to the centre 4:
        // the boundary runs 0 -> 4 -> 0.
        let c = vec![v(0., 0.), v(1., 0.), v(1., 1.), v(0., 1.), v(0.5, 0.5)];
        let tris = ear_clip(&[0, 4, 0, 1, 2, 3], &c).unwrap();
        assert_eq!(tris.len(), 4);
        let total: f64 = tris.iter().map(|t| area(t, &c)).sum();
        assert!((total - 1.0).abs() < 1e-12);
        assert!(tris.iter().all(|t| area(t, &c) > 1e-9));
        // the crease is a side of two triangles, once in each direction
        let along = |a: usize, b: usize| {
            tris.iter()
                .filter(|t| (0..3).any(|k| t[k] == a && t[(k + 1) % 3] == b))
                .count()
        };
        assert_eq!((along(0, 4), along(4, 0)), (1, 1));
    }

    #[test]
    fn ties_are_stable_under_rounding() {
        let c = vec![v(0., 0.), v(1., 0.), v(1.5, 1.), v(0.5, 1.)];
        let mut d = c.clone();
        d[2].x += 1e-15;
        assert_eq!(ear_clip(&[0, 1, 2, 3], &c), ear_clip(&[0, 1, 2, 3], &d));
    }

    /// A circle of 40,000 segments: every corner is a corner (not straight
    /// against the size of the circle), and it is split in linear time.
    #[test]
    fn fine_convex_polygons_and_large_non_convex_ones() {
        let n = 40_000;
        let c: Vec<_> = (0..n)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / n as f64;
                v(t.cos(), t.sin())
            })
            .collect();
        let poly: Vec<usize> = (0..n).collect();
        let tris = ear_clip(&poly, &c).unwrap();
        assert_eq!(tris.len(), n - 2);
        assert!(tris.iter().all(|t| area(t, &c) > 0.0));
        let total: f64 = tris.iter().map(|t| area(t, &c)).sum();
        let exact = 0.5 * n as f64 * (std::f64::consts::TAU / n as f64).sin();
        assert!((total - exact).abs() < 1e-9, "{total} {exact}");
        // The same circle twice around is not simple; a large star (not
        // convex) is refused by its size, not searched for ears.
        let twice: Vec<usize> = (0..2 * n).map(|k| (2 * k) % n).collect();
        assert!(ear_clip(&twice[..n], &c).is_err());
        let m = MAX_CORNERS + 2;
        let star: Vec<_> = (0..m)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / m as f64;
                let r = if k % 2 == 0 { 1.0 } else { 0.5 };
                v(r * t.cos(), r * t.sin())
            })
            .collect();
        let poly: Vec<usize> = (0..m).collect();
        assert_eq!(
            ear_clip(&poly, &star),
            Err(Untriangulable::TooManyCorners(m))
        );
    }
}
