//! The Kresling pattern, folding into a twisted polygonal tower.

use super::{Check, Draft};
use crate::scene::error::SceneError;
use crate::scene::fold::FoldFile;
use nalgebra::Vector3;
use std::f64::consts::PI;

/// A strip of `stories` rows of `sides` parallelograms, each split by a
/// diagonal crease into two congruent triangles, whose target state is the
/// deployed Kresling tower: regular `sides`-gon rings of side `side`, each
/// story `height` high and twisted by `twist` against the one below.
///
/// Ring `k` vertex `i` of the tower is at azimuth `2 pi i / n + k twist`,
/// radius R = side / (2 sin(pi/n)), height `k height`. The flat pattern is
/// laid out from the tower's triangle (sides a = `side`,
/// b^2 = 4 R^2 sin^2(twist/2) + H^2 for the story edges (i,k)-(i,k+1),
/// c^2 = 4 R^2 sin^2((twist - 2 pi/n)/2) + H^2 for the diagonals
/// (i+1,k)-(i,k+1)): vertex (i, k) at (i a + k s, k h) with
/// s = (a^2 + b^2 - c^2) / (2a), h = sqrt(b^2 - s^2). The strip's two ends
/// meet along a seam in the tower (not joined).
///
/// The tower is an isometric image of the flat sheet, but the way there is
/// not rigid (the Kresling pattern is bistable through facet strain); the
/// targets are the tower's dihedral angles.
#[derive(Clone, Debug, PartialEq)]
pub struct Kresling {
    /// Polygon sides n (>= 3).
    pub sides: usize,
    /// Stories (>= 1).
    pub stories: usize,
    /// Polygon side a (m).
    pub side: f64,
    /// Story height H in the deployed state (m).
    pub height: f64,
    /// Twist per story in the deployed state (degrees, in (0, 360/n)).
    pub twist: f64,
}

impl Default for Kresling {
    /// A hexagonal tower of 3 stories, 30 mm sides, 20 mm high, 40 degrees twist.
    fn default() -> Self {
        Kresling {
            sides: 6,
            stories: 3,
            side: 0.03,
            height: 0.02,
            twist: 40.0,
        }
    }
}

impl Kresling {
    fn radius(&self) -> f64 {
        self.side / (2.0 * (PI / self.sides as f64).sin())
    }

    /// Shear s and row height h of the flat layout.
    fn layout(&self) -> (f64, f64) {
        let (a, r, hh) = (self.side, self.radius(), self.height);
        let t = self.twist.to_radians();
        let alpha = 2.0 * PI / self.sides as f64;
        let b2 = (2.0 * r * (0.5 * t).sin()).powi(2) + hh * hh;
        let c2 = (2.0 * r * (0.5 * (t - alpha)).sin()).powi(2) + hh * hh;
        let s = (a * a + b2 - c2) / (2.0 * a);
        (s, (b2 - s * s).max(0.0).sqrt())
    }

    fn draft(&self) -> Draft {
        let (n, m) = (self.sides, self.stories);
        let (s, h) = self.layout();
        let mut d = Draft::default();
        let id = |i: usize, k: usize| k * (n + 1) + i;
        for k in 0..=m {
            for i in 0..=n {
                d.vertex(i as f64 * self.side + k as f64 * s, k as f64 * h);
            }
        }
        for k in 0..m {
            for i in 0..n {
                d.face(vec![id(i, k), id(i + 1, k), id(i, k + 1)]);
                d.face(vec![id(i + 1, k), id(i + 1, k + 1), id(i, k + 1)]);
            }
        }
        d
    }

    /// Vertex positions of the target state (the tower).
    pub fn folded(&self) -> Vec<Vector3<f64>> {
        let (n, r) = (self.sides, self.radius());
        let t = self.twist.to_radians();
        let mut out = Vec::new();
        for k in 0..=self.stories {
            for i in 0..=n {
                let phi = 2.0 * PI * i as f64 / n as f64 + k as f64 * t;
                out.push(Vector3::new(
                    r * phi.cos(),
                    r * phi.sin(),
                    k as f64 * self.height,
                ));
            }
        }
        out
    }

    /// The FOLD file.
    pub fn generate(&self) -> Result<FoldFile, SceneError> {
        let c = Check("kresling");
        c.count("--sides", self.sides, 3, 200)?;
        c.count("--stories", self.stories, 1, 200)?;
        c.positive("--side", self.side)?;
        c.positive("--height", self.height)?;
        c.open_range("--twist", self.twist, 0.0, 360.0 / self.sides as f64)?;
        let (_, h) = self.layout();
        if h < 1e-3 * self.side {
            return Err(c.fails(
                "--twist",
                "the tower's triangles are degenerate for this twist and height".into(),
            ));
        }
        let d = self.draft();
        let angles = d.angles_from(&self.folded());
        Ok(d.finish_creases(
            format!("Kresling {}x{}", self.sides, self.stories),
            format!(
                "Kresling pattern, {}-gon of side {} m, {} stories; targets: the deployed tower \
                 with story height {} m and twist {} deg.",
                self.sides, self.side, self.stories, self.height, self.twist
            ),
            &angles,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{assert_closure, assert_isometric, round_trip};
    use super::*;

    #[test]
    fn tower_is_isometric_and_closes() {
        for (n, m, twist) in [(6, 3, 40.0), (4, 2, 30.0), (8, 1, 20.0)] {
            let k = Kresling {
                sides: n,
                stories: m,
                twist,
                ..Default::default()
            };
            let folded = k.folded();
            assert_isometric(&k.draft(), &folded, 1e-15);
            for row in 0..=m {
                let a = row * (n + 1);
                assert!((folded[a] - folded[a + n]).norm() < 1e-15);
            }
            let s = round_trip(&k.generate().unwrap());
            assert_closure(&s, 1e-12);
        }
        let bad = Kresling {
            twist: 90.0,
            ..Default::default()
        };
        assert_eq!(bad.generate().unwrap_err().key(), Some("kresling --twist"));
    }
}
