//! Integration tests of the scene front door: the shipped example scenes
//! (loading, and drift against their generators), a file in Origami
//! Simulator's export form, the command line, and a mutation fuzzer that
//! feeds broken FOLD files to the reader (it must return Ok or Err, never
//! panic).
//!
//! Environment:
//! - `ORIGAMI_REGEN_SCENES=1` rewrites `scenes/*.fold` from the generators
//!   instead of comparing them.
//! - `ORIGAMI_FUZZ_CASES=N` runs N fuzz cases (default 3000).

use origami_fmu::ids::{EdgeId, FacetId};
use origami_fmu::mesh::EdgeKind;
use origami_fmu::model::Model;
use origami_fmu::scene::{self, patterns, refine};
use serde_json::Value;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;
use std::process::Command;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Equal JSON, numbers within a relative tolerance.
fn json_close(a: &Value, b: &Value, tol: f64) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            (x - y).abs() <= tol * (1.0 + x.abs().max(y.abs()))
        }
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(p, q)| json_close(p, q, tol))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len()
                && x.iter()
                    .all(|(k, v)| y.get(k).is_some_and(|w| json_close(v, w, tol)))
        }
        _ => a == b,
    }
}

#[test]
fn shipped_scenes_match_their_generators() {
    let regen = std::env::var_os("ORIGAMI_REGEN_SCENES").is_some();
    for (name, pattern) in patterns::shipped() {
        let path = repo().join("scenes").join(name);
        let text = pattern.generate().unwrap().to_json();
        if regen {
            std::fs::write(&path, &text).unwrap();
            continue;
        }
        let on_disk = std::fs::read_to_string(&path).unwrap_or_else(|e| {
            panic!("scenes/{name}: {e}; run ORIGAMI_REGEN_SCENES=1 cargo test --test scenes")
        });
        let a: Value = serde_json::from_str(&text).unwrap();
        let b: Value = serde_json::from_str(&on_disk).unwrap();
        assert!(
            json_close(&a, &b, 1e-12),
            "scenes/{name} differs from its generator; if the change is intended, \
             regenerate with ORIGAMI_REGEN_SCENES=1 cargo test --test scenes"
        );
    }
}

#[test]
fn shipped_scenes_load_cleanly_and_build_models() {
    let dir = repo().join("scenes");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".fold"))
        .collect();
    names.sort();
    for required in [
        "single_crease.fold",
        "miura_4x4.fold",
        "waterbomb.fold",
        "kresling.fold",
        "curved_crease.fold",
    ] {
        assert!(
            names.iter().any(|n| n == required),
            "scenes/{required} is missing"
        );
    }
    for name in &names {
        let path = dir.join(name);
        let (s, warnings) = scene::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(warnings.is_empty(), "{name}: {warnings:?}");
        assert_eq!(s.name, name.trim_end_matches(".fold"));
        assert!(s.mesh.edges().iter().any(|e| e.kind == EdgeKind::Crease));
        let text = origami_fmu::cli::check::summary(name, &s, &warnings).unwrap();
        assert!(text.contains("valid"), "{text}");
        let model = Model::new(s).unwrap();
        // Plain patterns get the default actuator; the controller's plant
        // declares a crease moment input.
        let first_input = if name == "controlled_crease.fold" {
            "torque"
        } else {
            "fold"
        };
        assert_eq!(model.inputs()[0].name, first_input, "{name}");
    }
    let (miura, _) = scene::load(dir.join("miura_4x4.fold")).unwrap();
    assert_eq!(miura.fold_vertex_count, 81);
    assert_eq!(miura.mesh.triangles().len(), 128);
}

#[test]
fn origami_simulator_export_loads() {
    let path = repo().join("tests/data/origami_simulator_export.fold");
    let (s, warnings) = scene::load(&path).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(s.fold_vertex_count, 8);
    assert_eq!(s.fold_edge_count, 13);
    // Already triangulated: no new diagonals; the F edges are smooth.
    assert_eq!(s.mesh.triangles().len(), 6);
    assert_eq!(s.mesh.edges().len(), 13);
    for e in 10..13 {
        assert_eq!(s.mesh.edges()[e].kind, EdgeKind::Smooth);
    }
    // V at 90 degrees, M without its sign: -180; frame_unit cm.
    assert_eq!(s.mesh.edges()[8].kind, EdgeKind::Crease);
    assert!((s.mesh.edges()[8].fold_target - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    assert!((s.mesh.edges()[9].fold_target + std::f64::consts::PI).abs() < 1e-15);
    assert!((s.mesh.edge_length(EdgeId(0)) - 0.1).abs() < 1e-15);
    assert!((s.mesh.edge_length(EdgeId(2)) - 0.1).abs() < 1e-15);
    let area: f64 = (0..6).map(|t| s.mesh.area(FacetId(t))).sum();
    assert!((area - 0.03).abs() < 1e-15);
    assert_eq!(s.actuators[0].edges, vec![EdgeId(8), EdgeId(9)]);
    let m = Model::new(s).unwrap();
    assert!(m.outputs().iter().any(|v| v.name == "crease[9].angle"));
}

#[test]
fn documented_example_loads() {
    let doc = std::fs::read_to_string(repo().join("docs/scenes.md")).unwrap();
    let section = doc.split("## A complete example").nth(1).unwrap();
    let json = section
        .split("```json")
        .nth(1)
        .unwrap()
        .split("```")
        .next()
        .unwrap();
    let (s, warnings) = scene::from_str(json).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(s.name, "hinge");
    assert!(!s.auto_damping);
    assert_eq!(s.mesh.triangles().len(), 16); // refined once
    let m = Model::new(s).unwrap();
    let inputs: Vec<&str> = m.inputs().iter().map(|v| v.name.as_str()).collect();
    assert_eq!(inputs, ["fold", "tip.x", "tip.y", "tip.z"]);
    let outputs: Vec<&str> = m.outputs().iter().map(|v| v.name.as_str()).collect();
    assert_eq!(outputs.len(), 6 * 3 + 1 + 5);
    assert!(outputs.contains(&"crease[6].angle"));
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_origami-fmu"))
}

#[test]
fn cli_help_everywhere() {
    let commands: &[&[&str]] = &[
        &[],
        &["pattern"],
        &["check"],
        &["pattern", "single-crease"],
        &["pattern", "miura"],
        &["pattern", "yoshimura"],
        &["pattern", "waterbomb-base"],
        &["pattern", "waterbomb"],
        &["pattern", "kresling"],
        &["pattern", "curved-crease"],
    ];
    for c in commands {
        let out = bin().args(*c).arg("--help").output().unwrap();
        assert!(out.status.success(), "{c:?} --help failed");
        assert!(
            String::from_utf8_lossy(&out.stdout).contains("Usage"),
            "{c:?}"
        );
    }
}

#[test]
fn cli_pattern_then_check() {
    let dir = std::env::temp_dir().join(format!("origami-fmu-scenes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("m.fold");
    let out = bin()
        .args([
            "pattern", "miura", "--nx", "2", "--ny", "3", "--a", "0.01", "--angle", "55", "-o",
        ])
        .arg(&file)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (s, _) = scene::load(&file).unwrap();
    assert_eq!(s.fold_vertex_count, 5 * 7);
    let out = bin().arg("check").arg(&file).output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for want in [
        "valid",
        "35 vertices",
        "DOFs",
        "inputs (1): fold",
        "warnings (0)",
    ] {
        assert!(text.contains(want), "missing {want:?} in\n{text}");
    }
    // stdout output and a negative angle
    let out = bin()
        .args(["pattern", "single-crease", "--angle", "-45"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let (s, _) = scene::from_str(&String::from_utf8_lossy(&out.stdout)).unwrap();
    assert!(s.mesh.edges()[..7].iter().any(|e| e.fold_target < 0.0));
    // bad parameter and bad scene: non-zero exit, message naming the key
    let out = bin()
        .args(["pattern", "miura", "--nx", "0"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("miura --nx"));
    let bad = dir.join("bad.fold");
    // one clockwise face among counter-clockwise ones: an error
    std::fs::write(
        &bad,
        r#"{"vertices_coords": [[0,0],[1,0],[1,1],[0,1],[2,0],[2,1]],
            "faces_vertices": [[0,1,2,3],[2,5,4,1]]}"#,
    )
    .unwrap();
    let out = bin().arg("check").arg(&bad).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("faces_vertices[1]") && err.contains("clockwise"),
        "{err}"
    );
    // every face clockwise: mirrored, with a warning
    std::fs::write(
        &bad,
        r#"{"vertices_coords": [[0,0],[1,0],[0,1]], "faces_vertices": [[0,2,1]]}"#,
    )
    .unwrap();
    let out = bin().arg("check").arg(&bad).output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("every face is clockwise"), "{text}");
    std::fs::write(&bad, "{\n  \"vertices_coords\": [[0,0],\n").unwrap();
    let out = bin().arg("check").arg(&bad).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("line 3"));
    let _ = std::fs::remove_dir_all(&dir);
}

// ---------------------------------------------------------------- fuzzing

use origami_fmu::rng::XorShift as Rng;

/// JSON pointers of every node.
fn pointers(v: &Value, here: String, out: &mut Vec<String>) {
    match v {
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                pointers(x, format!("{here}/{i}"), out);
            }
        }
        Value::Object(o) => {
            for (k, x) in o {
                let k = k.replace('~', "~0").replace('/', "~1");
                pointers(x, format!("{here}/{k}"), out);
            }
        }
        _ => {}
    }
    out.push(here);
}

const ODD_NUMBERS: &[f64] = &[
    0.0,
    -0.0,
    -1.0,
    1.0,
    2.0,
    3.0,
    0.5,
    -180.0,
    181.0,
    1e-320,
    1e-12,
    1e9,
    -1e308,
    1e308,
    9.007_199_254_740_992e15,
    1.8e19,
];

fn mutate_value(v: &mut Value, rng: &mut Rng) {
    let mut ps = Vec::new();
    pointers(v, String::new(), &mut ps);
    let p = ps[rng.below(ps.len())].clone();
    let Some(node) = v.pointer_mut(&p) else {
        return;
    };
    match rng.below(8) {
        0 => {
            if let Value::Object(o) = node {
                let keys: Vec<String> = o.keys().cloned().collect();
                if !keys.is_empty() {
                    o.remove(&keys[rng.below(keys.len())]);
                }
            }
        }
        1 | 2 => {
            let x = ODD_NUMBERS[rng.below(ODD_NUMBERS.len())];
            *node = if x.fract() == 0.0 && x.abs() < 1e18 && rng.below(2) == 0 {
                Value::from(x as i64)
            } else {
                Value::from(x)
            };
        }
        3 => {
            *node = match rng.below(6) {
                0 => Value::Null,
                1 => Value::from("x"),
                2 => Value::Array(vec![]),
                3 => Value::Object(Default::default()),
                4 => Value::Bool(true),
                _ => Value::from(u64::MAX),
            }
        }
        4 => {
            if let Value::Array(a) = node
                && a.len() >= 2
            {
                let (i, j) = (rng.below(a.len()), rng.below(a.len()));
                a.swap(i, j);
            }
        }
        5 => {
            if let Value::Array(a) = node {
                let n = rng.below(a.len() + 1);
                a.truncate(n);
            }
        }
        6 => {
            if let Value::Array(a) = node
                && !a.is_empty()
            {
                let x = a[rng.below(a.len())].clone();
                a.push(x);
            }
        }
        _ => {
            if node.is_number() {
                *node = Value::from(rng.below(40) as u64);
            }
        }
    }
}

fn mutate_text(text: &str, rng: &mut Rng) -> String {
    let mut s: Vec<char> = text.chars().collect();
    if s.is_empty() {
        return "{".to_string();
    }
    let at = rng.below(s.len());
    match rng.below(4) {
        0 => s.truncate(at),
        1 => {
            s.remove(at);
        }
        2 => {
            let bits = [
                "NaN", "Infinity", "-", "]", "}", "\"", ",", "1e999", "\u{0}",
            ];
            let ins = bits[rng.below(bits.len())];
            for (k, c) in ins.chars().enumerate() {
                s.insert(at + k, c);
            }
        }
        _ => {
            let digits = "0123456789";
            if s[at].is_ascii_digit() {
                s[at] = digits.chars().nth(rng.below(10)).unwrap();
            }
        }
    }
    s.into_iter().collect()
}

fn fuzz_bases() -> Vec<String> {
    let mut out = vec![
        std::fs::read_to_string(repo().join("tests/data/origami_simulator_export.fold")).unwrap(),
        patterns::WaterbombBase::default()
            .generate()
            .unwrap()
            .to_json(),
        patterns::Miura {
            nx: 1,
            ny: 1,
            ..Default::default()
        }
        .generate()
        .unwrap()
        .to_json(),
        patterns::Kresling {
            stories: 1,
            sides: 4,
            twist: 30.0,
            ..Default::default()
        }
        .generate()
        .unwrap()
        .to_json(),
    ];
    // a single crease with every ancf: key
    let mut single: Value = serde_json::from_str(
        &patterns::SingleCrease::default()
            .generate()
            .unwrap()
            .to_json(),
    )
    .unwrap();
    let keys: Value = serde_json::from_str(
        r#"{
        "ancf:name": "fuzz",
        "ancf:material": {"youngs_modulus": 3e9, "poisson_ratio": 0.3, "thickness": 1e-4, "density": 800},
        "ancf:crease": {"length_scale": 0.01, "damping_per_length": 1e-5},
        "ancf:damping": {"alpha": 1, "beta": 1e-4},
        "ancf:actuators": [{"name": "fold", "edges": [1], "mode": "rest_angle", "start": 0},
                           {"name": "t", "edges": "V", "mode": "torque"}],
        "ancf:supports": [{"vertices": [0, 5], "fix": "clamped"}],
        "ancf:loads": {"gravity": [0, 0, -9.81], "vertex_forces": [{"name": "tip", "vertex": 3}]},
        "ancf:motions": [{"name": "grip", "vertex": 2}],
        "ancf:contact": {"enabled": false, "friction": 0.3},
        "ancf:solver": {"integrator": "generalized-alpha", "rho_inf": 0.8, "max_step": 1e-3,
                        "min_step": 1e-9, "tolerance": 1e-6, "max_newton": 20, "stop_time": 1},
        "ancf:outputs": ["positions", "fold_angles", "energies"],
        "ancf:refine": 1
    }"#,
    )
    .unwrap();
    for (k, v) in keys.as_object().unwrap() {
        single[k] = v.clone();
    }
    out.push(single.to_string());
    // frames with inheritance
    out.push(
        r#"{"file_spec": 1.2, "file_frames": [
            {"frame_title": "cp", "vertices_coords": [[0,0],[1,0],[1,1],[0,1]],
             "faces_vertices": [[0,1,2],[0,2,3]], "edges_vertices": [[0,2]],
             "edges_assignment": ["V"], "edges_foldAngle": [120]},
            {"frame_inherit": true, "frame_parent": 1, "frame_unit": "mm"}]}"#
            .to_string(),
    );
    // edges only (faces traced), unitless
    out.push(std::fs::read_to_string(repo().join("tests/data/fold-spec/vertex.fold")).unwrap());
    // a cut across the sheet and a slit face (a crease ending inside it)
    out.push(
        r#"{"vertices_coords": [[0,0],[1,0],[2,0],[2,1],[1,1],[0,1],[1.5,0.5]],
            "edges_vertices": [[0,1],[1,2],[2,3],[3,4],[4,5],[5,0],[1,4],[2,6]],
            "edges_assignment": ["B","B","B","B","B","B","C","V"],
            "faces_vertices": [[0,1,4,5],[1,2,6,2,3,4]]}"#
            .to_string(),
    );
    for b in &out {
        scene::from_str(b).unwrap_or_else(|e| panic!("fuzz base does not load: {e}\n{b}"));
    }
    out
}

/// What the reader and the code after it do with one input.
fn exercise(text: &str) {
    if let Ok((s, _)) = scene::from_str(text) {
        if s.mesh.triangles().len() <= 20_000 {
            let _ = refine::refine(&s, 1);
        }
        let _ = Model::new(s);
    }
    let _ = scene::from_str_with(
        text,
        &scene::LoadOptions {
            frame: Some(scene::FrameSelector::Index(1)),
            ..Default::default()
        },
    );
}

#[test]
fn fuzzed_fold_files_never_panic() {
    let cases: usize = std::env::var("ORIGAMI_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3000);
    let bases = fuzz_bases();
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut panics = Vec::new();
    let (mut ok, mut err) = (0usize, 0usize);
    for case in 0..cases {
        let base = &bases[case % bases.len()];
        let text = if rng.below(4) == 0 {
            let mut t = base.clone();
            for _ in 0..1 + rng.below(3) {
                t = mutate_text(&t, &mut rng);
            }
            t
        } else {
            let mut v: Value = serde_json::from_str(base).unwrap();
            for _ in 0..1 + rng.below(3) {
                mutate_value(&mut v, &mut rng);
            }
            v.to_string()
        };
        match catch_unwind(AssertUnwindSafe(|| exercise(&text))) {
            Ok(()) => {
                if scene::from_str(&text).is_ok() {
                    ok += 1;
                } else {
                    err += 1;
                }
            }
            Err(_) => panics.push((case, text)),
        }
    }
    if let Some((case, text)) = panics.first() {
        panic!(
            "{} of {cases} fuzz cases panicked; first (case {case}):\n{text}",
            panics.len()
        );
    }
    eprintln!("fuzz: {cases} cases, {ok} loaded, {err} rejected");
    // The mutations must exercise both outcomes.
    assert!(ok > cases / 20 && err > cases / 20, "ok {ok}, err {err}");
}

#[test]
fn size_budget_refuses_a_million_facets_quickly() {
    use std::time::{Duration, Instant};
    let big = origami_fmu::benchmarks::unit_grid_fold(708); // 1,002,528 facets
    let text = big.to_json();
    let t = Instant::now();
    let e = scene::from_str(&text).unwrap_err().to_string();
    assert!(t.elapsed() < Duration::from_secs(60), "{:?}", t.elapsed());
    assert!(
        e.starts_with("faces_vertices: the pattern would triangulate into about 1002528 facets")
            && e.contains("size budget is 200000"),
        "{e}"
    );
    // Refinement past the budget, and a mesh built in code.
    let mut small = origami_fmu::benchmarks::unit_grid_fold(100); // 20,000 facets; two levels make 320,000
    small
        .ancf
        .insert("ancf:refine".into(), serde_json::json!(2));
    let e = scene::build::from_fold(&small, None)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("ancf:refine:") && e.contains("size budget"),
        "{e}"
    );
    small.ancf.clear();
    let (s, _) = scene::build::from_fold(&small, None).unwrap();
    let e = refine::refine(&s, 2).unwrap_err().to_string();
    assert!(e.contains("size budget"), "{e}");
    // A mid-sized sheet sets up in seconds (the 131k-facet timings are
    // `cargo bench --bench scene_size`).
    let t = Instant::now();
    let (s, _) =
        scene::build::from_fold(&origami_fmu::benchmarks::unit_grid_fold(150), None).unwrap(); // 45,000 facets
    let m = Model::new(s).unwrap();
    assert!(m.n_dofs() > 200_000);
    assert!(t.elapsed() < Duration::from_secs(60), "{:?}", t.elapsed());
}
