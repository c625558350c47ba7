//! One FMU instance: the FMI 2.0 co-simulation state machine around a
//! [`Model`], the value-reference map, the logger, and saved FMU states.
//!
//! Everything here is safe Rust on Rust slices; `exports.rs` turns the C
//! pointers into those slices through `ptr.rs`. Each method returns the
//! FMI status and logs the reason of anything that is not `fmi2OK`.
//!
//! Value references are contiguous: parameters `0..P`, inputs `P..P+I`,
//! outputs `P+I..P+I+O`, each block in the order of the Model's tables.
//!
//! A rejected call (bad argument, wrong order) changes nothing and leaves
//! the instance in the phase it was in, so the master may go on. A step the
//! solver cannot complete moves it to [`InstancePhase::StepFailed`] (state rolled
//! back, `fmi2Terminated` true), from which `fmi2SetFMUstate` retries. Only a
//! failure inside the model that leaves no consistent state (initialization
//! failed) moves it to [`InstancePhase::Error`], from which
//! `fmi2SetFMUstate` or `fmi2Reset` recover. A panic kills the instance.

mod error;

pub use error::InstanceError;

use super::container;
use super::ptr;
use super::resources::{self, SCENE_FILE};
use super::types::{Fmi2Type, StatusKind, fmi2CallbackFunctions, fmi2Status};
use crate::model::{Error as ModelError, InputId, Model, ModelState, OutputId, ParameterId};
use crate::scene::Scene;
use crate::text::num;
use serde::{Deserialize, Serialize};
use std::collections::HashSet;
use std::ffi::CString;
use std::sync::atomic::{AtomicUsize, Ordering};

use fmi2Status::*;

/// Phase of the FMI 2.0 co-simulation state machine (the model has its own,
/// coarser [`crate::model::Phase`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum InstancePhase {
    /// After `fmi2Instantiate` (and `fmi2Reset`): parameters, inputs, setup.
    Instantiated,
    /// Between `fmi2EnterInitializationMode` and `fmi2ExitInitializationMode`.
    InitializationMode,
    /// Ready for `fmi2DoStep`.
    StepComplete,
    /// After `fmi2DoStep` returned `fmi2Discard`: the state is rolled back to
    /// the start of that step and `fmi2Terminated` is true. Values may be
    /// read; `fmi2SetFMUstate` (to retry, e.g. with a smaller step),
    /// `fmi2Terminate`, `fmi2Reset` or free. FMI 2.0 section 4.2.4.
    StepFailed,
    /// After `fmi2Terminate`: values may be read; reset or free.
    Terminated,
    /// The model failed in a way that left no usable state: read values for
    /// debugging, `fmi2SetFMUstate`, `fmi2Reset` or free.
    Error,
}

impl InstancePhase {
    /// Human name used in log lines.
    pub fn name(self) -> &'static str {
        match self {
            InstancePhase::Instantiated => "instantiated",
            InstancePhase::InitializationMode => "initialization mode",
            InstancePhase::StepComplete => "step complete",
            InstancePhase::StepFailed => "step failed",
            InstancePhase::Terminated => "terminated",
            InstancePhase::Error => "error",
        }
    }
}

/// Log categories (declared in modelDescription.xml). The logger is only
/// called for enabled categories (FMI 2.0 section 2.1.5): with `loggingOn`
/// at instantiation all of them, without it `logStatusDiscard`,
/// `logStatusError` and `logStatusFatal` (so that a failed call or step says
/// why);
/// `fmi2SetDebugLogging` changes the selection.
pub const LOG_CATEGORIES: [(&str, &str); 5] = [
    (
        "logEvents",
        "Life-cycle events and a line per communication step",
    ),
    (
        "logStatusWarning",
        "Calls that returned fmi2Warning, and what a step noticed (the chord error of the contact surface past the thickness)",
    ),
    (
        "logStatusDiscard",
        "Steps that returned fmi2Discard (state rolled back)",
    ),
    (
        "logStatusError",
        "Calls that returned fmi2Error, with the reason",
    ),
    ("logStatusFatal", "Calls that returned fmi2Fatal"),
];

/// The host's logger, copied at instantiation, with the enabled categories.
pub struct Logger {
    callbacks: fmi2CallbackFunctions,
    instance_name: CString,
    /// Enabled `logEvents` etc. (indices into [`LOG_CATEGORIES`]).
    enabled: [bool; LOG_CATEGORIES.len()],
}

impl Logger {
    /// A logger for instance `name` with the host's callbacks.
    pub fn new(callbacks: fmi2CallbackFunctions, name: &str, logging_on: bool) -> Logger {
        // logEvents, logStatusWarning: debug output; logStatusDiscard,
        // logStatusError, logStatusFatal: on unless switched off (a master
        // that ends a run at a discard would otherwise end it silently).
        let enabled = [logging_on, logging_on, true, true, true];
        Logger {
            callbacks,
            instance_name: c_string(name),
            enabled,
        }
    }

    fn category(status: fmi2Status) -> usize {
        match status {
            fmi2OK | fmi2Pending => 0,
            fmi2Warning => 1,
            fmi2Discard => 2,
            fmi2Error => 3,
            fmi2Fatal => 4,
        }
    }

    /// Log `msg` with `status` under its category (`logEvents` for
    /// `fmi2OK`), only when that category is enabled.
    pub fn log(&self, status: fmi2Status, msg: &str) {
        let category = Self::category(status);
        if !self.enabled[category] {
            return;
        }
        if self.callbacks.logger.is_none() {
            return;
        }
        ptr::call_logger(
            &self.callbacks,
            &self.instance_name,
            status,
            &c_string(LOG_CATEGORIES[category].0),
            &c_string(msg),
        );
    }

    /// True when `fmi2OK` (debug) messages go out: build them only then.
    pub fn debug_enabled(&self) -> bool {
        self.enabled[0] && self.callbacks.logger.is_some()
    }

    /// Whether `logStatusWarning` reaches the host's logger.
    pub fn warnings_enabled(&self) -> bool {
        self.enabled[1] && self.callbacks.logger.is_some()
    }

    /// `fmi2SetDebugLogging` (FMI 2.0 section 2.1.5): with `on` and no
    /// categories, every category; with `on` and categories, exactly those;
    /// without `on`, none (no categories) or all but those listed stay as
    /// they were. Unknown names are an error and change nothing.
    pub fn set_debug_logging(&mut self, on: bool, categories: &[String]) -> fmi2Status {
        let mut listed = [false; LOG_CATEGORIES.len()];
        for c in categories {
            match LOG_CATEGORIES.iter().position(|(n, _)| n == c) {
                Some(k) => listed[k] = true,
                None => {
                    let known: Vec<&str> = LOG_CATEGORIES.iter().map(|c| c.0).collect();
                    self.log(
                        fmi2Error,
                        &format!(
                            "fmi2SetDebugLogging: unknown log category {c:?}; known: {}",
                            known.join(", ")
                        ),
                    );
                    return fmi2Error;
                }
            }
        }
        if categories.is_empty() {
            self.enabled = [on; LOG_CATEGORIES.len()];
        } else if on {
            self.enabled = listed;
        } else {
            for (e, l) in self.enabled.iter_mut().zip(listed) {
                *e &= !l;
            }
        }
        fmi2OK
    }
}

fn c_string(s: &str) -> CString {
    CString::new(s.replace('\0', "\\0")).expect("NULs replaced")
}

/// Which variable a value reference designates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VarRef {
    /// A parameter.
    Parameter(ParameterId),
    /// An input.
    Input(InputId),
    /// An output.
    Output(OutputId),
}

/// A saved FMU state: the model state plus what the FMI layer adds. This
/// is what `fmi2SerializeFMUstate` writes (as JSON).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SavedState {
    /// GUID of the FMU that saved it (checked on restore).
    pub guid: String,
    /// Phase of the state machine.
    pub phase: InstancePhase,
    /// Start time from `fmi2SetupExperiment`.
    pub start_time: f64,
    /// Stop time from `fmi2SetupExperiment`, if defined.
    pub stop_time: Option<f64>,
    /// The model's complete state.
    pub model: ModelState,
}

/// The phases in which inputs (and, before initialization ends,
/// parameters) may be set: FMI 2.0 allows neither after a failed step.
const SETTABLE: &[InstancePhase] = &[
    InstancePhase::Instantiated,
    InstancePhase::InitializationMode,
    InstancePhase::StepComplete,
];

/// Relative tolerance with which `currentCommunicationPoint` must match
/// the FMU's time in `fmi2DoStep`.
pub const TIME_TOLERANCE: f64 = 1e-9;

// Hosts may create an instance on one thread and use it on another (never
// two at once): what the instance owns besides the host's pointers must be
// Send. This fails to compile if the Model ever stops being Send.
const _: () = {
    const fn assert_send<T: Send>() {}
    assert_send::<Model>();
    assert_send::<Scene>();
};

/// The magic number of a live [`Instance`] ("origami0"), checked on every
/// call and cleared by `fmi2FreeInstance` (see `ptr.rs`).
pub const INSTANCE_MAGIC: u64 = 0x6f72_6967_616d_6930;

/// The magic number of a live [`FmuState`] ("origami1").
pub const STATE_MAGIC: u64 = 0x6f72_6967_616d_6931;

/// What an `fmi2FMUstate` points to: a saved state behind a magic number,
/// so that a foreign or freed pointer is (usually) detected.
#[repr(C)]
pub struct FmuState {
    /// [`STATE_MAGIC`] while alive; first, where `ptr.rs` reads it.
    pub(super) magic: u64,
    /// The state.
    pub state: SavedState,
}

/// Number of [`FmuState`]s alive in the process.
static LIVE_STATES: AtomicUsize = AtomicUsize::new(0);

/// How many FMU states are alive in the process (created by
/// `fmi2GetFMUstate` or `fmi2DeSerializeFMUstate` and not yet freed): what
/// the tests of freeing count.
pub fn live_states() -> usize {
    LIVE_STATES.load(Ordering::Relaxed)
}

impl FmuState {
    /// A live saved state.
    pub fn new(state: SavedState) -> FmuState {
        LIVE_STATES.fetch_add(1, Ordering::Relaxed);
        FmuState {
            magic: STATE_MAGIC,
            state,
        }
    }
}

impl Drop for FmuState {
    fn drop(&mut self) {
        LIVE_STATES.fetch_sub(1, Ordering::Relaxed);
    }
}

/// One FMU instance (`#[repr(C)]`: the magic number comes first).
#[repr(C)]
pub struct Instance {
    /// [`INSTANCE_MAGIC`] while alive; first, where `ptr.rs` reads it.
    pub(super) magic: u64,
    /// Logger and debug settings.
    pub log: Logger,
    /// Set after a panic: every later call but `fmi2FreeInstance` fails.
    pub dead: bool,
    guid: String,
    model: Model,
    /// The model's state right after instantiation (what `fmi2Reset` restores).
    initial: ModelState,
    phase: InstancePhase,
    start_time: f64,
    stop_time: Option<f64>,
    n_par: usize,
    n_in: usize,
    n_out: usize,
    /// Addresses of the `fmi2FMUstate`s this instance created and has not
    /// freed: `fmi2FreeInstance` frees them (also after a panic).
    states: HashSet<usize>,
    /// The chord error past the thickness was logged (once an instance).
    chord_logged: bool,
}

impl Instance {
    /// `fmi2Instantiate`: check the FMU type, read and validate the scene
    /// from the resource location, check the GUID, build the model. On
    /// failure the reason has been logged and `None` is returned.
    pub fn instantiate(
        log: Logger,
        fmu_type: i32,
        guid: Option<&str>,
        resource_location: Option<&str>,
    ) -> Option<Instance> {
        match Self::try_instantiate(&log, fmu_type, guid, resource_location) {
            Ok((guid, scene, model)) => {
                let initial = model.save_state();
                let (n_par, n_in, n_out) = (
                    model.parameters().len(),
                    model.inputs().len(),
                    model.outputs().len(),
                );
                log.log(
                    fmi2OK,
                    &format!(
                        "fmi2Instantiate: scene {:?}: {n_par} parameters, {n_in} inputs, {n_out} outputs",
                        scene.name
                    ),
                );
                Some(Instance {
                    magic: INSTANCE_MAGIC,
                    log,
                    dead: false,
                    guid,
                    model,
                    initial,
                    phase: InstancePhase::Instantiated,
                    start_time: 0.0,
                    stop_time: None,
                    n_par,
                    n_in,
                    n_out,
                    states: HashSet::new(),
                    chord_logged: false,
                })
            }
            Err(msg) => {
                log.log(fmi2Error, &format!("fmi2Instantiate failed: {msg}"));
                None
            }
        }
    }

    fn try_instantiate(
        _log: &Logger,
        fmu_type: i32,
        guid: Option<&str>,
        resource_location: Option<&str>,
    ) -> Result<(String, Scene, Model), InstanceError> {
        match Fmi2Type::from_c(fmu_type) {
            Some(Fmi2Type::CoSimulation) => {}
            Some(Fmi2Type::ModelExchange) => return Err(InstanceError::ModelExchange),
            None => return Err(InstanceError::BadFmuType(fmu_type)),
        }
        let guid = guid.ok_or(InstanceError::NullGuid)?;
        let uri = resource_location.ok_or(InstanceError::NullResourceLocation)?;
        let dir = resources::resource_dir_from_uri(uri).map_err(InstanceError::ResourceLocation)?;
        let path = dir.join(SCENE_FILE);
        let bytes = match std::fs::read(&path) {
            Ok(b) => b,
            Err(source) => return Err(InstanceError::ReadScene { path, source }),
        };
        // Validate before the GUID so that a broken scene reports why.
        let scene = match resources::parse_scene(&bytes) {
            Ok(s) => s,
            Err(source) => return Err(InstanceError::InvalidScene { path, source }),
        };
        let expected = resources::guid(&bytes);
        if guid != expected {
            return Err(InstanceError::GuidMismatch {
                host: guid.into(),
                path,
                expected,
            });
        }
        let model = Model::new(scene.clone()).map_err(InstanceError::Model)?;
        resources::check_variable_names(&model).map_err(InstanceError::VariableNames)?;
        Ok((expected, scene, model))
    }

    /// The model (read-only).
    pub fn model(&self) -> &Model {
        &self.model
    }
    /// Current phase.
    pub fn phase(&self) -> InstancePhase {
        self.phase
    }

    fn error(&self, msg: impl AsRef<str>) -> fmi2Status {
        self.log.log(fmi2Error, msg.as_ref());
        fmi2Error
    }

    /// Reject a call outside the phases it is allowed in.
    fn require(&self, function: &str, allowed: &[InstancePhase]) -> Result<(), fmi2Status> {
        if allowed.contains(&self.phase) {
            return Ok(());
        }
        let hint = match self.phase {
            InstancePhase::Instantiated => {
                "; call fmi2EnterInitializationMode and fmi2ExitInitializationMode first"
            }
            InstancePhase::InitializationMode => "; call fmi2ExitInitializationMode first",
            InstancePhase::Terminated => "; the instance is terminated (fmi2Reset to start again)",
            InstancePhase::Error => {
                "; the instance is in the error state (fmi2SetFMUstate or fmi2Reset)"
            }
            InstancePhase::StepFailed => {
                "; the last fmi2DoStep was discarded (fmi2SetFMUstate to a saved state to retry, \
                 fmi2Terminate or fmi2Reset)"
            }
            InstancePhase::StepComplete => "",
        };
        let allowed: Vec<&str> = allowed.iter().map(|p| p.name()).collect();
        Err(self.error(format!(
            "{function} is not allowed in state '{}' (only in: {}){hint}",
            self.phase.name(),
            allowed.join(", ")
        )))
    }

    /// Map a value reference to a variable.
    pub fn resolve(&self, vr: u32) -> Option<VarRef> {
        let vr = vr as usize;
        if vr < self.n_par {
            self.model.parameter_at(vr).map(VarRef::Parameter)
        } else if vr < self.n_par + self.n_in {
            self.model.input_at(vr - self.n_par).map(VarRef::Input)
        } else {
            self.model
                .output_at(vr - self.n_par - self.n_in)
                .map(VarRef::Output)
        }
    }

    fn var_name(&self, r: VarRef) -> &str {
        match r {
            VarRef::Parameter(i) => &self.model.parameters()[i.index()].name,
            VarRef::Input(i) => &self.model.inputs()[i.index()].name,
            VarRef::Output(i) => &self.model.outputs()[i.index()].name,
        }
    }

    /// `fmi2SetupExperiment`: record start and stop time; a defined
    /// tolerance sets `solver.tolerance` (see `experiment_tolerance`).
    pub fn setup_experiment(
        &mut self,
        tolerance: Option<f64>,
        start: f64,
        stop: Option<f64>,
    ) -> fmi2Status {
        if let Err(s) = self.require("fmi2SetupExperiment", &[InstancePhase::Instantiated]) {
            return s;
        }
        if !start.is_finite() {
            return self.error(format!(
                "fmi2SetupExperiment: startTime {} is not finite",
                num(start)
            ));
        }
        if let Some(stop) = stop
            && !(stop.is_finite() && stop >= start)
        {
            return self.error(format!(
                "fmi2SetupExperiment: stopTime {} must be finite and >= startTime {}",
                num(stop),
                num(start)
            ));
        }
        self.start_time = start;
        self.stop_time = stop;
        match tolerance {
            Some(tol) => self.experiment_tolerance(tol),
            None => fmi2OK,
        }
    }

    /// A tolerance from `fmi2SetupExperiment` becomes `solver.tolerance`,
    /// unless the master set that parameter to another value than its
    /// start (an explicit parameter wins, in either order: one set later
    /// simply overwrites). An out-of-range tolerance is not used
    /// (`fmi2Warning`, with the reason logged).
    fn experiment_tolerance(&mut self, tol: f64) -> fmi2Status {
        let Some(i) = self.model.parameter_id("solver.tolerance") else {
            return fmi2OK;
        };
        let start = self.model.parameters()[i.index()].start;
        let now = self.model.parameter(i).unwrap_or(start);
        if now != start {
            self.log.log(
                fmi2OK,
                &format!(
                    "fmi2SetupExperiment: tolerance {} not used: the parameter solver.tolerance was set to {}",
                    num(tol),
                    num(now)
                ),
            );
            return fmi2OK;
        }
        match self.model.set_parameter(i, tol) {
            Ok(()) => {
                self.log.log(
                    fmi2OK,
                    &format!(
                        "fmi2SetupExperiment: solver.tolerance = {} (the experiment's tolerance)",
                        num(tol)
                    ),
                );
                fmi2OK
            }
            Err(e) => {
                self.log.log(
                    fmi2Warning,
                    &format!("fmi2SetupExperiment: tolerance not used: {e}"),
                );
                fmi2Warning
            }
        }
    }

    /// `fmi2EnterInitializationMode`.
    pub fn enter_initialization_mode(&mut self) -> fmi2Status {
        if let Err(s) = self.require(
            "fmi2EnterInitializationMode",
            &[InstancePhase::Instantiated],
        ) {
            return s;
        }
        self.phase = InstancePhase::InitializationMode;
        fmi2OK
    }

    /// `fmi2ExitInitializationMode`: the model computes its initial state
    /// at the start time.
    pub fn exit_initialization_mode(&mut self) -> fmi2Status {
        if let Err(s) = self.require(
            "fmi2ExitInitializationMode",
            &[InstancePhase::InitializationMode],
        ) {
            return s;
        }
        let r =
            set_model_time(&mut self.model, self.start_time).and_then(|_| self.model.initialize());
        match r {
            Ok(()) => {
                self.phase = InstancePhase::StepComplete;
                self.log
                    .log(fmi2OK, &format!("initialized at t = {}", self.model.time()));
                fmi2OK
            }
            Err(e) => {
                self.phase = InstancePhase::Error;
                self.error(format!(
                    "fmi2ExitInitializationMode: the model failed to initialize: {e}"
                ))
            }
        }
    }

    /// `fmi2Terminate`.
    pub fn terminate(&mut self) -> fmi2Status {
        if let Err(s) = self.require(
            "fmi2Terminate",
            &[
                InstancePhase::StepComplete,
                InstancePhase::StepFailed,
                InstancePhase::Error,
            ],
        ) {
            return s;
        }
        self.phase = InstancePhase::Terminated;
        fmi2OK
    }

    /// `fmi2Reset`: back to the freshly instantiated model of the scene
    /// (its saved initial state: the scene is not read or built again).
    pub fn reset(&mut self) -> fmi2Status {
        match self.model.restore_state(&self.initial) {
            Ok(()) => {
                self.phase = InstancePhase::Instantiated;
                self.start_time = 0.0;
                self.stop_time = None;
                fmi2OK
            }
            Err(e) => {
                self.phase = InstancePhase::Error;
                self.error(format!("fmi2Reset: {e}"))
            }
        }
    }

    /// `fmi2GetReal`: parameters and inputs as set, outputs at the current
    /// time. Never hands out a non-finite value (that is an fmi2Error).
    pub fn get_real(&mut self, vrs: &[u32], values: &mut [f64]) -> fmi2Status {
        let mut refs = Vec::with_capacity(vrs.len());
        for &vr in vrs {
            match self.resolve(vr) {
                Some(r) => refs.push(r),
                None => {
                    return self.error(format!(
                        "fmi2GetReal: no Real variable with value reference {vr}"
                    ));
                }
            }
        }
        for (k, r) in refs.into_iter().enumerate() {
            let v = match r {
                VarRef::Parameter(i) => self.model.parameter(i).map_err(|e| e.to_string()),
                VarRef::Input(i) => self.model.input(i).map_err(|e| e.to_string()),
                VarRef::Output(i) => self.model.output(i).map_err(|e| e.to_string()),
            };
            match v {
                Ok(x) if x.is_finite() => values[k] = x,
                Ok(x) => {
                    return self.error(format!(
                        "fmi2GetReal: {} is {} at t = {}; the model state is broken",
                        self.var_name(r),
                        num(x),
                        num(self.model.time())
                    ));
                }
                Err(e) => return self.error(format!("fmi2GetReal: {e}")),
            }
        }
        fmi2OK
    }

    /// `fmi2SetReal`: all values are checked before any is applied; on any
    /// problem nothing changes. Parameters (variability fixed) only before
    /// `fmi2ExitInitializationMode`; outputs never.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> fmi2Status {
        if let Err(s) = self.require("fmi2SetReal", SETTABLE) {
            return s;
        }
        let mut refs = Vec::with_capacity(vrs.len());
        for (&vr, &v) in vrs.iter().zip(values) {
            let Some(r) = self.resolve(vr) else {
                return self.error(format!(
                    "fmi2SetReal: no Real variable with value reference {vr}"
                ));
            };
            match r {
                VarRef::Output(_) => {
                    return self.error(format!(
                        "fmi2SetReal: {} (value reference {vr}) is an output and cannot be set",
                        self.var_name(r)
                    ));
                }
                VarRef::Parameter(_) if self.phase == InstancePhase::StepComplete => {
                    return self.error(format!(
                        "fmi2SetReal: {} (value reference {vr}) is a fixed parameter; it can only be set \
                         before fmi2ExitInitializationMode",
                        self.var_name(r)
                    ));
                }
                _ => {}
            }
            if !v.is_finite() {
                return self.error(format!(
                    "fmi2SetReal: {} = {} is not a finite number; nothing was changed",
                    self.var_name(r),
                    num(v)
                ));
            }
            refs.push(r);
        }
        // Apply; should the model reject one (range checks), undo the rest.
        let mut undo: Vec<(VarRef, f64)> = Vec::with_capacity(refs.len());
        for (r, &v) in refs.iter().zip(values) {
            let old = match *r {
                VarRef::Parameter(i) => self.model.parameter(i),
                VarRef::Input(i) => self.model.input(i),
                VarRef::Output(_) => unreachable!("rejected above"),
            };
            let old = match old {
                Ok(o) => o,
                Err(e) => return self.error(format!("fmi2SetReal: {e}")),
            };
            let applied = match *r {
                VarRef::Parameter(i) => self.model.set_parameter(i, v),
                VarRef::Input(i) => self.model.set_input(i, v),
                VarRef::Output(_) => unreachable!(),
            };
            if let Err(e) = applied {
                for (r, old) in undo.into_iter().rev() {
                    // Restoring a value the model accepted before cannot fail.
                    let _ = match r {
                        VarRef::Parameter(i) => self.model.set_parameter(i, old),
                        VarRef::Input(i) => self.model.set_input(i, old),
                        VarRef::Output(_) => Ok(()),
                    };
                }
                return self.error(format!("fmi2SetReal: {e}; nothing was changed"));
            }
            undo.push((*r, old));
        }
        fmi2OK
    }

    /// `fmi2SetRealInputDerivatives`: first and second derivatives of
    /// inputs (all checked before any is applied). A derivative applies from the current
    /// communication point until it or the input's value is set again.
    pub fn set_input_derivatives(
        &mut self,
        vrs: &[u32],
        orders: &[i32],
        values: &[f64],
    ) -> fmi2Status {
        const F: &str = "fmi2SetRealInputDerivatives";
        if let Err(s) = self.require(F, SETTABLE) {
            return s;
        }
        let mut inputs = Vec::with_capacity(vrs.len());
        for (&vr, &order) in vrs.iter().zip(orders) {
            let i = match self.resolve(vr) {
                Some(VarRef::Input(i)) => i,
                Some(r) => {
                    return self.error(format!(
                        "{F}: {} (value reference {vr}) is not an input",
                        self.var_name(r)
                    ));
                }
                None => {
                    return self.error(format!("{F}: no Real variable with value reference {vr}"));
                }
            };
            if !(1..=2).contains(&order) {
                return self.error(format!(
                    "{F}: order {order} for {}: this FMU takes first and second derivatives \
                     (order 1 or 2); nothing was changed",
                    self.var_name(VarRef::Input(i))
                ));
            }
            inputs.push((i, order));
        }
        if let Some((&(i, _), &v)) = inputs.iter().zip(values).find(|(_, v)| !v.is_finite()) {
            return self.error(format!(
                "{F}: the derivative of {} = {} is not a finite number; nothing was changed",
                self.var_name(VarRef::Input(i)),
                num(v)
            ));
        }
        for (&(i, order), &v) in inputs.iter().zip(values) {
            // Finite values fail only for a reason shared by every input
            // (ramped inputs), so nothing has been applied when one fails.
            if let Err(e) = self.model.set_input_derivative(i, order, v) {
                return self.error(format!("{F}: {e}; nothing was changed"));
            }
        }
        fmi2OK
    }

    /// After a step, once an instance: a warning naming the facets where
    /// the curved surface lies farther than the contact thickness from the
    /// sampled surface that contact keeps apart (`contact.chord_error`).
    fn log_chord_error(&mut self) {
        if self.chord_logged || !self.log.warnings_enabled() {
            return;
        }
        let Some((worst, facets)) = self.model.chord_error() else {
            return;
        };
        if facets.is_empty() {
            return;
        }
        self.chord_logged = true;
        let shown: Vec<String> = facets.iter().take(20).map(|f| f.to_string()).collect();
        let more = if facets.len() > 20 {
            format!(" and {} more", facets.len() - 20)
        } else {
            String::new()
        };
        self.log.log(
            fmi2Warning,
            &format!(
                "t = {}: contact.chord_error {} m is past the contact thickness on facets {}{more}: \
                 contact keeps their sampled surface apart, and the curved facets may cross \
                 between its samples; raise ancf:contact subdivisions or refine the mesh",
                num(self.model.time()),
                num(worst),
                shown.join(", ")
            ),
        );
    }

    /// `fmi2DoStep`: advance from `t` (which must be the FMU's time) by
    /// `h`, not past the stop time. On a solver failure the state is rolled
    /// back, the result is `fmi2Discard` and the instance is in "step
    /// failed" (`fmi2Terminated` true): a master retries through
    /// `fmi2SetFMUstate`, and none can loop on the same failing step.
    pub fn do_step(&mut self, t: f64, h: f64) -> fmi2Status {
        if let Err(s) = self.require("fmi2DoStep", &[InstancePhase::StepComplete]) {
            return s;
        }
        if !(h.is_finite() && h > 0.0) {
            return self.error(format!(
                "fmi2DoStep: communicationStepSize {} must be a positive finite number",
                num(h)
            ));
        }
        let now = self.model.time();
        if !t.is_finite() || (t - now).abs() > TIME_TOLERANCE * now.abs().max(1.0) {
            return self.error(format!(
                "fmi2DoStep: currentCommunicationPoint {} does not match the FMU's time {}; \
                 use fmi2SetFMUstate to go back in time",
                num(t),
                num(now)
            ));
        }
        let target = t + h;
        if let Some(stop) = self.stop_time
            && target > stop + TIME_TOLERANCE * stop.abs().max(1.0)
        {
            return self.error(format!(
                "fmi2DoStep: the step from t = {} by {} ends at {}, after the stopTime {} \
                 set by fmi2SetupExperiment (FMI 2.0 section 2.1.6)",
                num(t),
                num(h),
                num(target),
                num(stop)
            ));
        }
        if let Err(e) = set_model_time(&mut self.model, t) {
            return self.error(format!("fmi2DoStep: {e}"));
        }
        match self.model.advance(h) {
            Ok(report) => {
                if let Err(e) = set_model_time(&mut self.model, target) {
                    self.phase = InstancePhase::Error;
                    return self.error(format!("fmi2DoStep: {e}"));
                }
                self.log_chord_error();
                if self.log.debug_enabled() {
                    self.log.log(
                    fmi2OK,
                    &format!(
                        "fmi2DoStep: t = {} + {}: {} internal steps ({} rejected), {} Newton iterations, smallest step {}",
                        num(t), num(h), report.steps, report.rejected, report.newton_iterations, num(report.min_step)
                    ),
                );
                }
                fmi2OK
            }
            Err(ModelError::StepFailed { time, reason }) => {
                self.phase = InstancePhase::StepFailed;
                self.log.log(
                    fmi2Discard,
                    &format!(
                        "fmi2DoStep: the step from t = {} by {} could not be completed (failed at t = {}: {reason}); \
                         the state is rolled back to t = {} (fmi2LastSuccessfulTime) and fmi2Terminated is true; \
                         to retry, restore a state saved at t with fmi2SetFMUstate and step again, \
                         e.g. with a smaller step",
                        num(t),
                        num(h),
                        num(time),
                        num(self.model.time())
                    ),
                );
                fmi2Discard
            }
            Err(e) => self.error(format!("fmi2DoStep: {e}")),
        }
    }

    /// `fmi2GetStatus` and friends: the value for `kind`, or the status to
    /// return (`fmi2Discard` for kinds this FMU does not provide).
    pub fn status_real(&self, kind: StatusKind) -> Result<f64, fmi2Status> {
        match kind {
            StatusKind::LastSuccessfulTime => Ok(self.model.time()),
            _ => Err(self.unsupported_status("fmi2GetRealStatus", kind)),
        }
    }

    /// `fmi2GetBooleanStatus`: only `fmi2Terminated`, true after a
    /// discarded step (the FMU cannot go on from there without a restore).
    pub fn status_boolean(&self, kind: StatusKind) -> Result<bool, fmi2Status> {
        match kind {
            StatusKind::Terminated => Ok(self.phase == InstancePhase::StepFailed),
            _ => Err(self.unsupported_status("fmi2GetBooleanStatus", kind)),
        }
    }

    /// `fmi2GetStatus`: only `fmi2DoStepStatus` (steps are synchronous,
    /// so the last step's status is final: fmi2OK).
    pub fn status(&self, kind: StatusKind) -> Result<fmi2Status, fmi2Status> {
        match kind {
            StatusKind::DoStepStatus => Ok(fmi2OK),
            _ => Err(self.unsupported_status("fmi2GetStatus", kind)),
        }
    }

    /// Log and return the status for a status kind a function does not offer.
    pub fn unsupported_status(&self, function: &str, kind: StatusKind) -> fmi2Status {
        self.log.log(
            fmi2Discard,
            &format!("{function}: status kind {kind:?} is not provided by this FMU (steps are synchronous)"),
        );
        fmi2Discard
    }

    /// Log and return `fmi2Error` for an unsupported function.
    pub fn unsupported(&self, function: &str, why: &str) -> fmi2Status {
        self.error(format!("{function} is not supported: {why}"))
    }

    /// `fmi2GetFMUstate`: a copy of everything needed to continue.
    pub fn save(&self) -> SavedState {
        SavedState {
            guid: self.guid.clone(),
            phase: self.phase,
            start_time: self.start_time,
            stop_time: self.stop_time,
            model: self.model.save_state(),
        }
    }

    /// `fmi2SetFMUstate`: restore a state saved by an instance of the same
    /// FMU, after checking every value it holds; on failure nothing changes.
    pub fn restore(&mut self, s: &SavedState) -> fmi2Status {
        if let Err(e) = self.check_saved(s) {
            return self.error(format!("fmi2SetFMUstate: {e}; nothing was changed"));
        }
        if let Err(e) = self.model.restore_state(&s.model) {
            return self.error(format!("fmi2SetFMUstate: {e}; nothing was changed"));
        }
        self.phase = s.phase;
        self.start_time = s.start_time;
        self.stop_time = s.stop_time;
        fmi2OK
    }

    /// Check a saved state against this instance: its FMU, times and
    /// phase, and every value of its model state
    /// ([`Model::check_state`]).
    fn check_saved(&self, s: &SavedState) -> Result<(), InstanceError> {
        if s.guid != self.guid {
            return Err(InstanceError::StateBytes(container::foreign(
                &s.guid, &self.guid,
            )));
        }
        let limit = |what: &'static str, x: f64| {
            crate::scene::limits::check_number(x)
                .map_err(|source| InstanceError::SavedTime { what, source })
        };
        limit("start_time", s.start_time)?;
        if let Some(stop) = s.stop_time {
            limit("stop_time", stop)?;
            if stop < s.start_time {
                return Err(InstanceError::StopBeforeStart {
                    stop,
                    start: s.start_time,
                });
            }
        }
        use crate::model::Phase;
        let fits = match s.phase {
            InstancePhase::Instantiated | InstancePhase::InitializationMode => {
                s.model.phase == Phase::Setup
            }
            InstancePhase::StepComplete | InstancePhase::StepFailed | InstancePhase::Terminated => {
                s.model.phase == Phase::Running
            }
            InstancePhase::Error => true,
        };
        if !fits {
            return Err(InstanceError::PhaseMismatch {
                phase: s.phase.name(),
                model_phase: s.model.phase,
            });
        }
        self.model
            .check_state(&s.model)
            .map_err(InstanceError::State)
    }

    /// The bytes of `fmi2SerializeFMUstate`: the state's JSON in the
    /// checksummed container of [`container`].
    pub fn serialize(s: &SavedState) -> Result<Vec<u8>, InstanceError> {
        let payload = serde_json::to_vec(s).map_err(InstanceError::Serialize)?;
        Ok(container::seal(&s.guid, &payload))
    }

    /// `fmi2DeSerializeFMUstate`: open the container, parse the state and
    /// check every value against this instance; the reason on failure.
    pub fn deserialize(&self, bytes: &[u8]) -> Result<SavedState, fmi2Status> {
        const F: &str = "fmi2DeSerializeFMUstate";
        let payload = container::open(&self.guid, bytes)
            .map_err(|e| self.error(format!("{F}: {e}; nothing was changed")))?;
        let s: SavedState = serde_json::from_slice(payload).map_err(|e| {
            self.error(format!(
                "{F}: the payload is not a state of this FMU ({e}); nothing was changed"
            ))
        })?;
        self.check_saved(&s)
            .map_err(|e| self.error(format!("{F}: {e}; nothing was changed")))?;
        Ok(s)
    }

    /// Record a state this instance created (freed with it at the latest).
    pub fn own_state(&mut self, address: usize) {
        self.states.insert(address);
    }

    /// Forget a state this instance created, before freeing it; false when
    /// it did not create it.
    pub fn disown_state(&mut self, address: usize) -> bool {
        self.states.remove(&address)
    }

    /// The states still alive, to be freed with the instance.
    pub fn take_states(&mut self) -> Vec<usize> {
        self.states.drain().collect()
    }
}

/// Put the model's clock at exactly `t` (so that communication points
/// never drift). Works through save/restore until the Model API has a
/// time setter; a no-op when the clock already reads `t`.
fn set_model_time(model: &mut Model, t: f64) -> Result<(), ModelError> {
    if model.time().to_bits() == t.to_bits() {
        return Ok(());
    }
    let mut s = model.save_state();
    s.time = t;
    model.restore_state(&s)
}
