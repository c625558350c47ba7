//! A host of the exported FMI functions for the tests that call them
//! directly: a capturing logger, a resources folder per scene, and an
//! instance handle that frees itself.
#![allow(dead_code)] // each test file uses a different subset

use origami_fmu::fmi::exports::*;
use origami_fmu::fmi::resources::{SCENE_FILE, file_uri, guid, scene_bytes};
use origami_fmu::fmi::types::*;
use origami_fmu::ids::VertexId;
use origami_fmu::mesh::builders::square_with_diagonal;
use origami_fmu::model::Model;
use origami_fmu::scene::{Scene, VertexInput};
use std::ffi::{CStr, CString, c_char, c_void};
use std::path::PathBuf;
use std::ptr::null_mut;
use std::sync::Mutex;

pub use fmi2Status::*;

/// The square of `tests/fmi_abi.rs`: one creased diagonal, a vertex force.
pub fn square() -> Scene {
    let mut s = Scene::with_defaults("square", square_with_diagonal(0.1, true, 1.5));
    s.vertex_forces.push(VertexInput {
        name: "tip".into(),
        vertex: VertexId(2),
    });
    s
}

/// The square with self-contact on (contact outputs, extra matrix pairs).
pub fn contact_square() -> Scene {
    let mut s = square();
    s.name = "contact_square".into();
    s.contact = Some(origami_fmu::contact::ContactSettings {
        thickness: 5e-4,
        ..Default::default()
    });
    s
}

/// Log lines captured by the test logger: (status, category, format,
/// message).
pub type Log = Mutex<Vec<(fmi2Status, String, String, String)>>;

/// The test logger. A C-variadic function cannot be defined in stable
/// Rust; this one takes the single string argument that the FMU always
/// passes after its "%s" format, which is how the C calling convention of
/// x86-64 and aarch64 Linux delivers it.
unsafe extern "C" fn logger(
    env: *mut c_void,
    _name: *const c_char,
    status: fmi2Status,
    category: *const c_char,
    format: *const c_char,
    message: *const c_char,
) {
    // SAFETY: env is the Log of `callbacks`, alive while the instance is;
    // the strings are NUL-terminated by the FMU.
    let log = unsafe { &*(env as *const Log) };
    let s = |p: *const c_char| unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned();
    log.lock()
        .unwrap()
        .push((status, s(category), s(format), s(message)));
}

/// Callbacks that log into `log`.
pub fn callbacks(log: &Log) -> fmi2CallbackFunctions {
    type Variadic = unsafe extern "C" fn(
        fmi2ComponentEnvironment,
        fmi2String,
        fmi2Status,
        fmi2String,
        fmi2String,
        ...
    );
    // SAFETY: see `logger`.
    #[allow(clippy::missing_transmute_annotations)]
    let f: Variadic = unsafe { std::mem::transmute(logger as *const ()) };
    fmi2CallbackFunctions {
        logger: Some(f),
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: log as *const Log as *mut c_void,
    }
}

/// A resources folder with `scene`; returns (resource URI, GUID).
pub fn resources(tag: &str, scene: &Scene) -> (String, String) {
    let bytes = scene_bytes(scene);
    let dir: PathBuf = std::env::temp_dir().join(format!(
        "origami_fmu_host_{}_{tag}/resources",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(SCENE_FILE), &bytes).unwrap();
    (file_uri(&dir), guid(&bytes))
}

/// One instance with its log; freed on drop.
pub struct Fmu {
    pub c: fmi2Component,
    pub log: Box<Log>,
    /// Number of parameters, inputs and outputs (value references follow).
    pub counts: (usize, usize, usize),
}

impl Fmu {
    /// An instance of `scene` with `loggingOn` (every category logged).
    pub fn of(tag: &str, scene: &Scene) -> Fmu {
        let (uri, g) = resources(tag, scene);
        let log: Box<Log> = Box::default();
        let cb = callbacks(&log);
        let name = CString::new(tag).unwrap();
        let (g, uri) = (CString::new(g).unwrap(), CString::new(uri).unwrap());
        // SAFETY: valid strings and callbacks; the log outlives the instance.
        let c = unsafe { fmi2Instantiate(name.as_ptr(), 1, g.as_ptr(), uri.as_ptr(), &cb, 0, 1) };
        assert!(!c.is_null(), "{:?}", log.lock().unwrap());
        let m = Model::new(scene.clone()).unwrap();
        let counts = (m.parameters().len(), m.inputs().len(), m.outputs().len());
        Fmu { c, log, counts }
    }

    /// Setup, enter and exit initialization mode (all fmi2OK).
    pub fn initialize(&self) {
        // SAFETY: a live instance.
        unsafe {
            assert_eq!(fmi2SetupExperiment(self.c, 0, 0.0, 0.0, 0, 0.0), fmi2OK);
            assert_eq!(fmi2EnterInitializationMode(self.c), fmi2OK);
            assert_eq!(
                fmi2ExitInitializationMode(self.c),
                fmi2OK,
                "{}",
                self.last()
            );
        }
    }

    /// Value references of the parameters, inputs and outputs.
    pub fn vrs(&self) -> (Vec<u32>, Vec<u32>, Vec<u32>) {
        let (p, i, o) = self.counts;
        let r = |a: usize, b: usize| (a as u32..b as u32).collect::<Vec<_>>();
        (r(0, p), r(p, p + i), r(p + i, p + i + o))
    }

    /// fmi2GetReal of `vrs`: (status, values).
    pub fn get(&self, vrs: &[u32]) -> (fmi2Status, Vec<f64>) {
        let mut v = vec![0.0; vrs.len()];
        // SAFETY: arrays of vrs.len() elements.
        let s = unsafe { fmi2GetReal(self.c, vrs.as_ptr(), vrs.len(), v.as_mut_ptr()) };
        (s, v)
    }

    /// Every output (asserting fmi2OK).
    pub fn outputs(&self) -> Vec<f64> {
        let (s, v) = self.get(&self.vrs().2);
        assert_eq!(s, fmi2OK, "{}", self.last());
        v
    }

    /// fmi2SetReal.
    pub fn set(&self, vrs: &[u32], values: &[f64]) -> fmi2Status {
        // SAFETY: arrays of vrs.len() elements.
        unsafe { fmi2SetReal(self.c, vrs.as_ptr(), vrs.len(), values.as_ptr()) }
    }

    /// fmi2DoStep.
    pub fn step(&self, t: f64, h: f64) -> fmi2Status {
        // SAFETY: a live instance.
        unsafe { fmi2DoStep(self.c, t, h, 0) }
    }

    /// fmi2GetFMUstate into a new state.
    pub fn save(&self) -> fmi2FMUstate {
        let mut s: fmi2FMUstate = null_mut();
        // SAFETY: a live instance and a writable slot.
        assert_eq!(unsafe { fmi2GetFMUstate(self.c, &mut s) }, fmi2OK);
        s
    }

    /// The serialized bytes of state `s`.
    pub fn serialize(&self, s: fmi2FMUstate) -> Vec<u8> {
        let mut size = 0usize;
        // SAFETY: a live instance and a state of it; a buffer of `size`.
        unsafe {
            assert_eq!(fmi2SerializedFMUstateSize(self.c, s, &mut size), fmi2OK);
            let mut buf = vec![0u8; size];
            assert_eq!(
                fmi2SerializeFMUstate(self.c, s, buf.as_mut_ptr().cast(), size),
                fmi2OK
            );
            buf
        }
    }

    /// fmi2DeSerializeFMUstate of `bytes` into a new state: (status, state).
    pub fn deserialize(&self, bytes: &[u8]) -> (fmi2Status, fmi2FMUstate) {
        let mut s: fmi2FMUstate = null_mut();
        // SAFETY: `bytes.len()` readable bytes, a writable slot.
        let st =
            unsafe { fmi2DeSerializeFMUstate(self.c, bytes.as_ptr().cast(), bytes.len(), &mut s) };
        (st, s)
    }

    /// fmi2SetFMUstate.
    pub fn restore(&self, s: fmi2FMUstate) -> fmi2Status {
        // SAFETY: a live instance; `s` is checked by the FMU.
        unsafe { fmi2SetFMUstate(self.c, s) }
    }

    /// fmi2FreeFMUstate (asserting fmi2OK).
    pub fn free_state(&self, mut s: fmi2FMUstate) {
        // SAFETY: a live instance and a state of it.
        assert_eq!(unsafe { fmi2FreeFMUstate(self.c, &mut s) }, fmi2OK);
        assert!(s.is_null());
    }

    /// The last message logged ("" when none).
    pub fn last(&self) -> String {
        let log = self.log.lock().unwrap();
        log.last().map(|l| l.3.clone()).unwrap_or_default()
    }

    /// Number of lines logged with `status`.
    pub fn count(&self, status: fmi2Status) -> usize {
        let log = self.log.lock().unwrap();
        log.iter().filter(|l| l.0 == status).count()
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        // SAFETY: the instance is freed once, here.
        unsafe { fmi2FreeInstance(self.c) };
    }
}
