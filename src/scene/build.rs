//! Building and validating a [`Scene`] from one FOLD frame.
//!
//! In order: the `ancf:` keys ([`super::keys`]); the faces (indices,
//! repeated vertices); the reference coordinates (unit, flatness); face
//! areas and orientation; edge sharing (non-manifold, overlapping faces);
//! the edges with their assignments and fold angles; the triangulation of
//! polygons ([`super::triangulate`]); the [`Mesh`]; and finally the physics
//! checked against the mesh (crease and vertex indices, overlaps). Every
//! error names the key and index; notes that do not stop the scene are
//! returned as warnings.
//!
//! Index conventions: FOLD vertex `i` is mesh vertex `i`; FOLD edge `e` is
//! mesh edge `e` with `fold_edge == Some(e)`; triangulation diagonals and
//! face sides missing from `edges_vertices` come after them, with
//! `fold_edge == None`.

use super::error::SceneError;
use super::fold::{Assignment, FoldFile, UNITS, unit_scale};
use super::keys::{self, EdgeSelection};
use super::triangulate::ear_clip;
use super::{ActuatorMode, Damping, Scene, Support, refine};
use crate::mesh::{Edge, EdgeKind, Mesh, MeshError};
use nalgebra::{Vector2, Vector3};
use std::collections::HashMap;

/// Relative tolerance (against the size of the sheet) of the flatness test
/// for 3D reference coordinates.
pub const COPLANAR_TOLERANCE: f64 = 1e-9;

/// Smallest sheet size (m) the model is asked to handle.
pub const MIN_EXTENT: f64 = 1e-9;
/// Largest sheet size, and largest distance from the origin (m).
pub const MAX_EXTENT: f64 = 1e6;

/// Relative area (against the mean squared side length) below which a face
/// is degenerate; the same threshold as [`Mesh::new`].
const DEGENERATE_AREA: f64 = 1e-12;

fn invalid(key: impl Into<String>, message: impl Into<String>) -> SceneError {
    SceneError::invalid(key, message)
}

/// Build the scene of a FOLD frame. `name` is the fallback model name (a
/// file stem) used when `ancf:name` is absent; then `file_title`,
/// `frame_title`, and `origami`. Returns the scene and the warnings.
pub fn from_fold(fold: &FoldFile, name: Option<&str>) -> Result<(Scene, Vec<String>), SceneError> {
    let mut warnings = Vec::new();
    let physics = keys::parse(&fold.ancf, &mut warnings)?;

    let nv = fold.vertices_coords.len();
    if nv == 0 {
        return Err(invalid("vertices_coords", "is empty"));
    }
    let faces = &fold.faces_vertices;
    if faces.is_empty() {
        return Err(invalid(
            "faces_vertices",
            "is empty; a scene needs at least one face",
        ));
    }
    check_faces(faces, nv)?;

    let scale = match &fold.frame_unit {
        None => 1.0,
        Some(u) => unit_scale(u).ok_or_else(|| {
            invalid(
                "frame_unit",
                format!(
                    "unknown unit \"{u}\"{}; expected one of {}",
                    super::error::suggestion(u, UNITS),
                    UNITS.join(", ")
                ),
            )
        })?,
    };
    let coords = reference_coords(&fold.vertices_coords, faces, scale)?;
    let (lo, hi) = bbox(&coords);
    let extent = (hi - lo).norm();
    let far = coords.iter().map(|c| c.amax()).fold(0.0, f64::max);
    if !((MIN_EXTENT..=MAX_EXTENT).contains(&extent) && far <= MAX_EXTENT) {
        return Err(invalid(
            "vertices_coords",
            format!(
                "the sheet is {extent:.3e} m across and reaches {far:.3e} m from the origin;                  the model handles {MIN_EXTENT:e} m to {MAX_EXTENT:e} m (check frame_unit)"
            ),
        ));
    }
    let unit_given = matches!(fold.frame_unit.as_deref(), Some(u) if u != "unit");
    if !unit_given && extent > 10.0 {
        warnings.push(format!(
            "frame_unit: the sheet is {extent:.3} m across; without frame_unit (or with \"unit\") \
             coordinates are read as metres; set frame_unit (e.g. \"mm\") if they are not"
        ));
    }

    check_areas(faces, &coords)?;
    let sides = Sides::new(faces)?;
    let edges = fold_edges(fold, &sides, &coords, &mut warnings)?;

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

    let mut triangles = Vec::new();
    let mut tri_face = Vec::new();
    for (f, face) in faces.iter().enumerate() {
        let tris = ear_clip(face, &coords).ok_or_else(|| {
            invalid(
                format!("faces_vertices[{f}]"),
                "is not a simple polygon (it cannot be triangulated); check it for self-intersections",
            )
        })?;
        tri_face.extend(std::iter::repeat_n(f, tris.len()));
        triangles.extend(tris);
    }

    let listed: Vec<Edge> = (0..edges.v.len())
        .map(|e| Edge {
            v: edges.v[e],
            kind: edges.kind[e],
            fold_target: edges.target[e],
            fold_edge: Some(e),
        })
        .collect();
    let mesh = Mesh::new(coords, triangles, listed).map_err(|e| translate(e, &tri_face))?;

    let scene_name = physics
        .name
        .clone()
        .or(name.map(str::to_string))
        .or(fold.file_title.clone())
        .or(fold.frame_title.clone())
        .unwrap_or_else(|| "origami".to_string());
    let mut scene = Scene::with_defaults(&scene_name, mesh);
    scene.fold_vertex_count = nv;
    scene.fold_edge_count = edges.v.len();
    apply_physics(&mut scene, physics.clone(), &edges, &mut warnings)?;

    // Thin-shell sanity: thickness against the shortest edge.
    let shortest = (0..scene.mesh.edges.len())
        .map(|e| scene.mesh.edge_length(e))
        .fold(f64::INFINITY, f64::min);
    if scene.material.thickness > 0.1 * shortest {
        warnings.push(format!(
            "ancf:material.thickness: {:.3e} m is more than a tenth of the shortest edge \
             ({shortest:.3e} m); the thin-shell model may be inaccurate",
            scene.material.thickness
        ));
    }

    if physics.refine > 0 {
        scene = refine::refine(&scene, physics.refine)?;
    }
    Ok((scene, warnings))
}

fn bbox(coords: &[Vector2<f64>]) -> (Vector2<f64>, Vector2<f64>) {
    let mut lo = coords[0];
    let mut hi = coords[0];
    for c in coords {
        lo = lo.inf(c);
        hi = hi.sup(c);
    }
    (lo, hi)
}

/// Indices in range, at least three vertices, no repeated vertex.
fn check_faces(faces: &[Vec<usize>], nv: usize) -> Result<(), SceneError> {
    for (f, face) in faces.iter().enumerate() {
        let key = format!("faces_vertices[{f}]");
        if face.len() < 3 {
            return Err(invalid(
                key,
                format!("has {} vertices; a face needs at least 3", face.len()),
            ));
        }
        for (j, &v) in face.iter().enumerate() {
            if v >= nv {
                return Err(invalid(
                    format!("{key}[{j}]"),
                    format!("vertex {v} does not exist (there are {nv} vertices)"),
                ));
            }
        }
        let mut sorted = face.clone();
        sorted.sort_unstable();
        if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
            return Err(invalid(key, format!("repeats vertex {}", w[0])));
        }
    }
    Ok(())
}

/// The flat reference coordinates in metres (see the module docs of
/// [`crate::scene`]): 2D as given; 3D with one z as x, y; otherwise the
/// vertices must be coplanar and are expressed in their plane, oriented by
/// the faces' winding.
fn reference_coords(
    raw: &[Vec<f64>],
    faces: &[Vec<usize>],
    scale: f64,
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
        return Ok(raw
            .iter()
            .map(|p| Vector2::new(p[0] * scale, p[1] * scale))
            .collect());
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
    // Newell's area vector of all faces: the normal of their best-fit plane,
    // pointing to the side from which the faces are counter-clockwise.
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
            "the faces have no common plane (their total area is zero); \
             the reference must be a flat crease pattern",
        ));
    }
    let mut n = n.normalize();
    if n.z.abs() > 1.0 - 1e-9 {
        // (Nearly) the xy plane: keep +z up so clockwise faces are reported.
        n = Vector3::z();
    }
    let (worst, dist) = pts
        .iter()
        .map(|p| (p - centroid).dot(&n).abs())
        .enumerate()
        .fold((0, 0.0), |acc, (i, d)| if d > acc.1 { (i, d) } else { acc });
    if dist > COPLANAR_TOLERANCE * extent {
        return Err(invalid(
            format!("vertices_coords[{worst}]"),
            format!(
                "the reference must be a flat crease pattern, but this vertex is {:.3e} m off \
                 the plane of the others (is this frame a folded state? use the unfolded \
                 crease pattern)",
                dist * scale
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
        .map(|p| Vector2::new(p.dot(&u) * scale, p.dot(&v) * scale))
        .collect())
}

fn shoelace(face: &[usize], c: &[Vector2<f64>]) -> f64 {
    let mut a = 0.0;
    for k in 0..face.len() {
        let (p, q) = (c[face[k]], c[face[(k + 1) % face.len()]]);
        a += p.perp(&q);
    }
    0.5 * a
}

/// No zero-length side, no zero-area face, all counter-clockwise.
fn check_areas(faces: &[Vec<usize>], c: &[Vector2<f64>]) -> Result<(), SceneError> {
    let mut sum = 0.0;
    let mut count = 0usize;
    for face in faces {
        for k in 0..face.len() {
            sum += (c[face[(k + 1) % face.len()]] - c[face[k]]).norm_squared();
            count += 1;
        }
    }
    let mean_len2 = sum / count as f64;
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
    }
    let areas: Vec<f64> = faces.iter().map(|f| shoelace(f, c)).collect();
    let all_cw = areas.iter().all(|&a| a < 0.0);
    for (f, &area) in areas.iter().enumerate() {
        let key = format!("faces_vertices[{f}]");
        if area.abs() <= DEGENERATE_AREA * mean_len2 {
            return Err(invalid(
                key,
                format!("has zero area ({area:.3e} m^2): its vertices are collinear"),
            ));
        }
        if area < 0.0 {
            let hint = if all_cw {
                " (every face is clockwise: the file may use a y-down convention; \
                 reverse the vertex order of every face)"
            } else {
                ""
            };
            return Err(invalid(
                key,
                format!(
                    "is clockwise (inverted); faces must be counter-clockwise seen from +z{hint}"
                ),
            ));
        }
    }
    Ok(())
}

/// Face sides, keyed by sorted vertex pair: which faces have them, and in
/// which direction.
struct Sides {
    map: HashMap<(usize, usize), Vec<(usize, bool)>>,
    /// Keys in the order of first appearance (face by face).
    order: Vec<(usize, usize)>,
    /// For each key, the direction of its first appearance.
    first: HashMap<(usize, usize), [usize; 2]>,
}

fn key(a: usize, b: usize) -> (usize, usize) {
    if a < b { (a, b) } else { (b, a) }
}

impl Sides {
    fn new(faces: &[Vec<usize>]) -> Result<Sides, SceneError> {
        let mut map: HashMap<(usize, usize), Vec<(usize, bool)>> = HashMap::new();
        let mut order = Vec::new();
        let mut first = HashMap::new();
        for (f, face) in faces.iter().enumerate() {
            for k in 0..face.len() {
                let (a, b) = (face[k], face[(k + 1) % face.len()]);
                let list = map.entry(key(a, b)).or_insert_with(|| {
                    order.push(key(a, b));
                    first.insert(key(a, b), [a, b]);
                    Vec::new()
                });
                list.push((f, a < b));
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
            if list.len() == 2 && list[0].1 == list[1].1 {
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
        Ok(Sides { map, order, first })
    }
    fn count(&self, a: usize, b: usize) -> usize {
        self.map.get(&key(a, b)).map_or(0, Vec::len)
    }
    fn faces(&self, a: usize, b: usize) -> Vec<usize> {
        self.map
            .get(&key(a, b))
            .map_or(vec![], |l| l.iter().map(|x| x.0).collect())
    }
}

/// The FOLD edges of the scene, with their mechanical kinds and targets.
pub(crate) struct FoldEdges {
    pub v: Vec<[usize; 2]>,
    pub assignment: Vec<Assignment>,
    pub kind: Vec<EdgeKind>,
    /// Target fold angle in radians.
    pub target: Vec<f64>,
}

fn fold_edges(
    fold: &FoldFile,
    sides: &Sides,
    coords: &[Vector2<f64>],
    warnings: &mut Vec<String>,
) -> Result<FoldEdges, SceneError> {
    let nv = coords.len();
    let (v, assignment, angles): (Vec<[usize; 2]>, Vec<Assignment>, Vec<Option<f64>>) = match &fold
        .edges_vertices
    {
        Some(ev) => {
            let ne = ev.len();
            let mut seen: HashMap<(usize, usize), usize> = HashMap::new();
            for (e, &[a, b]) in ev.iter().enumerate() {
                for (j, x) in [a, b].into_iter().enumerate() {
                    if x >= nv {
                        return Err(invalid(
                            format!("edges_vertices[{e}][{j}]"),
                            format!("vertex {x} does not exist (there are {nv} vertices)"),
                        ));
                    }
                }
                if a == b {
                    return Err(invalid(
                        format!("edges_vertices[{e}]"),
                        format!("both ends are vertex {a}"),
                    ));
                }
                if let Some(first) = seen.insert(key(a, b), e) {
                    return Err(invalid(
                        format!("edges_vertices[{e}]"),
                        format!(
                            "repeats edges_vertices[{first}] (vertices {a}-{b}); an edge may be listed once"
                        ),
                    ));
                }
            }
            let asg = match &fold.edges_assignment {
                Some(a) if a.len() != ne => {
                    return Err(invalid(
                        "edges_assignment",
                        format!(
                            "has {} entries but edges_vertices has {ne}; the arrays must have the same length",
                            a.len()
                        ),
                    ));
                }
                Some(a) => a.clone(),
                None => {
                    warnings.push(
                        "edges_assignment is missing: interior edges are read as U (creases \
                             with the angle of edges_foldAngle, else 0), boundary edges as B"
                            .to_string(),
                    );
                    vec![Assignment::Unassigned; ne]
                }
            };
            let ang = match &fold.edges_fold_angle {
                Some(a) if a.len() != ne => {
                    return Err(invalid(
                        "edges_foldAngle",
                        format!(
                            "has {} entries but edges_vertices has {ne}; the arrays must have the same length",
                            a.len()
                        ),
                    ));
                }
                Some(a) => a.clone(),
                None => vec![None; ne],
            };
            (ev.clone(), asg, ang)
        }
        None => {
            if fold.edges_assignment.is_some() || fold.edges_fold_angle.is_some() {
                return Err(invalid(
                    "edges_vertices",
                    "is missing, but edges_assignment or edges_foldAngle is given; they refer to edges_vertices",
                ));
            }
            let v: Vec<[usize; 2]> = sides.order.iter().map(|k| sides.first[k]).collect();
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
                "edges_vertices is missing: {} edges were derived from faces_vertices \
                     (interior edges as U creases with target 0, boundary edges as B), numbered \
                     in order of first appearance in faces_vertices",
                v.len()
            ));
            let n = v.len();
            (v, asg, vec![None; n])
        }
    };

    let ne = v.len();
    let mut kind = Vec::with_capacity(ne);
    let mut target = Vec::with_capacity(ne);
    for e in 0..ne {
        let [a, b] = v[e];
        let nf = sides.count(a, b);
        if nf == 0 {
            return Err(invalid(
                format!("edges_vertices[{e}]"),
                format!(
                    "edge {a}-{b} is not a side of any face; every edge must border one or two \
                     faces (split the faces along it)"
                ),
            ));
        }
        let asg_key = format!("edges_assignment[{e}]");
        let k = match assignment[e] {
            Assignment::Cut => {
                return Err(invalid(
                    asg_key,
                    format!("cut edges (C) are not supported yet (edge {a}-{b})"),
                ));
            }
            Assignment::Mountain | Assignment::Valley if nf == 1 => {
                return Err(invalid(
                    asg_key,
                    format!(
                        "crease ({}) on the boundary edge {a}-{b}, which borders only face {}; \
                         a crease needs a face on each side",
                        assignment[e].letter(),
                        sides.faces(a, b)[0]
                    ),
                ));
            }
            Assignment::Boundary if nf == 2 => {
                let fs = sides.faces(a, b);
                return Err(invalid(
                    asg_key,
                    format!(
                        "edge {a}-{b} is marked B (boundary) but borders two faces ({} and {})",
                        fs[0], fs[1]
                    ),
                ));
            }
            _ if nf == 1 => EdgeKind::Boundary,
            x if x.is_crease() => EdgeKind::Crease,
            _ => EdgeKind::Smooth,
        };
        let angle_key = format!("edges_foldAngle[{e}]");
        if let Some(d) = angles[e] {
            if !(-180.0..=180.0).contains(&d) {
                return Err(invalid(
                    angle_key,
                    format!("{d} degrees is outside [-180, 180]"),
                ));
            }
        }
        let deg = if k == EdgeKind::Crease {
            match (assignment[e], angles[e]) {
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
            if let Some(d) = angles[e].filter(|&d| d != 0.0) {
                warnings.push(format!(
                    "{angle_key}: the angle {d} of the {} edge {a}-{b} is ignored (not a crease)",
                    assignment[e].letter()
                ));
            }
            0.0
        };
        kind.push(k);
        target.push(deg.to_radians());
    }

    // Face sides that are not FOLD edges (only possible with edges_vertices).
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
    Ok(FoldEdges {
        v,
        assignment,
        kind,
        target,
    })
}

/// A [`MeshError`] in FOLD terms (these are caught earlier in all but rare
/// cases; the mapping keeps the message precise anyway).
fn translate(e: MeshError, tri_face: &[usize]) -> SceneError {
    let face = |t: usize| format!("faces_vertices[{}]", tri_face.get(t).copied().unwrap_or(0));
    match e {
        MeshError::Degenerate { triangle, area } => invalid(
            face(triangle),
            format!(
                "its triangulation has a degenerate triangle (area {area:.3e} m^2); the face is \
                 nearly degenerate"
            ),
        ),
        MeshError::Inverted { triangle } => invalid(
            face(triangle),
            "overlaps a neighbouring face (inconsistent orientation)",
        ),
        MeshError::NonManifoldVertex { vertex } => invalid(
            format!("vertices_coords[{vertex}]"),
            format!(
                "the faces around vertex {vertex} do not form one fan (sheets touching only at \
                 this vertex, or overlapping faces)"
            ),
        ),
        other => invalid("faces_vertices", other.to_string()),
    }
}

/// Material, damping, actuators, supports, loads, solver and outputs,
/// checked against the mesh.
fn apply_physics(
    scene: &mut Scene,
    p: keys::Physics,
    edges: &FoldEdges,
    warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    let nv = scene.fold_vertex_count;
    let ne = edges.v.len();
    scene.material = p.material;
    scene.crease = p.crease;
    let (alpha, beta) = p.damping.unwrap_or((0.0, 0.0));
    scene.damping = Damping {
        alpha,
        beta,
        crease: p.crease_damping.unwrap_or(0.0),
    };
    scene.auto_damping = p.damping.is_none();
    scene.gravity = p.gravity;
    scene.solver = p.solver;
    scene.outputs = p.outputs;

    let creases: Vec<usize> = (0..ne)
        .filter(|&e| edges.kind[e] == EdgeKind::Crease)
        .collect();
    match p.actuators {
        None => {
            // with_defaults made `fold` over every mesh crease (= FOLD creases).
            if creases.is_empty() {
                warnings.push(
                    "the pattern has no creases; the default actuator 'fold' drives nothing"
                        .to_string(),
                );
            }
        }
        Some(list) => {
            let mut rest_owner: HashMap<usize, (String, String)> = HashMap::new();
            scene.actuators.clear();
            for a in list {
                let sel_key = format!("{}.edges", a.key);
                let selected: Vec<usize> = match &a.edges {
                    EdgeSelection::All => {
                        if creases.is_empty() {
                            warnings.push(format!(
                                "{sel_key}: \"all\" selects nothing; the pattern has no creases"
                            ));
                        }
                        creases.clone()
                    }
                    EdgeSelection::Assignment(x) => {
                        let s: Vec<usize> = creases
                            .iter()
                            .copied()
                            .filter(|&e| edges.assignment[e] == *x)
                            .collect();
                        if s.is_empty() {
                            warnings.push(format!(
                                "{sel_key}: no crease has assignment {}; the actuator drives nothing",
                                x.letter()
                            ));
                        }
                        s
                    }
                    EdgeSelection::List(l) => {
                        let mut s = Vec::with_capacity(l.len());
                        for (i, &e) in l.iter().enumerate() {
                            let k = format!("{sel_key}[{i}]");
                            if e >= ne {
                                return Err(invalid(
                                    k,
                                    format!("FOLD edge {e} does not exist (there are {ne} edges)"),
                                ));
                            }
                            if edges.kind[e] != EdgeKind::Crease {
                                return Err(invalid(
                                    k,
                                    format!(
                                        "FOLD edge {e} is not a crease (assignment {}{})",
                                        edges.assignment[e].letter(),
                                        if edges.kind[e] == EdgeKind::Boundary {
                                            ", on the boundary"
                                        } else {
                                            ""
                                        }
                                    ),
                                ));
                            }
                            if s.contains(&e) {
                                return Err(invalid(k, format!("FOLD edge {e} is listed twice")));
                            }
                            s.push(e);
                        }
                        s
                    }
                };
                if a.mode == ActuatorMode::RestAngle {
                    for &e in &selected {
                        if let Some((name, key)) = rest_owner.get(&e) {
                            return Err(invalid(
                                sel_key,
                                format!(
                                    "FOLD edge {e} is already driven by the rest_angle actuator \
                                     '{name}' ({key}); a crease can follow only one rest angle"
                                ),
                            ));
                        }
                        rest_owner.insert(e, (a.name.clone(), a.key.clone()));
                    }
                }
                scene.actuators.push(super::Actuator {
                    name: a.name,
                    edges: selected, // mesh edge e == FOLD edge e before refinement
                    mode: a.mode,
                    start: a.start,
                });
            }
        }
    }

    let mut supported: HashMap<usize, String> = HashMap::new();
    for s in p.supports {
        for (i, &v) in s.vertices.iter().enumerate() {
            let k = format!("{}.vertices[{i}]", s.key);
            if v >= nv {
                return Err(invalid(
                    k,
                    format!("vertex {v} does not exist (there are {nv} vertices)"),
                ));
            }
            if let Some(first) = supported.get(&v) {
                return Err(invalid(
                    k,
                    format!("vertex {v} is already supported by {first}"),
                ));
            }
            supported.insert(v, s.key.clone());
        }
        scene.supports.push(Support {
            vertices: s.vertices,
            fix: s.fix,
        });
    }

    for (vi, key) in &p.vertex_forces {
        let k = format!("{key}.vertex");
        if vi.vertex >= nv {
            return Err(invalid(
                k,
                format!(
                    "vertex {} does not exist (there are {nv} vertices)",
                    vi.vertex
                ),
            ));
        }
        if let Some(s) = supported.get(&vi.vertex) {
            warnings.push(format!(
                "{k}: vertex {} is fixed by {s}; the force '{}' acts on a support",
                vi.vertex, vi.name
            ));
        }
    }
    let mut driven: HashMap<usize, String> = HashMap::new();
    for (vi, key) in &p.vertex_motions {
        let k = format!("{key}.vertex");
        if vi.vertex >= nv {
            return Err(invalid(
                k,
                format!(
                    "vertex {} does not exist (there are {nv} vertices)",
                    vi.vertex
                ),
            ));
        }
        if let Some(s) = supported.get(&vi.vertex) {
            return Err(invalid(
                k,
                format!(
                    "vertex {} is also fixed by {s}; a vertex cannot be both supported and driven",
                    vi.vertex
                ),
            ));
        }
        if let Some(first) = driven.insert(vi.vertex, key.clone()) {
            return Err(invalid(
                k,
                format!("vertex {} is already driven by {first}", vi.vertex),
            ));
        }
    }
    scene.vertex_forces = p.vertex_forces.into_iter().map(|x| x.0).collect();
    scene.vertex_motions = p.vertex_motions.into_iter().map(|x| x.0).collect();
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Fix, from_str};
    use serde_json::{Value, json};
    use std::f64::consts::PI;

    /// Two unit squares side by side with the valley crease 1-4 (FOLD edge 6).
    fn base() -> Value {
        json!({
            "file_spec": 1.2,
            "vertices_coords": [[0,0],[1,0],[2,0],[2,1],[1,1],[0,1]],
            "edges_vertices": [[0,1],[1,2],[2,3],[3,4],[4,5],[5,0],[1,4]],
            "edges_assignment": ["B","B","B","B","B","B","V"],
            "edges_foldAngle": [null,null,null,null,null,null,90],
            "faces_vertices": [[0,1,4,5],[1,2,3,4]]
        })
    }
    fn with(mut v: Value, key: &str, x: Value) -> Value {
        v[key] = x;
        v
    }
    fn load(v: &Value) -> Result<(Scene, Vec<String>), SceneError> {
        from_str(&v.to_string())
    }
    /// The error message, checked to start with `key: `.
    fn err(v: &Value, key: &str) -> String {
        let e = load(v).expect_err("should fail");
        assert_eq!(e.key(), Some(key), "{e}");
        e.to_string()
    }

    #[test]
    fn plain_file_gets_documented_defaults() {
        let (s, w) = load(&base()).unwrap();
        assert!(w.is_empty(), "{w:?}");
        assert_eq!(s.name, "origami");
        assert_eq!((s.fold_vertex_count, s.fold_edge_count), (6, 7));
        assert_eq!(s.mesh.triangles.len(), 4);
        // FOLD edges first, in order, tagged; diagonals after, untagged.
        for e in 0..7 {
            assert_eq!(s.mesh.edges[e].fold_edge, Some(e));
        }
        assert_eq!(s.mesh.edges.len(), 9);
        assert!(
            s.mesh.edges[7..]
                .iter()
                .all(|e| e.fold_edge.is_none() && e.kind == EdgeKind::Smooth)
        );
        assert_eq!(s.mesh.edges[6].kind, EdgeKind::Crease);
        assert!((s.mesh.edges[6].fold_target - PI / 2.0).abs() < 1e-15);
        assert_eq!(s.actuators.len(), 1);
        assert_eq!(s.actuators[0].name, "fold");
        assert_eq!(s.actuators[0].edges, vec![6]);
        assert_eq!(s.actuators[0].mode, ActuatorMode::RestAngle);
        assert!(s.auto_damping);
        assert!(s.supports.is_empty() && s.gravity.is_none());
        assert_eq!(s.material, crate::scene::Material::default());
        crate::model::Model::new(s).unwrap();
    }

    #[test]
    fn missing_angles_fold_fully_and_signs_win_with_a_warning() {
        let v = with(base(), "edges_foldAngle", Value::Null);
        let v = v.as_object().unwrap().clone();
        let mut v = Value::Object(v);
        v.as_object_mut().unwrap().remove("edges_foldAngle");
        let (s, _) = load(&v).unwrap();
        assert_eq!(s.mesh.edges[6].fold_target, PI);
        let v = with(
            v,
            "edges_assignment",
            json!(["B", "B", "B", "B", "B", "B", "M"]),
        );
        let (s, _) = load(&v).unwrap();
        assert_eq!(s.mesh.edges[6].fold_target, -PI);
        let v = with(v, "edges_foldAngle", json!([0, 0, 0, 0, 0, 0, 45]));
        let (s, w) = load(&v).unwrap();
        assert!((s.mesh.edges[6].fold_target - PI / 4.0).abs() < 1e-15);
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
        assert_eq!(s.mesh.edges[6].kind, EdgeKind::Crease);
        assert_eq!(s.mesh.edges[6].fold_target, 0.0);
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
    fn face_errors() {
        let e = err(
            &with(
                base(),
                "faces_vertices",
                json!([[0, 1, 4, 1], [1, 2, 3, 4]]),
            ),
            "faces_vertices[0]",
        );
        assert!(e.contains("repeats vertex 1"), "{e}");
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
        let e = err(
            &with(
                base(),
                "faces_vertices",
                json!([[0, 5, 4, 1], [1, 4, 3, 2]]),
            ),
            "faces_vertices[0]",
        );
        assert!(e.contains("every face is clockwise"), "{e}");
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
        let v = with(
            base(),
            "edges_assignment",
            json!(["V", "B", "B", "B", "B", "B", "V"]),
        );
        let e = err(&v, "edges_assignment[0]");
        assert!(e.contains("crease (V) on the boundary edge 0-1"), "{e}");
        let v = with(
            base(),
            "edges_assignment",
            json!(["B", "B", "B", "B", "B", "B", "B"]),
        );
        let e = err(&v, "edges_assignment[6]");
        assert!(e.contains("borders two faces"), "{e}");
        let v = with(
            base(),
            "edges_assignment",
            json!(["B", "B", "B", "B", "B", "B", "C"]),
        );
        let e = err(&v, "edges_assignment[6]");
        assert!(
            e.contains("cut edges (C) are not supported yet (edge 1-4)"),
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
        // U on the boundary is a boundary edge, F inside is smooth
        let v = with(
            base(),
            "edges_assignment",
            json!(["U", "B", "B", "B", "B", "B", "F"]),
        );
        let (s, _) = load(&v).unwrap();
        assert_eq!(s.mesh.edges[0].kind, EdgeKind::Boundary);
        assert_eq!(s.mesh.edges[6].kind, EdgeKind::Smooth);
        assert!(s.actuators[0].edges.is_empty());
    }

    #[test]
    fn unused_vertex_is_an_error() {
        let v = with(
            base(),
            "vertices_coords",
            json!([[0, 0], [1, 0], [2, 0], [2, 1], [1, 1], [0, 1], [5, 5]]),
        );
        let e = err(&v, "vertices_coords[6]");
        assert!(e.contains("not used by any face"), "{e}");
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
        let creases: Vec<_> = s
            .mesh
            .edges
            .iter()
            .filter(|e| e.kind == EdgeKind::Crease)
            .collect();
        assert_eq!(creases.len(), 1);
        assert_eq!(creases[0].fold_target, 0.0);
        let mut v = base();
        v.as_object_mut().unwrap().remove("edges_assignment");
        let (s, w) = load(&v).unwrap();
        assert!(
            w.iter().any(|w| w.contains("edges_assignment is missing")),
            "{w:?}"
        );
        assert!((s.mesh.edges[6].fold_target - PI / 2.0).abs() < 1e-15);
        assert_eq!(s.mesh.edges[0].kind, EdgeKind::Boundary);
        // FOLD's own converters write null for interior edges
        let v = with(
            base(),
            "edges_assignment",
            json!(["B", "B", "B", "B", "B", "B", null]),
        );
        let (s, _) = load(&v).unwrap();
        assert_eq!(s.mesh.edges[6].kind, EdgeKind::Crease);
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
        assert_eq!(crate::model::fold_edges(&s), vec![0]);
    }

    #[test]
    fn units_and_planes() {
        let (mm, _) = load(&with(base(), "frame_unit", json!("mm"))).unwrap();
        assert_eq!(mm.mesh.coords[2].x, 2e-3);
        let (inch, _) = load(&with(base(), "frame_unit", json!("in"))).unwrap();
        assert!((inch.mesh.coords[2].x - 0.0508).abs() < 1e-15);
        let e = err(&with(base(), "frame_unit", json!("mn")), "frame_unit");
        assert!(e.contains("did you mean"), "{e}");
        // big unitless sheet: a warning
        let v = with(
            base(),
            "vertices_coords",
            json!([[0, 0], [100, 0], [200, 0], [200, 100], [100, 100], [0, 100]]),
        );
        let (_, w) = load(&v).unwrap();
        assert!(w[0].starts_with("frame_unit:"), "{w:?}");
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
        assert_eq!(s.mesh.coords[3], Vector2::new(2.0, 1.0));
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
        for t in 0..4 {
            assert!((s.mesh.area(t) - flat.mesh.area(t)).abs() < 1e-15);
        }
        for e in 0..s.mesh.edges.len() {
            assert!((s.mesh.edge_length(e) - flat.mesh.edge_length(e)).abs() < 1e-15);
        }
        // a tilted plane
        let (c, sn) = (0.6f64, 0.8f64);
        let pts: Vec<Value> = [[0., 0.], [1., 0.], [2., 0.], [2., 1.], [1., 1.], [0., 1.]]
            .iter()
            .map(|p| json!([p[0], c * p[1], sn * p[1]]))
            .collect();
        let (s, _) = load(&with(base(), "vertices_coords", Value::from(pts.clone()))).unwrap();
        for e in 0..s.mesh.edges.len() {
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
        // absurd sizes
        let v = with(
            base(),
            "vertices_coords",
            json!([[0, 0], [1, 0], [2e300, 0], [2, 1], [1, 1], [0, 1]]),
        );
        err(&v, "vertices_coords");
        let v = with(base(), "frame_unit", json!("nm"));
        let v = with(
            v,
            "vertices_coords",
            json!([
                [0, 0],
                [1e-3, 0],
                [2e-3, 0],
                [2e-3, 1e-3],
                [1e-3, 1e-3],
                [0, 1e-3]
            ]),
        );
        let e = err(&v, "vertices_coords");
        assert!(e.contains("check frame_unit"), "{e}");
        // mixed dimensions
        let v = with(
            base(),
            "vertices_coords",
            json!([[0, 0], [1, 0], [2, 0], [2, 1, 0], [1, 1], [0, 1]]),
        );
        err(&v, "vertices_coords[3]");
    }

    #[test]
    fn non_convex_face_is_triangulated_inside() {
        let v = json!({
            "vertices_coords": [[0,0],[2,0],[2,1],[1,1],[1,2],[0,2]],
            "faces_vertices": [[0,1,2,3,4,5]]
        });
        let (s, _) = load(&v).unwrap();
        assert_eq!(s.mesh.triangles.len(), 4);
        let total: f64 = (0..4).map(|t| s.mesh.area(t)).sum();
        assert!((total - 3.0).abs() < 1e-14);
    }

    #[test]
    fn physics_against_the_mesh() {
        let v = with(
            base(),
            "ancf:actuators",
            json!([{"name": "a", "edges": [7]}]),
        );
        let e = err(&v, "ancf:actuators[0].edges[0]");
        assert!(e.contains("does not exist"), "{e}");
        let v = with(
            base(),
            "ancf:actuators",
            json!([{"name": "a", "edges": [0]}]),
        );
        let e = err(&v, "ancf:actuators[0].edges[0]");
        assert!(e.contains("not a crease (assignment B"), "{e}");
        let v = with(
            base(),
            "ancf:actuators",
            json!([{"name": "a"}, {"name": "b", "edges": "V"}]),
        );
        let e = err(&v, "ancf:actuators[1].edges");
        assert!(
            e.contains("already driven by the rest_angle actuator 'a'"),
            "{e}"
        );
        let v = with(
            base(),
            "ancf:actuators",
            json!([{"name": "a"}, {"name": "t", "edges": [6], "mode": "torque"}]),
        );
        let (s, _) = load(&v).unwrap();
        assert_eq!(s.actuators.len(), 2);
        assert_eq!(s.actuators[1].edges, vec![6]);
        let v = with(
            base(),
            "ancf:actuators",
            json!([{"name": "m", "edges": "M"}]),
        );
        let (s, w) = load(&v).unwrap();
        assert!(s.actuators[0].edges.is_empty());
        assert!(w[0].contains("no crease has assignment M"), "{w:?}");
        let v = with(base(), "ancf:actuators", json!([]));
        let (s, _) = load(&v).unwrap();
        assert!(s.actuators.is_empty());

        let v = with(base(), "ancf:supports", json!([{"vertices": [0, 6]}]));
        let e = err(&v, "ancf:supports[0].vertices[1]");
        assert!(e.contains("vertex 6 does not exist"), "{e}");
        let v = with(
            base(),
            "ancf:supports",
            json!([{"vertices": [0]}, {"vertices": [5, 0], "fix": "clamped"}]),
        );
        let e = err(&v, "ancf:supports[1].vertices[1]");
        assert!(e.contains("already supported by ancf:supports[0]"), "{e}");
        let v = with(
            base(),
            "ancf:supports",
            json!([{"vertices": [0, 5], "fix": "clamped"}]),
        );
        let v = with(v, "ancf:motions", json!([{"name": "grip", "vertex": 5}]));
        let e = err(&v, "ancf:motions[0].vertex");
        assert!(e.contains("both supported and driven"), "{e}");
        let v = with(
            v,
            "ancf:motions",
            json!([{"name": "grip", "vertex": 3}, {"name": "g2", "vertex": 3}]),
        );
        err(&v, "ancf:motions[1].vertex");
        let v = with(v, "ancf:motions", json!([{"name": "grip", "vertex": 3}]));
        let v = with(
            v,
            "ancf:loads",
            json!({"gravity": [0, 0, -9.81], "vertex_forces": [{"name": "push", "vertex": 0}]}),
        );
        let (s, w) = load(&v).unwrap();
        assert!(w[0].contains("acts on a support"), "{w:?}");
        assert_eq!(s.supports[0].fix, Fix::Clamped);
        assert_eq!(s.vertex_motions[0].vertex, 3);
        assert_eq!(s.vertex_forces[0].name, "push");
        assert_eq!(s.gravity, Some([0.0, 0.0, -9.81]));
        let m = crate::model::Model::new(s).unwrap();
        let names: Vec<&str> = m.inputs().iter().map(|x| x.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "fold", "push.x", "push.y", "push.z", "grip.x", "grip.y", "grip.z"
            ]
        );
        let v = with(
            base(),
            "ancf:loads",
            json!({"vertex_forces": [{"name": "p", "vertex": 60}]}),
        );
        err(&v, "ancf:loads.vertex_forces[0].vertex");
    }

    #[test]
    fn damping_and_material_keys() {
        let v = with(base(), "ancf:damping", json!({"alpha": 2.0}));
        let (s, _) = load(&v).unwrap();
        assert!(!s.auto_damping);
        assert_eq!((s.damping.alpha, s.damping.beta), (2.0, 0.0));
        let v = with(
            base(),
            "ancf:crease",
            json!({"length_scale": 0.02, "damping_per_length": 1e-4}),
        );
        let (s, _) = load(&v).unwrap();
        assert!(s.auto_damping);
        assert_eq!(s.damping.crease, 1e-4);
        let e = err(
            &with(base(), "ancf:material", json!({"thickness": -1})),
            "ancf:material.thickness",
        );
        assert!(e.contains("positive"), "{e}");
        let e = err(
            &with(base(), "ancf:material", json!({"poisson_ratio": 0.7})),
            "ancf:material.poisson_ratio",
        );
        assert!(e.contains("(-1, 0.5)"), "{e}");
        err(
            &with(base(), "ancf:material", json!({"youngs_modulus": 0})),
            "ancf:material.youngs_modulus",
        );
        err(
            &with(base(), "ancf:material", json!({"density": 0})),
            "ancf:material.density",
        );
        let (_, w) = load(&with(base(), "ancf:material", json!({"thickness": 0.2}))).unwrap();
        assert!(w[0].contains("thin-shell"), "{w:?}");
        let e = err(&with(base(), "ancf:stiffness", json!({})), "ancf:stiffness");
        assert!(e.contains("unknown key"), "{e}");
        let (s, _) = load(&with(base(), "ancf:name", json!("pair"))).unwrap();
        assert_eq!(s.name, "pair");
        let (s, _) = load(&with(base(), "file_title", json!("titled"))).unwrap();
        assert_eq!(s.name, "titled");
    }

    #[test]
    fn refine_key_keeps_fold_indices() {
        let v = with(base(), "ancf:refine", json!(2));
        let v = with(v, "ancf:actuators", json!([{"name": "f", "edges": [6]}]));
        let (s, _) = load(&v).unwrap();
        assert_eq!(s.mesh.triangles.len(), 64);
        assert_eq!((s.fold_vertex_count, s.fold_edge_count), (6, 7));
        let (flat, _) = load(&base()).unwrap();
        assert_eq!(&s.mesh.coords[..6], &flat.mesh.coords[..]);
        // crease 6 is now 4 mesh creases, all driven, all tagged 6
        assert_eq!(s.actuators[0].edges.len(), 4);
        for &e in &s.actuators[0].edges {
            assert_eq!(s.mesh.edges[e].kind, EdgeKind::Crease);
            assert_eq!(s.mesh.edges[e].fold_edge, Some(6));
        }
        let m = crate::model::Model::new(s).unwrap();
        assert_eq!(m.outputs().len(), 6 * 3 + 1 + 3);
    }
}
