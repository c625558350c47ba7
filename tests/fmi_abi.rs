//! The FMI 2.0 functions called directly, as a C host would: instantiation
//! checks, the state machine, value references, NaN rejection, FMU states,
//! the logger's "%s" format, and the symbols the cdylib exports.

mod common;
use common::fmi::{Log, callbacks};
use origami_fmu::fmi::exports::*;
use origami_fmu::fmi::resources::{SCENE_FILE, guid, scene_bytes};
use origami_fmu::fmi::types::*;
use origami_fmu::ids::VertexId;
use origami_fmu::mesh::builders::square_with_diagonal;
use origami_fmu::model::Model;
use origami_fmu::scene::Scene;
use std::ffi::{CStr, CString};
use std::path::{Path, PathBuf};
use std::ptr::{null, null_mut};
use std::sync::Mutex;

use fmi2Status::*;

fn scene() -> Scene {
    let mut s = Scene::with_defaults("square", square_with_diagonal(0.1, true, 1.5));
    s.vertex_forces.push(origami_fmu::scene::VertexInput {
        name: "tip".into(),
        vertex: VertexId(2),
    });
    s
}

/// A resources folder with the scene; returns (folder, GUID).
fn resources(tag: &str, bytes: &[u8]) -> (PathBuf, String) {
    let dir = std::env::temp_dir().join(format!(
        "origami_fmu_abi_{}_{tag}/resources",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(SCENE_FILE), bytes).unwrap();
    (dir, guid(bytes))
}

fn uri(dir: &Path) -> String {
    origami_fmu::fmi::resources::file_uri(dir)
}

struct Fmu {
    c: fmi2Component,
    log: Box<Log>,
}

impl Fmu {
    fn new(tag: &str) -> Fmu {
        Fmu::of(tag, &scene(), false)
    }
    /// An instance of `scene`, with `loggingOn` as given.
    fn of(tag: &str, scene: &Scene, logging_on: bool) -> Fmu {
        let (dir, g) = resources(tag, &scene_bytes(scene));
        let log: Box<Log> = Box::default();
        let c = instantiate_logging(&log, 1, &g, &uri(&dir), logging_on);
        assert!(!c.is_null(), "{:?}", log.lock().unwrap());
        Fmu { c, log }
    }
    /// Log lines of a category so far.
    fn lines(&self, category: &str) -> usize {
        let log = self.log.lock().unwrap();
        log.iter().filter(|l| l.1 == category).count()
    }
    fn initialized(tag: &str) -> Fmu {
        let f = Fmu::new(tag);
        unsafe {
            assert_eq!(fmi2SetupExperiment(f.c, 0, 0.0, 0.0, 0, 0.0), fmi2OK);
            assert_eq!(fmi2EnterInitializationMode(f.c), fmi2OK);
            assert_eq!(fmi2ExitInitializationMode(f.c), fmi2OK);
        }
        f
    }
    fn get(&self, vrs: &[u32]) -> Vec<f64> {
        let mut v = vec![0.0; vrs.len()];
        let s = unsafe { fmi2GetReal(self.c, vrs.as_ptr(), vrs.len(), v.as_mut_ptr()) };
        assert_eq!(s, fmi2OK, "{:?}", self.log.lock().unwrap());
        v
    }
    fn set(&self, vrs: &[u32], values: &[f64]) -> fmi2Status {
        unsafe { fmi2SetReal(self.c, vrs.as_ptr(), vrs.len(), values.as_ptr()) }
    }
    fn last_error(&self) -> String {
        let log = self.log.lock().unwrap();
        let (status, _, _, msg) = log.last().expect("a log line").clone();
        assert!(status >= fmi2Discard, "{msg}");
        msg
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        unsafe { fmi2FreeInstance(self.c) };
    }
}

fn instantiate(log: &Log, kind: i32, guid: &str, uri: &str) -> fmi2Component {
    instantiate_logging(log, kind, guid, uri, false)
}

fn instantiate_logging(
    log: &Log,
    kind: i32,
    guid: &str,
    uri: &str,
    logging_on: bool,
) -> fmi2Component {
    let cb = callbacks(log);
    let name = CString::new("test").unwrap();
    let guid = CString::new(guid).unwrap();
    let uri = CString::new(uri).unwrap();
    let on = logging_on as fmi2Boolean;
    unsafe { fmi2Instantiate(name.as_ptr(), kind, guid.as_ptr(), uri.as_ptr(), &cb, 0, on) }
}

fn model() -> Model {
    Model::new(scene()).unwrap()
}

fn vr_ranges() -> (Vec<u32>, Vec<u32>, Vec<u32>) {
    let m = model();
    let (p, i, o) = (m.parameters().len(), m.inputs().len(), m.outputs().len());
    let r = |a: usize, b: usize| (a as u32..b as u32).collect::<Vec<_>>();
    (r(0, p), r(p, p + i), r(p + i, p + i + o))
}

#[test]
fn instantiate_refuses_bad_arguments_with_a_reason() {
    let bytes = scene_bytes(&scene());
    let (dir, g) = resources("refuse", &bytes);
    let cases: Vec<(i32, String, String, &str)> = vec![
        (
            1,
            "{00000000-0000-0000-0000-000000000000}".into(),
            uri(&dir),
            "GUID mismatch",
        ),
        (0, g.clone(), uri(&dir), "co-simulation only"),
        (7, g.clone(), uri(&dir), "not a valid fmi2Type"),
        (
            1,
            g.clone(),
            format!("file://server{}", dir.display()),
            "host \"server\"",
        ),
        (
            1,
            g.clone(),
            "http://example.org/r".into(),
            "not a file: URI",
        ),
        (
            1,
            g.clone(),
            uri(&dir.join("missing")),
            "cannot read the scene",
        ),
    ];
    for (kind, guid, uri, expect) in cases {
        let log: Log = Mutex::default();
        let c = instantiate(&log, kind, &guid, &uri);
        assert!(c.is_null());
        let lines = log.lock().unwrap();
        assert_eq!(lines.len(), 1);
        let (status, category, format, msg) = &lines[0];
        assert_eq!(*status, fmi2Error);
        assert_eq!(category, "logStatusError");
        assert_eq!(format, "%s");
        assert!(msg.contains(expect), "{msg:?} should contain {expect:?}");
    }
    // A null callback struct: NULL, nothing to log to.
    let name = CString::new("x").unwrap();
    let c = unsafe { fmi2Instantiate(name.as_ptr(), 1, null(), null(), null(), 0, 0) };
    assert!(c.is_null());
    // Null GUID and resource location are refused with a log line.
    let log: Log = Mutex::default();
    let cb = callbacks(&log);
    let c = unsafe { fmi2Instantiate(name.as_ptr(), 1, null(), null(), &cb, 0, 0) };
    assert!(c.is_null());
    assert!(log.lock().unwrap()[0].3.contains("fmuGUID is NULL"));
}

#[test]
fn resource_uris_of_all_hosts_work() {
    let bytes = scene_bytes(&scene());
    let (dir, g) = resources("uri a%b", &bytes);
    let enc = dir
        .display()
        .to_string()
        .replace('%', "%25")
        .replace(' ', "%20");
    for u in [
        format!("file://{enc}"),
        format!("file://{enc}/"),
        format!("file://localhost{enc}"),
        format!("file:{enc}"),
    ] {
        let log: Log = Mutex::default();
        let c = instantiate(&log, 1, &g, &u);
        assert!(!c.is_null(), "{u}: {:?}", log.lock().unwrap());
        unsafe { fmi2FreeInstance(c) };
    }
}

#[test]
fn invalid_scenes_are_refused_with_the_reason() {
    let good = String::from_utf8(scene_bytes(&scene())).unwrap();
    let cases = [
        ("{ not json".to_string(), "not a valid scene JSON"),
        // a face that refers to vertex 9 of 4
        (
            good.replacen(
                "\"triangles\": [\n      [\n        0,",
                "\"triangles\": [\n      [\n        9,",
                1,
            ),
            "refers to vertex 9",
        ),
        (
            good.replacen("\"poisson_ratio\": 0.3", "\"poisson_ratio\": 0.7", 1),
            "material.poisson_ratio",
        ),
    ];
    for (k, (text, expect)) in cases.iter().enumerate() {
        assert_ne!(text, &good, "case {k} must change the scene");
        let (dir, g) = resources(&format!("bad{k}"), text.as_bytes());
        let log: Log = Mutex::default();
        assert!(instantiate(&log, 1, &g, &uri(&dir)).is_null());
        let msg = log.lock().unwrap()[0].3.clone();
        assert!(msg.contains(expect), "{msg:?} should contain {expect:?}");
        assert!(msg.contains("invalid scene"), "{msg}");
    }
}

#[test]
fn percent_in_messages_is_never_a_format() {
    // The decoded path contains "%s%n"; the logger gets format "%s" and
    // the path verbatim in the message.
    let (dir, g) = resources("fmt%s%n", b"{}");
    let enc = dir.display().to_string().replace('%', "%25");
    let log: Log = Mutex::default();
    assert!(instantiate(&log, 1, &g, &format!("file://{enc}")).is_null());
    let (_, _, format, msg) = log.lock().unwrap()[0].clone();
    assert_eq!(format, "%s");
    assert!(msg.contains("fmt%s%n"), "{msg}");
}

#[test]
fn value_references_are_parameters_inputs_outputs() {
    let f = Fmu::new("vr");
    let m = model();
    let (p, i, o) = vr_ranges();
    let starts =
        |t: &[origami_fmu::model::VariableSpec]| t.iter().map(|v| v.start).collect::<Vec<_>>();
    assert_eq!(f.get(&p), starts(m.parameters()));
    assert_eq!(f.get(&i), starts(m.inputs()));
    assert_eq!(f.get(&o), m.output_values());
    let beyond = [(p.len() + i.len() + o.len()) as u32];
    let mut v = [0.0];
    assert_eq!(
        unsafe { fmi2GetReal(f.c, beyond.as_ptr(), 1, v.as_mut_ptr()) },
        fmi2Error
    );
    assert!(
        f.last_error()
            .contains("no Real variable with value reference")
    );
}

#[test]
fn calls_out_of_order_are_errors_with_a_reason() {
    let f = Fmu::new("order");
    let (p, i, o) = vr_ranges();
    unsafe {
        assert_eq!(fmi2DoStep(f.c, 0.0, 0.01, 1), fmi2Error);
        assert!(
            f.last_error()
                .contains("fmi2DoStep is not allowed in state 'instantiated'")
        );
        assert_eq!(fmi2ExitInitializationMode(f.c), fmi2Error);
        assert_eq!(fmi2Terminate(f.c), fmi2Error);
        // parameters may change before initialization ends
        assert_eq!(f.set(&p[..1], &[2.0e9]), fmi2OK);
        assert_eq!(fmi2EnterInitializationMode(f.c), fmi2OK);
        assert_eq!(fmi2SetupExperiment(f.c, 0, 0.0, 0.0, 0, 0.0), fmi2Error);
        assert_eq!(f.set(&p[..1], &[2.5e9]), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(f.c), fmi2OK);
        assert_eq!(fmi2EnterInitializationMode(f.c), fmi2Error);
        // a fixed parameter after initialization
        assert_eq!(f.set(&p[..1], &[1.0e9]), fmi2Error);
        assert!(f.last_error().contains("fixed parameter"));
        assert_eq!(f.get(&p[..1]), vec![2.5e9]);
        // outputs are never settable
        assert_eq!(f.set(&o[..1], &[1.0]), fmi2Error);
        assert!(f.last_error().contains("is an output"));
        // inputs are
        assert_eq!(f.set(&i[..1], &[0.5]), fmi2OK);
        assert_eq!(fmi2DoStep(f.c, 0.0, 0.01, 1), fmi2OK);
        assert_eq!(fmi2Terminate(f.c), fmi2OK);
        assert_eq!(fmi2DoStep(f.c, 0.01, 0.01, 1), fmi2Error);
        assert!(f.last_error().contains("terminated"));
        assert_eq!(f.set(&i[..1], &[0.5]), fmi2Error);
        // reset goes back to instantiated with the scene's start values
        assert_eq!(fmi2Reset(f.c), fmi2OK);
        assert_eq!(f.get(&p[..1]), vec![model().parameters()[0].start]);
        assert_eq!(fmi2EnterInitializationMode(f.c), fmi2OK);
    }
}

#[test]
fn non_finite_values_are_rejected_and_nothing_changes() {
    let f = Fmu::initialized("nan");
    let (_, i, _) = vr_ranges();
    assert_eq!(f.set(&i, &vec![0.25; i.len()]), fmi2OK);
    let before = f.get(&i);
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        // the first value is fine, the last is not: neither is applied
        let mut values = vec![0.75; i.len()];
        *values.last_mut().unwrap() = bad;
        assert_eq!(f.set(&i, &values), fmi2Error);
        assert!(f.last_error().contains("not a finite number"));
        assert_eq!(f.get(&i), before);
    }
    unsafe { assert_eq!(fmi2DoStep(f.c, 0.0, 0.01, 1), fmi2OK) };
}

#[test]
fn null_pointers_are_errors() {
    let f = Fmu::initialized("null");
    unsafe {
        assert_eq!(fmi2GetReal(f.c, null(), 1, null_mut()), fmi2Error);
        assert_eq!(fmi2SetReal(f.c, null(), 1, null()), fmi2Error);
        assert_eq!(fmi2GetReal(f.c, null(), 0, null_mut()), fmi2OK);
        assert_eq!(fmi2GetFMUstate(f.c, null_mut()), fmi2Error);
        assert_eq!(fmi2SetFMUstate(f.c, null_mut()), fmi2Error);
        assert_eq!(
            fmi2SerializedFMUstateSize(f.c, null_mut(), null_mut()),
            fmi2Error
        );
        assert_eq!(fmi2GetRealStatus(f.c, 2, null_mut()), fmi2Error);
        assert_eq!(fmi2DoStep(null_mut(), 0.0, 0.1, 0), fmi2Error);
        assert_eq!(fmi2SetDebugLogging(f.c, 1, 2, null()), fmi2Error);
        fmi2FreeInstance(null_mut());
    }
}

#[test]
fn communication_points_must_match_and_never_drift() {
    let f = Fmu::initialized("time");
    let mut t = 0.0;
    let mut tl = 0.0;
    unsafe {
        assert_eq!(fmi2DoStep(f.c, 0.5, 0.1, 1), fmi2Error);
        assert!(f.last_error().contains("does not match the FMU's time"));
        assert_eq!(fmi2DoStep(f.c, 0.0, 0.0, 1), fmi2Error);
        assert_eq!(fmi2DoStep(f.c, 0.0, -1.0, 1), fmi2Error);
        assert_eq!(fmi2DoStep(f.c, 0.0, f64::NAN, 1), fmi2Error);
        // A master that accumulates t += h drifts; the FMU follows its
        // communication points exactly.
        for _ in 0..1000 {
            assert_eq!(fmi2DoStep(f.c, t, 0.1, 1), fmi2OK);
            t += 0.1;
            assert_eq!(fmi2GetRealStatus(f.c, 2, &mut tl), fmi2OK);
        }
        assert_eq!(tl.to_bits(), t.to_bits());
        // variable step sizes
        for h in [1e-5, 3.0, 0.0123] {
            assert_eq!(fmi2DoStep(f.c, t, h, 1), fmi2OK);
            t += h;
        }
        assert_eq!(fmi2GetRealStatus(f.c, 2, &mut tl), fmi2OK);
        assert_eq!(tl, t);
    }
}

#[test]
fn start_time_is_honoured() {
    let f = Fmu::new("start");
    let mut tl = 0.0;
    unsafe {
        assert_eq!(fmi2SetupExperiment(f.c, 1, 1e-6, 2.5, 1, 3.0), fmi2OK);
        assert_eq!(fmi2EnterInitializationMode(f.c), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(f.c), fmi2OK);
        assert_eq!(fmi2GetRealStatus(f.c, 2, &mut tl), fmi2OK);
        assert_eq!(tl, 2.5);
        assert_eq!(fmi2DoStep(f.c, 2.5, 0.5, 1), fmi2OK);
    }
}

/// Run `n` steps of `h` from the FMU's time `t` with a fold ramp; the
/// outputs after each step.
fn run(f: &Fmu, t0: f64, n: usize, h: f64) -> Vec<Vec<f64>> {
    let (_, i, o) = vr_ranges();
    let mut out = Vec::new();
    for k in 0..n {
        let t = t0 + k as f64 * h;
        assert_eq!(f.set(&i[..1], &[(t + h).min(1.0)]), fmi2OK);
        assert_eq!(unsafe { fmi2DoStep(f.c, t, h, 0) }, fmi2OK);
        out.push(f.get(&o));
    }
    out
}

#[test]
fn fmu_state_round_trips_bit_identically() {
    let f = Fmu::initialized("state");
    let (_, i, o) = vr_ranges();
    run(&f, 0.0, 5, 0.01);
    let mut s: fmi2FMUstate = null_mut();
    unsafe {
        assert_eq!(fmi2GetFMUstate(f.c, &mut s), fmi2OK);
        assert!(!s.is_null());
        let inputs = f.get(&i);
        let first = run(&f, 0.05, 5, 0.01);
        // restore, step again: identical
        assert_eq!(fmi2SetFMUstate(f.c, s), fmi2OK);
        assert_eq!(f.get(&i), inputs);
        let again = run(&f, 0.05, 5, 0.01);
        assert_eq!(bits(&first), bits(&again));
        // serialize, deserialize, restore into a fresh instance
        let mut size = 0usize;
        assert_eq!(fmi2SerializedFMUstateSize(f.c, s, &mut size), fmi2OK);
        let mut buf = vec![0 as fmi2Byte; size];
        assert_eq!(
            fmi2SerializeFMUstate(f.c, s, buf.as_mut_ptr(), size - 1),
            fmi2Error
        );
        assert_eq!(
            fmi2SerializeFMUstate(f.c, s, buf.as_mut_ptr(), size),
            fmi2OK
        );
        let g = Fmu::new("state2");
        let mut s2: fmi2FMUstate = null_mut();
        assert_eq!(
            fmi2DeSerializeFMUstate(g.c, buf.as_ptr(), size, &mut s2),
            fmi2OK
        );
        assert_eq!(fmi2SetFMUstate(g.c, s2), fmi2OK);
        let third = run(&g, 0.05, 5, 0.01);
        assert_eq!(bits(&first), bits(&third));
        assert_eq!(bits(&[g.get(&o)]), bits(&[f.get(&o)]));
        // overwrite in place, then free
        assert_eq!(fmi2GetFMUstate(f.c, &mut s), fmi2OK);
        assert_eq!(fmi2FreeFMUstate(f.c, &mut s), fmi2OK);
        assert!(s.is_null());
        assert_eq!(fmi2FreeFMUstate(g.c, &mut s2), fmi2OK);
        // garbage bytes are refused
        let junk = b"{\"guid\": 1}";
        let mut s3: fmi2FMUstate = null_mut();
        assert_eq!(
            fmi2DeSerializeFMUstate(g.c, junk.as_ptr() as *const fmi2Byte, junk.len(), &mut s3),
            fmi2Error
        );
        assert!(s3.is_null());
    }
}

#[test]
fn state_restores_the_phase() {
    let f = Fmu::new("phase");
    let mut s: fmi2FMUstate = null_mut();
    unsafe {
        assert_eq!(fmi2GetFMUstate(f.c, &mut s), fmi2OK);
        assert_eq!(fmi2EnterInitializationMode(f.c), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(f.c), fmi2OK);
        assert_eq!(fmi2DoStep(f.c, 0.0, 0.1, 0), fmi2OK);
        assert_eq!(fmi2SetFMUstate(f.c, s), fmi2OK);
        // back in "instantiated": stepping is out of order again
        assert_eq!(fmi2DoStep(f.c, 0.0, 0.1, 0), fmi2Error);
        assert_eq!(fmi2EnterInitializationMode(f.c), fmi2OK);
        assert_eq!(fmi2FreeFMUstate(f.c, &mut s), fmi2OK);
    }
}

fn bits(v: &[Vec<f64>]) -> Vec<Vec<u64>> {
    v.iter()
        .map(|r| r.iter().map(|x| x.to_bits()).collect())
        .collect()
}

#[test]
fn status_queries_and_unsupported_functions() {
    let f = Fmu::initialized("status");
    let mut st = fmi2OK;
    let mut b: fmi2Boolean = 7;
    let mut i: fmi2Integer = 0;
    let mut s: fmi2String = null();
    unsafe {
        assert_eq!(fmi2GetStatus(f.c, 0, &mut st), fmi2OK);
        assert_eq!(fmi2GetStatus(f.c, 1, &mut st), fmi2Discard);
        assert_eq!(fmi2GetStatus(f.c, 99, &mut st), fmi2Error);
        assert!(f.last_error().contains("not a valid fmi2StatusKind"));
        assert_eq!(fmi2GetBooleanStatus(f.c, 3, &mut b), fmi2OK);
        assert_eq!(b, FMI2_FALSE);
        assert_eq!(fmi2GetIntegerStatus(f.c, 0, &mut i), fmi2Discard);
        assert_eq!(fmi2GetStringStatus(f.c, 1, &mut s), fmi2Discard);
        assert_eq!(fmi2GetStringStatus(f.c, -1, &mut s), fmi2Error);
        assert_eq!(fmi2CancelStep(f.c), fmi2Error);
        assert_eq!(
            fmi2GetDirectionalDerivative(f.c, null(), 0, null(), 0, null(), null_mut()),
            fmi2Error
        );
        // canInterpolateInputs: an empty call is fine (derivatives: below).
        assert_eq!(
            fmi2SetRealInputDerivatives(f.c, null(), 0, null(), null()),
            fmi2OK
        );
        assert_eq!(
            fmi2GetRealOutputDerivatives(f.c, null(), 0, null(), null_mut()),
            fmi2Error
        );
        assert_eq!(fmi2EnterEventMode(f.c), fmi2Error);
        assert!(f.last_error().contains("co-simulation only"));
        assert_eq!(fmi2SetTime(f.c, 0.0), fmi2Error);
        assert_eq!(fmi2GetContinuousStates(f.c, null_mut(), 0), fmi2Error);
        // no Integer/Boolean/String variables
        assert_eq!(fmi2GetInteger(f.c, null(), 0, null_mut()), fmi2OK);
        let vr = [0u32];
        assert_eq!(fmi2GetInteger(f.c, vr.as_ptr(), 1, &mut i), fmi2Error);
        assert_eq!(fmi2SetBoolean(f.c, vr.as_ptr(), 1, &b), fmi2Error);
        assert_eq!(fmi2SetString(f.c, vr.as_ptr(), 1, &s), fmi2Error);
        assert_eq!(CStr::from_ptr(fmi2GetVersion()).to_str().unwrap(), "2.0");
        assert_eq!(
            CStr::from_ptr(fmi2GetTypesPlatform()).to_str().unwrap(),
            "default"
        );
    }
}

#[test]
fn debug_logging_switches_info_lines() {
    let f = Fmu::initialized("debug");
    let cat = CString::new("logEvents").unwrap();
    let bad = CString::new("logNothing").unwrap();
    unsafe {
        let n0 = f.log.lock().unwrap().len();
        assert_eq!(fmi2DoStep(f.c, 0.0, 0.1, 0), fmi2OK);
        assert_eq!(f.log.lock().unwrap().len(), n0, "debug logging is off");
        assert_eq!(fmi2SetDebugLogging(f.c, 1, 1, &cat.as_ptr()), fmi2OK);
        assert_eq!(fmi2DoStep(f.c, 0.1, 0.1, 0), fmi2OK);
        let log = f.log.lock().unwrap();
        assert_eq!(log.len(), n0 + 1);
        assert_eq!(log[n0].0, fmi2OK);
        assert_eq!(log[n0].1, "logEvents");
        assert!(log[n0].3.contains("fmi2DoStep"));
        drop(log);
        assert_eq!(fmi2SetDebugLogging(f.c, 1, 1, &bad.as_ptr()), fmi2Error);
    }
}

#[test]
fn instances_are_independent_across_threads() {
    let serial: Vec<_> = (0..4)
        .map(|k| {
            let f = Fmu::initialized(&format!("serial{k}"));
            run(&f, 0.0, 20, 0.01)
        })
        .collect();
    let parallel: Vec<_> = std::thread::scope(|s| {
        let hs: Vec<_> = (0..4)
            .map(|k| {
                s.spawn(move || {
                    let f = Fmu::initialized(&format!("thread{k}"));
                    run(&f, 0.0, 20, 0.01)
                })
            })
            .collect();
        hs.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for (a, b) in serial.iter().zip(&parallel) {
        assert_eq!(bits(a), bits(b));
    }
}

/// The cdylib that cargo built along with this test: integration tests run
/// from `target/<profile>/deps/`, where the library's cdylib is written
/// (it is copied up to `target/<profile>/` only by `cargo build`).
fn cdylib() -> PathBuf {
    std::env::current_exe()
        .unwrap()
        .parent()
        .unwrap()
        .join("liborigami_fmu.so")
}

#[test]
fn the_library_exports_exactly_the_fmi2_functions() {
    let lib = cdylib();
    if !lib.is_file() {
        panic!("{} missing: cargo builds it with the tests", lib.display());
    }
    let out = match std::process::Command::new("nm")
        .args(["-D", "--defined-only"])
        .arg(&lib)
        .output()
    {
        Ok(o) if o.status.success() => o,
        _ => {
            eprintln!("skipped: `nm` is not available");
            return;
        }
    };
    let text = String::from_utf8_lossy(&out.stdout);
    let symbols: Vec<&str> = text
        .lines()
        .filter_map(|l| l.split_whitespace().nth(2))
        .collect();
    let expected = [
        "fmi2GetTypesPlatform",
        "fmi2GetVersion",
        "fmi2SetDebugLogging",
        "fmi2Instantiate",
        "fmi2FreeInstance",
        "fmi2SetupExperiment",
        "fmi2EnterInitializationMode",
        "fmi2ExitInitializationMode",
        "fmi2Terminate",
        "fmi2Reset",
        "fmi2GetReal",
        "fmi2GetInteger",
        "fmi2GetBoolean",
        "fmi2GetString",
        "fmi2SetReal",
        "fmi2SetInteger",
        "fmi2SetBoolean",
        "fmi2SetString",
        "fmi2GetFMUstate",
        "fmi2SetFMUstate",
        "fmi2FreeFMUstate",
        "fmi2SerializedFMUstateSize",
        "fmi2SerializeFMUstate",
        "fmi2DeSerializeFMUstate",
        "fmi2GetDirectionalDerivative",
        "fmi2EnterEventMode",
        "fmi2NewDiscreteStates",
        "fmi2EnterContinuousTimeMode",
        "fmi2CompletedIntegratorStep",
        "fmi2SetTime",
        "fmi2SetContinuousStates",
        "fmi2GetDerivatives",
        "fmi2GetEventIndicators",
        "fmi2GetContinuousStates",
        "fmi2GetNominalsOfContinuousStates",
        "fmi2SetRealInputDerivatives",
        "fmi2GetRealOutputDerivatives",
        "fmi2DoStep",
        "fmi2CancelStep",
        "fmi2GetStatus",
        "fmi2GetRealStatus",
        "fmi2GetIntegerStatus",
        "fmi2GetBooleanStatus",
        "fmi2GetStringStatus",
    ];
    let mut got: Vec<&str> = symbols.clone();
    got.sort_unstable();
    let mut want = expected.to_vec();
    want.sort_unstable();
    assert_eq!(got, want, "nm -D --defined-only {}", lib.display());
}

/// A scene whose steps fail: at most two internal steps of 1 ms per
/// communication step, so any step longer than 2 ms is discarded.
fn capped_scene() -> Scene {
    let mut s = scene();
    s.solver.max_internal_steps = 2;
    s.solver.max_step = 1e-3;
    s
}

fn initialize(f: &Fmu, stop: Option<f64>) {
    unsafe {
        let (defined, t) = (stop.is_some() as fmi2Boolean, stop.unwrap_or(0.0));
        assert_eq!(fmi2SetupExperiment(f.c, 0, 0.0, 0.0, defined, t), fmi2OK);
        assert_eq!(fmi2EnterInitializationMode(f.c), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(f.c), fmi2OK);
    }
}

/// FMI 2.0 section 4.2.4: after a discarded step the FMU says it is
/// terminated (so fmpy, fmusim and OMSimulator stop instead of repeating
/// the step), its time is the last successful one, SetReal and DoStep are
/// refused, and a master retries through fmi2SetFMUstate with a smaller step.
#[test]
fn a_discarded_step_terminates_until_a_state_is_restored() {
    let f = Fmu::of("discard", &capped_scene(), false);
    initialize(&f, None);
    let (_, i, _) = vr_ranges();
    let mut b: fmi2Boolean = 7;
    let mut t: fmi2Real = -1.0;
    let mut saved: fmi2FMUstate = null_mut();
    unsafe {
        assert_eq!(fmi2DoStep(f.c, 0.0, 0.002, 0), fmi2OK);
        assert_eq!(fmi2GetBooleanStatus(f.c, 3, &mut b), fmi2OK);
        assert_eq!(b, FMI2_FALSE);
        assert_eq!(fmi2GetFMUstate(f.c, &mut saved), fmi2OK);
        assert_eq!(fmi2DoStep(f.c, 0.002, 0.01, 0), fmi2Discard);
        assert_eq!(fmi2GetBooleanStatus(f.c, 3, &mut b), fmi2OK);
        assert_eq!(b, FMI2_TRUE, "terminated after a discard");
        assert_eq!(fmi2GetRealStatus(f.c, 2, &mut t), fmi2OK);
        assert_eq!(t, 0.002, "last successful time");
        assert_eq!(f.set(&i[..1], &[0.5]), fmi2Error);
        assert!(f.last_error().contains("step failed"), "{}", f.last_error());
        assert_eq!(fmi2DoStep(f.c, 0.002, 0.001, 0), fmi2Error);
        // Retry: restore the state of t = 0.002, take a step that fits.
        assert_eq!(fmi2SetFMUstate(f.c, saved), fmi2OK);
        assert_eq!(fmi2GetBooleanStatus(f.c, 3, &mut b), fmi2OK);
        assert_eq!(b, FMI2_FALSE);
        assert_eq!(fmi2DoStep(f.c, 0.002, 0.002, 0), fmi2OK);
        assert_eq!(fmi2DoStep(f.c, 0.004, 0.01, 0), fmi2Discard);
        assert_eq!(fmi2Terminate(f.c), fmi2OK);
        assert_eq!(fmi2FreeFMUstate(f.c, &mut saved), fmi2OK);
    }
}

/// No step is without end: past `solver.max_step_cpu` seconds of CPU a
/// step is discarded with the state from before it and a log line naming
/// the limit; the master may restore a state and go on.
#[test]
fn a_step_past_its_cpu_limit_is_discarded_with_the_state_before_it() {
    let m = model();
    let cap = m
        .parameters()
        .iter()
        .position(|v| v.name == "solver.max_step_cpu")
        .expect("the parameter solver.max_step_cpu") as u32;
    let (_, _, o) = vr_ranges();
    let f = Fmu::new("cpu_cap");
    let mut t: fmi2Real = -1.0;
    let mut saved: fmi2FMUstate = null_mut();
    unsafe {
        assert_eq!(f.set(&[cap], &[1e-9]), fmi2OK);
        initialize(&f, None);
        assert_eq!(fmi2GetFMUstate(f.c, &mut saved), fmi2OK);
        let before = f.get(&o);
        assert_eq!(fmi2DoStep(f.c, 0.0, 0.01, 0), fmi2Discard);
        let why = f.last_error();
        assert!(why.contains("solver.max_step_cpu = 1e-9 s"), "{why}");
        assert!(why.contains("the state is the one before it"), "{why}");
        assert_eq!(fmi2GetRealStatus(f.c, 2, &mut t), fmi2OK);
        assert_eq!(t, 0.0, "last successful time");
        assert_eq!(bits(&[f.get(&o)]), bits(&[before]), "outputs as before");
        // The state of t = 0 back: stepping again is allowed (and, at this
        // limit, discarded again).
        assert_eq!(fmi2SetFMUstate(f.c, saved), fmi2OK);
        assert_eq!(fmi2DoStep(f.c, 0.0, 0.01, 0), fmi2Discard);
        assert_eq!(fmi2FreeFMUstate(f.c, &mut saved), fmi2OK);
        // The limit (a fixed parameter) raised in a new instance: the step
        // goes through to the bits of an instance at the default limit.
        let g = Fmu::new("cpu_cap_raised");
        assert_eq!(g.set(&[cap], &[1e3]), fmi2OK);
        initialize(&g, None);
        assert_eq!(fmi2DoStep(g.c, 0.0, 0.01, 0), fmi2OK);
        let plain = Fmu::initialized("cpu_cap_plain");
        assert_eq!(fmi2DoStep(plain.c, 0.0, 0.01, 0), fmi2OK);
        assert_eq!(bits(&[g.get(&o)]), bits(&[plain.get(&o)]));
    }
}

/// FMI 2.0 section 2.1.6: with a stop time defined, a step past it is an
/// error (and changes nothing).
#[test]
fn steps_past_the_stop_time_are_errors() {
    let f = Fmu::of("stop", &scene(), false);
    initialize(&f, Some(0.02));
    unsafe {
        assert_eq!(fmi2DoStep(f.c, 0.0, 0.01, 0), fmi2OK);
        assert_eq!(fmi2DoStep(f.c, 0.01, 0.01, 0), fmi2OK);
        assert_eq!(fmi2DoStep(f.c, 0.02, 0.01, 0), fmi2Error);
        assert!(f.last_error().contains("stopTime"), "{}", f.last_error());
        let mut t = 0.0;
        assert_eq!(fmi2GetRealStatus(f.c, 2, &mut t), fmi2OK);
        assert_eq!(t, 0.02);
    }
}

/// FMI 2.0 section 2.1.5: the logger is called only for enabled
/// categories. Without loggingOn, discards and errors are reported (a master
/// that ends its run at a discard must not end it silently);
/// fmi2SetDebugLogging(false) silences everything, and with a
/// list only the listed categories are called, once per failure.
#[test]
fn the_logger_is_called_only_for_enabled_categories() {
    let f = Fmu::of("logcat", &capped_scene(), false);
    initialize(&f, None);
    let mut saved: fmi2FMUstate = null_mut();
    unsafe {
        assert_eq!(fmi2GetFMUstate(f.c, &mut saved), fmi2OK);
        assert_eq!(fmi2DoStep(f.c, 0.0, 0.01, 0), fmi2Discard);
        assert_eq!(
            f.lines("logStatusDiscard"),
            1,
            "discards are reported by default"
        );
        assert_eq!(fmi2DoStep(f.c, 0.0, 0.01, 0), fmi2Error);
        assert_eq!(f.lines("logStatusError"), 1);
        // Everything off: no call at all.
        assert_eq!(fmi2SetDebugLogging(f.c, 0, 0, null()), fmi2OK);
        let n = f.log.lock().unwrap().len();
        assert_eq!(fmi2DoStep(f.c, 0.0, 0.01, 0), fmi2Error);
        assert_eq!(f.log.lock().unwrap().len(), n);
        // Only discards: one line per discarded step.
        let cat = CString::new("logStatusDiscard").unwrap();
        assert_eq!(fmi2SetDebugLogging(f.c, 1, 1, &cat.as_ptr()), fmi2OK);
        assert_eq!(fmi2SetFMUstate(f.c, saved), fmi2OK);
        assert_eq!(fmi2DoStep(f.c, 0.0, 0.01, 0), fmi2Discard);
        assert_eq!(fmi2DoStep(f.c, 0.0, 0.01, 0), fmi2Error);
        let log = f.log.lock().unwrap();
        assert_eq!(log.len(), n + 1, "{log:?}");
        assert_eq!(log[n].1, "logStatusDiscard");
        drop(log);
        assert_eq!(fmi2FreeFMUstate(f.c, &mut saved), fmi2OK);
    }
    // loggingOn at instantiation: the discard is reported.
    let g = Fmu::of("logcat_on", &capped_scene(), true);
    initialize(&g, None);
    assert_eq!(unsafe { fmi2DoStep(g.c, 0.0, 0.01, 0) }, fmi2Discard);
    assert_eq!(g.lines("logStatusDiscard"), 1);
}

/// canInterpolateInputs: a first derivative set with the value makes the
/// input grow linearly over the step (the input reads u + du h after it), a
/// second one along a parabola; orders above 2, non-inputs and non-finite
/// values are refused.
#[test]
fn input_derivatives_extrapolate_over_the_step() {
    let f = Fmu::initialized("derivatives");
    let (p, i, o) = vr_ranges();
    let order1 = [1 as fmi2Integer];
    unsafe {
        assert_eq!(f.set(&i[..1], &[0.2]), fmi2OK);
        assert_eq!(
            fmi2SetRealInputDerivatives(f.c, i.as_ptr(), 1, order1.as_ptr(), [5.0].as_ptr()),
            fmi2OK
        );
        assert_eq!(fmi2DoStep(f.c, 0.0, 0.1, 0), fmi2OK);
        assert!((f.get(&i[..1])[0] - 0.7).abs() < 1e-12);
        // Setting the value resets the slope: held from here.
        assert_eq!(f.set(&i[..1], &[0.7]), fmi2OK);
        assert_eq!(fmi2DoStep(f.c, 0.1, 0.1, 0), fmi2OK);
        assert_eq!(f.get(&i[..1])[0], 0.7);
        // A second derivative: the parabola 0.7 + t^2 / 2 over the step.
        let order2 = [2 as fmi2Integer];
        assert_eq!(
            fmi2SetRealInputDerivatives(f.c, i.as_ptr(), 1, order2.as_ptr(), [1.0].as_ptr()),
            fmi2OK
        );
        assert_eq!(fmi2DoStep(f.c, 0.2, 0.1, 0), fmi2OK);
        assert!((f.get(&i[..1])[0] - 0.705).abs() < 1e-12);
        // Not set again: it goes on along the parabola (slope 0.1 now).
        assert_eq!(fmi2DoStep(f.c, 0.3, 0.1, 0), fmi2OK);
        assert!((f.get(&i[..1])[0] - 0.72).abs() < 1e-12);
        let order3 = [3 as fmi2Integer];
        assert_eq!(
            fmi2SetRealInputDerivatives(f.c, i.as_ptr(), 1, order3.as_ptr(), [1.0].as_ptr()),
            fmi2Error
        );
        assert!(
            f.last_error().contains("order 1 or 2"),
            "{}",
            f.last_error()
        );
        assert_eq!(
            fmi2SetRealInputDerivatives(f.c, p.as_ptr(), 1, order1.as_ptr(), [1.0].as_ptr()),
            fmi2Error
        );
        assert_eq!(
            fmi2SetRealInputDerivatives(f.c, o.as_ptr(), 1, order1.as_ptr(), [1.0].as_ptr()),
            fmi2Error
        );
        assert_eq!(
            fmi2SetRealInputDerivatives(f.c, i.as_ptr(), 1, order1.as_ptr(), [f64::NAN].as_ptr()),
            fmi2Error
        );
    }
}

/// fmi2SetupExperiment's tolerance (toleranceDefined) sets the parameter
/// solver.tolerance, unless the master set that parameter to another value
/// (in either order); an out-of-range tolerance is not used (fmi2Warning).
#[test]
fn the_experiment_tolerance_sets_the_solver_tolerance() {
    let m = model();
    let vr = m
        .parameters()
        .iter()
        .position(|v| v.name == "solver.tolerance")
        .unwrap() as u32;
    let start = m.parameters()[vr as usize].start;
    let f = Fmu::new("tol_defined");
    unsafe {
        assert_eq!(fmi2SetupExperiment(f.c, 1, 1e-6, 0.0, 0, 0.0), fmi2OK);
    }
    assert_eq!(f.get(&[vr]), vec![1e-6]);
    // Not defined: the start value stays.
    let g = Fmu::new("tol_undefined");
    unsafe {
        assert_eq!(fmi2SetupExperiment(g.c, 0, 1e-6, 0.0, 0, 0.0), fmi2OK);
    }
    assert_eq!(g.get(&[vr]), vec![start]);
    // Set before: the parameter wins; set after: it overwrites.
    let h = Fmu::new("tol_param_first");
    assert_eq!(h.set(&[vr], &[1e-5]), fmi2OK);
    unsafe {
        assert_eq!(fmi2SetupExperiment(h.c, 1, 1e-7, 0.0, 0, 0.0), fmi2OK);
    }
    assert_eq!(h.get(&[vr]), vec![1e-5]);
    let k = Fmu::new("tol_param_after");
    unsafe {
        assert_eq!(fmi2SetupExperiment(k.c, 1, 1e-7, 0.0, 0, 0.0), fmi2OK);
    }
    assert_eq!(k.set(&[vr], &[1e-5]), fmi2OK);
    assert_eq!(k.get(&[vr]), vec![1e-5]);
    // Out of range: not used, with a warning.
    let w = Fmu::new("tol_bad");
    unsafe {
        assert_eq!(fmi2SetupExperiment(w.c, 1, 2.0, 0.0, 0, 0.0), fmi2Warning);
        assert_eq!(fmi2EnterInitializationMode(w.c), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(w.c), fmi2OK);
    }
    assert_eq!(w.get(&[vr]), vec![start]);
}

/// A contact surface whose curved facets bend farther from their samples
/// than the contact thickness (flat-folder's small bird base, 0.1 mm
/// paper, 3 samples per facet side, folding) is named in the log once, as
/// a warning, while the step itself returns fmi2OK; the output
/// `contact.chord_error` says how far.
#[test]
fn a_chord_error_past_the_thickness_is_logged_once() {
    let path = "tests/data/flat-folder/244_komatsuoripa_Smallbird_Base.fold";
    let (mut s, _) = origami_fmu::scene::load(path).unwrap();
    s.contact = Some(s.default_contact());
    let thickness = s.contact.unwrap().thickness;
    let m = Model::new(s.clone()).unwrap();
    let fold = m.parameters().len() as u32;
    let chord = (m.parameters().len()
        + m.inputs().len()
        + m.outputs()
            .iter()
            .position(|v| v.name == "contact.chord_error")
            .expect("the output contact.chord_error")) as u32;
    let f = Fmu::of("chord", &s, true);
    initialize(&f, None);
    let (h, mut t, mut worst) = (0.01, 0.0, 0.0f64);
    while f.lines("logStatusWarning") == 0 && t < 0.45 {
        assert_eq!(f.set(&[fold], &[t / 0.5]), fmi2OK);
        assert_eq!(unsafe { fmi2DoStep(f.c, t, h, 0) }, fmi2OK);
        t += h;
        worst = worst.max(f.get(&[chord])[0]);
    }
    assert!(worst > thickness, "chord error {worst} m");
    let log = f.log.lock().unwrap();
    let line = &log.iter().find(|l| l.1 == "logStatusWarning").unwrap().3;
    assert!(
        line.contains("contact.chord_error")
            && line.contains("past the contact thickness on facets"),
        "{line}"
    );
    drop(log);
    assert_eq!(f.set(&[fold], &[t / 0.5]), fmi2OK);
    assert_eq!(unsafe { fmi2DoStep(f.c, t, h, 0) }, fmi2OK);
    assert_eq!(f.lines("logStatusWarning"), 1, "once an instance");
}
