//! Fuzz targets run as tests (issue 38): the FMU state deserializer, the
//! FOLD reader, the FMU's scene file and sequences of FMI calls. Each replays its corpus in
//! `tests/fuzz_corpus/` and then mutates real inputs at random
//! (xorshift with a fixed seed: every run checks the same cases, so a
//! failure reproduces). `FUZZ_ITERATIONS=N` runs N random cases per target
//! instead of the default, and `FUZZ_SEED=S` another sequence of them:
//! longer runs look further.
//!
//! What must hold whatever the input: no panic (in the FMI layer: no
//! `fmi2Fatal`), every value handed out finite, every change of the bytes
//! of a serialized state refused, every accepted state stepping on.

mod common;

use common::fmi::*;
use origami_fmu::fmi::container;
use origami_fmu::fmi::exports::*;
use origami_fmu::fmi::types::fmi2FMUstate;
use origami_fmu::model::Model;
use origami_fmu::rng::XorShift;
use origami_fmu::scene::{self, FrameSelector, LoadOptions, Scene};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::ptr::null_mut;

/// Random cases per target: `FUZZ_ITERATIONS`, else `default`.
fn iterations(default: usize) -> usize {
    std::env::var("FUZZ_ITERATIONS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

/// The generator of target `salt`: `FUZZ_SEED` (default 38) mixed with it.
fn rng(salt: u64) -> XorShift {
    let seed: u64 = std::env::var("FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(38);
    XorShift((seed ^ salt.wrapping_mul(0x9e37_79b9_7f4a_7c15)) | 1)
}

fn corpus(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fuzz_corpus")
        .join(name)
}

/// Numbers that have broken parsers and solvers: zeros, signs, the
/// limits of the scene rules and of f64, indices too large to exist.
const NUMBERS: &[f64] = &[
    0.0,
    -0.0,
    1.0,
    -1.0,
    0.5,
    2.0,
    3.0,
    0.25,
    100.0,
    1e-300,
    -1e-300,
    5e-324,
    1e-30,
    1e-15,
    1e-9,
    1e-3,
    1e6,
    1e9,
    1e16,
    1e18,
    1e30,
    1.5e30,
    -1e30,
    1e300,
    1e308,
    -1e308,
    4294967295.0,
];

/// Random changes of JSON documents.
struct Mutator {
    rng: XorShift,
    /// Keys an object may gain (the reader's own, so that the change
    /// reaches its checks).
    keys: &'static [&'static str],
}

impl Mutator {
    fn below(&mut self, n: usize) -> usize {
        self.rng.below(n)
    }

    fn number(&mut self) -> Value {
        match self.below(8) {
            0 => json!(u64::MAX),
            1 => json!(i64::MIN),
            2 => json!(self.below(12)),
            _ => json!(NUMBERS[self.below(NUMBERS.len())]),
        }
    }

    fn any(&mut self, doc: &Value) -> Value {
        match self.below(9) {
            0 => Value::Null,
            1 => json!("x"),
            2 => json!(true),
            3 => json!([]),
            4 => json!({}),
            5 => json!([self.number()]),
            6 => json!([[0, 1, 2], [2, 1, 0]]),
            // A piece of the document elsewhere (right types, wrong place).
            7 => {
                let p = pointers(doc);
                doc.pointer(&p[self.below(p.len())])
                    .cloned()
                    .unwrap_or(Value::Null)
            }
            _ => self.number(),
        }
    }

    /// One random change somewhere in `doc`.
    fn mutate(&mut self, doc: &mut Value) {
        let p = pointers(doc);
        let at = p[self.below(p.len())].clone();
        let op = self.below(10);
        let replacement = match op {
            0..=2 => Some(self.number()),
            3 => Some(self.any(doc)),
            _ => None,
        };
        let key = self.keys.get(self.below(self.keys.len().max(1))).copied();
        let value = self.any(doc);
        let (r1, r2) = (self.rng.next_u64() as usize, self.rng.next_u64() as usize);
        let factor = [-1.0, 10.0, 0.1, 1e10, 1e-10][r2 % 5];
        let Some(node) = doc.pointer_mut(&at) else {
            return;
        };
        if let Some(x) = replacement {
            *node = x;
            return;
        }
        match node {
            Value::Array(a) if !a.is_empty() => match op {
                4 => {
                    a.remove(r1 % a.len());
                }
                5 => {
                    let x = a[r1 % a.len()].clone();
                    a.insert(r2 % (a.len() + 1), x);
                }
                6 => a.truncate(r1 % a.len()),
                _ => {
                    let n = a.len();
                    a.swap(r1 % n, r2 % n);
                }
            },
            Value::Object(o) if !o.is_empty() && op < 7 => {
                let k = o.keys().nth(r1 % o.len()).cloned().unwrap_or_default();
                o.remove(&k);
            }
            Value::Object(o) => {
                if let Some(k) = key {
                    o.insert(k.to_string(), value);
                }
            }
            Value::Number(n) => {
                let x = n.as_f64().unwrap_or(0.0);
                *node = match op {
                    7 => json!(x + 1.0),
                    8 => json!(x - 1.0),
                    _ => json!(x * factor),
                };
            }
            _ => *node = value,
        }
    }

    /// One random change of raw bytes: flipped bits, a byte set, a
    /// truncation, an inserted or removed byte, a repeated stretch.
    fn mutate_bytes(&mut self, b: &mut Vec<u8>) {
        if b.is_empty() {
            b.push(b'{');
            return;
        }
        let i = self.below(b.len());
        match self.below(6) {
            0 => {
                for _ in 0..1 + self.below(4) {
                    let j = self.below(b.len());
                    b[j] ^= 1 << self.below(8);
                }
            }
            1 => b[i] = self.rng.next_u64() as u8,
            2 => b.truncate(i),
            3 => b.insert(i, b"{}[],:\"0e-9"[self.below(11)]),
            4 => {
                b.remove(i);
            }
            _ => {
                let end = (i + 1 + self.below(64)).min(b.len());
                let piece = b[i..end].to_vec();
                b.splice(i..i, piece);
            }
        }
    }
}

/// JSON pointers of every node of `v` (the root included).
fn pointers(v: &Value) -> Vec<String> {
    fn walk(v: &Value, at: String, out: &mut Vec<String>) {
        match v {
            Value::Array(a) => {
                for (i, x) in a.iter().enumerate() {
                    walk(x, format!("{at}/{i}"), out);
                }
            }
            Value::Object(o) => {
                for (k, x) in o {
                    let k = k.replace('~', "~0").replace('/', "~1");
                    walk(x, format!("{at}/{k}"), out);
                }
            }
            _ => {}
        }
        out.push(at);
    }
    let mut out = Vec::new();
    walk(v, String::new(), &mut out);
    out
}

/// Names of the variables of `scene` in value-reference order.
fn names(scene: &Scene) -> Vec<String> {
    let m = Model::new(scene.clone()).unwrap();
    m.parameters()
        .iter()
        .chain(m.inputs())
        .chain(m.outputs())
        .map(|v| v.name.clone())
        .collect()
}

/// The FMU's time (fmi2LastSuccessfulTime).
fn time(f: &Fmu) -> f64 {
    let mut t = f64::NAN;
    // SAFETY: a live instance and a writable value.
    assert_eq!(unsafe { fmi2GetRealStatus(f.c, 2, &mut t) }, fmi2OK);
    t
}

/// Every variable read: fmi2OK with finite values, or fmi2Error; never
/// fmi2Fatal.
fn read_all(f: &Fmu, what: &str) {
    let (p, i, o) = f.vrs();
    let all: Vec<u32> = p.into_iter().chain(i).chain(o).collect();
    let (s, v) = f.get(&all);
    assert!(s == fmi2OK || s == fmi2Error, "{what}: fmi2GetReal {s:?}");
    if s == fmi2OK {
        assert!(v.iter().all(|x| x.is_finite()), "{what}: {v:?}");
    }
}

/// Nothing fatal so far on `f`.
fn alive(f: &Fmu, what: &str) {
    assert_eq!(f.count(fmi2Fatal), 0, "{what}: {}", f.last());
}

/// After `bytes` (mutated) were handed to fmi2DeSerializeFMUstate:
/// refused, or accepted and then restored, stepped and read without a
/// fatal error; the instance is put back to `base` either way.
fn check_deserialized(f: &Fmu, bytes: &[u8], base: fmi2FMUstate, what: &str) -> bool {
    let (st, s) = f.deserialize(bytes);
    assert!(st == fmi2OK || st == fmi2Error, "{what}: {st:?}");
    if st != fmi2OK {
        assert!(s.is_null(), "{what}");
        alive(f, what);
        return false;
    }
    assert_eq!(
        f.restore(s),
        fmi2OK,
        "{what}: accepted, then refused: {}",
        f.last()
    );
    read_all(f, what);
    let t = time(f);
    let st = f.step(t, 1e-4);
    assert!(st != fmi2Fatal, "{what}: fmi2DoStep fatal: {}", f.last());
    read_all(f, what);
    alive(f, what);
    f.free_state(s);
    assert_eq!(f.restore(base), fmi2OK, "{what}");
    true
}

/// The serialized state deserializer: the corpus of forged edits, random
/// byte changes (all refused: the checksum) and random changes of the
/// payload sealed with a valid checksum (refused, or accepted and safe).
#[test]
fn fuzz_serialized_states() {
    let n = iterations(600);
    let edits: Value =
        serde_json::from_str(&std::fs::read_to_string(corpus("state_edits.json")).unwrap())
            .unwrap();
    let mut m = Mutator {
        rng: rng(1),
        keys: &[],
    };
    let (mut accepted, mut refused) = (0, 0);
    for mut scene in [square(), contact_square()] {
        // A forged state within every range may still be stiff enough to
        // take the smallest steps: each check step stops at 200 of them.
        scene.solver.max_internal_steps = 200;
        let variables = names(&scene);
        let f = Fmu::of("fuzz_state", &scene);
        let fresh = f.save();
        f.initialize();
        let fold = variables.iter().position(|v| v == "fold").unwrap() as u32;
        assert_eq!(f.set(&[fold], &[0.8]), fmi2OK);
        for k in 0..3 {
            assert_eq!(f.step(k as f64 * 1e-3, 1e-3), fmi2OK, "{}", f.last());
        }
        let running = f.save();
        for (base, phase) in [(fresh, "instantiated"), (running, "running")] {
            assert_eq!(f.restore(base), fmi2OK);
            let bytes = f.serialize(base);
            let guid = container::guid(&bytes).unwrap().to_string();
            let payload: Value =
                serde_json::from_slice(container::open(&guid, &bytes).unwrap()).unwrap();
            let seal = |v: &Value| container::seal(&guid, &serde_json::to_vec(v).unwrap());
            // The corpus: each entry's edits, where the state has the values.
            for e in edits.as_array().unwrap() {
                let mut v = payload.clone();
                for edit in e["edits"].as_array().unwrap() {
                    let mut at = edit[0].as_str().unwrap().to_string();
                    for (k, name) in variables.iter().enumerate() {
                        at = at.replace(&format!("{{{name}}}"), &k.to_string());
                    }
                    if let Some(node) = v.pointer_mut(&at) {
                        *node = edit[1].clone();
                    }
                }
                let what = format!("{} ({phase}): {}", scene.name, e["why"]);
                check_deserialized(&f, &seal(&v), base, &what);
            }
            for i in 0..n {
                let what = format!("{} ({phase}), case {i}", scene.name);
                if i % 4 == 0 {
                    let mut b = bytes.clone();
                    m.mutate_bytes(&mut b);
                    if b != bytes {
                        let (st, s) = f.deserialize(&b);
                        assert_eq!(st, fmi2Error, "{what}: changed bytes accepted");
                        assert!(s.is_null());
                        refused += 1;
                    }
                    continue;
                }
                let mut v = payload.clone();
                for _ in 0..1 + m.below(3) {
                    m.mutate(&mut v);
                }
                if check_deserialized(&f, &seal(&v), base, &what) {
                    accepted += 1;
                } else {
                    refused += 1;
                }
            }
        }
        f.free_state(fresh);
        f.free_state(running);
        alive(&f, "end");
    }
    eprintln!("fuzz_serialized_states: {accepted} accepted, {refused} refused");
    assert!(
        refused > accepted,
        "the mutations should mostly break states"
    );
}

/// The small real FOLD files: the repository's (tests/data, scenes/) and
/// the corpus's crafted ones.
fn fold_seeds() -> Vec<(String, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut out = Vec::new();
    for dir in [
        "tests/fuzz_corpus/fold",
        "tests/data",
        "tests/data/fold-spec",
        "tests/data/flat-folder",
        "scenes",
    ] {
        let mut files: Vec<PathBuf> = std::fs::read_dir(root.join(dir))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "fold"))
            .filter(|p| p.metadata().unwrap().len() < 100_000)
            .collect();
        files.sort();
        for p in files {
            let text = std::fs::read_to_string(&p).unwrap();
            out.push((p.display().to_string(), text));
        }
    }
    out
}

/// Load FOLD `text` as the CLI would and, for a small valid scene, make
/// its FMU description, initialize it and step: nothing may panic, and
/// what comes out is finite.
fn load_and_run(text: &str, options: &LoadOptions) {
    let Ok(loaded) = scene::from_str_report(text, options) else {
        return;
    };
    let scene = loaded.scene;
    if scene.mesh.triangles().len() > 2000 {
        return; // valid and large: the speed tests' business
    }
    let Ok(contents) = origami_fmu::fmi::fmu_contents(&scene) else {
        return;
    };
    let Ok(mut m) = Model::new(contents.scene) else {
        return;
    };
    if m.initialize().is_err() {
        return;
    }
    for i in m.input_ids() {
        let _ = m.set_input(i, 0.5);
    }
    if m.advance(1e-3).is_ok() {
        assert!(m.output_values().iter().all(|x| x.is_finite()));
    }
}

/// The FOLD reader (and what the CLI does with a scene it accepts): the
/// corpus and real files, then random changes of their JSON and bytes,
/// read with random options.
#[test]
fn fuzz_fold_reader() {
    let n = iterations(1200);
    let seeds = fold_seeds();
    let mut m = Mutator {
        rng: rng(2),
        keys: &[
            "ancf:refine",
            "ancf:solver",
            "ancf:contact",
            "ancf:supports",
            "ancf:actuators",
            "ancf:material",
            "ancf:crease",
            "ancf:damping",
            "ancf:loads",
            "ancf:motions",
            "ancf:outputs",
            "ancf:import",
            "ancf:name",
            "file_frames",
            "frame_parent",
            "frame_inherit",
            "frame_unit",
            "frame_title",
            "vertices_coords",
            "edges_vertices",
            "edges_assignment",
            "edges_foldAngle",
            "faces_vertices",
            "enabled",
            "vertices",
            "edges",
            "fix",
            "mode",
            "max_step",
            "subdivisions",
        ],
    };
    for (_, text) in &seeds {
        load_and_run(text, &LoadOptions::default());
    }
    for i in 0..n {
        let (path, text) = &seeds[m.below(seeds.len())];
        let mutated = if i % 5 == 0 {
            let mut b = text.clone().into_bytes();
            for _ in 0..1 + m.below(3) {
                m.mutate_bytes(&mut b);
            }
            String::from_utf8_lossy(&b).into_owned()
        } else {
            let Ok(mut v) = serde_json::from_str::<Value>(text) else {
                continue;
            };
            for _ in 0..1 + m.below(4) {
                m.mutate(&mut v);
            }
            v.to_string()
        };
        let options = LoadOptions {
            frame: match m.below(6) {
                0 => Some(FrameSelector::Index(m.below(3))),
                1 => Some(FrameSelector::Title("cp".into())),
                _ => None,
            },
            size: [None, None, None, Some(0.2), Some(1e-300), Some(1e300)][m.below(6)],
            unit: [
                None,
                None,
                None,
                Some("mm".to_string()),
                Some("furlong".into()),
            ][m.below(5)]
            .clone(),
            ..Default::default()
        };
        let run = std::panic::catch_unwind(|| load_and_run(&mutated, &options));
        if run.is_err() {
            let keep = std::env::temp_dir().join(format!("fuzz_fold_{i}.fold"));
            std::fs::write(&keep, &mutated).unwrap();
            panic!(
                "case {i} (from {path}, options {options:?}) panicked; the input is in {}",
                keep.display()
            );
        }
    }
}

/// The scene file of an FMU (`resources/scene.json`, what fmi2Instantiate
/// reads): real scenes' JSON changed at random, through the FMU's reader
/// and, where accepted, built, initialized and stepped.
#[test]
fn fuzz_scene_json() {
    let n = iterations(600);
    let every_key = std::fs::read_to_string(corpus("fold/every_key.fold")).unwrap();
    let seeds: Vec<Vec<u8>> = [
        square(),
        contact_square(),
        scene::from_str(&every_key).unwrap().0,
        origami_fmu::benchmarks::miura_scene(1),
    ]
    .iter()
    .map(origami_fmu::fmi::resources::scene_bytes)
    .collect();
    // The corpus: scene files that broke the reader once.
    for (k, e) in std::fs::read_dir(corpus("scene")).unwrap().enumerate() {
        let bytes = std::fs::read(e.unwrap().path()).unwrap();
        run_scene(&bytes, &format!("corpus file {k}"));
    }
    let mut m = Mutator {
        rng: rng(4),
        keys: &[
            "contact",
            "gravity",
            "fold_edge",
            "kind",
            "vertices",
            "edges",
        ],
    };
    for i in 0..n {
        let seed = &seeds[m.below(seeds.len())];
        let bytes = if i % 5 == 0 {
            let mut b = seed.clone();
            m.mutate_bytes(&mut b);
            b
        } else {
            let mut v: Value = serde_json::from_slice(seed).unwrap();
            for _ in 0..1 + m.below(3) {
                m.mutate(&mut v);
            }
            serde_json::to_vec(&v).unwrap()
        };
        run_scene(&bytes, &format!("case {i}"));
    }
}

/// Read scene-file `bytes` as fmi2Instantiate does and, where accepted,
/// build, initialize and step the model: no panic, finite outputs.
fn run_scene(bytes: &[u8], what: &str) {
    let run = std::panic::catch_unwind(|| {
        let Ok(mut scene) = origami_fmu::fmi::resources::parse_scene(bytes) else {
            return;
        };
        if scene.mesh.triangles().len() > 2000 {
            return;
        }
        scene.solver.max_internal_steps = scene.solver.max_internal_steps.min(2000);
        let Ok(mut model) = Model::new(scene) else {
            return;
        };
        if origami_fmu::fmi::resources::check_variable_names(&model).is_err()
            || model.initialize().is_err()
        {
            return;
        }
        for k in model.input_ids() {
            let _ = model.set_input(k, 0.5);
        }
        if model.advance(1e-3).is_ok() {
            assert!(model.output_values().iter().all(|x| x.is_finite()));
        }
    });
    if run.is_err() {
        let keep = std::env::temp_dir().join("fuzz_scene_failure.json");
        std::fs::write(&keep, bytes).unwrap();
        panic!("{what} panicked; the scene is in {}", keep.display());
    }
}

/// One FMI call of a sequence.
#[derive(Clone, Debug)]
enum Call {
    Init,
    Setup(f64, Option<f64>),
    Enter,
    Exit,
    Get,
    Set(u32, f64),
    Deriv(u32, f64),
    Step(f64),
    StepAt(f64, f64),
    Terminate,
    Reset,
    Save,
    Restore,
    Free,
    Reload,
}

/// Parse one line of `fmi_calls.txt`.
fn parse_calls(line: &str, variables: &[String]) -> Vec<Call> {
    let vr = |name: &str| {
        variables
            .iter()
            .position(|v| v == name)
            .unwrap_or_else(|| panic!("no variable {name}")) as u32
    };
    let num = |s: &str| s.parse::<f64>().unwrap();
    line.split(';')
        .map(|op| {
            let w: Vec<&str> = op.split_whitespace().collect();
            match w[..] {
                ["init"] => Call::Init,
                ["setup", a] => Call::Setup(num(a), None),
                ["setup", a, b] => Call::Setup(num(a), Some(num(b))),
                ["enter"] => Call::Enter,
                ["exit"] => Call::Exit,
                ["get"] => Call::Get,
                ["set", n, x] => Call::Set(vr(n), num(x)),
                ["deriv", n, x] => Call::Deriv(vr(n), num(x)),
                ["step", h] => Call::Step(num(h)),
                ["stepat", t, h] => Call::StepAt(num(t), num(h)),
                ["terminate"] => Call::Terminate,
                ["reset"] => Call::Reset,
                ["save"] => Call::Save,
                ["restore"] => Call::Restore,
                ["free"] => Call::Free,
                ["reload"] => Call::Reload,
                _ => panic!("unknown call {op:?}"),
            }
        })
        .collect()
}

/// Run `calls` on a fresh instance of `scene`: no call is fatal, every
/// status is one the standard allows for it, what is read is finite.
fn run_calls(scene: &Scene, calls: &[Call], what: &str) {
    let f = Fmu::of("fuzz_calls", scene);
    let mut states: Vec<fmi2FMUstate> = Vec::new();
    for (k, call) in calls.iter().enumerate() {
        let what = format!("{what}, call {k} {call:?}");
        // SAFETY: a live instance; arrays of the lengths passed.
        let st = unsafe {
            match *call {
                Call::Init => {
                    fmi2SetupExperiment(f.c, 0, 0.0, 0.0, 0, 0.0);
                    fmi2EnterInitializationMode(f.c);
                    fmi2ExitInitializationMode(f.c)
                }
                Call::Setup(t0, stop) => {
                    fmi2SetupExperiment(f.c, 0, 0.0, t0, stop.is_some() as i32, stop.unwrap_or(0.0))
                }
                Call::Enter => fmi2EnterInitializationMode(f.c),
                Call::Exit => fmi2ExitInitializationMode(f.c),
                Call::Get => {
                    read_all(&f, &what);
                    fmi2OK
                }
                Call::Set(vr, x) => f.set(&[vr], &[x]),
                Call::Deriv(vr, x) => fmi2SetRealInputDerivatives(f.c, &vr, 1, &1, &x),
                Call::Step(h) => f.step(time(&f), h),
                Call::StepAt(t, h) => f.step(t, h),
                Call::Terminate => fmi2Terminate(f.c),
                Call::Reset => fmi2Reset(f.c),
                Call::Save => {
                    let mut s: fmi2FMUstate = null_mut();
                    let st = fmi2GetFMUstate(f.c, &mut s);
                    if st == fmi2OK {
                        states.push(s);
                    }
                    st
                }
                Call::Restore => match states.last() {
                    Some(&s) => f.restore(s),
                    None => fmi2OK,
                },
                Call::Free => match states.pop() {
                    Some(mut s) => fmi2FreeFMUstate(f.c, &mut s),
                    None => fmi2OK,
                },
                Call::Reload => match states.last() {
                    Some(&s) => {
                        let bytes = f.serialize(s);
                        let (st, s2) = f.deserialize(&bytes);
                        if st == fmi2OK {
                            states.push(s2);
                        }
                        st
                    }
                    None => fmi2OK,
                },
            }
        };
        assert!(
            matches!(st, fmi2OK | fmi2Discard | fmi2Error),
            "{what}: {st:?}: {}",
            f.last()
        );
        alive(&f, &what);
    }
    read_all(&f, what);
    // Unfreed states go with the instance (fmi2FreeInstance on drop).
}

/// Sequences of FMI calls: the corpus, then random ones with values from
/// the edges of every range.
#[test]
fn fuzz_fmi_call_sequences() {
    let n = iterations(400);
    let mut scenes = [("square", square()), ("contact", contact_square())];
    for (_, s) in scenes.iter_mut() {
        s.solver.max_internal_steps = 2000;
    }
    let text = std::fs::read_to_string(corpus("fmi_calls.txt")).unwrap();
    for line in text
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
    {
        let (name, calls) = line.split_once(':').unwrap();
        let (_, scene) = scenes.iter().find(|s| s.0 == name.trim()).unwrap();
        let calls = parse_calls(calls, &names(scene));
        run_calls(scene, &calls, line);
    }
    let mut m = Mutator {
        rng: rng(3),
        keys: &[],
    };
    let steps = [1e-4, 1e-3, 1e-2, 0.05, 0.0, -1e-3, 1e-300, 1e300, f64::NAN];
    for i in 0..n {
        let (name, scene) = &scenes[i % scenes.len()];
        let count = names(scene).len() as u32;
        let mut calls = Vec::new();
        for _ in 0..5 + m.below(25) {
            let x = match m.below(4) {
                0 => f64::NAN,
                1 => m.rng.range(-2.0, 2.0),
                _ => NUMBERS[m.below(NUMBERS.len())],
            };
            let vr = m.below(count as usize + 2) as u32;
            let h = steps[m.below(steps.len())];
            calls.push(match m.below(16) {
                0 => Call::Init,
                1 => Call::Setup(x, [None, Some(x.abs() + 0.05)][m.below(2)]),
                2 => Call::Enter,
                3 => Call::Exit,
                4 => Call::Get,
                5 | 6 => Call::Set(vr, x),
                7 => Call::Deriv(vr, x),
                8 | 9 => Call::Step(h),
                10 => Call::StepAt(x, h),
                11 => Call::Terminate,
                12 => Call::Reset,
                13 => Call::Save,
                14 => Call::Restore,
                _ => [Call::Free, Call::Reload][m.below(2)].clone(),
            });
        }
        run_calls(scene, &calls, &format!("{name} case {i}: {calls:?}"));
    }
}
