//! Building and validating a [`Scene`] from one FOLD frame.
//!
//! In order: the `ancf:` keys ([`super::keys`]); the size budget; the
//! listed edges; the faces (given, or traced from the edges by
//! [`super::planar`]); the reference coordinates (flatness, orientation:
//! a sheet whose faces are all clockwise is mirrored, a mix of orientations
//! is a folded state); the size (unit or scale, see [`DEFAULT_SIZE`]); face
//! areas; edge sharing (non-manifold, overlapping faces); the edges with
//! their assignments and fold angles; vertex splitting along cuts and where
//! sheets touch; the triangulation of polygons ([`super::triangulate`]);
//! the [`Mesh`]; and finally the physics checked against the mesh (crease
//! and vertex indices, overlaps). Every error names the key and index and
//! says what to do; notes that do not stop the scene are returned as
//! warnings, and what the loader decided (unit, F edges, traced faces,
//! split vertices) as notes.
//!
//! Index conventions: FOLD vertex `i` is mesh vertex `i`; copies of split
//! vertices come after the FOLD vertices. FOLD edge `e` is mesh edge `e`
//! with `fold_edge == Some(e)`; the second side of a cut edge, triangulation
//! diagonals and face sides missing from `edges_vertices` come after them
//! (the cut side tagged with its FOLD edge, the others with `None`).
//!
//! Everything here is linear or near-linear in the size of the pattern
//! (hash maps keyed by vertex pairs, sorting), so that patterns up to the
//! [`MAX_FACETS`] budget load in seconds.

use super::error::SceneError;
use super::fold::{Assignment, FoldFile, UNITS, unit_scale};
use super::keys::{self, EdgeSelection};
use super::planar::{self, SideAt, shoelace};
use super::triangulate::ear_clip;
use super::{ActuatorMode, Damping, FlatEdges, LoadOptions, Loaded, Scene, Support, refine};
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

/// The length (m) of the longest side of the bounding box of a sheet
/// whose file gives no physical unit (no `frame_unit`, or FOLD's default
/// `unit`): such a sheet is scaled to it, a 10 cm sheet of paper.
pub const DEFAULT_SIZE: f64 = 0.1;

/// The size budget: the most facets (triangles, after triangulation and
/// refinement) a scene may have. Setting a scene up takes about 27 kB of
/// memory per facet and time-stepping it about 75 kB per facet (the sparse
/// Cholesky factor; it grows faster than linearly), so that a scene at the
/// budget needs about 16 GB to simulate (docs/scenes.md, "Size budget").
/// Checked before the large allocations: on the face count right after
/// reading the file, on the triangle count after triangulation, by
/// refinement, and by [`crate::model::Model::new`].
pub const MAX_FACETS: usize = 200_000;

/// The error above [`MAX_FACETS`]; `what` says where the count comes from.
pub fn over_budget(key: &str, facets: usize, what: &str) -> SceneError {
    invalid(
        key,
        format!(
            "{what} {facets} facets (triangles); the size budget is {MAX_FACETS} facets (about \
             16 GB of memory to simulate; docs/scenes.md, \"Size budget\"): use a coarser \
             pattern, or simulate a part of it"
        ),
    )
}

/// Relative area (against the mean squared side length) below which a face
/// is degenerate; the same threshold as [`Mesh::new`].
const DEGENERATE_AREA: f64 = 1e-12;

/// The phrase that marks an error as "this frame is a folded state": the
/// loader then names the frames of the file that are crease patterns.
const FOLDED_STATE: &str = "a folded state";

/// True for the message of an error that says the frame read is a folded
/// state rather than a crease pattern.
pub(crate) fn is_folded_state(message: &str) -> bool {
    message.contains(FOLDED_STATE)
}

fn invalid(key: impl Into<String>, message: impl Into<String>) -> SceneError {
    SceneError::invalid(key, message)
}

/// Build the scene of a FOLD frame. `name` is the fallback model name (a
/// file stem) used when `ancf:name` is absent; then `file_title`,
/// `frame_title`, and `origami`. Returns the scene and the warnings.
pub fn from_fold(fold: &FoldFile, name: Option<&str>) -> Result<(Scene, Vec<String>), SceneError> {
    let options = LoadOptions {
        name: name.map(str::to_string),
        ..Default::default()
    };
    from_fold_with(fold, &options).map(|l| (l.scene, l.warnings))
}

/// True for a file written by Origami Simulator (its `file_creator`), whose
/// F edges are triangulation lines.
pub fn is_origami_simulator_export(fold: &FoldFile) -> bool {
    fold.file_creator
        .as_deref()
        .is_some_and(|c| c.trim_start().starts_with("Origami Simulator"))
}

/// [`from_fold`] with the options of [`LoadOptions`] (`frame` is not used
/// here: the frame is already picked), returning the loader's notes too.
pub fn from_fold_with(fold: &FoldFile, options: &LoadOptions) -> Result<Loaded, SceneError> {
    let mut warnings = Vec::new();
    let mut notes = Vec::new();
    let physics = keys::parse(&fold.ancf, &mut warnings)?;

    let nv = fold.vertices_coords.len();
    if nv == 0 {
        return Err(invalid("vertices_coords", "is empty"));
    }
    // The size budget, before anything large is allocated.
    let estimate: usize = if fold.faces_vertices.is_empty() {
        2 * nv // a planar triangulation has about two triangles per vertex
    } else {
        fold.faces_vertices
            .iter()
            .map(|f| f.len().saturating_sub(2))
            .sum()
    };
    if estimate > MAX_FACETS {
        return Err(over_budget(
            "faces_vertices",
            estimate,
            "the pattern would triangulate into about",
        ));
    }
    let listed = read_edges(fold, nv, &mut warnings)?;

    let f_mode = options.f_edges.or(physics.import.f_edges).unwrap_or(
        if is_origami_simulator_export(fold) {
            FlatEdges::Smooth
        } else {
            FlatEdges::Crease
        },
    );

    // The flat reference in metres, and the faces (given, or traced).
    let traced = fold.faces_vertices.is_empty();
    if traced && listed.is_none() {
        return Err(invalid(
            "faces_vertices",
            "is empty and there is no edges_vertices to trace faces from; a scene needs at \
             least one face",
        ));
    }
    if !traced {
        check_faces(&fold.faces_vertices, nv)?;
    }
    let given = (!traced).then_some(&fold.faces_vertices[..]);
    let mut coords = reference_coords(&fold.vertices_coords, given, fold)?;
    let (scale, size_note) = choose_scale(fold, options, &physics.import, &coords)?;
    for c in &mut coords {
        *c *= scale;
    }
    let (lo, hi) = bbox(&coords);
    let extent = (hi - lo).norm();
    let far = coords.iter().map(|c| c.amax()).fold(0.0, f64::max);
    if !((MIN_EXTENT..=MAX_EXTENT).contains(&extent) && far <= MAX_EXTENT) {
        return Err(invalid(
            "vertices_coords",
            format!(
                "the sheet is {extent:.3e} m across and reaches {far:.3e} m from the origin; the \
                 model handles {MIN_EXTENT:e} m to {MAX_EXTENT:e} m (check frame_unit, --unit or \
                 --size)"
            ),
        ));
    }
    let mut faces: Vec<Vec<usize>> = match &listed {
        Some(l) if traced => {
            let boundary: Vec<bool> = l
                .assignment
                .iter()
                .map(|&a| a == Assignment::Boundary)
                .collect();
            let faces = planar::trace_faces(&coords, &l.v, &boundary)?;
            if faces.is_empty() {
                return Err(invalid(
                    "edges_vertices",
                    "no face can be traced from the edges: they enclose no area (a scene \
                     needs at least one face)",
                ));
            }
            notes.push(format!(
                "faces: faces_vertices is missing; {} faces were traced from the edges (planar \
                 graph)",
                faces.len()
            ));
            faces
        }
        _ => fold.faces_vertices.clone(),
    };
    check_areas(&faces, &coords)?;
    orient(&mut coords, &faces, fold, &mut warnings)?;
    notes.push(size_note);
    let slits = faces.iter().filter(|f| has_slit(f)).count();
    if slits > 0 {
        notes.push(format!(
            "slits: {slits} face(s) run along an edge and back (a crease or cut ending \
             inside the face); such a crease folds and stops in the paper, such a cut opens"
        ));
    }

    let sides = Sides::new(&faces)?;
    let edges = fold_edges(listed, &sides, f_mode, &mut warnings)?;
    let n_flat = (0..edges.v.len())
        .filter(|&e| edges.assignment[e] == Assignment::Flat && edges.kind[e] != EdgeKind::Boundary)
        .count();
    if n_flat > 0 {
        notes.push(match f_mode {
            FlatEdges::Crease => format!(
                "F edges: {n_flat} read as creases with target 0 unless edges_foldAngle gives \
                 one (FOLD: a flat fold line); --f-edges smooth or ancf:import.f_edges reads \
                 them as triangulation lines"
            ),
            FlatEdges::Smooth => format!(
                "F edges: {n_flat} read as smooth edges (triangulation lines{}); --f-edges \
                 crease reads them as creases",
                if options.f_edges.or(physics.import.f_edges).is_none() {
                    ", as Origami Simulator writes them"
                } else {
                    ""
                }
            ),
        });
    }

    let mut used = vec![false; nv];
    for face in &faces {
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

    // Cuts and vertices where sheets touch: split into copies.
    let mut mesh_edges: Vec<Edge> = (0..edges.v.len())
        .map(|e| Edge {
            v: edges.v[e],
            kind: edges.kind[e],
            fold_target: edges.target[e],
            fold_edge: Some(e),
        })
        .collect();
    let copies = split(
        &mut faces,
        &mut coords,
        &sides,
        &edges,
        &mut mesh_edges,
        &mut warnings,
        &mut notes,
    )?;

    let mut triangles = Vec::new();
    let mut tri_face = Vec::new();
    for (f, face) in faces.iter().enumerate() {
        let tris = ear_clip(face, &coords).ok_or_else(|| {
            invalid(
                format!("faces_vertices[{f}]"),
                "is not a simple polygon (it cannot be triangulated); check it for \
                 self-intersections",
            )
        })?;
        tri_face.extend(std::iter::repeat_n(f, tris.len()));
        triangles.extend(tris);
    }
    if triangles.len() > MAX_FACETS {
        return Err(over_budget(
            "faces_vertices",
            triangles.len(),
            "the pattern triangulates into",
        ));
    }
    let refined = triangles
        .len()
        .saturating_mul(4usize.saturating_pow(physics.refine as u32));
    if refined > MAX_FACETS {
        return Err(over_budget(
            "ancf:refine",
            refined,
            &format!("{} level(s) of refinement would make", physics.refine),
        ));
    }

    let mesh = Mesh::new(coords, triangles, mesh_edges).map_err(|e| translate(e, &tri_face))?;

    let scene_name = physics
        .name
        .clone()
        .or(options.name.clone())
        .or(fold.file_title.clone())
        .or(fold.frame_title.clone())
        .unwrap_or_else(|| "origami".to_string());
    let mut scene = Scene::with_defaults(&scene_name, mesh);
    scene.fold_vertex_count = nv;
    scene.fold_edge_count = edges.v.len();
    // with_defaults drives every mesh crease: the FOLD creases (mesh edges
    // after the FOLD edges are diagonals and cut sides, never creases).
    apply_physics(&mut scene, physics.clone(), &edges, &copies, &mut warnings)?;

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
    Ok(Loaded {
        scene,
        warnings,
        notes,
    })
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

/// A number for a note: four significant digits.
fn short(x: f64) -> String {
    if x == 0.0 || (1e-3..1e4).contains(&x.abs()) {
        let s = format!("{x:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        format!("{x:.3e}")
    }
}

/// The factor from file coordinates to metres, and the note that says how
/// it was chosen: `--size`/`--unit` ([`LoadOptions`]), else
/// `ancf:import.size`/`unit`, else a real `frame_unit`, else
/// [`DEFAULT_SIZE`] on the longest side.
fn choose_scale(
    fold: &FoldFile,
    options: &LoadOptions,
    import: &keys::Import,
    coords: &[Vector2<f64>],
) -> Result<(f64, String), SceneError> {
    let (lo, hi) = bbox(coords);
    let side = (hi - lo).amax();
    if !(side > 0.0 && side.is_finite()) {
        return Err(invalid(
            "vertices_coords",
            "the sheet has no extent (all vertices at one point)",
        ));
    }
    if options.size.is_some() && options.unit.is_some() {
        return Err(invalid("--size", "give either a size or a unit, not both"));
    }
    if let Some(s) = options.size {
        if !(s > 0.0 && s.is_finite()) {
            return Err(invalid(
                "--size",
                format!("{s} is not a positive length (m)"),
            ));
        }
    }
    let dims = |k: f64| {
        format!(
            "{} m x {} m",
            short(k * (hi.x - lo.x)),
            short(k * (hi.y - lo.y))
        )
    };
    let by_size = |s: f64, why: String| -> (f64, String) {
        let k = s / side;
        (
            k,
            format!(
                "size: {}: {why} scales the longest side to {} m (1 file unit = {} m)",
                dims(k),
                short(s),
                short(k)
            ),
        )
    };
    let by_unit = |u: &str, why: String| -> (f64, String) {
        let k = unit_scale(u).expect("checked unit");
        (
            k,
            format!("size: {}: {why} (1 file unit = {} m)", dims(k), short(k)),
        )
    };
    if let Some(s) = options.size {
        return Ok(by_size(s, format!("--size {}", short(s))));
    }
    if let Some(u) = &options.unit {
        let u = keys::check_unit("--unit", u)?;
        return Ok(by_unit(&u, format!("--unit {u}")));
    }
    if let Some(s) = import.size {
        return Ok(by_size(s, format!("ancf:import.size {}", short(s))));
    }
    if let Some(u) = &import.unit {
        return Ok(by_unit(u, format!("ancf:import.unit \"{u}\"")));
    }
    match fold.frame_unit.as_deref() {
        Some("unit") | None => {
            let (k, note) = by_size(
                DEFAULT_SIZE,
                format!(
                    "{} (no physical unit): the default size",
                    if fold.frame_unit.is_some() {
                        "frame_unit \"unit\""
                    } else {
                        "no frame_unit"
                    }
                ),
            );
            Ok((
                k,
                format!("{note}; --size, --unit or ancf:import change it"),
            ))
        }
        Some(u) => {
            if unit_scale(u).is_none() {
                return Err(invalid(
                    "frame_unit",
                    format!(
                        "unknown unit \"{u}\"{}; expected one of {} (or give --unit or --size)",
                        super::error::suggestion(u, UNITS),
                        UNITS.join(", ")
                    ),
                ));
            }
            Ok(by_unit(u, format!("frame_unit \"{u}\"")))
        }
    }
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
fn has_slit(face: &[usize]) -> bool {
    let n = face.len();
    let sides: std::collections::HashSet<(usize, usize)> =
        (0..n).map(|k| (face[k], face[(k + 1) % n])).collect();
    (0..n).any(|k| sides.contains(&(face[(k + 1) % n], face[k])))
}

/// The flat reference coordinates in file units (see the module docs of
/// [`crate::scene`]): 2D as given; 3D with one z as x, y; otherwise the
/// vertices must be coplanar and are expressed in their plane, oriented by
/// the faces' winding (without faces: seen from +z, else +y, else +x).
fn reference_coords(
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
        None => {
            // No faces yet: the normal of the best-fit plane (the smallest
            // principal axis), seen from +z (else +y, else +x).
            let mut m = nalgebra::Matrix3::zeros();
            for p in &pts {
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

/// No zero-length side, no zero-area face.
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
        let area = shoelace(face, c);
        if area.abs() <= DEGENERATE_AREA * mean_len2 {
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
fn orient(
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

/// Where a side occurs: face, position in it, and whether it runs from the
/// smaller vertex index to the larger.
type Occurrence = (usize, usize, bool);

/// Face sides, keyed by sorted vertex pair: where they occur (face,
/// position) and in which direction.
struct Sides {
    map: HashMap<(usize, usize), Vec<Occurrence>>,
    /// Keys in the order of first appearance (face by face).
    order: Vec<(usize, usize)>,
}

fn key(a: usize, b: usize) -> (usize, usize) {
    if a < b { (a, b) } else { (b, a) }
}

impl Sides {
    fn new(faces: &[Vec<usize>]) -> Result<Sides, SceneError> {
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
    fn count(&self, a: usize, b: usize) -> usize {
        self.map.get(&key(a, b)).map_or(0, Vec::len)
    }
    fn faces(&self, a: usize, b: usize) -> Vec<usize> {
        self.map
            .get(&key(a, b))
            .map_or(vec![], |l| l.iter().map(|x| x.0).collect())
    }
    /// The occurrences (face, position) of side a-b.
    fn at(&self, a: usize, b: usize) -> Vec<SideAt> {
        self.map
            .get(&key(a, b))
            .map_or(vec![], |l| l.iter().map(|x| (x.0, x.1)).collect())
    }
}

/// The edges as listed in the file, checked: indices, loops, repeats,
/// array lengths.
struct Listed {
    v: Vec<[usize; 2]>,
    assignment: Vec<Assignment>,
    angles: Vec<Option<f64>>,
}

fn read_edges(
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
pub(crate) struct FoldEdges {
    pub v: Vec<[usize; 2]>,
    pub assignment: Vec<Assignment>,
    pub kind: Vec<EdgeKind>,
    /// Target fold angle in radians.
    pub target: Vec<f64>,
}

fn fold_edges(
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
        None => {
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

/// Split vertices along cut edges and where sheets only touch at a vertex
/// ([`planar::split_vertices`]); renumber the mesh edges on split vertices
/// and add the second side of every cut. Returns, for each copy (mesh
/// vertex `nv + j`), the FOLD vertex it copies.
fn split(
    faces: &mut [Vec<usize>],
    coords: &mut Vec<Vector2<f64>>,
    sides: &Sides,
    edges: &FoldEdges,
    mesh_edges: &mut Vec<Edge>,
    warnings: &mut Vec<String>,
    notes: &mut Vec<String>,
) -> Result<Vec<usize>, SceneError> {
    let cut: HashMap<(usize, usize), usize> = (0..edges.v.len())
        .filter(|&e| edges.assignment[e] == Assignment::Cut)
        .map(|e| (key(edges.v[e][0], edges.v[e][1]), e))
        .collect();
    let shared: Vec<(SideAt, SideAt, bool)> = sides
        .order
        .iter()
        .filter_map(|k| {
            let l = &sides.map[k];
            (l.len() == 2).then(|| ((l[0].0, l[0].1), (l[1].0, l[1].1), cut.contains_key(k)))
        })
        .collect();
    let original: Vec<Vec<usize>> = faces.to_vec();
    let nv = coords.len();
    let copies = planar::split_vertices(faces, coords, &shared);
    if copies.is_empty() {
        let closed = (0..edges.v.len()).find(|&e| {
            edges.assignment[e] == Assignment::Cut && sides.count(edges.v[e][0], edges.v[e][1]) == 2
        });
        if let Some(e) = closed {
            let [a, b] = edges.v[e];
            return Err(invalid(
                format!("edges_vertices[{e}]"),
                format!(
                    "the cut {a}-{b} cannot open: both of its ends stay joined to the sheet (a \
                     cut inside the sheet must run along at least two edges, or reach the \
                     boundary)"
                ),
            ));
        }
        return Ok(copies);
    }
    // Where a side of an original face now runs.
    let now = |(f, k): SideAt, a: usize| -> [usize; 2] {
        let n = faces[f].len();
        let (p, q) = (faces[f][k], faces[f][(k + 1) % n]);
        if original[f][k] == a { [p, q] } else { [q, p] }
    };
    for (e, edge) in mesh_edges.iter_mut().enumerate() {
        let [a, _] = edges.v[e];
        let at = sides.at(edges.v[e][0], edges.v[e][1]);
        edge.v = now(at[0], a);
        if edges.assignment[e] == Assignment::Cut && at.len() == 2 {
            let other = now(at[1], a);
            if key(other[0], other[1]) == key(edge.v[0], edge.v[1]) {
                let [a, b] = edges.v[e];
                return Err(invalid(
                    format!("edges_vertices[{e}]"),
                    format!(
                        "the cut {a}-{b} cannot open: both of its ends stay joined to the sheet \
                         (a cut inside the sheet must run along at least two edges, or reach the \
                         boundary)"
                    ),
                ));
            }
        }
    }
    for (e, &[a, b]) in edges.v.iter().enumerate() {
        if edges.assignment[e] == Assignment::Cut {
            let at = sides.at(a, b);
            if at.len() == 2 {
                let v = now(at[1], a);
                mesh_edges.push(Edge {
                    v,
                    kind: EdgeKind::Boundary,
                    fold_target: 0.0,
                    fold_edge: Some(e),
                });
            }
        }
    }
    // Which copies come from cuts, which from sheets touching at a point.
    let mut on_cut = vec![false; nv];
    for k in cut.keys() {
        on_cut[k.0] = true;
        on_cut[k.1] = true;
    }
    let (by_cut, touching): (Vec<usize>, Vec<usize>) = copies.iter().partition(|&&v| on_cut[v]);
    if !by_cut.is_empty() {
        notes.push(format!(
            "cuts: {} cut edge(s) (C) open the sheet; {} vertex copies were made along them \
             (mesh vertices {} on); outputs vertex[i] follow the first copy, supports hold all",
            cut.len(),
            by_cut.len(),
            nv
        ));
    }
    if let Some(&v) = touching.first() {
        warnings.push(format!(
            "vertices_coords[{v}]: at {} vertex(es) (first: {v}) the faces form separate fans \
             (sheets touching only at a point); each is split into one vertex per fan, so the \
             sheets are free to move apart there",
            touching.len()
        ));
    }
    Ok(copies)
}

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
    p: keys::PhysicsKeys,
    edges: &FoldEdges,
    copies: &[usize],
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
    scene.contact = p.contact.map(|mut c| {
        if c.thickness == 0.0 {
            c.thickness = p.material.thickness;
        }
        c
    });
    scene.solver = p.solver;
    scene.outputs = p.outputs;

    let creases: Vec<usize> = (0..ne)
        .filter(|&e| edges.kind[e] == EdgeKind::Crease)
        .collect();
    let zero = |list: &[usize]| list.iter().all(|&e| edges.target[e] == 0.0);
    match p.actuators {
        None => {
            // with_defaults made `fold` over every mesh crease (= FOLD creases).
            if creases.is_empty() {
                warnings.push(
                    "the pattern has no creases; the default actuator 'fold' drives nothing"
                        .to_string(),
                );
            } else if zero(&creases) {
                warnings.push(format!(
                    "the default actuator 'fold' drives nothing: all {} creases have the target \
                     0 (U or F edges without edges_foldAngle); give the creases M/V assignments \
                     or edges_foldAngle, or drive them with a torque actuator (ancf:actuators)",
                    creases.len()
                ));
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
                if a.mode == ActuatorMode::RestAngle && !selected.is_empty() && zero(&selected) {
                    warnings.push(format!(
                        "{sel_key}: every crease the rest_angle actuator '{}' drives has the \
                         target 0, so it drives nothing; give them edges_foldAngle, or use \
                         \"mode\": \"torque\"",
                        a.name
                    ));
                }
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
        // A support on a split vertex holds all its copies.
        let mut vertices = s.vertices;
        if !copies.is_empty() {
            let held: std::collections::HashSet<usize> = vertices.iter().copied().collect();
            vertices.extend(
                copies
                    .iter()
                    .enumerate()
                    .filter(|(_, v)| held.contains(v))
                    .map(|(j, _)| nv + j),
            );
        }
        scene.supports.push(Support {
            vertices,
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
    use crate::scene::{FlatEdges, LoadOptions};
    use serde_json::{Value, json};
    use std::f64::consts::PI;

    /// Two unit squares side by side with the valley crease 1-4 (FOLD edge 6),
    /// in metres.
    fn base() -> Value {
        json!({
            "file_spec": 1.2,
            "frame_unit": "m",
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
        assert_eq!(m.edges[4].kind, EdgeKind::Crease);
        assert_eq!(m.edge_faces[4].len(), 2);
        assert_eq!(m.triangles.len(), 4);
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
        assert_eq!(s.mesh.coords[3], Vector2::new(2.0, -1.0));
        assert!((s.mesh.edges[6].fold_target - PI / 2.0).abs() < 1e-15);
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
        assert_eq!(s.mesh.edges[0].kind, EdgeKind::Boundary);
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
        // a cut across the sheet: two separate panels, vertices 1 and 4 split
        let v = with(
            base(),
            "edges_assignment",
            json!(["B", "B", "B", "B", "B", "B", "C"]),
        );
        let l = from_fold_with(
            &crate::scene::fold::parse(&v.to_string(), None).unwrap().0,
            &LoadOptions::default(),
        )
        .unwrap();
        let s = &l.scene;
        assert_eq!(s.mesh.n_vertices(), 8);
        assert_eq!(s.fold_vertex_count, 6);
        assert_eq!(s.mesh.coords[6], s.mesh.coords[1]);
        assert_eq!(s.mesh.coords[7], s.mesh.coords[4]);
        assert!(
            l.notes.iter().any(|n| n.starts_with("cuts: 1 cut edge")),
            "{:?}",
            l.notes
        );
        assert!(
            l.warnings[0].contains("angle 90 of the C edge 1-4 is ignored"),
            "{:?}",
            l.warnings
        );
        // both sides of the cut are boundary edges on FOLD edge 6
        let cut: Vec<&Edge> = s
            .mesh
            .edges
            .iter()
            .filter(|e| e.fold_edge == Some(6))
            .collect();
        assert_eq!(cut.len(), 2);
        assert!(cut.iter().all(|e| e.kind == EdgeKind::Boundary));
        assert!(s.actuators[0].edges.is_empty());
        // a support on a split vertex holds both copies
        let (s, _) = load(&with(
            v.clone(),
            "ancf:supports",
            json!([{"vertices": [1]}]),
        ))
        .unwrap();
        assert_eq!(s.supports[0].vertices, vec![1, 6]);
        crate::model::Model::new(s).unwrap();
        // a cut of one edge inside the sheet cannot open
        let v = json!({
            "frame_unit": "m",
            "vertices_coords": [[0,0],[3,0],[3,3],[0,3],[1,1],[2,2]],
            "edges_vertices": [[0,1],[1,2],[2,3],[3,0],[4,5],[0,4],[4,3],[1,5],[5,2],[1,4],[3,5]],
            "edges_assignment": ["B","B","B","B","C","F","F","F","F","F","F"],
            "faces_vertices": [[0,1,4],[1,5,4],[1,2,5],[2,3,5],[3,4,5],[3,0,4]]
        });
        let e = err(&v, "edges_vertices[4]");
        assert!(e.contains("cannot open"), "{e}");
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
        assert_eq!(s.mesh.edges[0].kind, EdgeKind::Boundary);
        assert_eq!(s.mesh.edges[6].kind, EdgeKind::Crease);
        assert_eq!(s.mesh.edges[6].fold_target, 0.0);
        assert_eq!(s.actuators[0].edges, vec![6]);
        assert!(w.iter().any(|w| w.contains("drives nothing")), "{w:?}");
        let parsed = crate::scene::fold::parse(&v.to_string(), None).unwrap().0;
        let smooth = LoadOptions {
            f_edges: Some(FlatEdges::Smooth),
            ..Default::default()
        };
        let l = from_fold_with(&parsed, &smooth).unwrap();
        assert_eq!(l.scene.mesh.edges[6].kind, EdgeKind::Smooth);
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
        assert_eq!(s.mesh.edges[6].kind, EdgeKind::Smooth);
        let keyed = with(v.clone(), "ancf:import", json!({"f_edges": "smooth"}));
        assert_eq!(load(&keyed).unwrap().0.mesh.edges[6].kind, EdgeKind::Smooth);
        let j = with(
            base(),
            "edges_assignment",
            json!(["B", "B", "B", "B", "B", "B", "J"]),
        );
        let (s, _) = load(&j).unwrap();
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
        // a unitless sheet is scaled to DEFAULT_SIZE on its longest side,
        // whatever its coordinates; "unit" is no unit
        for unit in [None, Some("unit")] {
            let mut v = with(
                base(),
                "vertices_coords",
                json!([[0, 0], [100, 0], [200, 0], [200, 100], [100, 100], [0, 100]]),
            );
            match unit {
                Some(u) => v["frame_unit"] = json!(u),
                None => {
                    v.as_object_mut().unwrap().remove("frame_unit");
                }
            }
            let parsed = crate::scene::fold::parse(&v.to_string(), None).unwrap().0;
            let l = from_fold_with(&parsed, &LoadOptions::default()).unwrap();
            assert!(l.warnings.is_empty(), "{:?}", l.warnings);
            assert_eq!(l.scene.mesh.coords[2].x, DEFAULT_SIZE);
            assert!((l.scene.mesh.coords[3].y - 0.5 * DEFAULT_SIZE).abs() < 1e-15);
            assert!(
                l.notes[0].starts_with("size: 0.1 m x 0.05 m:") && l.notes[0].contains("default"),
                "{:?}",
                l.notes
            );
            // --size and --unit, and the ancf:import key
            let o = LoadOptions {
                size: Some(0.3),
                ..Default::default()
            };
            let l = from_fold_with(&parsed, &o).unwrap();
            assert!((l.scene.mesh.coords[2].x - 0.3).abs() < 1e-15);
            let o = LoadOptions {
                unit: Some("mm".into()),
                ..Default::default()
            };
            let l = from_fold_with(&parsed, &o).unwrap();
            assert!((l.scene.mesh.coords[2].x - 0.2).abs() < 1e-15);
            assert!(l.notes[0].contains("--unit mm"), "{:?}", l.notes);
            let o = LoadOptions {
                unit: Some("mn".into()),
                ..Default::default()
            };
            let e = from_fold_with(&parsed, &o).unwrap_err().to_string();
            assert!(
                e.starts_with("--unit:") && e.contains("did you mean"),
                "{e}"
            );
            let (s, _) = load(&with(v.clone(), "ancf:import", json!({"size": 0.5}))).unwrap();
            assert!((s.mesh.coords[2].x - 0.5).abs() < 1e-15);
            let (s, _) = load(&with(v.clone(), "ancf:import", json!({"unit": "cm"}))).unwrap();
            assert!((s.mesh.coords[2].x - 2.0).abs() < 1e-15);
        }
        // a real unit is kept; --size rescales it anyway
        let v = with(base(), "frame_unit", json!("cm"));
        let parsed = crate::scene::fold::parse(&v.to_string(), None).unwrap().0;
        let l = from_fold_with(&parsed, &LoadOptions::default()).unwrap();
        assert_eq!(l.scene.mesh.coords[2].x, 0.02);
        assert!(l.notes[0].contains("frame_unit \"cm\""), "{:?}", l.notes);
        let o = LoadOptions {
            size: Some(1.0),
            ..Default::default()
        };
        assert_eq!(
            from_fold_with(&parsed, &o).unwrap().scene.mesh.coords[2].x,
            1.0
        );
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
            "frame_unit": "m",
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
