//! The edges: the face sides and who shares them ([`Sides`]: non-manifold
//! and overlapping faces), the edges as listed in the file ([`read_edges`])
//! or derived from the faces, and their mechanical kinds and target angles
//! ([`fold_edges`]).

use super::{invalid, vertex_exists};
use crate::mesh::EdgeKind;
use crate::scene::FlatEdges;
use crate::scene::error::SceneError;
use crate::scene::fold::{Assignment, FoldFile};
use crate::scene::planar::SideAt;
use std::collections::HashMap;

/// Where a side occurs: face, position in it, and whether it runs from the
/// smaller vertex index to the larger.
pub(super) type Occurrence = (usize, usize, bool);

/// Face sides, keyed by sorted vertex pair: where they occur (face,
/// position) and in which direction.
pub(super) struct Sides {
    pub(super) map: HashMap<(usize, usize), Vec<Occurrence>>,
    /// Keys in the order of first appearance (face by face).
    pub(super) order: Vec<(usize, usize)>,
}

pub(super) fn key(a: usize, b: usize) -> (usize, usize) {
    if a < b { (a, b) } else { (b, a) }
}

impl Sides {
    pub(super) fn new(faces: &[Vec<usize>]) -> Result<Sides, SceneError> {
        let n: usize = faces.iter().map(Vec::len).sum();
        let mut map: HashMap<(usize, usize), Vec<Occurrence>> = HashMap::with_capacity(n);
        let mut order = Vec::with_capacity(n / 2 + 1);
        for (f, face) in faces.iter().enumerate() {
            for k in 0..face.len() {
                let (a, b) = (face[k], face[(k + 1) % face.len()]);
                let list = map.entry(key(a, b)).or_insert_with(|| {
                    order.push(key(a, b));
                    Vec::new()
                });
                list.push((f, k, a < b));
            }
        }
        for k in &order {
            let list = &map[k];
            if list.len() > 2 {
                let fs: Vec<usize> = list.iter().map(|x| x.0).collect();
                return Err(invalid(
                    format!("faces_vertices[{}]", list[2].0),
                    format!(
                        "edge {}-{} is shared by faces {fs:?}; at most two faces may share an \
                         edge (non-manifold)",
                        k.0, k.1
                    ),
                ));
            }
            if list.len() == 2 && list[0].2 == list[1].2 {
                return Err(invalid(
                    format!("faces_vertices[{}]", list[1].0),
                    format!(
                        "runs along edge {}-{} in the same direction as face {}: the two faces \
                         overlap",
                        k.0, k.1, list[0].0
                    ),
                ));
            }
        }
        Ok(Sides { map, order })
    }
    pub(super) fn count(&self, a: usize, b: usize) -> usize {
        self.map.get(&key(a, b)).map_or(0, Vec::len)
    }
    pub(super) fn faces(&self, a: usize, b: usize) -> Vec<usize> {
        self.map
            .get(&key(a, b))
            .map_or(vec![], |l| l.iter().map(|x| x.0).collect())
    }
    /// The occurrences (face, position) of side a-b.
    pub(super) fn at(&self, a: usize, b: usize) -> Vec<SideAt> {
        self.map
            .get(&key(a, b))
            .map_or(vec![], |l| l.iter().map(|x| (x.0, x.1)).collect())
    }
}

/// The edges as listed in the file, checked: indices, loops, repeats,
/// array lengths.
pub(super) struct Listed {
    pub(super) v: Vec<[usize; 2]>,
    pub(super) assignment: Vec<Assignment>,
    pub(super) angles: Vec<Option<f64>>,
}

pub(super) fn read_edges(
    fold: &FoldFile,
    nv: usize,
    warnings: &mut Vec<String>,
) -> Result<Option<Listed>, SceneError> {
    let Some(ev) = &fold.edges_vertices else {
        if fold.edges_assignment.is_some() || fold.edges_fold_angle.is_some() {
            return Err(invalid(
                "edges_vertices",
                "is missing, but edges_assignment or edges_foldAngle is given; they refer to \
                 edges_vertices",
            ));
        }
        return Ok(None);
    };
    let ne = ev.len();
    let mut seen: HashMap<(usize, usize), usize> = HashMap::with_capacity(ne);
    for (e, &[a, b]) in ev.iter().enumerate() {
        for (j, x) in [a, b].into_iter().enumerate() {
            vertex_exists(x, nv, || format!("edges_vertices[{e}][{j}]"))?;
        }
        if a == b {
            return Err(invalid(
                format!("edges_vertices[{e}]"),
                format!("both ends are vertex {a}: an edge needs two vertices; remove it"),
            ));
        }
        if let Some(first) = seen.insert(key(a, b), e) {
            return Err(invalid(
                format!("edges_vertices[{e}]"),
                format!(
                    "repeats edges_vertices[{first}] (vertices {a}-{b}); an edge may be listed \
                     once: remove one of them"
                ),
            ));
        }
    }
    // Per-edge arrays have one entry per edge.
    let per_edge = |key: &str, len: usize| {
        if len == ne {
            Ok(())
        } else {
            Err(invalid(
                key,
                format!(
                    "has {len} entries but edges_vertices has {ne}; the arrays must have the same \
                     length"
                ),
            ))
        }
    };
    let assignment = match &fold.edges_assignment {
        Some(a) => {
            per_edge("edges_assignment", a.len())?;
            a.clone()
        }
        None => {
            warnings.push(
                "edges_assignment is missing: interior edges are read as U (creases with the \
                 angle of edges_foldAngle, else 0), boundary edges as B"
                    .to_string(),
            );
            vec![Assignment::Unassigned; ne]
        }
    };
    let angles = match &fold.edges_fold_angle {
        Some(a) => {
            per_edge("edges_foldAngle", a.len())?;
            a.clone()
        }
        None => vec![None; ne],
    };
    Ok(Some(Listed {
        v: ev.clone(),
        assignment,
        angles,
    }))
}

/// The FOLD edges of the scene, with their mechanical kinds and targets.
pub(super) struct FoldEdges {
    pub v: Vec<[usize; 2]>,
    pub assignment: Vec<Assignment>,
    pub kind: Vec<EdgeKind>,
    /// Target fold angle in radians.
    pub target: Vec<f64>,
}

impl FoldEdges {
    /// The FOLD edges that are creases, in order.
    pub(super) fn creases(&self) -> Vec<usize> {
        (0..self.v.len())
            .filter(|&e| self.kind[e] == EdgeKind::Crease)
            .collect()
    }
}

pub(super) fn fold_edges(
    listed: Option<Listed>,
    sides: &Sides,
    f_mode: FlatEdges,
    warnings: &mut Vec<String>,
) -> Result<FoldEdges, SceneError> {
    let Listed {
        v,
        assignment,
        angles,
    } = match listed {
        Some(l) => l,
        None => derived_edges(sides, warnings),
    };

    let ne = v.len();
    let is_crease =
        |a: Assignment| a.is_crease() || (a == Assignment::Flat && f_mode == FlatEdges::Crease);
    let mut kind = Vec::with_capacity(ne);
    let mut target = Vec::with_capacity(ne);
    let mut crease_on_boundary: Vec<usize> = Vec::new();
    for e in 0..ne {
        let [a, b] = v[e];
        let nf = sides.count(a, b);
        if nf == 0 {
            return Err(invalid(
                format!("edges_vertices[{e}]"),
                format!(
                    "edge {a}-{b} is not a side of any face; every edge must border one or two \
                     faces (it may cross a face or end inside one): split the faces along it, or \
                     remove faces_vertices to have the faces traced from the edges"
                ),
            ));
        }
        let asg_key = format!("edges_assignment[{e}]");
        let k = match assignment[e] {
            Assignment::Mountain | Assignment::Valley if nf == 1 => {
                crease_on_boundary.push(e);
                EdgeKind::Boundary
            }
            Assignment::Boundary if nf == 2 => {
                let fs = sides.faces(a, b);
                return Err(invalid(
                    asg_key,
                    format!(
                        "edge {a}-{b} is marked B (boundary) but borders two faces ({} and {}): \
                         mark it C to cut the sheet there, or M, V, F or J",
                        fs[0], fs[1]
                    ),
                ));
            }
            Assignment::Cut => EdgeKind::Boundary,
            _ if nf == 1 => EdgeKind::Boundary,
            x if is_crease(x) => EdgeKind::Crease,
            _ => EdgeKind::Smooth,
        };
        let angle_key = format!("edges_foldAngle[{e}]");
        if let Some(d) = angles[e]
            && !(-180.0..=180.0).contains(&d)
        {
            return Err(invalid(
                angle_key,
                format!("{d} degrees is outside [-180, 180]"),
            ));
        }
        let deg = target_degrees(e, k, assignment[e], angles[e], [a, b], warnings);
        kind.push(k);
        target.push(deg.to_radians());
    }
    if let Some(&e) = crease_on_boundary.first() {
        let [a, b] = v[e];
        warnings.push(format!(
            "edges_assignment[{e}]: {} crease(s) on the boundary (first: {} on edge {a}-{b}, \
             which borders only face {}) are read as boundary edges; a crease needs a face on \
             each side",
            crease_on_boundary.len(),
            assignment[e].letter(),
            sides.faces(a, b)[0]
        ));
    }

    warn_unlisted_sides(&v, sides, warnings);
    Ok(FoldEdges {
        v,
        assignment,
        kind,
        target,
    })
}

/// Without edges_vertices: the faces' sides, numbered in order of first
/// appearance (interior ones as U creases, boundary ones as B).
fn derived_edges(sides: &Sides, warnings: &mut Vec<String>) -> Listed {
    let v: Vec<[usize; 2]> = sides
        .order
        .iter()
        // In the direction of the first appearance.
        .map(|k| {
            if sides.map[k][0].2 {
                [k.0, k.1]
            } else {
                [k.1, k.0]
            }
        })
        .collect();
    let asg = sides
        .order
        .iter()
        .map(|k| {
            if sides.map[k].len() == 1 {
                Assignment::Boundary
            } else {
                Assignment::Unassigned
            }
        })
        .collect();
    warnings.push(format!(
        "edges_vertices is missing: {} edges were derived from faces_vertices (interior \
         edges as U creases with target 0, boundary edges as B), numbered in order of \
         first appearance in faces_vertices",
        v.len()
    ));
    let n = v.len();
    Listed {
        v,
        assignment: asg,
        angles: vec![None; n],
    }
}

/// The target fold angle (degrees) of FOLD edge `e` (`ab` its vertices) of
/// kind `k`: the file's angle, else full mountain or valley, else 0; an
/// angle against the assignment, or on an edge that is not a crease, is
/// noted.
fn target_degrees(
    e: usize,
    k: EdgeKind,
    assignment: Assignment,
    angle: Option<f64>,
    [a, b]: [usize; 2],
    warnings: &mut Vec<String>,
) -> f64 {
    let angle_key = format!("edges_foldAngle[{e}]");
    if k == EdgeKind::Crease {
        match (assignment, angle) {
            (Assignment::Mountain, None) => -180.0,
            (Assignment::Valley, None) => 180.0,
            (_, None) => 0.0,
            (Assignment::Mountain, Some(d)) if d > 0.0 => {
                warnings.push(format!(
                    "{angle_key}: mountain crease {a}-{b} has the valley (positive) angle {d}; \
                     the angle's sign wins"
                ));
                d
            }
            (Assignment::Valley, Some(d)) if d < 0.0 => {
                warnings.push(format!(
                    "{angle_key}: valley crease {a}-{b} has the mountain (negative) angle {d}; \
                     the angle's sign wins"
                ));
                d
            }
            (_, Some(d)) => d,
        }
    } else {
        if let Some(d) = angle.filter(|&d| d != 0.0) {
            warnings.push(format!(
                "{angle_key}: the angle {d} of the {} edge {a}-{b} is ignored (not a crease)",
                assignment.letter()
            ));
        }
        0.0
    }
}

/// Face sides that are not FOLD edges (only possible with edges_vertices).
fn warn_unlisted_sides(v: &[[usize; 2]], sides: &Sides, warnings: &mut Vec<String>) {
    let listed: std::collections::HashSet<(usize, usize)> =
        v.iter().map(|&[a, b]| key(a, b)).collect();
    let missing: Vec<&(usize, usize)> =
        sides.order.iter().filter(|k| !listed.contains(k)).collect();
    if let Some(first) = missing.first() {
        warnings.push(format!(
            "edges_vertices: {} face side(s) are not listed (first: {}-{}); they are read as \
             smooth or boundary edges without crease outputs",
            missing.len(),
            first.0,
            first.1
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::super::fixtures::{base, err, load, with};
    use super::*;
    use crate::ids::{EdgeId, FoldEdgeId};
    use crate::scene::LoadOptions;
    use crate::scene::build::from_fold_with;
    use serde_json::{Value, json};
    use std::f64::consts::PI;

    #[test]
    fn missing_angles_fold_fully_and_signs_win_with_a_warning() {
        let v = with(base(), "edges_foldAngle", Value::Null);
        let v = v.as_object().unwrap().clone();
        let mut v = Value::Object(v);
        v.as_object_mut().unwrap().remove("edges_foldAngle");
        let (s, _) = load(&v).unwrap();
        assert_eq!(s.mesh.edges()[6].fold_target, PI);
        let v = with(
            v,
            "edges_assignment",
            json!(["B", "B", "B", "B", "B", "B", "M"]),
        );
        let (s, _) = load(&v).unwrap();
        assert_eq!(s.mesh.edges()[6].fold_target, -PI);
        let v = with(v, "edges_foldAngle", json!([0, 0, 0, 0, 0, 0, 45]));
        let (s, w) = load(&v).unwrap();
        assert!((s.mesh.edges()[6].fold_target - PI / 4.0).abs() < 1e-15);
        assert_eq!(w.len(), 1);
        assert!(
            w[0].starts_with("edges_foldAngle[6]: mountain crease"),
            "{w:?}"
        );
        // U without angle: a free crease with target 0
        let v = with(
            v,
            "edges_assignment",
            json!(["B", "B", "B", "B", "B", "B", "U"]),
        );
        let v = with(v, "edges_foldAngle", json!([0, 0, 0, 0, 0, 0, null]));
        let (s, _) = load(&v).unwrap();
        assert_eq!(s.mesh.edges()[6].kind, EdgeKind::Crease);
        assert_eq!(s.mesh.edges()[6].fold_target, 0.0);
    }

    #[test]
    fn inconsistent_lengths_and_indices() {
        let e = err(
            &with(base(), "edges_assignment", json!(["B", "B", "V"])),
            "edges_assignment",
        );
        assert!(e.contains("same length"), "{e}");
        let e = err(
            &with(base(), "edges_foldAngle", json!([1, 2])),
            "edges_foldAngle",
        );
        assert!(e.contains("same length"), "{e}");
        let e = err(
            &with(
                base(),
                "faces_vertices",
                json!([[0, 1, 4, 5], [1, 2, 9, 4]]),
            ),
            "faces_vertices[1][2]",
        );
        assert!(e.contains("vertex 9 does not exist"), "{e}");
        let mut v = base();
        v["edges_vertices"][3] = json!([3, 40]);
        let e = err(&v, "edges_vertices[3][1]");
        assert!(e.contains("vertex 40"), "{e}");
        let mut v = base();
        v["edges_vertices"][3] = json!([3, 3]);
        err(&v, "edges_vertices[3]");
        let mut v = with(base(), "edges_vertices", Value::Null);
        v.as_object_mut().unwrap().remove("edges_vertices");
        err(&v, "edges_vertices");
    }

    #[test]
    fn non_manifold_and_overlapping_faces() {
        // a third face on edge 1-4
        let v = json!({
            "vertices_coords": [[0,0],[1,0],[2,0],[2,1],[1,1],[0,1],[1.5,0.5]],
            "faces_vertices": [[0,1,4,5],[1,2,3,4],[1,6,4]]
        });
        let e = err(&v, "faces_vertices[2]");
        assert!(e.contains("non-manifold") && e.contains("1-4"), "{e}");
        // the same square twice
        let v = json!({
            "vertices_coords": [[0,0],[1,0],[1,1],[0,1]],
            "faces_vertices": [[0,1,2,3],[0,1,2,3]]
        });
        let e = err(&v, "faces_vertices[1]");
        assert!(e.contains("overlap"), "{e}");
    }

    #[test]
    fn edge_errors() {
        let mut v = base();
        v["edges_vertices"][5] = json!([1, 0]);
        let e = err(&v, "edges_vertices[5]");
        assert!(e.contains("repeats edges_vertices[0]"), "{e}");
        // a crease on the boundary: read as boundary, with a warning
        let v = with(
            base(),
            "edges_assignment",
            json!(["V", "B", "B", "B", "B", "B", "V"]),
        );
        let (s, w) = load(&v).unwrap();
        assert_eq!(s.mesh.edges()[0].kind, EdgeKind::Boundary);
        assert!(
            w[0].starts_with("edges_assignment[0]: 1 crease(s) on the boundary"),
            "{w:?}"
        );
        let v = with(
            base(),
            "edges_assignment",
            json!(["B", "B", "B", "B", "B", "B", "B"]),
        );
        let e = err(&v, "edges_assignment[6]");
        assert!(
            e.contains("borders two faces") && e.contains("mark it C"),
            "{e}"
        );
        let v = with(base(), "edges_foldAngle", json!([0, 0, 0, 0, 0, 0, 180.5]));
        let e = err(&v, "edges_foldAngle[6]");
        assert!(e.contains("outside [-180, 180]"), "{e}");
        let v = with(base(), "edges_foldAngle", json!([0, 0, 0, 0, 0, 0, -181]));
        err(&v, "edges_foldAngle[6]");
        // an edge across a face (0-4 is a diagonal of face 0)
        let mut v = base();
        v["edges_vertices"][6] = json!([0, 4]);
        let e = err(&v, "edges_vertices[6]");
        assert!(e.contains("not a side of any face"), "{e}");
        // U on the boundary is a boundary edge; F inside is a crease with
        // target 0 (FOLD), or smooth when asked or in an Origami Simulator
        // export; J is smooth
        let v = with(
            base(),
            "edges_assignment",
            json!(["U", "B", "B", "B", "B", "B", "F"]),
        );
        let mut v = v;
        v.as_object_mut().unwrap().remove("edges_foldAngle");
        let (s, w) = load(&v).unwrap();
        assert_eq!(s.mesh.edges()[0].kind, EdgeKind::Boundary);
        assert_eq!(s.mesh.edges()[6].kind, EdgeKind::Crease);
        assert_eq!(s.mesh.edges()[6].fold_target, 0.0);
        assert_eq!(s.actuators[0].edges, vec![EdgeId(6)]);
        assert!(w.iter().any(|w| w.contains("drives nothing")), "{w:?}");
        let parsed = crate::scene::fold::parse(&v.to_string(), None).unwrap().0;
        let smooth = LoadOptions {
            f_edges: Some(FlatEdges::Smooth),
            ..Default::default()
        };
        let l = from_fold_with(&parsed, &smooth).unwrap();
        assert_eq!(l.scene.mesh.edges()[6].kind, EdgeKind::Smooth);
        assert!(
            l.notes
                .iter()
                .any(|n| n.starts_with("F edges: 1 read as smooth")),
            "{:?}",
            l.notes
        );
        let os = with(
            v.clone(),
            "file_creator",
            json!("Origami Simulator: http://git.amandaghassaei.com/OrigamiSimulator/"),
        );
        let (s, _) = load(&os).unwrap();
        assert_eq!(s.mesh.edges()[6].kind, EdgeKind::Smooth);
        let keyed = with(v.clone(), "ancf:import", json!({"f_edges": "smooth"}));
        assert_eq!(
            load(&keyed).unwrap().0.mesh.edges()[6].kind,
            EdgeKind::Smooth
        );
        let j = with(
            base(),
            "edges_assignment",
            json!(["B", "B", "B", "B", "B", "B", "J"]),
        );
        let (s, _) = load(&j).unwrap();
        assert_eq!(s.mesh.edges()[6].kind, EdgeKind::Smooth);
        assert!(s.actuators[0].edges.is_empty());
    }

    #[test]
    fn derived_and_unassigned_edges() {
        let mut v = base();
        for k in ["edges_vertices", "edges_assignment", "edges_foldAngle"] {
            v.as_object_mut().unwrap().remove(k);
        }
        let (s, w) = load(&v).unwrap();
        assert_eq!(s.fold_edge_count, 7);
        assert!(w[0].contains("derived from faces_vertices"), "{w:?}");
        let creases: Vec<_> = s.mesh.creases().collect();
        assert_eq!(creases.len(), 1);
        assert_eq!(creases[0].fold_target, 0.0);
        let mut v = base();
        v.as_object_mut().unwrap().remove("edges_assignment");
        let (s, w) = load(&v).unwrap();
        assert!(
            w.iter().any(|w| w.contains("edges_assignment is missing")),
            "{w:?}"
        );
        assert!((s.mesh.edges()[6].fold_target - PI / 2.0).abs() < 1e-15);
        assert_eq!(s.mesh.edges()[0].kind, EdgeKind::Boundary);
        // FOLD's own converters write null for interior edges
        let v = with(
            base(),
            "edges_assignment",
            json!(["B", "B", "B", "B", "B", "B", null]),
        );
        let (s, _) = load(&v).unwrap();
        assert_eq!(s.mesh.edges()[6].kind, EdgeKind::Crease);
        // sides not listed: a warning, no crease output
        let mut v = base();
        v["edges_vertices"] = json!([[1, 4]]);
        v["edges_assignment"] = json!(["M"]);
        v["edges_foldAngle"] = json!([-90]);
        let (s, w) = load(&v).unwrap();
        assert_eq!(s.fold_edge_count, 1);
        assert!(
            w.iter()
                .any(|w| w.contains("6 face side(s) are not listed")),
            "{w:?}"
        );
        assert_eq!(crate::model::fold_edges(&s), vec![FoldEdgeId(0)]);
    }
}
