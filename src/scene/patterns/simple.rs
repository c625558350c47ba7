//! Two panels joined by one straight crease.

use super::{Check, Draft, crease};
use crate::scene::error::SceneError;
use crate::scene::fold::FoldFile;

/// Two `width` x `length` panels side by side (x from 0 to `2 width`, y from
/// 0 to `length`) with the crease x = `width` folding to `angle`.
///
/// Vertices 0..5 run (0,0), (w,0), (2w,0), (2w,L), (w,L), (0,L); the crease
/// is 1-4. The default is a 0.05 m x 0.1 m panel pair folding to a 90 degree
/// valley.
#[derive(Clone, Debug, PartialEq)]
pub struct SingleCrease {
    /// Width of each panel (m).
    pub width: f64,
    /// Length of the crease (m).
    pub length: f64,
    /// Target fold angle (degrees, valley positive, in [-180, 180]).
    pub angle: f64,
}

impl Default for SingleCrease {
    fn default() -> Self {
        SingleCrease {
            width: 0.05,
            length: 0.1,
            angle: 90.0,
        }
    }
}

impl SingleCrease {
    /// The FOLD file.
    pub fn generate(&self) -> Result<FoldFile, SceneError> {
        let c = Check("single-crease");
        c.positive("--width", self.width)?;
        c.positive("--length", self.length)?;
        if !(self.angle.is_finite() && (-180.0..=180.0).contains(&self.angle)) {
            return Err(c.fails("--angle", format!("{} must be in [-180, 180]", self.angle)));
        }
        let (w, l) = (self.width, self.length);
        let mut d = Draft::default();
        for (x, y) in [
            (0.0, 0.0),
            (w, 0.0),
            (2.0 * w, 0.0),
            (2.0 * w, l),
            (w, l),
            (0.0, l),
        ] {
            d.vertex(x, y);
        }
        d.face(vec![0, 1, 4, 5]);
        d.face(vec![1, 2, 3, 4]);
        let angle = self.angle;
        Ok(d.finish(
            "single crease".into(),
            format!(
                "Two {w} m x {l} m panels joined by the crease 1-4, folding to {angle} degrees."
            ),
            move |_, _| crease(angle),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::fold::Assignment;

    #[test]
    fn one_crease_with_the_given_target() {
        let f = SingleCrease::default().generate().unwrap();
        let s = super::super::tests::round_trip(&f);
        let creases: Vec<_> = s.mesh.creases().collect();
        assert_eq!(creases.len(), 1);
        assert_eq!(creases[0].v, [1, 4].map(crate::ids::VertexId));
        assert!((creases[0].fold_target - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        let m = SingleCrease {
            angle: -45.0,
            ..Default::default()
        };
        let f = m.generate().unwrap();
        let e = f
            .edges_vertices
            .as_ref()
            .unwrap()
            .iter()
            .position(|&v| v == [1, 4] || v == [4, 1])
            .unwrap();
        assert_eq!(
            f.edges_assignment.as_ref().unwrap()[e],
            Assignment::Mountain
        );
        let bad = SingleCrease {
            width: 0.0,
            ..Default::default()
        };
        assert_eq!(
            bad.generate().unwrap_err().key(),
            Some("single-crease --width")
        );
    }
}
