//! Miura-ori with rigid-folding targets (Schenk & Guest 2013).

use super::{Check, Draft};
use crate::scene::error::SceneError;
use crate::scene::fold::FoldFile;
use nalgebra::Vector3;

/// A Miura-ori sheet of `nx` x `ny` unit cells (each 2 x 2 parallelogram
/// facets) with sides `a` and `b` and sector angle `sector_angle`.
///
/// Flat layout, vertex `(i, j)` with `i in 0..=2nx`, `j in 0..=2ny` and index
/// `j (2nx + 1) + i`:
///
/// ```text
/// x = i a + (j mod 2) b cos(gamma),   y = j b sin(gamma)
/// ```
///
/// so the `a` sides lie along the crease lines that are straight in the
/// flat sheet (x) and the `b` sides along the zig-zag lines (y).
///
/// Targets are the fold angles of the rigid-folded state at the
/// Schenk & Guest (2013, PNAS 110:3276) fold angle `theta` (the angle
/// between the facets and the xy plane; 0 flat, 90 flat-folded), whose
/// vertex positions are
///
/// ```text
/// H = a sin(theta) sin(gamma)                       (height)
/// L = a sqrt(1 - sin^2(theta) sin^2(gamma))         (x per a side)
/// S = b cos(theta) tan(gamma) / sqrt(1 + cos^2(theta) tan^2(gamma))   (y per b side)
/// V = b / sqrt(1 + cos^2(theta) tan^2(gamma))       (zig-zag offset in x)
/// X = i L + (j mod 2) V,   Y = j S,   Z = (i mod 2) H
/// ```
///
/// Every edge length and facet diagonal of the flat sheet is kept
/// (L V = a b cos(gamma)), so the state is a rigid folding and each target
/// is its signed dihedral angle. The zig-zag lines fold alternately as whole
/// mountains and valleys; along each straight line the creases alternate.
#[derive(Clone, Debug, PartialEq)]
pub struct Miura {
    /// Unit cells along x (the straight crease lines).
    pub nx: usize,
    /// Unit cells along y (the zig-zag crease lines).
    pub ny: usize,
    /// Facet side along the straight crease lines (m).
    pub a: f64,
    /// Facet side along the zig-zag crease lines (m).
    pub b: f64,
    /// Sector angle gamma between the a and b sides (degrees, in (0, 90)).
    pub sector_angle: f64,
    /// Schenk & Guest fold angle theta of the target state (degrees, in (0, 90)).
    pub fold_angle: f64,
}

impl Default for Miura {
    /// 4 x 4 cells, a = b = 20 mm, gamma = 60 degrees, theta = 60 degrees.
    fn default() -> Self {
        Miura {
            nx: 4,
            ny: 4,
            a: 0.02,
            b: 0.02,
            sector_angle: 60.0,
            fold_angle: 60.0,
        }
    }
}

impl Miura {
    fn check(&self) -> Result<(), SceneError> {
        let c = Check("miura");
        c.count("--nx", self.nx, 1, 200)?;
        c.count("--ny", self.ny, 1, 200)?;
        c.positive("--a", self.a)?;
        c.positive("--b", self.b)?;
        c.open_range("--angle", self.sector_angle, 0.0, 90.0)?;
        c.open_range("--fold", self.fold_angle, 0.0, 90.0)
    }

    fn draft(&self) -> Draft {
        let (nx, ny, a, b) = (self.nx, self.ny, self.a, self.b);
        let g = self.sector_angle.to_radians();
        let mut d = Draft::default();
        for j in 0..=2 * ny {
            for i in 0..=2 * nx {
                d.vertex(
                    i as f64 * a + (j % 2) as f64 * b * g.cos(),
                    j as f64 * b * g.sin(),
                );
            }
        }
        let id = |i: usize, j: usize| j * (2 * nx + 1) + i;
        for j in 0..2 * ny {
            for i in 0..2 * nx {
                d.face(vec![id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        d
    }

    /// Vertex positions of the target state (same order as the FOLD file).
    pub fn folded(&self) -> Vec<Vector3<f64>> {
        let (a, b) = (self.a, self.b);
        let g = self.sector_angle.to_radians();
        let t = self.fold_angle.to_radians();
        let h = a * t.sin() * g.sin();
        let l = a * (1.0 - (t.sin() * g.sin()).powi(2)).sqrt();
        let den = (1.0 + (t.cos() * g.tan()).powi(2)).sqrt();
        let s = b * t.cos() * g.tan() / den;
        let v = b / den;
        let mut out = Vec::new();
        for j in 0..=2 * self.ny {
            for i in 0..=2 * self.nx {
                out.push(Vector3::new(
                    i as f64 * l + (j % 2) as f64 * v,
                    j as f64 * s,
                    (i % 2) as f64 * h,
                ));
            }
        }
        out
    }

    /// The FOLD file.
    pub fn generate(&self) -> Result<FoldFile, SceneError> {
        self.check()?;
        let d = self.draft();
        let angles = d.angles_from(&self.folded());
        Ok(d.finish_creases(
            format!("Miura-ori {}x{}", self.nx, self.ny),
            format!(
                "Miura-ori, {} x {} cells, a = {} m, b = {} m, sector angle {} deg; targets: \
                 rigid-folded state at theta = {} deg (Schenk & Guest 2013).",
                self.nx, self.ny, self.a, self.b, self.sector_angle, self.fold_angle
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
    fn default_is_rigid_foldable_and_round_trips() {
        let m = Miura::default();
        let f = m.generate().unwrap();
        assert_isometric(&m.draft(), &m.folded(), 1e-15);
        let scene = round_trip(&f);
        assert_eq!(scene.fold_vertex_count, 81);
        assert_eq!(scene.mesh.triangles().len(), 128);
        assert_closure(&scene, 1e-12);
        // Zig-zag lines: whole lines of one kind, alternating line to line.
        let ev = f.edges_vertices.as_ref().unwrap();
        let asg = f.edges_assignment.as_ref().unwrap();
        let col = |v: usize| v % 9;
        for (e, &[p, q]) in ev.iter().enumerate() {
            if asg[e] == Assignment::Boundary {
                continue;
            }
            if col(p) == col(q) {
                let expect = if col(p) % 2 == 0 {
                    asg.iter()
                        .zip(ev)
                        .find(|(_, v)| col(v[0]) == col(v[1]) && col(v[0]) == 2)
                        .unwrap()
                        .0
                } else {
                    asg.iter()
                        .zip(ev)
                        .find(|(_, v)| col(v[0]) == col(v[1]) && col(v[0]) == 1)
                        .unwrap()
                        .0
                };
                assert_eq!(asg[e], *expect, "edge {e}");
            }
        }
        let n_creases = scene.mesh.creases().count();
        // interior edges of an 8 x 8 facet grid: 7*8 + 8*7
        assert_eq!(n_creases, 112);
    }

    #[test]
    fn other_parameters_stay_rigid() {
        for (gamma, theta) in [(45.0, 30.0), (75.0, 85.0), (30.0, 10.0)] {
            let m = Miura {
                nx: 2,
                ny: 3,
                a: 0.01,
                b: 0.03,
                sector_angle: gamma,
                fold_angle: theta,
            };
            assert_isometric(&m.draft(), &m.folded(), 1e-15);
            let scene = round_trip(&m.generate().unwrap());
            assert_closure(&scene, 1e-12);
        }
        let bad = Miura {
            sector_angle: 90.0,
            ..Default::default()
        };
        assert_eq!(bad.generate().unwrap_err().key(), Some("miura --angle"));
    }
}
