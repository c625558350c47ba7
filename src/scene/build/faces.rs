//! The faces and the flat reference: face indices and slits, the reference
//! coordinates (flat, in their plane), side lengths and areas, and the
//! orientation (a sheet drawn clockwise is mirrored; a mix of orientations
//! is a folded state).

use super::{FOLDED_STATE, invalid, vertex_exists};
use crate::mesh::{is_degenerate, mean_side_length2};
use crate::scene::error::SceneError;
use crate::scene::fold::FoldFile;
use crate::scene::planar::shoelace;
use crate::scene::triangulate::{MAX_CORNERS, Untriangulable, ear_clip};
use nalgebra::{Vector2, Vector3};

/// Relative tolerance (against the size of the sheet) of the flatness test
/// for 3D reference coordinates.
pub const COPLANAR_TOLERANCE: f64 = 1e-9;

/// Indices in range, at least three vertices, no repeated vertex.
pub(super) fn check_faces(faces: &[Vec<usize>], nv: usize) -> Result<(), SceneError> {
    for (f, face) in faces.iter().enumerate() {
        let key = format!("faces_vertices[{f}]");
        if face.len() < 3 {
            return Err(invalid(
                key,
                format!("has {} vertices; a face needs at least 3", face.len()),
            ));
        }
        for (j, &v) in face.iter().enumerate() {
            vertex_exists(v, nv, || format!("{key}[{j}]"))?;
        }
        let mut sorted = face.clone();
        sorted.sort_unstable();
        if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
            // Allowed where the boundary runs out along an edge and back (a
            // crease or cut ending inside the face: a slit).
            if !has_slit(face) {
                return Err(invalid(
                    key,
                    format!(
                        "repeats vertex {} without a slit (no side of the face is run along \
                         both ways): the face touches itself there; split it into simple \
                         polygons at that vertex",
                        w[0]
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// True when a face runs along one of its sides in both directions (a
/// crease or cut that ends inside the face: a slit).
pub(super) fn has_slit(face: &[usize]) -> bool {
    let n = face.len();
    let sides: std::collections::HashSet<(usize, usize)> =
        (0..n).map(|k| (face[k], face[(k + 1) % n])).collect();
    (0..n).any(|k| sides.contains(&(face[(k + 1) % n], face[k])))
}

/// The flat reference coordinates in file units (see the module docs of
/// [`crate::scene`]): 2D as given; 3D with one z as x, y; otherwise the
/// vertices must be coplanar and are expressed in their plane, oriented by
/// the faces' winding (without faces: seen from +z, else +y, else +x).
pub(super) fn reference_coords(
    raw: &[Vec<f64>],
    faces: Option<&[Vec<usize>]>,
    fold: &FoldFile,
) -> Result<Vec<Vector2<f64>>, SceneError> {
    let dim = raw[0].len();
    for (i, p) in raw.iter().enumerate() {
        if p.len() != dim {
            return Err(invalid(
                format!("vertices_coords[{i}]"),
                format!(
                    "has {} coordinates but vertices_coords[0] has {dim}; use one dimension",
                    p.len()
                ),
            ));
        }
        if let Some(j) = p.iter().position(|x| !x.is_finite()) {
            return Err(invalid(
                format!("vertices_coords[{i}][{j}]"),
                "is not a finite number",
            ));
        }
    }
    if dim == 2 || raw.iter().all(|p| p[2] == raw[0][2]) {
        return Ok(raw.iter().map(|p| Vector2::new(p[0], p[1])).collect());
    }
    let pts: Vec<Vector3<f64>> = raw.iter().map(|p| Vector3::new(p[0], p[1], p[2])).collect();
    let mut lo = pts[0];
    let mut hi = pts[0];
    for p in &pts {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let extent = (hi - lo).norm();
    let centroid = pts.iter().sum::<Vector3<f64>>() / pts.len() as f64;
    let mut n = match faces {
        Some(faces) => {
            // Newell's area vector of all faces: the normal of their best-fit
            // plane, pointing to the side from which the faces are
            // counter-clockwise.
            let mut n = Vector3::zeros();
            for face in faces {
                for k in 0..face.len() {
                    let a = pts[face[k]] - centroid;
                    let b = pts[face[(k + 1) % face.len()]] - centroid;
                    n += a.cross(&b);
                }
            }
            if n.norm() <= 1e-12 * extent * extent {
                return Err(invalid(
                    "vertices_coords",
                    format!(
                        "the faces have no common plane (their total area is zero): this frame \
                         is {FOLDED_STATE} or not a sheet; the reference must be a flat crease \
                         pattern"
                    ),
                ));
            }
            n.normalize()
        }
        None => best_fit_normal(&pts, centroid),
    };
    if n.z.abs() > 1.0 - 1e-9 {
        // (Nearly) the xy plane: keep +z up; clockwise faces are then
        // handled (and reported) like those of a 2D file.
        n = Vector3::z();
    }
    let (worst, dist) = pts
        .iter()
        .map(|p| (p - centroid).dot(&n).abs())
        .enumerate()
        .fold((0, 0.0), |acc, (i, d)| if d > acc.1 { (i, d) } else { acc });
    if dist > COPLANAR_TOLERANCE * extent {
        let hint = if fold.frame_classes.iter().any(|c| c == "foldedForm") {
            " (its frame_classes says foldedForm)"
        } else {
            ""
        };
        return Err(invalid(
            format!("vertices_coords[{worst}]"),
            format!(
                "this vertex is {:.3e} of the sheet size off the plane of the others: this frame \
                 is {FOLDED_STATE}{hint}, not a flat crease pattern; the model starts from the \
                 flat, unfolded crease pattern",
                dist / extent
            ),
        ));
    }
    let mut u = Vector3::x() - n * n.x;
    if u.norm() < 0.5 {
        u = Vector3::y() - n * n.y;
    }
    let u = u.normalize();
    let v = n.cross(&u);
    Ok(pts
        .iter()
        .map(|p| Vector2::new(p.dot(&u), p.dot(&v)))
        .collect())
}

/// The normal of the points' best-fit plane (the smallest principal axis
/// about `centroid`), seen from +z (else +y, else +x).
fn best_fit_normal(pts: &[Vector3<f64>], centroid: Vector3<f64>) -> Vector3<f64> {
    let mut m = nalgebra::Matrix3::zeros();
    for p in pts {
        let d = p - centroid;
        m += d * d.transpose();
    }
    let eig = m.symmetric_eigen();
    let k = eig.eigenvalues.imin();
    let mut n: Vector3<f64> = eig.eigenvectors.column(k).into_owned();
    let flip = if n.z.abs() > 1e-9 {
        n.z < 0.0
    } else if n.y.abs() > 1e-9 {
        n.y < 0.0
    } else {
        n.x < 0.0
    };
    if flip {
        n = -n;
    }
    n
}

/// No zero-length side, no zero-area face (the threshold of [`crate::mesh::Mesh::new`],
/// on the polygons before they are triangulated).
pub(super) fn check_areas(faces: &[Vec<usize>], c: &[Vector2<f64>]) -> Result<(), SceneError> {
    let mean_len2 = mean_side_length2(faces.iter().map(|f| &f[..]), c);
    for (f, face) in faces.iter().enumerate() {
        for k in 0..face.len() {
            let (a, b) = (face[k], face[(k + 1) % face.len()]);
            if (c[b] - c[a]).norm_squared() <= 1e-20 * mean_len2 {
                return Err(invalid(
                    format!("faces_vertices[{f}]"),
                    format!("vertices {a} and {b} are at the same point (zero-length side)"),
                ));
            }
        }
        let area = shoelace(face, c);
        if is_degenerate(area, mean_len2) {
            return Err(invalid(
                format!("faces_vertices[{f}]"),
                format!("has zero area ({area:.3e}): its vertices are collinear"),
            ));
        }
    }
    Ok(())
}

/// Faces counter-clockwise seen from +z: a sheet whose faces are all
/// clockwise (drawn with y pointing down) is mirrored in y, with a warning,
/// so that it is seen from the side from which its faces are
/// counter-clockwise (the rule for 3D coordinates too); a mix of clockwise
/// and counter-clockwise faces is a flat-folded state (or one wrongly
/// ordered face) and an error.
pub(super) fn orient(
    coords: &mut [Vector2<f64>],
    faces: &[Vec<usize>],
    fold: &FoldFile,
    warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    let cw: Vec<usize> = (0..faces.len())
        .filter(|&f| shoelace(&faces[f], coords) < 0.0)
        .collect();
    if cw.is_empty() {
        return Ok(());
    }
    if cw.len() == faces.len() {
        for c in coords.iter_mut() {
            c.y = 0.0 - c.y; // (not -0.0)
        }
        warnings.push(
            "faces_vertices: every face is clockwise seen from +z (the file draws with y \
             pointing down): the sheet is read mirrored in y (y -> -y), seen from the side from \
             which its faces are counter-clockwise, so that its valleys fold towards +z"
                .to_string(),
        );
        return Ok(());
    }
    let f = cw[0];
    let folded_hint = fold.frame_classes.iter().any(|c| c == "foldedForm");
    if cw.len() >= 2 || folded_hint {
        return Err(invalid(
            format!("faces_vertices[{f}]"),
            format!(
                "is clockwise while {} of the {} faces are counter-clockwise: faces lie flipped \
                 over others, so this frame is {FOLDED_STATE} (flat-folded){}, not a crease \
                 pattern; the model starts from the flat, unfolded crease pattern, whose faces \
                 are all counter-clockwise",
                faces.len() - cw.len(),
                faces.len(),
                if folded_hint {
                    ", as its frame_classes foldedForm says"
                } else {
                    ""
                }
            ),
        ));
    }
    Err(invalid(
        format!("faces_vertices[{f}]"),
        "is clockwise (inverted) while every other face is counter-clockwise; faces must be \
         counter-clockwise seen from +z: reverse its vertex order",
    ))
}

/// Every vertex is used by a face.
pub(super) fn check_used(faces: &[Vec<usize>], nv: usize) -> Result<(), SceneError> {
    let mut used = vec![false; nv];
    for face in faces {
        for &v in face {
            used[v] = true;
        }
    }
    if let Some(v) = used.iter().position(|u| !u) {
        return Err(invalid(
            format!("vertices_coords[{v}]"),
            format!("vertex {v} is not used by any face; remove it or make it part of a face"),
        ));
    }

    Ok(())
}

/// The faces cut into counter-clockwise triangles ([`ear_clip`]), and for
/// each triangle the face it comes from.
pub(super) fn triangulate(
    faces: &[Vec<usize>],
    coords: &[Vector2<f64>],
) -> Result<(Vec<[usize; 3]>, Vec<usize>), SceneError> {
    let mut triangles = Vec::new();
    let mut tri_face = Vec::new();
    for (f, face) in faces.iter().enumerate() {
        let tris = ear_clip(face, coords).map_err(|why| {
            let message = match why {
                Untriangulable::NotSimple => "is not a simple polygon (it cannot be \
                                              triangulated); check it for self-intersections"
                    .to_string(),
                Untriangulable::TooManyCorners(n) => format!(
                    "has {n} corners and is not strictly convex; faces of more than \
                     {MAX_CORNERS} corners are triangulated only when convex: split it"
                ),
            };
            invalid(format!("faces_vertices[{f}]"), message)
        })?;
        tri_face.extend(std::iter::repeat_n(f, tris.len()));
        triangles.extend(tris);
    }
    Ok((triangles, tri_face))
}

#[cfg(test)]
mod tests {
    use super::super::fixtures::{base, err, load, with};
    use crate::ids::FacetId;
    use crate::mesh::EdgeKind;
    use crate::scene::LoadOptions;
    use crate::scene::build::from_fold_with;
    use nalgebra::Vector2;
    use serde_json::{Value, json};
    use std::f64::consts::PI;

    #[test]
    fn face_errors() {
        let e = err(
            &with(
                base(),
                "faces_vertices",
                json!([[0, 1, 4, 1], [1, 2, 3, 4]]),
            ),
            "faces_vertices[0]",
        );
        assert!(e.contains("zero area"), "{e}");
        // two triangles touching at vertex 2: a face that touches itself
        let v = json!({
            "frame_unit": "m",
            "vertices_coords": [[0,0],[2,0],[1,1],[2,2],[0,2]],
            "faces_vertices": [[0,1,2,3,4,2]]
        });
        let e = err(&v, "faces_vertices[0]");
        assert!(e.contains("repeats vertex 2 without a slit"), "{e}");
        // a crease from a corner to the centre of a square: a slit face,
        // triangulated with the crease between two triangles
        let v = json!({
            "frame_unit": "m",
            "vertices_coords": [[0,0],[1,0],[1,1],[0,1],[0.5,0.5]],
            "edges_vertices": [[0,1],[1,2],[2,3],[3,0],[0,4]],
            "edges_assignment": ["B","B","B","B","V"],
            "edges_foldAngle": [0,0,0,0,90],
            "faces_vertices": [[0,4,0,1,2,3]]
        });
        let parsed = crate::scene::fold::parse(&v.to_string(), None).unwrap().0;
        let l = from_fold_with(&parsed, &LoadOptions::default()).unwrap();
        assert!(
            l.notes.iter().any(|n| n.starts_with("slits: 1 face")),
            "{:?}",
            l.notes
        );
        let m = &l.scene.mesh;
        assert_eq!(m.edges()[4].kind, EdgeKind::Crease);
        assert_eq!(m.edge_faces()[4].len(), 2);
        assert_eq!(m.triangles().len(), 4);
        let mut model = crate::model::Model::new(l.scene.clone()).unwrap();
        model.initialize().unwrap();
        let e = err(
            &with(base(), "faces_vertices", json!([[0, 1], [1, 2, 3, 4]])),
            "faces_vertices[0]",
        );
        assert!(e.contains("at least 3"), "{e}");
        let e = err(
            &with(
                base(),
                "faces_vertices",
                json!([[0, 5, 4, 1], [1, 2, 3, 4]]),
            ),
            "faces_vertices[0]",
        );
        assert!(e.contains("clockwise"), "{e}");
        assert!(!e.contains("every face"), "{e}");
        // every face clockwise: mirrored in y, with a warning
        let (s, w) = load(&with(
            base(),
            "faces_vertices",
            json!([[0, 5, 4, 1], [1, 4, 3, 2]]),
        ))
        .unwrap();
        assert!(w[0].contains("every face is clockwise"), "{w:?}");
        assert_eq!(s.mesh.coords()[3], Vector2::new(2.0, -1.0));
        assert!((s.mesh.edges()[6].fold_target - PI / 2.0).abs() < 1e-15);
        // clockwise and counter-clockwise faces: a flat-folded state
        let v = json!({
            "frame_unit": "m",
            "frame_classes": ["foldedForm"],
            "vertices_coords": [[0,0],[1,0],[0,0],[0,1]],
            "faces_vertices": [[0,1,3],[1,2,3]]
        });
        let e = err(&v, "faces_vertices[1]");
        assert!(
            e.contains("folded state (flat-folded)") && e.contains("foldedForm"),
            "{e}"
        );
        // collinear: vertices 0, 1, 2 on the x axis
        let mut v = with(
            base(),
            "faces_vertices",
            json!([[0, 1, 2], [0, 1, 4, 5], [1, 2, 3, 4]]),
        );
        v["edges_vertices"] = json!([]);
        v["edges_assignment"] = json!([]);
        v["edges_foldAngle"] = json!([]);
        let e = err(&v, "faces_vertices[0]");
        assert!(e.contains("zero area"), "{e}");
        // coincident vertices
        let v = with(
            base(),
            "vertices_coords",
            json!([[0, 0], [1, 0], [2, 0], [2, 1], [1, 1], [1, 1]]),
        );
        let e = err(&v, "faces_vertices[0]");
        assert!(e.contains("same point"), "{e}");
    }

    #[test]
    fn planes() {
        // 3D with one z: as 2D
        let v = with(
            base(),
            "vertices_coords",
            json!([
                [0, 0, 3],
                [1, 0, 3],
                [2, 0, 3],
                [2, 1, 3],
                [1, 1, 3],
                [0, 1, 3]
            ]),
        );
        let (s, _) = load(&v).unwrap();
        assert_eq!(s.mesh.coords()[3], Vector2::new(2.0, 1.0));
        // Origami Simulator style: the pattern in the xz plane
        let v = with(
            base(),
            "vertices_coords",
            json!([
                [0, 0, 0],
                [1, 0, 0],
                [2, 0, 0],
                [2, 0, 1],
                [1, 0, 1],
                [0, 0, 1]
            ]),
        );
        let (s, _) = load(&v).unwrap();
        let (flat, _) = load(&base()).unwrap();
        for t in (0..4).map(FacetId) {
            assert!((s.mesh.area(t) - flat.mesh.area(t)).abs() < 1e-15);
        }
        for e in s.mesh.edge_ids() {
            assert!((s.mesh.edge_length(e) - flat.mesh.edge_length(e)).abs() < 1e-15);
        }
        // a tilted plane
        let (c, sn) = (0.6f64, 0.8f64);
        let pts: Vec<Value> = [[0., 0.], [1., 0.], [2., 0.], [2., 1.], [1., 1.], [0., 1.]]
            .iter()
            .map(|p| json!([p[0], c * p[1], sn * p[1]]))
            .collect();
        let (s, _) = load(&with(base(), "vertices_coords", Value::from(pts.clone()))).unwrap();
        for e in s.mesh.edge_ids() {
            assert!((s.mesh.edge_length(e) - flat.mesh.edge_length(e)).abs() < 1e-14);
        }
        // folded: not flat
        let mut bent = pts;
        bent[2] = json!([2.0, 0.0, 0.3]);
        let e = err(
            &with(base(), "vertices_coords", Value::from(bent)),
            "vertices_coords[2]",
        );
        assert!(e.contains("flat crease pattern"), "{e}");
        // mixed dimensions
        let v = with(
            base(),
            "vertices_coords",
            json!([[0, 0], [1, 0], [2, 0], [2, 1, 0], [1, 1], [0, 1]]),
        );
        err(&v, "vertices_coords[3]");
    }
}
