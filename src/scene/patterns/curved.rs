//! A strip with one curved crease: a circular arc discretized into many
//! short straight crease edges.

use super::{Check, Draft, crease};
use crate::scene::error::SceneError;
use crate::scene::fold::{Assignment, FoldFile};

/// A `width` x `length` strip (x across, y along) crossed lengthwise by a
/// circular-arc crease of radius `radius` through (x0, 0) and (x0, length),
/// bulging towards +x by the sagitta `s = R - sqrt(R^2 - (length/2)^2)`,
/// centred so that `x0 = (width - s) / 2`. The arc is cut into `segments`
/// straight crease edges; each side of it is one column of quads whose
/// rungs (the lines y = const) are smooth `J` (join) edges.
///
/// Every crease edge gets the same target `angle`. Folding a curved crease
/// bends the panels, so this target is not reachable rigidly: this is the
/// case the shell model is for (bar-and-hinge models need a dense
/// triangulation to mimic it).
#[derive(Clone, Debug, PartialEq)]
pub struct CurvedCrease {
    /// Strip width across the crease (m).
    pub width: f64,
    /// Strip length along the crease (m).
    pub length: f64,
    /// Radius of the arc (m, at least length/2).
    pub radius: f64,
    /// Straight crease edges along the arc (>= 2).
    pub segments: usize,
    /// Target fold angle of every crease edge (degrees, valley positive).
    pub angle: f64,
}

impl Default for CurvedCrease {
    /// A 0.1 m x 0.2 m strip, arc radius 0.15 m in 16 segments, 90 degree valley.
    fn default() -> Self {
        CurvedCrease {
            width: 0.1,
            length: 0.2,
            radius: 0.15,
            segments: 16,
            angle: 90.0,
        }
    }
}

impl CurvedCrease {
    /// The FOLD file.
    pub fn generate(&self) -> Result<FoldFile, SceneError> {
        let c = Check("curved-crease");
        c.positive("--width", self.width)?;
        c.positive("--length", self.length)?;
        c.positive("--radius", self.radius)?;
        c.count("--segments", self.segments, 2, 10_000)?;
        if !(self.angle.is_finite() && self.angle != 0.0 && (-180.0..=180.0).contains(&self.angle))
        {
            return Err(c.fails(
                "--angle",
                format!("{} must be non-zero and in [-180, 180]", self.angle),
            ));
        }
        let (w, l, r, n) = (self.width, self.length, self.radius, self.segments);
        if r < 0.5 * l {
            return Err(c.fails(
                "--radius",
                format!(
                    "{r} is smaller than half the length ({}); the arc cannot span the strip",
                    0.5 * l
                ),
            ));
        }
        let sag = r - (r * r - 0.25 * l * l).sqrt();
        if sag > 0.8 * w {
            return Err(c.fails(
                "--radius",
                format!(
                    "the arc bulges {sag:.4e} m, too much for a {w} m wide strip (at most 80%)"
                ),
            ));
        }
        let x0 = 0.5 * (w - sag);
        let mut d = Draft::default();
        let mut rows = Vec::new();
        for k in 0..=n {
            let y = l * k as f64 / n as f64;
            let dy = y - 0.5 * l;
            let xc = x0 + (r * r - dy * dy).sqrt() - (r - sag);
            rows.push([d.vertex(0.0, y), d.vertex(xc, y), d.vertex(w, y)]);
        }
        let mut creases = std::collections::HashSet::new();
        for k in 0..n {
            let ([l0, c0, r0], [l1, c1, r1]) = (rows[k], rows[k + 1]);
            d.face(vec![l0, c0, c1, l1]);
            d.face(vec![c0, r0, r1, c1]);
            creases.insert((c0.min(c1), c0.max(c1)));
        }
        let angle = self.angle;
        Ok(d.finish(
            "curved crease".into(),
            format!(
                "A {w} m x {l} m strip with a circular-arc crease of radius {r} m in {n} \
                 segments, folding to {angle} deg."
            ),
            |a, b| {
                if creases.contains(&(a.min(b), a.max(b))) {
                    crease(angle)
                } else {
                    (Assignment::Join, 0.0)
                }
            },
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::round_trip;
    use super::*;

    #[test]
    fn arc_of_short_creases() {
        let cc = CurvedCrease::default();
        let f = cc.generate().unwrap();
        let s = round_trip(&f);
        let creases: Vec<_> = s.mesh.creases().collect();
        assert_eq!(creases.len(), 16);
        // all crease vertices on the circle
        let w = cc.width;
        let sag = cc.radius - (cc.radius.powi(2) - 0.25 * cc.length.powi(2)).sqrt();
        let centre = nalgebra::Vector2::new(0.5 * (w - sag) + sag - cc.radius, 0.5 * cc.length);
        for e in &creases {
            for v in e.v {
                let d = (s.mesh.coord(v) - centre).norm();
                assert!((d - cc.radius).abs() < 1e-12, "{d}");
            }
        }
        let bad = CurvedCrease {
            radius: 0.05,
            ..Default::default()
        };
        assert_eq!(
            bad.generate().unwrap_err().key(),
            Some("curved-crease --radius")
        );
    }
}
