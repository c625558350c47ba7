//! Parametric crease-pattern generators. Each returns a plain FOLD file (2D
//! coordinates in metres, counter-clockwise polygon faces, every edge listed
//! with its assignment and `edges_foldAngle`) that Origami Simulator can load
//! too, and that [`crate::scene::from_fold`] turns into a scene with the
//! default physics.
//!
//! Fold targets are the fold angles of an intended folded state, so that
//! full actuation (fold fraction 1) drives the sheet to it:
//!
//! | generator | intended state | targets |
//! |-----------|----------------|---------|
//! | [`SingleCrease`] | two panels at the given angle | given |
//! | [`Miura`] | rigid-folded Miura-ori at fold angle theta | Schenk & Guest 2013 kinematics |
//! | [`Yoshimura`] | the strip closed into a polygonal tube (antiprism stack) | from the 3D state |
//! | [`WaterbombBase`] | the symmetric rigid-folded base | from the 3D state |
//! | [`WaterbombTessellation`] | the flat-folded (collapsed) tessellation | +-180 deg |
//! | [`Kresling`] | the deployed twisted tower | from the 3D state |
//! | [`CurvedCrease`] | a uniform fold along a circular-arc crease | given (panels must bend) |
//!
//! Where the state is known in 3D ([`Miura::folded`] and friends), every
//! target is the signed dihedral angle of that state (valley positive), so
//! the targets are mutually consistent: the state is an isometry of the
//! flat sheet with planar faces.

mod curved;
mod kresling;
mod miura;
mod simple;
mod waterbomb;
mod yoshimura;

pub use curved::CurvedCrease;
pub use kresling::Kresling;
pub use miura::Miura;
pub use simple::SingleCrease;
pub use waterbomb::{WaterbombBase, WaterbombTessellation};
pub use yoshimura::Yoshimura;

use super::error::SceneError;
use super::fold::{Assignment, FoldFile};
use nalgebra::{Vector2, Vector3};
use std::collections::HashMap;

/// Any of the generators, for the CLI and the shipped scenes.
#[derive(Clone, Debug, PartialEq)]
pub enum Pattern {
    /// Two panels and one crease.
    SingleCrease(SingleCrease),
    /// Miura-ori.
    Miura(Miura),
    /// Yoshimura (diamond) pattern.
    Yoshimura(Yoshimura),
    /// A single waterbomb base.
    WaterbombBase(WaterbombBase),
    /// The waterbomb (magic-ball) tessellation.
    Waterbomb(WaterbombTessellation),
    /// Kresling tower pattern.
    Kresling(Kresling),
    /// A strip with a curved (circular-arc) crease.
    CurvedCrease(CurvedCrease),
}

impl Pattern {
    /// Generate the FOLD file.
    pub fn generate(&self) -> Result<FoldFile, SceneError> {
        match self {
            Pattern::SingleCrease(p) => p.generate(),
            Pattern::Miura(p) => p.generate(),
            Pattern::Yoshimura(p) => p.generate(),
            Pattern::WaterbombBase(p) => p.generate(),
            Pattern::Waterbomb(p) => p.generate(),
            Pattern::Kresling(p) => p.generate(),
            Pattern::CurvedCrease(p) => p.generate(),
        }
    }
}

/// The example scenes shipped in `scenes/`: file name and generator (all
/// with default parameters).
pub fn shipped() -> Vec<(&'static str, Pattern)> {
    vec![
        (
            "single_crease.fold",
            Pattern::SingleCrease(SingleCrease::default()),
        ),
        ("miura_4x4.fold", Pattern::Miura(Miura::default())),
        ("yoshimura.fold", Pattern::Yoshimura(Yoshimura::default())),
        (
            "waterbomb.fold",
            Pattern::WaterbombBase(WaterbombBase::default()),
        ),
        (
            "waterbomb_tessellation.fold",
            Pattern::Waterbomb(WaterbombTessellation::default()),
        ),
        ("kresling.fold", Pattern::Kresling(Kresling::default())),
        (
            "curved_crease.fold",
            Pattern::CurvedCrease(CurvedCrease::default()),
        ),
    ]
}

/// Parameter checks with messages that name the parameter.
pub(crate) struct Check<'a>(pub &'a str);

impl Check<'_> {
    fn err(&self, param: &str, msg: String) -> SceneError {
        SceneError::invalid(format!("{} {param}", self.0), msg)
    }
    pub fn positive(&self, param: &str, x: f64) -> Result<(), SceneError> {
        if x.is_finite() && x > 0.0 {
            Ok(())
        } else {
            Err(self.err(param, format!("{x} must be a positive number")))
        }
    }
    pub fn open_range(&self, param: &str, x: f64, lo: f64, hi: f64) -> Result<(), SceneError> {
        if x.is_finite() && x > lo && x < hi {
            Ok(())
        } else {
            Err(self.err(param, format!("{x} must be strictly between {lo} and {hi}")))
        }
    }
    pub fn count(&self, param: &str, n: usize, lo: usize, hi: usize) -> Result<(), SceneError> {
        if (lo..=hi).contains(&n) {
            Ok(())
        } else {
            Err(self.err(param, format!("{n} must be in {lo}..={hi}")))
        }
    }
    pub fn fails(&self, param: &str, msg: String) -> SceneError {
        self.err(param, msg)
    }
}

/// A pattern under construction: 2D vertices and counter-clockwise faces.
#[derive(Default)]
pub(crate) struct Draft {
    pub coords: Vec<Vector2<f64>>,
    pub faces: Vec<Vec<usize>>,
}

/// Signed area of a polygon.
pub(crate) fn polygon_area(face: &[usize], c: &[Vector2<f64>]) -> f64 {
    (0..face.len())
        .map(|k| c[face[k]].perp(&c[face[(k + 1) % face.len()]]))
        .sum::<f64>()
        * 0.5
}

impl Draft {
    pub fn vertex(&mut self, x: f64, y: f64) -> usize {
        self.coords.push(Vector2::new(x, y));
        self.coords.len() - 1
    }
    /// Add a face, reversing it if it is clockwise.
    pub fn face(&mut self, mut f: Vec<usize>) {
        if polygon_area(&f, &self.coords) < 0.0 {
            f.reverse();
        }
        self.faces.push(f);
    }

    /// Face sides in order of first appearance, with the faces on their
    /// left (forward) and right.
    fn sides(&self) -> Vec<([usize; 2], usize, Option<usize>)> {
        let mut index: HashMap<(usize, usize), usize> = HashMap::new();
        let mut out: Vec<([usize; 2], usize, Option<usize>)> = Vec::new();
        for (f, face) in self.faces.iter().enumerate() {
            for k in 0..face.len() {
                let (a, b) = (face[k], face[(k + 1) % face.len()]);
                let key = (a.min(b), a.max(b));
                match index.get(&key) {
                    Some(&i) => out[i].2 = Some(f),
                    None => {
                        index.insert(key, out.len());
                        out.push(([a, b], f, None));
                    }
                }
            }
        }
        out
    }

    /// Target fold angles in degrees of every interior side, from a folded
    /// 3D state (same vertex order): the signed dihedral angle, valley
    /// positive.
    pub fn angles_from(&self, folded: &[Vector3<f64>]) -> HashMap<(usize, usize), f64> {
        let normal = |f: usize| {
            let face = &self.faces[f];
            let mut n = Vector3::zeros();
            for k in 0..face.len() {
                n += folded[face[k]].cross(&folded[face[(k + 1) % face.len()]]);
            }
            n.normalize()
        };
        let mut out = HashMap::new();
        for ([a, b], f1, f2) in self.sides() {
            if let Some(f2) = f2 {
                out.insert(
                    (a.min(b), a.max(b)),
                    dihedral(normal(f1), normal(f2), folded[b] - folded[a]),
                );
            }
        }
        out
    }

    /// The FOLD file. Sides with one face are `B`; interior sides get
    /// `interior(a, b)`: an assignment and a target in degrees.
    pub fn finish(
        &self,
        title: String,
        description: String,
        interior: impl Fn(usize, usize) -> (Assignment, f64),
    ) -> FoldFile {
        // Coordinates to 14 decimals of the sheet size: drops the rounding
        // noise of the trigonometry (0.010000000000000002 becomes 0.01).
        let (mut lo, mut hi) = (self.coords[0], self.coords[0]);
        for c in &self.coords {
            lo = lo.inf(c);
            hi = hi.sup(c);
        }
        let digits = (14.0 - (hi - lo).norm().log10().ceil()).clamp(0.0, 22.0) as i32;
        let scale = 10f64.powi(digits);
        let round = |x: f64| (x * scale).round() / scale + 0.0;
        let mut ev = Vec::new();
        let mut asg = Vec::new();
        let mut ang = Vec::new();
        for ([a, b], _, f2) in self.sides() {
            ev.push([a, b]);
            if f2.is_some() {
                let (x, d) = interior(a, b);
                asg.push(x);
                ang.push(Some(d));
            } else {
                asg.push(Assignment::Boundary);
                ang.push(None);
            }
        }
        FoldFile {
            file_spec: Some(1.2),
            file_creator: Some("origami-fmu".into()),
            file_title: Some(title),
            file_description: Some(description),
            file_classes: vec!["singleModel".into()],
            frame_classes: vec!["creasePattern".into()],
            frame_attributes: vec!["2D".into()],
            frame_unit: Some("m".into()),
            vertices_coords: self
                .coords
                .iter()
                .map(|c| vec![round(c.x), round(c.y)])
                .collect(),
            edges_vertices: Some(ev),
            edges_assignment: Some(asg),
            edges_fold_angle: Some(ang),
            faces_vertices: self.faces.clone(),
            ..Default::default()
        }
    }

    /// [`Draft::finish`] with every interior side a crease whose target is
    /// taken from `angles` (M for negative, V for positive).
    pub fn finish_creases(
        &self,
        title: String,
        description: String,
        angles: &HashMap<(usize, usize), f64>,
    ) -> FoldFile {
        self.finish(title, description, |a, b| {
            crease(angles[&(a.min(b), a.max(b))])
        })
    }
}

/// The assignment that matches a target angle in degrees.
pub(crate) fn crease(deg: f64) -> (Assignment, f64) {
    if deg > 0.0 {
        (Assignment::Valley, deg)
    } else if deg < 0.0 {
        (Assignment::Mountain, deg)
    } else {
        (Assignment::Unassigned, 0.0)
    }
}

/// Signed fold angle in degrees across an edge with direction `e` (from
/// its first to its second vertex), between face `n1` on its left (in the
/// flat pattern) and face `n2` on its right: `atan2((n2 x n1) . e, n1 . n2)`,
/// positive for a valley (the faces turn towards their +z side).
pub(crate) fn dihedral(n1: Vector3<f64>, n2: Vector3<f64>, e: Vector3<f64>) -> f64 {
    let e = e.normalize();
    n2.cross(&n1).dot(&e).atan2(n1.dot(&n2)).to_degrees()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::mesh::EdgeKind;
    use crate::scene::{Scene, fold};
    use nalgebra::{Rotation3, Unit};

    /// Generate, check that the file builds a scene without warnings, and
    /// that writing and reading it back gives the same mesh.
    pub fn round_trip(file: &FoldFile) -> Scene {
        let (scene, warnings) = crate::scene::from_fold(file, None).unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        let (back, w2) = fold::parse(&file.to_json(), None).unwrap();
        assert!(w2.is_empty(), "{w2:?}");
        let (again, _) = crate::scene::from_fold(&back, None).unwrap();
        assert_same_mesh(&scene, &again);
        scene
    }

    pub fn assert_same_mesh(a: &Scene, b: &Scene) {
        let (m, n) = (&a.mesh, &b.mesh);
        assert_eq!(m.triangles(), n.triangles());
        assert_eq!(m.coords().len(), n.coords().len());
        for (p, q) in m.coords().iter().zip(n.coords()) {
            assert!((p - q).norm() <= 1e-15 * (1.0 + p.norm()), "{p} vs {q}");
        }
        assert_eq!(m.edges().len(), n.edges().len());
        for (e, f) in m.edges().iter().zip(n.edges()) {
            assert_eq!((e.v, e.kind, e.fold_edge), (f.v, f.kind, f.fold_edge));
            assert!((e.fold_target - f.fold_target).abs() < 1e-14);
        }
        assert_eq!(a.fold_edge_count, b.fold_edge_count);
        assert_eq!(a.actuators, b.actuators);
    }

    /// Every triangle edge and face diagonal keeps its length in the folded
    /// state, and every face stays planar.
    pub fn assert_isometric(d: &Draft, folded: &[Vector3<f64>], tol: f64) {
        for face in &d.faces {
            for &p in face {
                for &q in face {
                    let l2 = (d.coords[p] - d.coords[q]).norm();
                    let l3 = (folded[p] - folded[q]).norm();
                    assert!((l2 - l3).abs() < tol, "{p}-{q}: {l2} vs {l3}");
                }
            }
        }
    }

    /// Rigid-folding closure at every interior vertex of the scene's mesh:
    /// the product of the rotations about the crease directions, in
    /// counter-clockwise order, by the target angles is the identity.
    pub fn assert_closure(scene: &Scene, tol: f64) {
        let m = &scene.mesh;
        for v in m.vertex_ids() {
            let fan = m.fan(v).unwrap();
            if !fan.closed {
                continue;
            }
            let mut r = Rotation3::identity();
            for &e in &fan.edges {
                let edge = m.edge(e);
                let other = if edge.v[0] == v { edge.v[1] } else { edge.v[0] };
                let d = m.coord(other) - m.coord(v);
                let axis = Unit::new_normalize(Vector3::new(d.x, d.y, 0.0));
                let angle = if edge.kind == EdgeKind::Crease {
                    edge.fold_target
                } else {
                    0.0
                };
                r *= Rotation3::from_axis_angle(&axis, angle);
            }
            let dev = (r.matrix() - nalgebra::Matrix3::identity()).norm();
            assert!(dev < tol, "closure fails at vertex {v}: {dev}");
        }
    }

    #[test]
    fn dihedral_sign_is_valley_positive() {
        // Edge along +x; face 1 (left, y > 0) and face 2 rise by t each.
        let t = 0.3f64;
        let n1 = Vector3::new(0.0, -t.sin(), t.cos());
        let n2 = Vector3::new(0.0, t.sin(), t.cos());
        let rho = dihedral(n1, n2, Vector3::x());
        assert!((rho - (2.0 * t).to_degrees()).abs() < 1e-12);
        assert!((dihedral(n2, n1, Vector3::x()) + rho).abs() < 1e-12);
    }

    #[test]
    fn shipped_patterns_generate_and_round_trip() {
        for (name, p) in shipped() {
            let file = p.generate().unwrap_or_else(|e| panic!("{name}: {e}"));
            let scene = round_trip(&file);
            assert!(
                scene
                    .mesh
                    .edges()
                    .iter()
                    .any(|e| e.kind == EdgeKind::Crease),
                "{name} has no creases"
            );
            crate::model::Model::new(scene).unwrap();
        }
    }
}
