//! A FOLD file's frames as keyframes of a folding sequence: the frames
//! after the crease pattern read, in order, one stage each, their fold
//! angles from their own `edges_foldAngle`, else from the dihedral angles
//! of their folded `vertices_coords` (docs/scenes.md, "Frames as
//! keyframes").
//!
//! The frames are read here ([`read`]); the builder turns them into stages
//! on the pattern's mesh ([`stages`]), where the facets on either side of
//! each crease are known.

use super::error::SceneError;
use super::fold::{Assignment, FoldFile, FrameSelector, Frames};
use super::keys::{EdgeSelection, StageSpec, StageTarget};
use super::sequence::MAX_STAGES;
use crate::ids::{EdgeId, VertexId};
use crate::mesh::{EdgeKind, Mesh};
use nalgebra::Vector3;

/// Where a keyframe's fold angles come from.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum AngleSource {
    /// Its own `edges_foldAngle` (degrees; `None` for null: not named).
    Given(Vec<Option<f64>>),
    /// Its folded `vertices_coords` (2D or 3D), one per FOLD vertex.
    Folded(Vec<Vec<f64>>),
}

/// A frame after the crease pattern, read as a keyframe.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct KeyFrame {
    /// FOLD frame number (`file_frames[frame - 1]`).
    pub frame: usize,
    /// `frame_title`.
    pub title: Option<String>,
    /// Its fold angles.
    pub source: AngleSource,
    /// Its `edges_assignment` (own or inherited): the side of a crease
    /// folded flat.
    pub assignment: Option<Vec<Assignment>>,
}

/// Why the frames after the crease pattern are not keyframes.
#[derive(Debug)]
pub(crate) struct NotKeyframes {
    /// The first frame that is not one, and why.
    pub error: SceneError,
    /// Whether any following frame carries fold angles or folded
    /// coordinates (else the file simply has no keyframes).
    pub any_angles: bool,
}

/// `file_frames[k-1]`, the key of FOLD frame `k`.
fn frame_key(k: usize) -> String {
    format!("file_frames[{}]", k - 1)
}

/// The frames after frame `cp` (the crease pattern, read as `cp_file`) as
/// keyframes, in order; each must fold the same pattern (its vertices and
/// edges) and carry fold angles (its own `edges_foldAngle`) or folded
/// `vertices_coords`.
pub(crate) fn read(
    frames: &Frames,
    cp: usize,
    cp_file: &FoldFile,
) -> Result<Vec<KeyFrame>, NotKeyframes> {
    let mut out = Vec::new();
    let mut any_angles = false;
    let mut first_error = None;
    let count = frames.len().saturating_sub(cp + 1);
    if count > MAX_STAGES {
        return Err(NotKeyframes {
            error: SceneError::invalid(
                "file_frames",
                format!("{count} frames follow the crease pattern; at most {MAX_STAGES} keyframes"),
            ),
            any_angles: true,
        });
    }
    for k in cp + 1..frames.len() {
        match keyframe(frames, k, cp, cp_file) {
            Ok(kf) => {
                any_angles = true;
                out.push(kf);
            }
            Err((e, carries)) => {
                any_angles |= carries;
                first_error.get_or_insert(e);
            }
        }
    }
    match first_error {
        Some(error) => Err(NotKeyframes { error, any_angles }),
        None if out.is_empty() => Err(NotKeyframes {
            error: SceneError::invalid(
                "file_frames",
                format!("no frame follows the crease pattern (frame {cp})"),
            ),
            any_angles: false,
        }),
        None => Ok(out),
    }
}

/// FOLD frame `k` as a keyframe, or why not (and whether it carries angles).
fn keyframe(
    frames: &Frames,
    k: usize,
    cp: usize,
    cp_file: &FoldFile,
) -> Result<KeyFrame, (SceneError, bool)> {
    let key = frame_key(k);
    let (f, _) = frames
        .frame(Some(&FrameSelector::Index(k)))
        .map_err(|e| (e, false))?;
    let own_angles = frames.has_own(k, "edges_foldAngle") || frames.has_own(k, "edges_foldAngles");
    let folded = coords_differ(&f.vertices_coords, &cp_file.vertices_coords);
    let carries = own_angles || folded;
    let refuse =
        |sub: &str, why: String| (SceneError::invalid(format!("{key}{sub}"), why), carries);
    let nv = cp_file.vertices_coords.len();
    if f.vertices_coords.len() != nv {
        return Err(refuse(
            ".vertices_coords",
            format!(
                "has {} vertices, the crease pattern (frame {cp}) {nv}: a keyframe folds the \
                 same pattern",
                f.vertices_coords.len()
            ),
        ));
    }
    if f.edges_vertices != cp_file.edges_vertices {
        return Err(refuse(
            ".edges_vertices",
            format!(
                "differs from the crease pattern's (frame {cp}): a keyframe folds the same \
                 pattern"
            ),
        ));
    }
    let source = if own_angles {
        let angles = f.edges_fold_angle.clone().unwrap_or_default();
        let ne = cp_file.edges_vertices.as_ref().map_or(0, Vec::len);
        if angles.len() != ne {
            return Err(refuse(
                ".edges_foldAngle",
                format!("has {} angles for {ne} edges", angles.len()),
            ));
        }
        AngleSource::Given(angles)
    } else if folded {
        AngleSource::Folded(f.vertices_coords.clone())
    } else {
        return Err(refuse(
            "",
            "carries no fold angles (no edges_foldAngle of its own, and its vertices_coords \
             are the crease pattern's)"
                .into(),
        ));
    };
    Ok(KeyFrame {
        frame: k,
        // Its own title: an inherited one names the parent.
        title: f
            .frame_title
            .clone()
            .filter(|_| frames.has_own(k, "frame_title")),
        source,
        assignment: f.edges_assignment.clone(),
    })
}

/// Whether two vertex lists differ by more than round-off of their size
/// (a missing z is 0).
fn coords_differ(a: &[Vec<f64>], b: &[Vec<f64>]) -> bool {
    if a.len() != b.len() {
        return true;
    }
    let at = |p: &[f64], i: usize| p.get(i).copied().unwrap_or(0.0);
    let mut size: f64 = 0.0;
    let mut diff: f64 = 0.0;
    for (p, q) in a.iter().zip(b) {
        for i in 0..3 {
            size = size.max(at(q, i).abs());
            diff = diff.max((at(p, i) - at(q, i)).abs());
        }
    }
    diff > 1e-9 * size.max(f64::MIN_POSITIVE)
}

/// The stages of `keyframes` on the crease pattern's `mesh` (before
/// refinement: FOLD edge `e` is mesh edge `e`; mesh vertex `nv + j` is a
/// copy of FOLD vertex `copies[j]`), one per keyframe, sharing the drive
/// equally: every crease to its angle in the frame. `kind`, `assignment`
/// and `target` are the FOLD edges' (the crease pattern's). Angles beyond
/// +-180 degrees are clamped, with a warning.
pub(crate) fn stages(
    keyframes: &[KeyFrame],
    mesh: &Mesh,
    (nv, copies): (usize, &[usize]),
    (kind, target): (&[EdgeKind], &[f64]),
    warnings: &mut Vec<String>,
) -> Result<Vec<StageSpec>, SceneError> {
    let creases: Vec<usize> = (0..kind.len())
        .filter(|&e| kind[e] == EdgeKind::Crease)
        .collect();
    let fold_vertex = |v: VertexId| {
        let i = v.index();
        if i < nv { i } else { copies[i - nv] }
    };
    // Each crease's angle after the stages so far (rad): the side a crease
    // folded flat keeps.
    let mut previous: Vec<f64> = vec![0.0; kind.len()];
    let mut clamped = 0usize;
    let mut out = Vec::with_capacity(keyframes.len());
    for kf in keyframes {
        let key = frame_key(kf.frame);
        let mut named = Vec::new();
        let mut degrees = Vec::new();
        for &e in &creases {
            let angle = match &kf.source {
                AngleSource::Given(list) => match list.get(e).copied().flatten() {
                    Some(d) => d.to_radians(),
                    None => continue,
                },
                AngleSource::Folded(coords) => {
                    let point = |v: VertexId| {
                        let p = &coords[fold_vertex(v)];
                        Vector3::new(
                            p.first().copied().unwrap_or(0.0),
                            p.get(1).copied().unwrap_or(0.0),
                            p.get(2).copied().unwrap_or(0.0),
                        )
                    };
                    let side = kf
                        .assignment
                        .as_ref()
                        .and_then(|a| a.get(e))
                        .and_then(|a| match a {
                            Assignment::Mountain => Some(-1.0),
                            Assignment::Valley => Some(1.0),
                            _ => None,
                        })
                        .or_else(|| (previous[e] != 0.0).then(|| previous[e].signum()))
                        .unwrap_or(if target[e] < 0.0 { -1.0 } else { 1.0 });
                    crease_dihedral(mesh, EdgeId(e), point, side).ok_or_else(|| {
                        SceneError::invalid(
                            format!("{key}.vertices_coords"),
                            format!(
                                "a facet beside FOLD edge {e} has no area in this frame, so \
                                 its fold angle is undefined"
                            ),
                        )
                    })?
                }
            };
            let deg = angle.to_degrees();
            if deg.abs() > 180.0 {
                clamped += 1;
            }
            let deg = deg.clamp(-180.0, 180.0);
            previous[e] = deg.to_radians();
            named.push(e);
            degrees.push(deg);
        }
        if named.is_empty() {
            return Err(SceneError::invalid(
                format!("{key}.edges_foldAngle"),
                "gives no crease an angle (every entry is null): a keyframe must fold",
            ));
        }
        out.push(StageSpec {
            edges: EdgeSelection::List(named),
            target: StageTarget::DegreesEach(degrees),
            share: None,
            title: Some(
                kf.title
                    .clone()
                    .unwrap_or_else(|| format!("frame {}", kf.frame)),
            ),
            key,
        });
    }
    if clamped > 0 {
        warnings.push(format!(
            "file_frames: {clamped} keyframe angle(s) beyond +-180 degrees read as +-180 (a \
             crease cannot fold past flat)"
        ));
    }
    Ok(out)
}

/// The fold angle (rad, valley positive) of mesh crease `e` between its
/// two facets at the vertex positions `point`: the signed angle between
/// their normals about the crease, seen from the facets' front (the side
/// their counter-clockwise order faces in the pattern). Folded flat
/// (within 1e-9 rad of +-pi) it takes the sign `side`. None when a facet
/// has no area or the crease has not two facets.
pub(crate) fn crease_dihedral(
    mesh: &Mesh,
    e: EdgeId,
    point: impl Fn(VertexId) -> Vector3<f64>,
    side: f64,
) -> Option<f64> {
    let [t1, t2] = mesh.faces_of(e) else {
        return None;
    };
    let edge = mesh.edge(e);
    let tri1 = mesh.triangles()[t1.index()];
    let tri2 = mesh.triangles()[t2.index()];
    let normal = |t: [VertexId; 3]| {
        let n = (point(t[1]) - point(t[0])).cross(&(point(t[2]) - point(t[0])));
        let len = n.norm();
        (len > 0.0 && len.is_finite()).then(|| n / len)
    };
    let (n1, n2) = (normal(tri1)?, normal(tri2)?);
    // The crease as the first facet runs along it (its interior on the left).
    let k = tri1.iter().position(|&v| v == edge.v[0])?;
    let (a, b) = if tri1[(k + 1) % 3] == edge.v[1] {
        (edge.v[0], edge.v[1])
    } else {
        (edge.v[1], edge.v[0])
    };
    let d = (point(b) - point(a)).normalize();
    let angle = (-n1.cross(&n2).dot(&d)).atan2(n1.dot(&n2));
    let pi = std::f64::consts::PI;
    Some(if angle.abs() > pi - 1e-9 {
        pi.copysign(side)
    } else {
        angle
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::builders;

    /// Two unit panels hinged on a crease: the second turned about it by
    /// `phi` toward the front (a valley for phi > 0).
    fn hinged(phi: f64) -> (Mesh, Vec<Vector3<f64>>) {
        let mesh = builders::grid(2.0, 1.0, 2, 1, &[(1, 1.0)]);
        let pts: Vec<Vector3<f64>> = mesh
            .coords()
            .iter()
            .map(|c| {
                if c.x <= 1.0 {
                    Vector3::new(c.x, c.y, 0.0)
                } else {
                    let r = c.x - 1.0;
                    Vector3::new(1.0 + r * phi.cos(), c.y, r * phi.sin())
                }
            })
            .collect();
        (mesh, pts)
    }

    fn crease(mesh: &Mesh) -> EdgeId {
        mesh.edge_ids()
            .find(|&e| mesh.edge(e).kind == EdgeKind::Crease)
            .unwrap()
    }

    /// Lifting the panel toward +z (the front) is a valley, positive; away
    /// from it a mountain; flat folded takes the given side.
    #[test]
    fn dihedral_sign_and_flat_side() {
        for phi in [0.3f64, 1.2, 2.5, -0.7, -2.9] {
            let (mesh, pts) = hinged(phi);
            let a = crease_dihedral(&mesh, crease(&mesh), |v| pts[v.index()], 1.0).unwrap();
            assert!((a - phi).abs() < 1e-12, "{a} vs {phi}");
        }
        let (mesh, pts) = hinged(std::f64::consts::PI);
        let e = crease(&mesh);
        let pi = std::f64::consts::PI;
        assert_eq!(
            crease_dihedral(&mesh, e, |v| pts[v.index()], -1.0),
            Some(-pi)
        );
        assert_eq!(crease_dihedral(&mesh, e, |v| pts[v.index()], 1.0), Some(pi));
        let (mesh, pts) = hinged(0.0);
        let flat = crease_dihedral(&mesh, crease(&mesh), |v| pts[v.index()], 1.0).unwrap();
        assert!(flat.abs() < 1e-15);
    }
}
