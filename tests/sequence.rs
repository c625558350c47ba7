//! Folding in sequence (`ancf:sequence`, FOLD frames as keyframes): the
//! one `fold` input walks the stages in order and back, through every
//! input path (slopes, held values, first-order hold, the built-in ramp, a
//! servo); the rest angles stay continuous and the energy balance closes;
//! bad sequences are refused naming the stage; a file's frames read as
//! stages; a motion written as FOLD reads back as the same stages.

mod common;

use origami_fmu::Model;
use origami_fmu::ids::FoldEdgeId;
use origami_fmu::scene::{self, Integrator, Keyframes, LoadOptions, Sequence, Stage};
use serde_json::{Value, json};
use std::f64::consts::PI;

/// Three 30 mm panels in a row: a valley (FOLD edge 8, 90 deg) and a
/// mountain (edge 9, -90 deg), with `sequence` as its `ancf:sequence`.
fn strip(sequence: Value) -> Value {
    json!({
        "frame_unit": "m",
        "vertices_coords": [[0,0],[0.03,0],[0.06,0],[0.09,0],[0.09,0.03],[0.06,0.03],[0.03,0.03],[0,0.03]],
        "edges_vertices": [[0,1],[1,2],[2,3],[3,4],[4,5],[5,6],[6,7],[7,0],[1,6],[2,5]],
        "edges_assignment": ["B","B","B","B","B","B","B","B","V","M"],
        "edges_foldAngle": [0,0,0,0,0,0,0,0,90,-90],
        "faces_vertices": [[0,1,6,7],[1,2,5,6],[2,3,4,5]],
        "ancf:sequence": sequence
    })
}

/// The valley to its target in the first half, then the mountain to -60 deg.
fn two_stages() -> Value {
    json!([
        {"edges": [8], "share": 0.5, "title": "valley"},
        {"edges": "M", "degrees": -60, "share": 0.5}
    ])
}

fn load(v: &Value) -> Result<(scene::Scene, Vec<String>), scene::SceneError> {
    scene::from_str(&v.to_string())
}

fn model(v: &Value) -> Model {
    Model::new(load(v).unwrap().0).unwrap()
}

/// The fold angles of FOLD edges 8 and 9, in degrees.
fn angles(m: &Model) -> [f64; 2] {
    let a = |e: usize| {
        let id = m.output_id(&format!("crease[{e}].angle")).unwrap();
        m.output(id).unwrap().to_degrees()
    };
    [a(8), a(9)]
}

fn output(m: &Model, name: &str) -> f64 {
    m.output(m.output_id(name).unwrap()).unwrap()
}

/// Drive the `fold` input linearly from `from` to `to` over `time` s with
/// its slope (10 ms steps), then hold it for `hold` s.
fn drive(m: &mut Model, from: f64, to: f64, time: f64, hold: f64) {
    let fold = m.input_id("fold").unwrap();
    let n = (time / 0.01).round() as usize;
    for k in 0..n {
        let u = from + (to - from) * k as f64 / n as f64;
        m.set_input(fold, u).unwrap();
        m.set_input_derivative(fold, 1, (to - from) / time).unwrap();
        m.advance(0.01).unwrap();
    }
    m.set_input(fold, to).unwrap();
    for _ in 0..(hold / 0.01).round() as usize {
        m.advance(0.01).unwrap();
    }
}

#[test]
fn the_scene_has_the_stages_their_actuator_and_outputs() {
    let (s, warnings) = load(&strip(two_stages())).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let sq = s.sequence.as_ref().unwrap();
    assert_eq!(sq.actuator, "fold");
    assert_eq!(sq.stages.len(), 2);
    assert_eq!(sq.stages[0].title.as_deref(), Some("valley"));
    assert_eq!(sq.stages[0].targets, vec![(FoldEdgeId(8), PI / 2.0)]);
    assert_eq!(sq.stages[1].targets[0].0, FoldEdgeId(9));
    assert!((sq.stages[1].targets[0].1 + PI / 3.0).abs() < 1e-15);
    assert_eq!(s.actuators.len(), 1);
    assert_eq!(s.actuators[0].name, "fold");
    assert_eq!(s.actuators[0].edges.len(), 2);
    let m = Model::new(s).unwrap();
    let names: Vec<&str> = m.outputs().iter().map(|v| v.name.as_str()).collect();
    assert_eq!(
        &names[names.len() - 2..],
        &["sequence.stage", "sequence.progress"]
    );
    // Equal shares when none is given.
    let (s, _) = load(&strip(
        json!([{"edges": [8]}, {"edges": [9]}, {"edges": "all", "fraction": 0.5}]),
    ))
    .unwrap();
    let shares: Vec<f64> = s.sequence.unwrap().stages.iter().map(|s| s.share).collect();
    assert_eq!(shares, vec![1.0 / 3.0; 3]);
}

/// Stage 0 folds the valley while the mountain waits; stage 1 the
/// mountain while the valley holds; driven back, the mountain unfolds
/// first. The outputs say where the drive is.
#[test]
fn stages_fold_in_order_and_unfold_in_reverse() {
    let mut m = model(&strip(two_stages()));
    m.initialize().unwrap();
    drive(&mut m, 0.0, 0.25, 0.25, 0.0);
    let [v, w] = angles(&m);
    assert!((v - 45.0).abs() < 2.0 && w.abs() < 1.0, "quarter: {v} {w}");
    assert_eq!(output(&m, "sequence.stage"), 0.0);
    assert!((output(&m, "sequence.progress") - 0.5).abs() < 1e-12);
    drive(&mut m, 0.25, 0.5, 0.25, 0.3);
    let [v, w] = angles(&m);
    assert!((v - 90.0).abs() < 1.0 && w.abs() < 1.0, "half: {v} {w}");
    assert_eq!(output(&m, "sequence.stage"), 0.0);
    assert_eq!(output(&m, "sequence.progress"), 1.0);
    drive(&mut m, 0.5, 1.0, 0.5, 0.3);
    let [v, w] = angles(&m);
    assert!(
        (v - 90.0).abs() < 1.0 && (w + 60.0).abs() < 1.0,
        "full: {v} {w}"
    );
    assert_eq!(output(&m, "sequence.stage"), 1.0);
    // Back: the last stage unfolds first.
    drive(&mut m, 1.0, 0.5, 0.5, 0.3);
    let [v, w] = angles(&m);
    assert!(
        (v - 90.0).abs() < 1.0 && w.abs() < 1.0,
        "back to half: {v} {w}"
    );
    drive(&mut m, 0.5, 0.0, 0.5, 0.3);
    let [v, w] = angles(&m);
    assert!(v.abs() < 1.0 && w.abs() < 1.0, "flat again: {v} {w}");
    assert_eq!(output(&m, "sequence.stage"), 0.0);
    assert_eq!(output(&m, "sequence.progress"), 0.0);
}

/// Held values (a staircase), first-order hold, the built-in ramp and a
/// servo all walk the stages: at the middle of the drive the valley is
/// folded and the mountain not, and all end where the slopes end.
#[test]
fn every_input_path_walks_the_stages() {
    let reference = {
        let mut m = model(&strip(two_stages()));
        m.initialize().unwrap();
        drive(&mut m, 0.0, 1.0, 1.0, 0.5);
        angles(&m)
    };
    let paths = ["held", "first_order_hold", "ramp", "servo"];
    for path in paths {
        let mut m = model(&strip(two_stages()));
        let set = |m: &mut Model, name: &str, x: f64| {
            let p = m.parameter_id(name).unwrap();
            m.set_parameter(p, x).unwrap();
        };
        match path {
            "first_order_hold" => set(&mut m, "input.first_order_hold", 1.0),
            "ramp" => set(&mut m, "ramp.time", 1.0),
            "servo" => set(&mut m, "actuator.time_constant", 0.005),
            _ => {}
        }
        m.initialize().unwrap();
        let fold = m.input_id("fold").unwrap();
        let mut middle = None;
        for k in 1..=150 {
            let t = k as f64 * 0.01;
            // Held: the value at the step start; first-order hold: at its end.
            let u = match path {
                "first_order_hold" => t.min(1.0),
                _ => (t - 0.01).min(1.0),
            };
            m.set_input(fold, u).unwrap();
            m.advance(0.01).unwrap();
            if k == 50 {
                middle = Some(angles(&m));
            }
        }
        let [v, w] = middle.unwrap();
        assert!(v > 80.0 && w.abs() < 2.0, "{path}: at 0.5 s {v} {w}");
        let end = angles(&m);
        for (a, b) in end.iter().zip(&reference) {
            assert!(
                (a - b).abs() < 0.1,
                "{path}: ends at {end:?}, slopes at {reference:?}"
            );
        }
    }
}

/// The work the sequence's rest angles do closes the energy balance as a
/// plain actuator's does (tests/dynamics_accuracy.rs's undamped hinge,
/// rho_inf = 1, under gravity): folded over two periods through three
/// stages (out, back, out again: the rest angle's rate jumps at each
/// boundary), by held values with slopes or by a held staircase whose
/// every jump does its work at once; kinetic + strain + crease energy less
/// the input work stays within 1e-3 of the largest input work.
#[test]
fn the_energy_balance_closes_across_stages() {
    const W: f64 = 0.02;
    for slopes in [true, false] {
        let mut scene = common::two_panels(W, 1.0, Integrator::GeneralizedAlpha);
        common::crease_ratio(&mut scene, W, 1e-3);
        scene.auto_damping = false;
        scene.solver.rho_inf = 1.0;
        scene.gravity = Some([0.0, 0.0, -9.81]);
        let crease = scene.actuators[0].edges[0];
        let e = scene.mesh.edge(crease).fold_edge.unwrap();
        let stage = |share: f64, angle: f64| Stage {
            title: None,
            share,
            targets: vec![(e, angle)],
        };
        scene.sequence = Some(Sequence {
            actuator: "fold".into(),
            stages: vec![stage(0.3, 0.2), stage(0.3, 0.05), stage(0.4, 0.3)],
        });
        let omega = common::hinge_omega(&scene, W);
        let period = 2.0 * PI / omega;
        scene.solver.max_step = period / 40.0;
        let mut m = Model::new(scene).unwrap();
        m.initialize().unwrap();
        let fold = m.input_id("fold").unwrap();
        let dt = period / 20.0;
        let (mut worst, mut largest): (f64, f64) = (0.0, 0.0);
        for k in 0..100 {
            let t = k as f64 * dt;
            let ramp = 2.0 * period;
            m.set_input(fold, (t / ramp).min(1.0)).unwrap();
            if slopes {
                m.set_input_derivative(fold, 1, if t < ramp { 1.0 / ramp } else { 0.0 })
                    .unwrap();
            }
            m.advance(dt).unwrap();
            let w = m.work().input;
            largest = largest.max(w.abs());
            worst = worst.max((common::total_energy(&m) - w).abs());
        }
        println!(
            "slopes {slopes}: balance within {:.3e} of the largest input work {largest:.3e} J",
            worst / largest
        );
        assert!(largest > 0.0);
        assert!(
            worst <= 1e-3 * largest,
            "slopes {slopes}: off by {worst:.3e} of {largest:.3e} J"
        );
        let a = m.output(m.output_id("sequence.stage").unwrap()).unwrap();
        assert_eq!(a, 2.0);
    }
}

/// Every bad sequence is refused at load time with the key of the stage.
#[test]
fn bad_sequences_name_the_stage() {
    let cases: Vec<(Value, &str, &str)> = vec![
        (
            json!([{"edges": [8, 99]}]),
            "ancf:sequence[0].edges[1]",
            "does not exist",
        ),
        (
            json!([{"edges": [8]}, {"edges": [3]}]),
            "ancf:sequence[1].edges[0]",
            "not a crease",
        ),
        (
            json!([{"edges": [8]}, {"edges": "U"}]),
            "ancf:sequence[1].edges",
            "selects no crease",
        ),
        (json!([{"edges": []}]), "ancf:sequence[0].edges", "empty"),
        (
            json!([{"edges": [8], "share": 0.5}, {"edges": [9], "share": 0.4}]),
            "ancf:sequence",
            "add up to 0.9",
        ),
        (
            json!([{"edges": [8], "share": 0.5}, {"edges": [9]}]),
            "ancf:sequence[1].share",
            "missing",
        ),
        (
            json!([{"edges": [8], "share": 0}]),
            "ancf:sequence[0].share",
            "out of range",
        ),
        (
            json!([{"edges": [8], "fraction": 0.5, "degrees": 30}]),
            "ancf:sequence[0]",
            "not both",
        ),
        (
            json!([{"edges": [8], "degrees": 200}]),
            "ancf:sequence[0].degrees",
            "[-180, 180]",
        ),
        (
            json!([{"edges": [8], "fraction": 2.5}]),
            "ancf:sequence[0].fraction",
            "[-180, 180]",
        ),
        (
            json!([{"edges": [8, 9], "degrees": [10]}]),
            "ancf:sequence[0].degrees",
            "one angle per edge",
        ),
        (
            json!([{"edges": "M", "degrees": [10]}]),
            "ancf:sequence[0].degrees",
            "needs a list of edges",
        ),
        (
            json!([{"edges": [8], "speed": 1}]),
            "ancf:sequence[0]",
            "unknown field 'speed'",
        ),
        (json!([]), "ancf:sequence", "at least one stage"),
        (json!({"edges": [8]}), "ancf:sequence", "expected an array"),
    ];
    for (seq, key, what) in cases {
        let e = load(&strip(seq.clone())).unwrap_err().to_string();
        assert!(e.starts_with(&format!("{key}:")), "{seq}: {e}");
        assert!(e.contains(what), "{seq}: {e}");
    }
    // A crease in a stage and in another rest-angle actuator.
    let mut v = strip(two_stages());
    v["ancf:actuators"] = json!([{"name": "m", "edges": [9]}]);
    let e = load(&v).unwrap_err().to_string();
    assert!(
        e.starts_with("ancf:sequence[1].edges:")
            && e.contains("also driven by the rest_angle actuator 'm'"),
        "{e}"
    );
    // An actuator may drive other creases, or the same ones by torque.
    v["ancf:actuators"] = json!([{"name": "push", "edges": [9], "mode": "torque"}]);
    let (s, _) = load(&v).unwrap();
    assert_eq!(s.actuators[0].name, "fold");
    assert_eq!(s.actuators[1].name, "push");
    // The sequence's input name is taken.
    v["ancf:actuators"] = json!([{"name": "fold", "edges": [9], "mode": "torque"}]);
    let e = load(&v).unwrap_err().to_string();
    assert!(
        e.starts_with("ancf:actuators[0].name:") && e.contains("ancf:sequence"),
        "{e}"
    );
    // A fraction of creases whose file angle is 0 folds nothing.
    let mut v = strip(json!([{"edges": [8], "fraction": 0.5}]));
    v["edges_foldAngle"] = json!([0, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
    v["edges_assignment"] = json!(["B", "B", "B", "B", "B", "B", "B", "B", "U", "U"]);
    let e = load(&v).unwrap_err().to_string();
    assert!(
        e.starts_with("ancf:sequence[0].fraction:") && e.contains("folds nothing"),
        "{e}"
    );
}

/// A crease pattern with two frames after it: one with its own
/// `edges_foldAngle`, one with folded 3D coordinates (the valley at 90
/// deg, the mountain at -45 deg).
fn framed() -> Value {
    let c = (PI / 4.0).cos() * 0.03;
    let s = (PI / 4.0).sin() * 0.03;
    // Panel 0 turned up about x = 0.03 by 90 deg (valley); panel 2 turned
    // down about x = 0.06 by 45 deg (mountain).
    let folded = json!([
        [0.03, 0, 0.03],
        [0.03, 0, 0],
        [0.06, 0, 0],
        [0.06 + c, 0, -s],
        [0.06 + c, 0.03, -s],
        [0.06, 0.03, 0],
        [0.03, 0.03, 0],
        [0.03, 0.03, 0.03]
    ]);
    let mut v = strip(json!(null));
    v.as_object_mut().unwrap().remove("ancf:sequence");
    v["file_frames"] = json!([
        {"frame_title": "half", "frame_inherit": true, "frame_parent": 0,
         "edges_foldAngle": [0,0,0,0,0,0,0,0,45,null]},
        {"frame_inherit": true, "frame_parent": 1, "frame_classes": ["foldedForm"],
         "vertices_coords": folded}
    ]);
    v
}

#[test]
fn frames_read_as_keyframes() {
    let text = framed().to_string();
    let loaded = scene::from_str_report(&text, &LoadOptions::default()).unwrap();
    assert!(
        loaded
            .notes
            .iter()
            .any(|n| n.contains("frames 1-2 read as a folding sequence")),
        "{:?}",
        loaded.notes
    );
    let sq = loaded.scene.sequence.unwrap();
    assert_eq!(sq.stages.len(), 2);
    assert_eq!(sq.stages[0].title.as_deref(), Some("half"));
    // The null angle leaves edge 9 out of the first stage.
    assert_eq!(sq.stages[0].targets, vec![(FoldEdgeId(8), PI / 4.0)]);
    assert_eq!(sq.stages[1].title.as_deref(), Some("frame 2"));
    let t = &sq.stages[1].targets;
    assert_eq!(t.len(), 2);
    assert!((t[0].1 - PI / 2.0).abs() < 1e-12, "{t:?}");
    assert!((t[1].1 + PI / 4.0).abs() < 1e-12, "{t:?}");
    // Off: the crease pattern alone, as before.
    let off = LoadOptions {
        keyframes: Keyframes::Off,
        ..Default::default()
    };
    let (s, _) = scene::from_str_with(&text, &off).unwrap();
    assert!(s.sequence.is_none());
    // A frame that is another crease pattern: not keyframes (a note), or
    // an error naming it when asked for.
    let mut v = framed();
    v["file_frames"][1] = json!({"frame_inherit": true, "frame_parent": 0, "frame_title": "cp"});
    let text = v.to_string();
    let loaded = scene::from_str_report(&text, &LoadOptions::default()).unwrap();
    assert!(loaded.scene.sequence.is_none());
    assert!(
        loaded
            .notes
            .iter()
            .any(|n| n.contains("not read as a folding sequence") && n.contains("file_frames[1]")),
        "{:?}",
        loaded.notes
    );
    let on = LoadOptions {
        keyframes: Keyframes::On,
        ..Default::default()
    };
    let e = scene::from_str_with(&text, &on).unwrap_err().to_string();
    assert!(
        e.starts_with("file_frames[1]:") && e.contains("carries no fold angles"),
        "{e}"
    );
    // A frame of another pattern.
    let mut v = framed();
    v["file_frames"][0]["vertices_coords"] = json!([[0, 0], [1, 0], [0, 1]]);
    let e = scene::from_str_with(&v.to_string(), &on)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("file_frames[0].vertices_coords:") && e.contains("same pattern"),
        "{e}"
    );
    // A file with a sequence of its own keeps it.
    let mut v = framed();
    v["ancf:sequence"] = json!([{"edges": [9]}]);
    let (s, _) = scene::from_str(&v.to_string()).unwrap();
    assert_eq!(s.sequence.unwrap().stages.len(), 1);
    let e = scene::from_str_with(&v.to_string(), &on)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("ancf:sequence:"), "{e}");
}

/// A motion written as FOLD reads back as a sequence whose stages are its
/// frames: every frame's angles, the last the model's outputs.
#[test]
fn a_motion_reads_back_as_its_stages() {
    let v = strip(two_stages());
    let text = v.to_string();
    let mut m = model(&v);
    m.initialize().unwrap();
    let (cp, _) = scene::fold::parse(&text, None).unwrap();
    let mut motion = origami_fmu::motion::Motion::new(&cp, &m);
    motion.record(&m);
    let fold = m.input_id("fold").unwrap();
    let mut recorded = vec![angles(&m)];
    for k in 1..=20 {
        m.set_input(fold, k as f64 / 20.0).unwrap();
        m.advance(0.02).unwrap();
        motion.record(&m);
        recorded.push(angles(&m));
    }
    let back = motion.to_json();
    let loaded = scene::from_str_report(&back, &LoadOptions::default()).unwrap();
    let sq = loaded.scene.sequence.unwrap();
    assert_eq!(sq.stages.len(), 21);
    for (k, (stage, want)) in sq.stages.iter().zip(&recorded).enumerate() {
        for (&(_, t), w) in stage.targets.iter().zip(want) {
            assert!((t.to_degrees() - w).abs() < 1e-9, "frame {k}: {t} vs {w}");
        }
    }
    // The top level is the crease pattern in metres; the physics but the
    // sequence comes along.
    let top: Value = serde_json::from_str(&back).unwrap();
    assert_eq!(top["frame_unit"], "m");
    assert!(top.get("ancf:sequence").is_none());
    assert_eq!(top["file_frames"].as_array().unwrap().len(), 21);
    let last = &top["file_frames"][20];
    assert_eq!(last["vertices_coords"].as_array().unwrap().len(), 8);
    let x0 = m.vertex_position(origami_fmu::ids::VertexId(3));
    for c in 0..3 {
        assert_eq!(last["vertices_coords"][3][c].as_f64().unwrap(), x0[c]);
    }
}

/// Rabbit Ear's blintz base (`tests/data/rabbit-ear/blintz-frames.fold`):
/// a crease pattern and 32 frames of folded coordinates, the four corners
/// folding in to flat. Read as 32 stages, it folds through its frames in
/// order: dwelling at the end of each stage, every crease is within 2 deg
/// of that frame's angle (between the corner's and the centre's facets,
/// measured here from the frame's coordinates). (The frames' flaps are not
/// rigid: the corner is 0.87 of its flat distance from its neighbours at
/// frame 16, so the frames' shapes are no reference; their angles are.)
#[test]
fn rabbit_ears_blintz_folds_through_its_32_frames() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/rabbit-ear/blintz-frames.fold"
    );
    let text = std::fs::read_to_string(path).unwrap();
    let file: Value = serde_json::from_str(&text).unwrap();
    let (s, warnings) = scene::from_str(&text).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let sq = s.sequence.clone().unwrap();
    assert_eq!(sq.stages.len(), 32);
    // The frames' shapes and corner angles, from their coordinates.
    let frames: Vec<Vec<[f64; 3]>> = file["file_frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            f["vertices_coords"]
                .as_array()
                .unwrap()
                .iter()
                .map(|p| {
                    let c = |i: usize| p.get(i).and_then(Value::as_f64).unwrap_or(0.0);
                    [c(0), c(1), c(2)]
                })
                .collect()
        })
        .collect();
    let normal = |p: &[[f64; 3]], [a, b, c]: [usize; 3]| {
        let v = |i: usize| nalgebra::Vector3::from(p[i]);
        (v(b) - v(a)).cross(&(v(c) - v(a))).normalize()
    };
    // Crease 8 joins corner 0's facet [0, 1, 7] and the centre [1, 3, 5(, 7)].
    let corner_angle = |p: &[[f64; 3]]| {
        let c = normal(p, [1, 3, 5]);
        let t = normal(p, [0, 1, 7]);
        c.dot(&t).clamp(-1.0, 1.0).acos().to_degrees()
    };
    let mut m = Model::new(s).unwrap();
    m.initialize().unwrap();
    let fold = m.input_id("fold").unwrap();
    let edges: Vec<_> = (8..12)
        .map(|e| m.output_id(&format!("crease[{e}].angle")).unwrap())
        .collect();
    let mut worst_angle: f64 = 0.0;
    for (k, frame) in frames.iter().enumerate() {
        // The stage over 50 ms with the input's slope, then a dwell.
        let (u0, u1) = (k as f64 / 32.0, (k + 1) as f64 / 32.0);
        for j in 0..5 {
            m.set_input(fold, u0 + (u1 - u0) * j as f64 / 5.0).unwrap();
            m.set_input_derivative(fold, 1, (u1 - u0) / 0.05).unwrap();
            m.advance(0.01).unwrap();
        }
        m.set_input(fold, u1).unwrap();
        for _ in 0..15 {
            m.advance(0.01).unwrap();
        }
        assert_eq!(output(&m, "sequence.stage"), k as f64);
        assert_eq!(output(&m, "sequence.progress"), 1.0);
        let want = corner_angle(frame);
        for &id in &edges {
            let got = m.output(id).unwrap().to_degrees();
            worst_angle = worst_angle.max((got - want).abs());
            assert!(
                (got - want).abs() < 2.0,
                "frame {}: {got} deg, the frame {want}",
                k + 1
            );
        }
    }
    println!("blintz: every frame's angles within {worst_angle:.3} deg");
}

/// A scene file (the FMU's `resources/scene.json`) whose sequence was
/// edited is refused with the reason, never a panic; so is a model of a
/// scene whose sequence does not fit it.
#[test]
fn a_tampered_sequence_is_refused() {
    use origami_fmu::fmi::resources::{parse_scene, scene_bytes};
    let (s, _) = load(&strip(two_stages())).unwrap();
    let good: Value = serde_json::from_slice(&scene_bytes(&s)).unwrap();
    assert!(parse_scene(&scene_bytes(&s)).is_ok());
    type Edit = Box<dyn Fn(&mut Value)>;
    let edits: Vec<(&str, Edit)> = vec![
        (
            "add up to",
            Box::new(|v| v["sequence"]["stages"][0]["share"] = json!(0.2)),
        ),
        (
            "does not exist",
            Box::new(|v| v["sequence"]["stages"][1]["targets"][0][0] = json!(1_000_000)),
        ),
        (
            "within [-pi, pi]",
            Box::new(|v| v["sequence"]["stages"][1]["targets"][0][1] = json!(10.0)),
        ),
        (
            "folds no crease",
            Box::new(|v| v["sequence"]["stages"][1]["targets"] = json!([])),
        ),
        (
            "no stages",
            Box::new(|v| v["sequence"]["stages"] = json!([])),
        ),
        (
            "no rest_angle actuator",
            Box::new(|v| v["sequence"]["actuator"] = json!("push")),
        ),
        (
            "share",
            Box::new(|v| v["sequence"]["stages"][0]["share"] = json!(-1.0)),
        ),
        (
            "invalid type: string \"half\"",
            Box::new(|v| v["sequence"]["stages"][0]["share"] = json!("half")),
        ),
    ];
    for (what, edit) in edits {
        let mut v = good.clone();
        edit(&mut v);
        let bytes = serde_json::to_vec(&v).unwrap();
        let e = parse_scene(&bytes).expect_err(what).to_string();
        assert!(e.contains(what), "{what}: {e}");
    }
    let mut bad = s.clone();
    bad.sequence.as_mut().unwrap().stages[0].share = 0.9;
    let e = Model::new(bad).err().unwrap().to_string();
    assert!(e.contains("sequence: the shares add up to"), "{e}");
}

/// The pictures and the CLI's progress line say where the drive is.
#[test]
fn pictures_label_the_stage() {
    let mut m = model(&strip(two_stages()));
    m.initialize().unwrap();
    drive(&mut m, 0.0, 0.75, 0.3, 0.0);
    let sheet = origami_fmu::pictures::Sheet::new(&m);
    let frame = sheet.frame(&m, &m.output_values());
    assert_eq!(frame.stage.as_deref(), Some("stage 2/2, 50 %"));
    let dir = std::env::temp_dir().join(format!("sequence_pictures_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    origami_fmu::pictures::write_gif(&dir.join("a.gif"), &sheet, &[&frame], "strip").unwrap();
    origami_fmu::pictures::write_snapshots(&dir.join("a.png"), &sheet, &[&frame, &frame], "strip")
        .unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
}
