//! The Yoshimura (diamond) pattern, folding into a polygonal tube.

use super::{Check, Draft};
use crate::scene::error::SceneError;
use crate::scene::fold::FoldFile;
use nalgebra::Vector3;
use std::f64::consts::PI;

/// A strip of `rows` bands of isosceles triangles (base `width`, height
/// `height`), `sides` triangles per band, whose target state closes the
/// strip into a tube with a regular `sides`-gon cross-section: a stack of
/// antiprisms, the classic Yoshimura buckling pattern.
///
/// Flat layout: vertex row `r` (y = r `height`) has vertices at
/// x = k `width` on even rows and at x = 0, (k + 1/2) `width`, `sides` `width`
/// on odd rows (the half triangles at both ends give straight sides). The
/// horizontal lines and the diagonals are creases.
///
/// Target state: ring `r` is a regular polygon of circumradius
/// R = w / (2 sin(pi/n)), rotated by pi/n on odd rows, at height r H with
/// H = sqrt(h^2 - (w/2)^2 tan^2(pi/(2n))); the end points of odd rows sit at
/// chord midpoints, so both ends of the strip meet along a seam (not
/// joined). Horizontal creases become valleys and diagonals mountains (seen
/// from outside, the sheet's +z side).
#[derive(Clone, Debug, PartialEq)]
pub struct Yoshimura {
    /// Triangles per band = sides of the tube's polygon (>= 3).
    pub sides: usize,
    /// Bands of triangles (>= 1).
    pub rows: usize,
    /// Triangle base (m).
    pub width: f64,
    /// Triangle height (m); must exceed (width/2) tan(pi/(2 sides)).
    pub height: f64,
}

impl Default for Yoshimura {
    /// A hexagonal tube of 4 bands, 30 mm bases and 20 mm heights.
    fn default() -> Self {
        Yoshimura {
            sides: 6,
            rows: 4,
            width: 0.03,
            height: 0.02,
        }
    }
}

impl Yoshimura {
    /// Vertex x positions (in units of `width`) of row `r`.
    fn row_x(&self, r: usize) -> Vec<f64> {
        let n = self.sides;
        if r.is_multiple_of(2) {
            (0..=n).map(|k| k as f64).collect()
        } else {
            let mut v = vec![0.0];
            v.extend((0..n).map(|k| k as f64 + 0.5));
            v.push(n as f64);
            v
        }
    }

    fn draft(&self) -> Draft {
        let mut d = Draft::default();
        let mut rows: Vec<Vec<usize>> = Vec::new();
        for r in 0..=self.rows {
            rows.push(
                self.row_x(r)
                    .into_iter()
                    .map(|x| d.vertex(x * self.width, r as f64 * self.height))
                    .collect(),
            );
        }
        let n = self.sides;
        for r in 0..self.rows {
            let (lo, hi) = (&rows[r], &rows[r + 1]);
            if r % 2 == 0 {
                // lo: n+1 ring vertices; hi: n+2 with the end points.
                d.face(vec![lo[0], hi[1], hi[0]]);
                for i in 0..n {
                    d.face(vec![lo[i], lo[i + 1], hi[i + 1]]);
                    if i + 1 < n {
                        d.face(vec![lo[i + 1], hi[i + 2], hi[i + 1]]);
                    }
                }
                d.face(vec![lo[n], hi[n + 1], hi[n]]);
            } else {
                d.face(vec![lo[0], lo[1], hi[0]]);
                for i in 0..n {
                    d.face(vec![hi[i], lo[i + 1], hi[i + 1]]);
                    if i + 1 < n {
                        d.face(vec![lo[i + 1], lo[i + 2], hi[i + 1]]);
                    }
                }
                d.face(vec![lo[n], lo[n + 1], hi[n]]);
            }
        }
        d
    }

    fn ring_height(&self) -> f64 {
        let t = (PI / (2.0 * self.sides as f64)).tan();
        (self.height.powi(2) - (0.5 * self.width * t).powi(2)).sqrt()
    }

    /// Vertex positions of the target state (the tube).
    pub fn folded(&self) -> Vec<Vector3<f64>> {
        let n = self.sides as f64;
        let radius = self.width / (2.0 * (PI / n).sin());
        let hh = self.ring_height();
        let mut out = Vec::new();
        for r in 0..=self.rows {
            let z = r as f64 * hh;
            for x in self.row_x(r) {
                let phi = 2.0 * PI * x / n;
                let on_ring = r % 2 == 0 || x.fract() != 0.0;
                let rad = if on_ring {
                    radius
                } else {
                    radius * (PI / n).cos()
                };
                out.push(Vector3::new(rad * phi.cos(), rad * phi.sin(), z));
            }
        }
        out
    }

    /// The FOLD file.
    pub fn generate(&self) -> Result<FoldFile, SceneError> {
        let c = Check("yoshimura");
        c.count("--sides", self.sides, 3, 200)?;
        c.count("--rows", self.rows, 1, 200)?;
        c.positive("--width", self.width)?;
        c.positive("--height", self.height)?;
        let min_h = 0.5 * self.width * (PI / (2.0 * self.sides as f64)).tan();
        if self.height <= 1.001 * min_h {
            return Err(c.fails(
                "--height",
                format!(
                    "{} is too small: the tube needs height > {min_h:.4e} m (width/2 tan(pi/2n))",
                    self.height
                ),
            ));
        }
        let d = self.draft();
        let angles = d.angles_from(&self.folded());
        Ok(d.finish_creases(
            format!("Yoshimura {}x{}", self.sides, self.rows),
            format!(
                "Yoshimura pattern, {} triangles per band, {} bands, base {} m, height {} m; \
                 targets: the strip closed into a {}-gon tube (antiprism stack).",
                self.sides, self.rows, self.width, self.height, self.sides
            ),
            &angles,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{assert_closure, assert_isometric, round_trip};
    use super::*;
    use crate::scene::fold::Assignment;

    #[test]
    fn tube_state_is_isometric_with_valley_rings() {
        for (n, rows) in [(6, 4), (3, 1), (8, 3)] {
            let y = Yoshimura {
                sides: n,
                rows,
                ..Default::default()
            };
            let d = y.draft();
            let folded = y.folded();
            assert_isometric(&d, &folded, 1e-15);
            // the seam closes: first and last vertex of each row coincide
            let mut k = 0;
            for r in 0..=rows {
                let len = y.row_x(r).len();
                assert!((folded[k] - folded[k + len - 1]).norm() < 1e-15);
                k += len;
            }
            let f = y.generate().unwrap();
            let s = round_trip(&f);
            assert_closure(&s, 1e-12);
            let ev = f.edges_vertices.as_ref().unwrap();
            for (e, a) in f.edges_assignment.as_ref().unwrap().iter().enumerate() {
                let [p, q] = ev[e];
                let horizontal = d.coords[p].y == d.coords[q].y;
                match a {
                    Assignment::Boundary => {}
                    Assignment::Valley => assert!(horizontal, "edge {e}"),
                    Assignment::Mountain => assert!(!horizontal, "edge {e}"),
                    other => panic!("{other:?}"),
                }
            }
        }
        let bad = Yoshimura {
            height: 0.001,
            ..Default::default()
        };
        assert_eq!(
            bad.generate().unwrap_err().key(),
            Some("yoshimura --height")
        );
    }
}
