//! Reference geometry of crease curves (docs/model.md, "Curved creases").
//!
//! Where exactly two crease edges meet at a vertex and they are not
//! collinear, the polyline stands for a smooth curve (or a kink): the two
//! sides of the crease share only the curve's tangent there, so the crease can
//! fold at that vertex. The tangent is the one of the circle through the
//! vertex and its two crease neighbours,
//! `t ~ (X_v - X_a)/|X_v - X_a|^2 + (X_b - X_v)/|X_b - X_v|^2`: exact for a
//! circular arc whatever the segment lengths (the bisector of the chords is
//! exact only for equal segments), and the chord direction when the three
//! points are collinear.
//!
//! A crease edge with such a vertex at one or both ends is curved in the
//! reference: the cubic Hermite curve between its two vertices whose end
//! tangents are the curve tangents, with magnitude `chord / cos^2(phi/4)`
//! (`phi` the angle between the end tangents: the cubic closest to a circular
//! arc). The two facets on the edge take that side as theirs, so they share
//! it exactly. Every other side stays the straight chord.

use crate::ids::{EdgeId, VertexId};
use crate::mesh::{EdgeKind, Mesh};
use nalgebra::Vector2;

/// Two unit directions closer than this (1 - |cos|) count as parallel.
const PARALLEL_TOL: f64 = 1e-9;

/// Largest turn of the crease at a vertex (rad) that counts as a curve: a
/// polyline standing for a smooth curve turns gently at each vertex; a
/// sharper turn is a corner, which keeps the straight-crease rule (its sides
/// stay straight; curved ones would fold the facets there over themselves,
/// measured from a turn of about 60 degrees on).
const MAX_CURVE_TURN: f64 = std::f64::consts::FRAC_PI_4;

/// The crease curve tangents of a mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CreaseCurves {
    /// Unit curve tangent at each vertex where two non-collinear creases
    /// meet (orientation arbitrary), `None` elsewhere.
    tangent: Vec<Option<Vector2<f64>>>,
}

impl CreaseCurves {
    /// Find the curved crease vertices of a validated mesh: interior
    /// vertices with exactly two creases that turn by more than round-off and
    /// at most `MAX_CURVE_TURN`. (On the boundary the sectors between a
    /// crease and the boundary are free, so two creases there fold without it.)
    pub fn new(mesh: &Mesh) -> CreaseCurves {
        let nv = mesh.n_vertices();
        let mut nbrs: Vec<Vec<VertexId>> = vec![Vec::new(); nv];
        let mut boundary = vec![false; nv];
        for (e, faces) in mesh.edges().iter().zip(mesh.edge_faces()) {
            if e.kind == EdgeKind::Crease {
                nbrs[e.v[0].index()].push(e.v[1]);
                nbrs[e.v[1].index()].push(e.v[0]);
            }
            if faces.len() == 1 {
                boundary[e.v[0].index()] = true;
                boundary[e.v[1].index()] = true;
            }
        }
        let tangent = mesh
            .vertex_ids()
            .map(|v| {
                let [a, b] = nbrs[v.index()][..] else {
                    return None;
                };
                if boundary[v.index()] {
                    return None;
                }
                let x = mesh.coord(v);
                let (da, db) = (x - mesh.coord(a), mesh.coord(b) - x);
                let cos_turn = da.normalize().dot(&db.normalize());
                let collinear = 1.0 - cos_turn < PARALLEL_TOL;
                if collinear || cos_turn < MAX_CURVE_TURN.cos() {
                    return None;
                }
                let t = da / da.norm_squared() + db / db.norm_squared();
                Some(t.normalize())
            })
            .collect();
        CreaseCurves { tangent }
    }

    /// Whether any crease vertex is curved.
    pub fn any(&self) -> bool {
        self.tangent.iter().any(Option::is_some)
    }

    /// Whether two non-collinear creases meet at `v` (its creases share one
    /// tangent slot and each side its own second vector).
    pub fn is_curved(&self, v: VertexId) -> bool {
        self.tangent.get(v.index()).is_some_and(Option::is_some)
    }

    /// Unit tangent at `v` of the side from `v` towards `w` along edge `e`:
    /// the curve tangent (oriented towards `w`) on a crease edge at a curved
    /// vertex, the chord direction otherwise.
    pub fn direction(&self, mesh: &Mesh, e: EdgeId, v: VertexId, w: VertexId) -> Vector2<f64> {
        let chord = mesh.coord(w) - mesh.coord(v);
        match self.tangent[v.index()] {
            Some(t) if mesh.edge(e).kind == EdgeKind::Crease => {
                if t.dot(&chord) >= 0.0 {
                    t
                } else {
                    -t
                }
            }
            _ => chord.normalize(),
        }
    }

    /// Whether edge `e` is curved in the reference.
    pub fn is_curved_edge(&self, mesh: &Mesh, e: EdgeId) -> bool {
        let edge = mesh.edge(e);
        edge.kind == EdgeKind::Crease && (self.is_curved(edge.v[0]) || self.is_curved(edge.v[1]))
    }

    /// The reference side vector at `v` towards `w` along edge `e`: what a
    /// facet's gradient DOF there means (`G_s` times it). The chord
    /// `X_w - X_v` on a straight side, the Hermite end tangent on a curved one.
    pub fn side(&self, mesh: &Mesh, e: EdgeId, v: VertexId, w: VertexId) -> Vector2<f64> {
        let chord = mesh.coord(w) - mesh.coord(v);
        if !self.is_curved_edge(mesh, e) {
            return chord;
        }
        let (tv, tw) = (
            self.direction(mesh, e, v, w),
            -self.direction(mesh, e, w, v),
        );
        let phi = tv.dot(&tw).clamp(-1.0, 1.0).acos();
        let c = (0.25 * phi).cos();
        tv * (chord.norm() / (c * c))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ids::vertex_ids;
    use crate::mesh::Edge;

    const V: fn(usize) -> VertexId = VertexId;

    /// A fan of triangles around a crease polyline a - v - b (a kink of
    /// `turn` radians at v), with apexes on both sides.
    fn kinked(turn: f64) -> Mesh {
        let v = Vector2::new(0.0, 0.0);
        let a = Vector2::new(-1.0, 0.0);
        let b = Vector2::new(turn.cos(), turn.sin());
        let up = Vector2::new(0.0, 1.5);
        let down = Vector2::new(0.1, -1.5);
        let coords = vec![v, a, b, up, down];
        let tris = [[0, 2, 3], [0, 3, 1], [0, 1, 4], [0, 4, 2]].map(vertex_ids);
        Mesh::new(
            coords,
            tris.to_vec(),
            vec![Edge::crease(V(1), V(0), 1.0), Edge::crease(V(0), V(2), 1.0)],
        )
        .unwrap()
    }

    #[test]
    fn circle_tangent_at_a_curve_vertex() {
        // Points on the unit circle at angles -0.3, 0, 0.5: the tangent at
        // angle 0 is +y (unequal segments: the chord bisector is not exact).
        let m = Mesh::new(
            vec![
                Vector2::new(f64::cos(-0.3), f64::sin(-0.3)),
                Vector2::new(1.0, 0.0),
                Vector2::new(f64::cos(0.5), f64::sin(0.5)),
                Vector2::new(0.0, 0.0),
                Vector2::new(2.0, 0.1),
            ],
            [[0, 1, 3], [1, 2, 3], [1, 0, 4], [2, 1, 4]]
                .map(vertex_ids)
                .to_vec(),
            vec![Edge::crease(V(0), V(1), 1.0), Edge::crease(V(1), V(2), 1.0)],
        )
        .unwrap();
        let c = CreaseCurves::new(&m);
        assert!(c.is_curved(V(1)) && !c.is_curved(V(0)) && !c.is_curved(V(3)));
        let e = m.find_edge(V(1), V(2)).unwrap();
        let t = c.direction(&m, e, V(1), V(2));
        assert!((t - Vector2::new(0.0, 1.0)).norm() < 1e-12, "{t}");
        // The side vector: along the tangent, longer than the chord.
        let s = c.side(&m, e, V(1), V(2));
        let chord = (m.coord(V(2)) - m.coord(V(1))).norm();
        assert!(s.normalize().dot(&t) > 1.0 - 1e-12 && s.norm() > chord);
        // A smooth edge at the curve vertex stays straight.
        let e3 = m.find_edge(V(1), V(3)).unwrap();
        assert_eq!(c.side(&m, e3, V(1), V(3)), m.coord(V(3)) - m.coord(V(1)));
    }

    #[test]
    fn straight_creases_and_corners_are_not_curved() {
        let m = kinked(0.0);
        let c = CreaseCurves::new(&m);
        assert!(!c.any());
        let k = kinked(0.4);
        assert!(CreaseCurves::new(&k).is_curved(V(0)));
        // A 69 degree corner keeps straight sides (curved ones would fold
        // a facet over) and the model builds.
        let corner = kinked(1.2);
        assert!(!CreaseCurves::new(&corner).any());
        let layout = crate::dofs::DofLayout::new(&corner);
        assert_eq!(layout.vertex_slots(V(0)).len(), 3);
    }

    /// The Hermite side with these end tangents is close to the circular
    /// arc through its ends: for a 30 degree arc the midpoint is within
    /// 1e-5 of the radius.
    #[test]
    fn hermite_side_follows_a_circle() {
        let phi: f64 = 30f64.to_radians();
        let (p0, p1) = (Vector2::new(1.0, 0.0), Vector2::new(phi.cos(), phi.sin()));
        let chord = (p1 - p0).norm();
        let c = (0.25 * phi).cos();
        let m0 = Vector2::new(0.0, 1.0) * chord / (c * c);
        let m1 = Vector2::new(-phi.sin(), phi.cos()) * chord / (c * c);
        let t = 0.5;
        let h = |t: f64| {
            let (t2, t3) = (t * t, t * t * t);
            p0 * (2.0 * t3 - 3.0 * t2 + 1.0)
                + m0 * (t3 - 2.0 * t2 + t)
                + p1 * (-2.0 * t3 + 3.0 * t2)
                + m1 * (t3 - t2)
        };
        assert!((h(t).norm() - 1.0).abs() < 1e-5, "{}", h(t).norm());
    }
}
