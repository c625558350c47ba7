//! The waterbomb base and the waterbomb (magic-ball) tessellation.

use super::{Check, Draft, crease};
use crate::scene::error::SceneError;
use crate::scene::fold::{Assignment, FoldFile};
use nalgebra::Vector3;
use std::f64::consts::FRAC_1_SQRT_2;

/// A square sheet with both diagonals and both midlines creased: the
/// degree-8 waterbomb base, folded in its symmetric rigid mode.
///
/// Vertex 0 is the centre; vertices `1 + k` (k = 0..8) lie counter-clockwise
/// at azimuth 45k degrees: edge midpoints for even k, corners for odd k.
///
/// In the target state the corner creases point down at `fold` degrees
/// below the sheet plane (azimuths kept) and the midline creases at the
/// angle mu below it that keeps the 45 degree sector angles:
/// `cos(beta) cos(mu) cos 45 + sin(beta) sin(mu) = cos 45`, the root with
/// `mu < beta`: the midlines stand out as four flaps that close as beta
/// goes to 90. Seen from +z the midlines are mountains and the diagonals
/// valleys (the classic waterbomb base); targets are the dihedral angles of
/// that state.
#[derive(Clone, Debug, PartialEq)]
pub struct WaterbombBase {
    /// Side of the square (m).
    pub size: f64,
    /// Tilt beta of the corner creases below the sheet plane in the target
    /// state (degrees, in (0, 90)).
    pub fold: f64,
}

impl Default for WaterbombBase {
    /// A 0.1 m square folded to beta = 60 degrees.
    fn default() -> Self {
        WaterbombBase {
            size: 0.1,
            fold: 60.0,
        }
    }
}

impl WaterbombBase {
    fn draft(&self) -> Draft {
        let (l, c) = (self.size, 0.5 * self.size);
        let mut d = Draft::default();
        d.vertex(c, c);
        for k in 0..8 {
            let psi = (45.0 * k as f64).to_radians();
            let r = if k % 2 == 0 { c } else { c * 2f64.sqrt() };
            // Snap to the exact square (cos/sin of multiples of 45 degrees).
            let snap = |x: f64| (x / c).round() * c;
            d.vertex(
                snap(c + r * psi.cos()).clamp(0.0, l),
                snap(c + r * psi.sin()).clamp(0.0, l),
            );
        }
        for k in 0..8 {
            d.face(vec![0, 1 + k, 1 + (k + 1) % 8]);
        }
        d
    }

    /// Angle mu (radians) of the midline creases below the plane.
    fn midline_tilt(&self) -> f64 {
        let b = self.fold.to_radians();
        let (a, bb, c) = (b.cos() * FRAC_1_SQRT_2, b.sin(), FRAC_1_SQRT_2);
        let r = a.hypot(bb);
        bb.atan2(a) - (c / r).min(1.0).acos()
    }

    /// Vertex positions of the target state.
    pub fn folded(&self) -> Vec<Vector3<f64>> {
        let c = 0.5 * self.size;
        let beta = self.fold.to_radians();
        let mu = self.midline_tilt();
        let mut out = vec![Vector3::new(c, c, 0.0)];
        for k in 0..8 {
            let psi = (45.0 * k as f64).to_radians();
            let (tilt, r) = if k % 2 == 0 {
                (mu, c)
            } else {
                (beta, c * 2f64.sqrt())
            };
            out.push(
                Vector3::new(c, c, 0.0)
                    + r * Vector3::new(tilt.cos() * psi.cos(), tilt.cos() * psi.sin(), -tilt.sin()),
            );
        }
        out
    }

    /// The FOLD file.
    pub fn generate(&self) -> Result<FoldFile, SceneError> {
        let c = Check("waterbomb-base");
        c.positive("--size", self.size)?;
        c.open_range("--fold", self.fold, 0.0, 90.0)?;
        let d = self.draft();
        let angles = d.angles_from(&self.folded());
        Ok(d.finish_creases(
            "waterbomb base".into(),
            format!(
                "Waterbomb base, {} m square; targets: symmetric rigid-folded state with the \
                 corner creases {} deg below the sheet plane.",
                self.size, self.fold
            ),
            &angles,
        ))
    }
}

/// The waterbomb tessellation (the "magic ball" pattern): bands of
/// degree-6 waterbomb bases, alternate bands offset by half a base.
///
/// On a grid of spacing `d = size / 2`, vertex columns `i in 0..=2nx` and
/// band boundaries `y = 2 b d` (`b in 0..=ny`) carry vertices; band `b` has
/// base centres at `y = (2b + 1) d` in the columns with `i + b` odd. Every
/// vertical grid line and every interior band boundary is a mountain
/// crease; the diagonals from each centre to the four corners of its
/// `size` x `size` square are valleys. Each centre is a waterbomb base
/// (vertical midline, four diagonals); each band-boundary vertex is a
/// flat-foldable degree-6 vertex.
///
/// There is no simple rigid-folded state to take partial targets from, so
/// the targets are those of the collapsed (flat-folded) tessellation,
/// `-fold` for mountains and `+fold` for valleys with `fold = 180` by
/// default; a smaller `fold` scales all targets alike (as Origami
/// Simulator's fold percent does), which is not a consistent state: the
/// facets then bend.
#[derive(Clone, Debug, PartialEq)]
pub struct WaterbombTessellation {
    /// Bases per band (along x).
    pub nx: usize,
    /// Bands (along y).
    pub ny: usize,
    /// Side of one base square (m).
    pub size: f64,
    /// Magnitude of every target (degrees, in (0, 180]).
    pub fold: f64,
}

impl Default for WaterbombTessellation {
    /// 4 x 4 bases of 20 mm, targets +-180 degrees.
    fn default() -> Self {
        WaterbombTessellation {
            nx: 4,
            ny: 4,
            size: 0.02,
            fold: 180.0,
        }
    }
}

impl WaterbombTessellation {
    fn is_centre_col(i: usize, b: usize) -> bool {
        (i + b) % 2 == 1
    }

    /// The FOLD file.
    pub fn generate(&self) -> Result<FoldFile, SceneError> {
        let c = Check("waterbomb");
        c.count("--nx", self.nx, 1, 200)?;
        c.count("--ny", self.ny, 1, 200)?;
        c.positive("--size", self.size)?;
        if !(self.fold.is_finite() && self.fold > 0.0 && self.fold <= 180.0) {
            return Err(c.fails("--fold", format!("{} must be in (0, 180]", self.fold)));
        }
        let (nx, ny) = (self.nx, self.ny);
        let h = 0.5 * self.size;
        let mut d = Draft::default();
        // Band-boundary rows first, then the centres band by band.
        let row = |i: usize, b: usize| b * (2 * nx + 1) + i;
        for b in 0..=ny {
            for i in 0..=2 * nx {
                d.vertex(i as f64 * h, 2.0 * b as f64 * h);
            }
        }
        let mut centre = std::collections::HashMap::new();
        for b in 0..ny {
            for i in 0..=2 * nx {
                if Self::is_centre_col(i, b) {
                    centre.insert((i, b), d.vertex(i as f64 * h, (2 * b + 1) as f64 * h));
                }
            }
        }
        let mut valleys = std::collections::HashSet::new();
        for b in 0..ny {
            for i in 0..2 * nx {
                let (ci, ni) = if Self::is_centre_col(i, b) {
                    (i, i + 1)
                } else {
                    (i + 1, i)
                };
                let m = centre[&(ci, b)];
                d.face(vec![row(ci, b), row(ni, b), m]);
                d.face(vec![row(ni, b), row(ni, b + 1), m]);
                d.face(vec![m, row(ni, b + 1), row(ci, b + 1)]);
                for corner in [row(ni, b), row(ni, b + 1)] {
                    valleys.insert((m.min(corner), m.max(corner)));
                }
            }
        }
        let fold = self.fold;
        Ok(d.finish(
            "waterbomb tessellation".into(),
            format!(
                "Waterbomb (magic-ball) tessellation, {nx} x {ny} bases of {} m; grid lines \
                 mountain, diagonals valley; targets +-{fold} deg (flat-folded at 180).",
                self.size
            ),
            |a, b| {
                if valleys.contains(&(a.min(b), a.max(b))) {
                    crease(fold)
                } else {
                    (Assignment::Mountain, -fold)
                }
            },
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{assert_closure, assert_isometric, round_trip};
    use super::*;
    use crate::mesh::EdgeKind;

    #[test]
    fn base_is_rigid_with_mountain_midlines() {
        for beta in [10.0, 60.0, 89.0] {
            let w = WaterbombBase {
                size: 0.1,
                fold: beta,
            };
            assert_isometric(&w.draft(), &w.folded(), 1e-14);
            let f = w.generate().unwrap();
            let s = round_trip(&f);
            assert_closure(&s, 1e-12);
            let asg = f.edges_assignment.as_ref().unwrap();
            for (e, &[p, q]) in f.edges_vertices.as_ref().unwrap().iter().enumerate() {
                if p == 0 || q == 0 {
                    let other = p + q;
                    // odd vertices are edge midpoints, even ones corners
                    let expect = if other % 2 == 1 {
                        Assignment::Mountain
                    } else {
                        Assignment::Valley
                    };
                    assert_eq!(asg[e], expect, "edge {p}-{q} at beta {beta}");
                }
            }
        }
        let s = round_trip(&WaterbombBase::default().generate().unwrap());
        assert_eq!(s.mesh.creases().count(), 8);
    }

    #[test]
    fn tessellation_is_flat_foldable_at_180() {
        let t = WaterbombTessellation {
            nx: 3,
            ny: 3,
            ..Default::default()
        };
        let s = round_trip(&t.generate().unwrap());
        // Flat-folded closure: rotations by +-pi multiply to the identity.
        assert_closure(&s, 1e-9);
        // every interior vertex has degree 6
        for v in s.mesh.vertex_ids() {
            let fan = s.mesh.fan(v).unwrap();
            if fan.closed {
                assert_eq!(fan.edges.len(), 6, "vertex {v}");
                let c = fan
                    .edges
                    .iter()
                    .filter(|&&e| s.mesh.edge(e).kind == EdgeKind::Crease)
                    .count();
                assert_eq!(c, 6);
            }
        }
    }
}
