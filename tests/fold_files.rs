//! Real FOLD files from public projects (tests/data, sources and licences in
//! tests/data/SOURCES.md): each loads with default settings, builds an FMU
//! description, folds a little and is checked; the unitless single-diagonal
//! file of the FOLD specification folds to 180 degrees with the README's
//! input without overshooting; folded states are refused with what to do.

use origami_fmu::fmi;
use origami_fmu::ids::FoldEdgeId;
use origami_fmu::mesh::EdgeKind;
use origami_fmu::model::Model;
use origami_fmu::scene::{self, FrameSelector, LoadOptions};
use std::path::PathBuf;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// Index of output `name`.
fn output(m: &Model, name: &str) -> usize {
    m.outputs()
        .iter()
        .position(|v| v.name == name)
        .unwrap_or_else(|| panic!("no output {name}"))
}

/// The README's input: `fold` ramped from 0 to 1 by 0.6 s, then held,
/// in communication steps of 5 ms up to 1 s, each step given the ramp's
/// value at its start and its slope (as the main job does). Returns the
/// largest and the last value of output `watch`.
fn readme_fold(m: &mut Model, watch: usize) -> (f64, f64) {
    m.initialize().unwrap();
    let dt = 0.005;
    let mut max = f64::NEG_INFINITY;
    for k in 0..200 {
        let t = k as f64 * dt;
        let (u0, u1) = ((t / 0.6).min(1.0), ((t + dt) / 0.6).min(1.0));
        m.set_input(m.input_at(0).unwrap(), u0).unwrap();
        m.set_input_derivative(m.input_at(0).unwrap(), 1, (u1 - u0) / dt)
            .unwrap();
        m.advance(dt).unwrap();
        max = max.max(m.output_values()[watch]);
    }
    (max, m.output_values()[watch])
}

#[test]
fn unitless_diagonal_folds_to_180_degrees_without_overshoot() {
    // The FOLD specification's diagonal-cp.fold: a unit square (no
    // frame_unit) with one valley diagonal to 180 degrees.
    let l =
        scene::load_report(data("fold-spec/diagonal-cp.fold"), &LoadOptions::default()).unwrap();
    assert!(l.warnings.is_empty(), "{:?}", l.warnings);
    assert!(
        l.notes[0].starts_with("size: 0.1 m x 0.1 m: no frame_unit"),
        "{:?}",
        l.notes
    );
    let mut m = Model::new(l.scene).unwrap();
    let watch = output(&m, "crease[4].angle");
    let (max, last) = readme_fold(&mut m, watch);
    let (max, last) = (max.to_degrees(), last.to_degrees());
    assert!(max <= 185.0, "overshoot to {max} degrees");
    assert!((last - 180.0).abs() < 2.0, "ends at {last} degrees");
}

/// Load with defaults, build the FMU description, fold to 20 % in 0.1 s,
/// and check that every crease with a target moved towards it.
fn load_build_fold(name: &str) -> scene::Loaded {
    let l = scene::load_report(data(name), &LoadOptions::default())
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let c = fmi::fmu_contents(&l.scene).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert!(c.model_description.contains("name=\"fold\""), "{name}");
    let s = l.scene.clone();
    let mut m = Model::new(s.clone()).unwrap();
    m.initialize().unwrap();
    for k in 0..10 {
        // The ramp 0 -> 0.2 over 0.1 s: value at the step start and slope.
        m.set_input(m.input_at(0).unwrap(), 0.02 * k as f64)
            .unwrap();
        m.set_input_derivative(m.input_at(0).unwrap(), 1, 2.0)
            .unwrap();
        m.advance(0.01).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    let out = m.output_values();
    assert!(out.iter().all(|x| x.is_finite()), "{name}");
    let mut moved = 0;
    for (e, edge) in s.mesh.edges().iter().enumerate() {
        if edge.kind != EdgeKind::Crease
            || edge.fold_target == 0.0
            || edge.fold_edge != Some(FoldEdgeId(e))
        {
            continue;
        }
        let a = out[output(&m, &format!("crease[{e}].angle"))];
        if a * edge.fold_target > 0.0 {
            moved += 1;
        }
        assert!(
            a.abs() < edge.fold_target.abs() + 0.05,
            "{name}: crease {e} at {a} beyond its target {}",
            edge.fold_target
        );
    }
    let targets = s
        .mesh
        .edges()
        .iter()
        .filter(|e| e.kind == EdgeKind::Crease && e.fold_target != 0.0)
        .count();
    assert!(targets > 0, "{name}: no crease to fold");
    // Most creases fold their own way at once (a few may first be pushed
    // the other way by their neighbours).
    assert!(
        4 * moved >= 3 * targets,
        "{name}: only {moved} of {targets} creases folded towards their targets"
    );
    l
}

#[test]
fn real_crease_patterns_load_build_and_fold() {
    // Cube net, unitless; its frame_classes says foldedForm but it is flat.
    let l = load_build_fold("fold-spec/cube-cp.fold");
    assert_eq!(l.scene.mesh.triangles().len(), 12);
    assert!(
        l.notes[0].contains("1 file unit = 0.025 m"),
        "{:?}",
        l.notes
    );
    // The same net as edges only: the faces are traced.
    let l = load_build_fold("fold-spec/vertex.fold");
    assert!(
        l.notes
            .iter()
            .any(|n| n.starts_with("faces: faces_vertices is missing; 6 faces")),
        "{:?}",
        l.notes
    );
    // A flat-folder grid crease pattern (valleys to 180 degrees).
    let l = load_build_fold("flat-folder/003_brown_3x3_A2.fold");
    assert!(l.warnings.is_empty(), "{:?}", l.warnings);
    // An Origami Simulator export (cm, pattern in the x-z plane): its F
    // edges are triangulation lines.
    let l = load_build_fold("origami_simulator_export.fold");
    assert_eq!(l.scene.mesh.edges()[10].kind, EdgeKind::Smooth);
    assert!(
        l.notes
            .iter()
            .any(|n| n.contains("as Origami Simulator writes them")),
        "{:?}",
        l.notes
    );
}

#[test]
fn folded_states_are_refused_with_what_to_do() {
    // A 3D folded form, no other frame.
    let e = scene::load(data("fold-spec/simple.fold"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("is a folded state") && e.contains("export the unfolded crease pattern"),
        "{e}"
    );
    // A flat-folded state: mirrored faces.
    let e = scene::load(data("fold-spec/diagonal-folded.fold"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("folded state (flat-folded)"), "{e}");
    // The folded state on top, the crease pattern in file_frames[0]: the
    // error names frame 1; --frame 1 reads it.
    let folded: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(data("fold-spec/diagonal-folded.fold")).unwrap(),
    )
    .unwrap();
    let mut cp: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(data("fold-spec/diagonal-cp.fold")).unwrap())
            .unwrap();
    cp["frame_title"] = "crease pattern".into();
    let mut both = folded;
    both["file_frames"] = serde_json::json!([cp]);
    let text = both.to_string();
    let e = scene::from_str(&text).unwrap_err().to_string();
    assert!(
        e.contains("frame 1 ('crease pattern') is a crease pattern: read it with --frame 1"),
        "{e}"
    );
    let o = LoadOptions {
        frame: Some(FrameSelector::Index(1)),
        ..Default::default()
    };
    let (s, _) = scene::from_str_with(&text, &o).unwrap();
    assert_eq!(s.mesh.triangles().len(), 2);
    // Among many frames: the first few crease patterns are named (each
    // frame is read once, however many there are).
    let mut many = both.clone();
    let mut frames = Vec::new();
    for k in 1..=300 {
        let mut f = if k % 3 == 0 { cp.clone() } else { both.clone() };
        f.as_object_mut().unwrap().remove("file_frames");
        f["frame_title"] = format!("f{k}").into();
        frames.push(f);
    }
    many["file_frames"] = frames.into();
    let e = scene::from_str(&many.to_string()).unwrap_err().to_string();
    assert!(
        e.contains("frames 3 ('f3'), 6 ('f6'), 9 ('f9'), 12 ('f12'), 15 ('f15') and more are"),
        "{e}"
    );
}

/// A file beyond the size budget is refused from a count of its raw
/// arrays, before they are parsed (docs/fold_files.md, "Large files").
#[test]
fn files_beyond_the_size_budget_are_refused_before_parsing() {
    let budget = origami_fmu::scene::build::MAX_FACETS;
    let faces = vec!["[0,1,2,3]"; budget / 2 + 1].join(",");
    let text =
        format!(r#"{{"vertices_coords": [[0,0],[1,0],[1,1],[0,1]], "faces_vertices": [{faces}]}}"#);
    let e = scene::from_str(&text).unwrap_err();
    assert_eq!(e.key(), Some("faces_vertices"));
    assert!(e.to_string().contains("size budget"), "{e}");
    // Vertices or edges beyond what a pattern within the budget can have.
    let points = vec!["[0,0]"; 3 * budget + 1].join(",");
    let text = format!(r#"{{"vertices_coords": [{points}], "faces_vertices": [[0,1,2]]}}"#);
    let e = scene::from_str(&text).unwrap_err();
    assert_eq!(e.key(), Some("vertices_coords"), "{e}");
    // In a frame of file_frames too.
    let text = format!(
        r#"{{"file_frames": [{{"vertices_coords": [[0,0],[1,0],[1,1],[0,1]], "faces_vertices": [{faces}]}}]}}"#
    );
    let e = scene::from_str(&text).unwrap_err();
    assert!(e.to_string().contains("size budget"), "{e}");
}

/// Origami Simulator's BoxPleatPyramid (the speed bench's large real
/// pattern): it loads with defaults as docs/fold_files.md says (5202 facets,
/// 3264 creases, unitless read as a 0.1 m sheet, F edges smooth), builds a
/// model and initializes; folding it is the bench's job (minutes).
#[test]
fn box_pleat_pyramid_loads_and_initializes() {
    let l = scene::load_report(
        data("origami-simulator/BoxPleatPyramid.fold"),
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(l.scene.mesh.triangles().len(), 5202);
    assert!(
        l.notes.iter().any(|n| n.starts_with("size: 0.1 m x 0.1 m")),
        "{:?}",
        l.notes
    );
    // The size is the bounding box's diagonal.
    let size = l.scene.mesh.size();
    assert!((size - 0.1 * 2f64.sqrt()).abs() < 1e-6, "size {size}");
    let mut m = Model::new(l.scene).unwrap();
    let creases = m
        .outputs()
        .iter()
        .filter(|v| v.name.starts_with("crease["))
        .count();
    assert_eq!(creases, 3264);
    m.initialize().unwrap();
    assert!(m.output_values().iter().all(|x| x.is_finite()));
}
