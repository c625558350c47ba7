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
//! to keep the cost quadratic.

use nalgebra::Vector2;

/// Polygons larger than this are clipped at the first ear found.
pub const QUALITY_LIMIT: usize = 64;

fn cross(o: Vector2<f64>, a: Vector2<f64>, b: Vector2<f64>) -> f64 {
    (a - o).perp(&(b - o))
}

fn quality(a: Vector2<f64>, b: Vector2<f64>, c: Vector2<f64>) -> f64 {
    let area = 0.5 * cross(a, b, c);
    let s = (b - a).norm_squared() + (c - b).norm_squared() + (a - c).norm_squared();
    4.0 * 3f64.sqrt() * area / s
}

/// Triangulate `poly` (vertex indices into `coords`, counter-clockwise, at
/// least 3; a vertex may repeat where the boundary runs along a slit and
/// back). Returns counter-clockwise triangles, or `None` when the polygon is
/// not simple (no ear can be cut).
pub fn ear_clip(poly: &[usize], coords: &[Vector2<f64>]) -> Option<Vec<[usize; 3]>> {
    let n = poly.len();
    if n < 3 {
        return None;
    }
    if n == 3 {
        return Some(vec![[poly[0], poly[1], poly[2]]]);
    }
    let (mut lo, mut hi) = (coords[poly[0]], coords[poly[0]]);
    for &v in poly {
        lo = lo.inf(&coords[v]);
        hi = hi.sup(&coords[v]);
    }
    let eps = 1e-12 * (hi - lo).norm_squared();
    let mut rest: Vec<usize> = poly.to_vec();
    let mut out = Vec::with_capacity(n - 2);
    while rest.len() > 3 {
        let m = rest.len();
        let mut best: Option<(usize, f64)> = None;
        for i in 0..m {
            let (ip, inx) = ((i + m - 1) % m, (i + 1) % m);
            let (a, b, c) = (coords[rest[ip]], coords[rest[i]], coords[rest[inx]]);
            if cross(a, b, c) <= eps {
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
                cross(a, b, p) >= -eps && cross(b, c, p) >= -eps && cross(c, a, p) >= -eps
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
        let (i, _) = best?;
        let m = rest.len();
        out.push([rest[(i + m - 1) % m], rest[i], rest[(i + 1) % m]]);
        rest.remove(i);
    }
    let (a, b, c) = (coords[rest[0]], coords[rest[1]], coords[rest[2]]);
    if cross(a, b, c) <= eps {
        return None;
    }
    out.push([rest[0], rest[1], rest[2]]);
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
        assert_eq!(ear_clip(&[0, 1, 2, 3], &c), None);
        let c = vec![v(0., 0.), v(1., 0.), v(1., 1.), v(0., 1.)];
        assert_eq!(ear_clip(&[3, 2, 1, 0], &c), None);
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
}
