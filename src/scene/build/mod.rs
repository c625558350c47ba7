//! Building and validating a [`Scene`] from one FOLD frame.
//!
//! In order: the `ancf:` keys ([`super::keys`]); the size budget; the
//! listed edges; the faces (given, or traced from the edges by
//! `super::planar`); the reference coordinates (flatness, orientation:
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
//!
//! This file holds the entry points ([`from_fold`], [`from_fold_with`]), the
//! size budget and the order of the steps; each step is in its own file:
//! `size.rs` (unit or scale, the range of sizes), `faces.rs` (face indices,
//! reference coordinates, areas, orientation, triangulation), `edges.rs`
//! (face sides and who shares them, the listed or derived edges, their kinds
//! and targets), `split.rs` (cuts and vertices where sheets touch),
//! `physics.rs` (the `ancf:` physics checked against the mesh); each with
//! its tests (their shared sheet: `fixtures.rs`). The faces are checked as
//! polygons here, with the file's keys, before [`Mesh::new`] checks the
//! triangles again for every other caller; what only the triangles can show
//! is translated back to the faces.

mod edges;
mod faces;
#[cfg(test)]
mod fixtures;
mod physics;
mod sequence;
mod size;
mod split;

pub use faces::COPLANAR_TOLERANCE;
pub use size::{DEFAULT_SIZE, MAX_EXTENT, MIN_EXTENT};

use super::error::SceneError;
use super::fold::{Assignment, FoldFile};
use super::keyframes::KeyFrame;
use super::keys;
use super::planar;
use super::{FlatEdges, LoadOptions, Loaded, Scene, refine};
use crate::ids::{FacetId, FoldEdgeId, VertexId, vertex_ids};
use crate::mesh::{Edge, EdgeKind, Mesh, MeshError};
use edges::{FoldEdges, Listed, Sides, fold_edges, read_edges};
use faces::{
    check_areas, check_faces, check_used, has_slit, orient, reference_coords, triangulate,
};
use nalgebra::Vector2;
use physics::apply_physics;
use size::{check_extent, choose_scale};
use split::split;

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

/// About how many facets a pattern of `n_vertices` triangulates into:
/// `faces` (count, corners in all) give `corners - 2 count`; without them
/// (faces traced from the edges) a planar triangulation has about two
/// triangles per vertex. What the size budget is checked on, by the FOLD
/// reader before the arrays are parsed and by the builder after.
pub fn facet_estimate(n_vertices: usize, faces: Option<(usize, usize)>) -> usize {
    match faces {
        Some((count, corners)) => corners.saturating_sub(2 * count),
        None => 2 * n_vertices,
    }
}

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

/// FOLD vertex `v` exists (of `nv`), else the error at `key()`.
fn vertex_exists(v: usize, nv: usize, key: impl FnOnce() -> String) -> Result<(), SceneError> {
    if v < nv {
        Ok(())
    } else {
        Err(invalid(
            key(),
            format!("vertex {v} does not exist (there are {nv} vertices)"),
        ))
    }
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
    from_fold_keyframes(fold, options, &[])
}

/// [`from_fold_with`] with the file's keyframes (the frames after this one,
/// [`super::keyframes`]): a folding sequence, one stage each.
pub(crate) fn from_fold_keyframes(
    fold: &FoldFile,
    options: &LoadOptions,
    keyframes: &[KeyFrame],
) -> Result<Loaded, SceneError> {
    let mut warnings = Vec::new();
    let mut notes = Vec::new();
    let mut physics = keys::parse(&fold.ancf, &mut warnings)?;

    let nv = fold.vertices_coords.len();
    if nv == 0 {
        return Err(invalid("vertices_coords", "is empty"));
    }
    check_size_budget(fold, nv)?;
    let listed = read_edges(fold, nv, &mut warnings)?;

    let f_mode = options.f_edges.or(physics.import.f_edges).unwrap_or(
        if is_origami_simulator_export(fold) {
            FlatEdges::Smooth
        } else {
            FlatEdges::Crease
        },
    );

    let (mut coords, mut faces) = reference_and_faces(
        fold,
        options,
        &physics.import,
        listed.as_ref(),
        &mut warnings,
        &mut notes,
    )?;
    let sides = Sides::new(&faces)?;
    let edges = fold_edges(listed, &sides, f_mode, &mut warnings)?;
    if let Some(note) = flat_edges_note(
        &edges,
        f_mode,
        options.f_edges.or(physics.import.f_edges).is_none(),
    ) {
        notes.push(note);
    }

    check_used(&faces, nv)?;

    // Cuts and vertices where sheets touch: split into copies.
    // The FOLD edges first, in order: FOLD edge e is mesh edge e
    // (`EdgeId::of_fold_edge`) until refinement.
    let mut mesh_edges: Vec<Edge> = (0..edges.v.len())
        .map(|e| Edge {
            v: edges.v[e].map(VertexId::of_fold_vertex),
            kind: edges.kind[e],
            fold_target: edges.target[e],
            fold_edge: Some(FoldEdgeId(e)),
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

    let (triangles, tri_face) = triangulate(&faces, &coords)?;
    if triangles.len() > MAX_FACETS {
        return Err(over_budget(
            "faces_vertices",
            triangles.len(),
            "the pattern triangulates into",
        ));
    }
    check_refined_budget(triangles.len(), physics.refine)?;

    // The faces hold mesh vertices now (split copies after the FOLD ones).
    let triangles = triangles.into_iter().map(vertex_ids).collect();
    let mesh = Mesh::new(coords, triangles, mesh_edges).map_err(|e| translate(e, &tri_face))?;

    let scene_name = physics
        .name
        .clone()
        .or(options.name.clone())
        .or(fold.file_title.clone())
        .or(fold.frame_title.clone())
        .unwrap_or_else(|| "origami".to_string());
    if !keyframes.is_empty() && physics.sequence.is_none() {
        physics.sequence = Some(super::keyframes::stages(
            keyframes,
            &mesh,
            (nv, &copies),
            (&edges.kind, &edges.target),
            &mut warnings,
        )?);
    }
    let mut scene = Scene::with_defaults(&scene_name, mesh);
    scene.fold_vertex_count = nv;
    scene.fold_edge_count = edges.v.len();
    // with_defaults drives every mesh crease: the FOLD creases (mesh edges
    // after the FOLD edges are diagonals and cut sides, never creases).
    apply_physics(
        &mut scene,
        physics.clone(),
        &edges,
        &copies,
        options.contact,
        &mut warnings,
    )?;

    warnings.extend(thin_shell_warning(&scene));

    if physics.refine > 0 {
        scene = refine::refine(&scene, physics.refine)?;
    }
    Ok(Loaded {
        scene,
        warnings,
        notes,
    })
}

/// The size budget, before anything large is allocated: the facets the
/// FOLD arrays would triangulate into.
fn check_size_budget(fold: &FoldFile, nv: usize) -> Result<(), SceneError> {
    let faces = &fold.faces_vertices;
    let corners = faces.iter().map(Vec::len).sum();
    let estimate = facet_estimate(nv, (!faces.is_empty()).then_some((faces.len(), corners)));
    if estimate > MAX_FACETS {
        return Err(over_budget(
            "faces_vertices",
            estimate,
            "the pattern would triangulate into about",
        ));
    }
    Ok(())
}

/// The facets left after `levels` of refinement within the budget.
fn check_refined_budget(triangles: usize, levels: usize) -> Result<(), SceneError> {
    let refined = triangles.saturating_mul(4usize.saturating_pow(levels as u32));
    if refined > MAX_FACETS {
        return Err(over_budget(
            "ancf:refine",
            refined,
            &format!("{levels} level(s) of refinement would make"),
        ));
    }
    Ok(())
}

/// Faces as lists of vertex indices, counter-clockwise.
type Faces = Vec<Vec<usize>>;

/// The flat reference in metres, and the faces (given, or traced from
/// the edges), oriented and checked.
fn reference_and_faces(
    fold: &FoldFile,
    options: &LoadOptions,
    import: &keys::Import,
    listed: Option<&Listed>,
    warnings: &mut Vec<String>,
    notes: &mut Vec<String>,
) -> Result<(Vec<Vector2<f64>>, Faces), SceneError> {
    let nv = fold.vertices_coords.len();
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
    let (scale, size_note) = choose_scale(fold, options, import, &coords)?;
    for c in &mut coords {
        *c *= scale;
    }
    check_extent(&coords)?;
    let faces: Vec<Vec<usize>> = match listed {
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
    orient(&mut coords, &faces, fold, warnings)?;
    notes.push(size_note);
    let slits = faces.iter().filter(|f| has_slit(f)).count();
    if slits > 0 {
        notes.push(format!(
            "slits: {slits} face(s) run along an edge and back (a crease or cut ending \
             inside the face); such a crease folds and stops in the paper, such a cut opens"
        ));
    }
    Ok((coords, faces))
}

/// What the loader made of the FOLD file's flat (F) edges, if it has any.
fn flat_edges_note(edges: &FoldEdges, f_mode: FlatEdges, by_default: bool) -> Option<String> {
    let n_flat = (0..edges.v.len())
        .filter(|&e| edges.assignment[e] == Assignment::Flat && edges.kind[e] != EdgeKind::Boundary)
        .count();
    (n_flat > 0).then(|| match f_mode {
        FlatEdges::Crease => format!(
            "F edges: {n_flat} read as creases with target 0 unless edges_foldAngle gives \
                 one (FOLD: a flat fold line); --f-edges smooth or ancf:import.f_edges reads \
                 them as triangulation lines"
        ),
        FlatEdges::Smooth => format!(
            "F edges: {n_flat} read as smooth edges (triangulation lines{}); --f-edges \
                 crease reads them as creases",
            if by_default {
                ", as Origami Simulator writes them"
            } else {
                ""
            }
        ),
    })
}

/// Thin-shell sanity: the thickness against the shortest edge.
fn thin_shell_warning(scene: &Scene) -> Option<String> {
    let shortest = scene
        .mesh
        .edge_ids()
        .map(|e| scene.mesh.edge_length(e))
        .fold(f64::INFINITY, f64::min);
    (scene.material.thickness > 0.1 * shortest).then(|| {
        format!(
            "ancf:material.thickness: {:.3e} m is more than a tenth of the shortest edge \
             ({shortest:.3e} m); the thin-shell model may be inaccurate",
            scene.material.thickness
        )
    })
}

fn translate(e: MeshError, tri_face: &[usize]) -> SceneError {
    let face = |t: FacetId| {
        let f = tri_face.get(t.index()).copied().unwrap_or(0);
        format!("faces_vertices[{f}]")
    };
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

#[cfg(test)]
mod tests {
    use super::fixtures::{base, err, load, with};
    use crate::ids::{EdgeId, FacetId, FoldEdgeId};
    use crate::mesh::EdgeKind;
    use crate::scene::ActuatorMode;
    use serde_json::json;
    use std::f64::consts::PI;

    #[test]
    fn plain_file_gets_documented_defaults() {
        let (s, w) = load(&base()).unwrap();
        assert!(w.is_empty(), "{w:?}");
        assert_eq!(s.name, "origami");
        assert_eq!((s.fold_vertex_count, s.fold_edge_count), (6, 7));
        assert_eq!(s.mesh.triangles().len(), 4);
        // FOLD edges first, in order, tagged; diagonals after, untagged.
        for e in 0..7 {
            assert_eq!(s.mesh.edges()[e].fold_edge, Some(FoldEdgeId(e)));
        }
        assert_eq!(s.mesh.edges().len(), 9);
        assert!(
            s.mesh.edges()[7..]
                .iter()
                .all(|e| e.fold_edge.is_none() && e.kind == EdgeKind::Smooth)
        );
        assert_eq!(s.mesh.edges()[6].kind, EdgeKind::Crease);
        assert!((s.mesh.edges()[6].fold_target - PI / 2.0).abs() < 1e-15);
        assert_eq!(s.actuators.len(), 1);
        assert_eq!(s.actuators[0].name, "fold");
        assert_eq!(s.actuators[0].edges, vec![EdgeId(6)]);
        assert_eq!(s.actuators[0].mode, ActuatorMode::RestAngle);
        assert!(s.auto_damping);
        assert!(s.supports.is_empty() && s.gravity.is_none());
        assert_eq!(s.material, crate::scene::Material::default());
        crate::model::Model::new(s).unwrap();
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
    fn non_convex_face_is_triangulated_inside() {
        let v = json!({
            "frame_unit": "m",
            "vertices_coords": [[0,0],[2,0],[2,1],[1,1],[1,2],[0,2]],
            "faces_vertices": [[0,1,2,3,4,5]]
        });
        let (s, _) = load(&v).unwrap();
        assert_eq!(s.mesh.triangles().len(), 4);
        let total: f64 = (0..4).map(|t| s.mesh.area(FacetId(t))).sum();
        assert!((total - 3.0).abs() < 1e-14);
    }

    #[test]
    fn refine_key_keeps_fold_indices() {
        let v = with(base(), "ancf:refine", json!(2));
        let v = with(v, "ancf:actuators", json!([{"name": "f", "edges": [6]}]));
        let (s, _) = load(&v).unwrap();
        assert_eq!(s.mesh.triangles().len(), 64);
        assert_eq!((s.fold_vertex_count, s.fold_edge_count), (6, 7));
        let (flat, _) = load(&base()).unwrap();
        assert_eq!(&s.mesh.coords()[..6], flat.mesh.coords());
        // crease 6 is now 4 mesh creases, all driven, all tagged 6
        assert_eq!(s.actuators[0].edges.len(), 4);
        for &e in &s.actuators[0].edges {
            assert_eq!(s.mesh.edge(e).kind, EdgeKind::Crease);
            assert_eq!(s.mesh.edge(e).fold_edge, Some(FoldEdgeId(6)));
        }
        let m = crate::model::Model::new(s).unwrap();
        assert_eq!(m.outputs().len(), 6 * 3 + 1 + 5);
    }
}
