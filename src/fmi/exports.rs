//! Every function of the FMI 2.0 standard, exported with its C name.
//!
//! Each body runs under [`guard`] (or `catch_unwind` directly for the
//! functions without an instance): a panic becomes `fmi2Fatal` plus a log
//! line and marks the instance dead; it never unwinds into the host. Every
//! pointer goes through the checked helpers of `ptr.rs`: a null,
//! misaligned or foreign argument (an instance or state handle without its
//! magic number) is rejected with `fmi2Error` before it is dereferenced.
//! The Model Exchange functions, directional derivatives, output
//! derivatives and `fmi2CancelStep` return `fmi2Error` with a log line.
#![allow(non_snake_case)]

use super::instance::{FmuState, Instance, Logger, SavedState};
use super::ptr::{self, Refused};
use super::types::*;
use std::ffi::c_int;
use std::panic::{AssertUnwindSafe, catch_unwind};

use fmi2Status::*;

fn panic_message(p: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic".into()
    }
}

/// Run `body` on the instance behind the host's handle `c`: handle check
/// (null, foreign or freed: `fmi2Error`), dead check, and `catch_unwind`
/// (a panic returns `fmi2Fatal`, logs, and kills the instance).
///
/// # Safety
/// `c` is null or an instance from `fmi2Instantiate`, not yet freed (the
/// magic number catches most violations) and not used by another thread
/// meanwhile.
pub unsafe fn guard(
    c: fmi2Component,
    function: &str,
    body: impl FnOnce(&mut Instance) -> fmi2Status,
) -> fmi2Status {
    // SAFETY: by the caller's contract.
    run(unsafe { ptr::handle::<Instance>(c) }, function, body)
}

/// [`guard`] in an exported function, whose `c` comes from the host. Only
/// the handle check is in the `unsafe` block, not `$body`.
macro_rules! guarded {
    ($c:ident, $function:expr, $body:expr) => {
        // SAFETY: by the FMI contract, a non-null fmi2Component is a
        // pointer returned by our fmi2Instantiate and not yet freed, and the
        // host never calls into one instance from two threads at once.
        run(unsafe { ptr::handle::<Instance>($c) }, $function, $body)
    };
}

/// The body of [`guard`] once the handle is checked.
fn run(
    inst: Result<&mut Instance, Refused>,
    function: &str,
    body: impl FnOnce(&mut Instance) -> fmi2Status,
) -> fmi2Status {
    run_with(inst, function, false, body)
}

/// [`run`], also on a dead instance when `dead_ok` (freeing what it owns).
fn run_with(
    inst: Result<&mut Instance, Refused>,
    function: &str,
    dead_ok: bool,
    body: impl FnOnce(&mut Instance) -> fmi2Status,
) -> fmi2Status {
    let Ok(inst) = inst else {
        return fmi2Error;
    };
    if inst.dead && !dead_ok {
        inst.log.log(
            fmi2Fatal,
            &format!("{function}: the instance is dead after an internal error; only fmi2FreeInstance is allowed"),
        );
        return fmi2Fatal;
    }
    match catch_unwind(AssertUnwindSafe(|| body(&mut *inst))) {
        Ok(s) => s,
        Err(p) => {
            let msg = panic_message(&*p);
            inst.dead = true;
            let _ = catch_unwind(AssertUnwindSafe(|| {
                inst.log.log(
                    fmi2Fatal,
                    &format!("{function}: internal error ({msg}); the instance is dead, free it"),
                )
            }));
            fmi2Fatal
        }
    }
}

/// Log why the pointer argument `what` of `function` was refused.
fn refused(inst: &Instance, function: &str, what: &str, why: Refused) -> fmi2Status {
    let msg = match why {
        Refused::Null => format!("{function}: {what} is NULL"),
        Refused::Invalid => {
            format!("{function}: {what} is not a valid pointer (misaligned, too long or not UTF-8)")
        }
    };
    inst.log.log(fmi2Error, &msg);
    fmi2Error
}

/// Log why an `fmi2FMUstate` was refused.
fn state_refused(inst: &Instance, function: &str, why: Refused) -> fmi2Status {
    match why {
        Refused::Null => refused(inst, function, "FMUstate", why),
        Refused::Invalid => {
            inst.log.log(
                fmi2Error,
                &format!("{function}: FMUstate was not created by this FMU or was freed"),
            );
            fmi2Error
        }
    }
}

/// An `fmi2FMUstate` as our state; `None` (and logged) when null or not ours.
///
/// # Safety
/// `s` is null or was returned by our fmi2GetFMUstate/fmi2DeSerializeFMUstate
/// and not freed (the magic number catches most violations).
unsafe fn state_arg<'a>(
    inst: &Instance,
    function: &str,
    s: fmi2FMUstate,
) -> Option<&'a mut FmuState> {
    // SAFETY: by the caller's contract.
    unsafe { ptr::handle::<FmuState>(s) }
        .map_err(|e| state_refused(inst, function, e))
        .ok()
}

/// Store `state` in the host's `*FMUstate`: a new state of this instance
/// when it is NULL, else in place of the state of ours it holds.
///
/// # Safety
/// `*slot` is null or a state from us, not freed.
unsafe fn store_state(
    inst: &mut Instance,
    function: &str,
    slot: &mut fmi2FMUstate,
    state: SavedState,
) -> fmi2Status {
    if slot.is_null() {
        *slot = ptr::into_handle(FmuState::new(state));
        inst.own_state(*slot as usize);
        return fmi2OK;
    }
    // SAFETY: by the caller's contract.
    match unsafe { state_arg(inst, function, *slot) } {
        Some(old) => {
            old.state = state;
            fmi2OK
        }
        None => fmi2Error,
    }
}

// ---------------------------------------------------------------------------
// Inquire platform and version, logging.

/// `fmi2GetTypesPlatform`: "default".
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetTypesPlatform() -> fmi2String {
    c"default".as_ptr()
}

/// `fmi2GetVersion`: "2.0".
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetVersion() -> fmi2String {
    c"2.0".as_ptr()
}

/// `fmi2SetDebugLogging`: switch debug (`logEvents`) messages on or off;
/// status messages (warnings, discards, errors) are always logged.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: fmi2Component,
    loggingOn: fmi2Boolean,
    nCategories: usize,
    categories: *const fmi2String,
) -> fmi2Status {
    guarded!(c, "fmi2SetDebugLogging", |inst| {
        // SAFETY: host contract: nCategories strings.
        let cats = match unsafe { ptr::slice_arg(categories, nCategories) } {
            Ok(cats) => cats,
            Err(e) => return refused(inst, "fmi2SetDebugLogging", "categories", e),
        };
        let mut names = Vec::with_capacity(cats.len());
        for &p in cats {
            // SAFETY: host contract: each is a C string.
            match unsafe { ptr::str_arg(p) } {
                Ok(s) => names.push(s.to_string()),
                Err(e) => return refused(inst, "fmi2SetDebugLogging", "a category", e),
            }
        }
        inst.log.set_debug_logging(loggingOn != FMI2_FALSE, &names)
    })
}

// ---------------------------------------------------------------------------
// Creation and destruction.

/// `fmi2Instantiate`: a co-simulation instance of the scene in the FMU's
/// resources, or NULL after logging why (wrong fmuType, GUID, resource
/// location, unreadable or invalid scene).
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Instantiate(
    instanceName: fmi2String,
    fmuType: c_int,
    fmuGUID: fmi2String,
    fmuResourceLocation: fmi2String,
    functions: *const fmi2CallbackFunctions,
    visible: fmi2Boolean,
    loggingOn: fmi2Boolean,
) -> fmi2Component {
    let _ = visible;
    // SAFETY: host contract: NULL or a valid struct; copied by value, the
    // host may free its struct.
    let Ok(callbacks) = (unsafe { ptr::in_arg(functions) }) else {
        return std::ptr::null_mut();
    };
    let r = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: host contract: NUL-terminated strings or NULL.
        let name = unsafe { ptr::str_arg(instanceName) }.unwrap_or("");
        let log = Logger::new(callbacks, name, loggingOn != FMI2_FALSE);
        if instanceName.is_null() || name.is_empty() {
            log.log(
                fmi2Error,
                "fmi2Instantiate failed: instanceName is NULL, empty or not UTF-8",
            );
            return std::ptr::null_mut();
        }
        // SAFETY: as above.
        let (guid, resources) = unsafe {
            (
                ptr::str_arg(fmuGUID).ok(),
                ptr::str_arg(fmuResourceLocation).ok(),
            )
        };
        match Instance::instantiate(log, fmuType, guid, resources) {
            Some(inst) => ptr::into_handle(inst),
            None => std::ptr::null_mut(),
        }
    }));
    match r {
        Ok(p) => p,
        Err(p) => {
            let msg = panic_message(&*p);
            let _ = catch_unwind(AssertUnwindSafe(|| {
                Logger::new(callbacks, "origami_fmu", true).log(
                    fmi2Fatal,
                    &format!("fmi2Instantiate: internal error ({msg})"),
                )
            }));
            std::ptr::null_mut()
        }
    }
}

/// `fmi2FreeInstance`: release the instance and every FMU state it
/// created that the host has not freed, also after a panic (NULL, and a
/// pointer that is detectably not a live instance of ours, are ignored).
///
/// # Safety
/// `c` is NULL or an instance from `fmi2Instantiate`, not freed before.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
    // SAFETY: host contract as above (the magic number, cleared here,
    // catches most second frees).
    if let Ok(mut b) = unsafe { ptr::free_handle::<Instance>(c) } {
        for address in b.take_states() {
            // SAFETY: the instance created this state and it was not freed
            // (freeing removes it from the instance's list).
            if let Ok(s) = unsafe { ptr::free_handle::<FmuState>(address as fmi2FMUstate) } {
                let _ = catch_unwind(AssertUnwindSafe(move || drop(s)));
            }
        }
        let _ = catch_unwind(AssertUnwindSafe(move || drop(b)));
    }
}

// ---------------------------------------------------------------------------
// Initialization, termination, reset.

/// `fmi2SetupExperiment`: start time (any), stop time (recorded); a defined
/// tolerance sets the parameter `solver.tolerance` unless the master set it.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: fmi2Component,
    toleranceDefined: fmi2Boolean,
    tolerance: fmi2Real,
    startTime: fmi2Real,
    stopTimeDefined: fmi2Boolean,
    stopTime: fmi2Real,
) -> fmi2Status {
    guarded!(c, "fmi2SetupExperiment", |inst| {
        inst.setup_experiment(
            (toleranceDefined != FMI2_FALSE).then_some(tolerance),
            startTime,
            (stopTimeDefined != FMI2_FALSE).then_some(stopTime),
        )
    })
}

/// `fmi2EnterInitializationMode`.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
    guarded!(c, "fmi2EnterInitializationMode", |i| {
        i.enter_initialization_mode()
    })
}

/// `fmi2ExitInitializationMode`: the model computes its initial state.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
    guarded!(c, "fmi2ExitInitializationMode", |i| {
        i.exit_initialization_mode()
    })
}

/// `fmi2Terminate`.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
    guarded!(c, "fmi2Terminate", |i| i.terminate())
}

/// `fmi2Reset`: back to the state right after `fmi2Instantiate`.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
    guarded!(c, "fmi2Reset", |i| i.reset())
}

// ---------------------------------------------------------------------------
// Getting and setting values.

/// `fmi2GetReal`: parameters, inputs and outputs by value reference.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Real,
) -> fmi2Status {
    guarded!(c, "fmi2GetReal", |inst| {
        // SAFETY: host contract: nvr elements each.
        let (vrs, values) =
            match unsafe { (ptr::slice_arg(vr, nvr), ptr::slice_arg_mut(value, nvr)) } {
                (Ok(vrs), Ok(values)) => (vrs, values),
                (Err(e), _) | (_, Err(e)) => return refused(inst, "fmi2GetReal", "vr or value", e),
            };
        inst.get_real(vrs, values)
    })
}

/// `fmi2SetReal`: parameters (before initialization ends) and inputs. All
/// values are checked first; a non-finite value or a bad reference is an
/// error and nothing changes.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Real,
) -> fmi2Status {
    guarded!(c, "fmi2SetReal", |inst| {
        // SAFETY: host contract: nvr elements each.
        let (vrs, values) = match unsafe { (ptr::slice_arg(vr, nvr), ptr::slice_arg(value, nvr)) } {
            (Ok(vrs), Ok(values)) => (vrs, values),
            (Err(e), _) | (_, Err(e)) => return refused(inst, "fmi2SetReal", "vr or value", e),
        };
        inst.set_real(vrs, values)
    })
}

fn no_variables_of_type(inst: &Instance, function: &str, nvr: usize, ty: &str) -> fmi2Status {
    if nvr == 0 {
        fmi2OK
    } else {
        inst.log.log(
            fmi2Error,
            &format!("{function}: this FMU has no {ty} variables"),
        );
        fmi2Error
    }
}

/// One of the six Get/Set functions of a type this FMU has no variables
/// of: fmi2OK for no value references, else fmi2Error with a log line.
macro_rules! no_variables_fn {
    ($name:ident, $value:ty, $ty:literal) => {
        #[doc = concat!("`", stringify!($name), "`: there are no ", $ty, " variables.")]
        ///
        /// # Safety
        /// Arguments as the FMI 2.0 standard requires.
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $name(
            c: fmi2Component,
            _vr: *const fmi2ValueReference,
            nvr: usize,
            _value: $value,
        ) -> fmi2Status {
            guarded!(c, stringify!($name), |i| {
                no_variables_of_type(i, stringify!($name), nvr, $ty)
            })
        }
    };
}

no_variables_fn!(fmi2GetInteger, *mut fmi2Integer, "Integer");
no_variables_fn!(fmi2GetBoolean, *mut fmi2Boolean, "Boolean");
no_variables_fn!(fmi2GetString, *mut fmi2String, "String");
no_variables_fn!(fmi2SetInteger, *const fmi2Integer, "Integer");
no_variables_fn!(fmi2SetBoolean, *const fmi2Boolean, "Boolean");
no_variables_fn!(fmi2SetString, *const fmi2String, "String");

// ---------------------------------------------------------------------------
// FMU state.

/// `fmi2GetFMUstate`: save everything needed to continue bit-identically.
/// A non-null `*FMUstate` from an earlier call is overwritten in place.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetFMUstate(
    c: fmi2Component,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    guarded!(c, "fmi2GetFMUstate", |inst| {
        // SAFETY: host contract: NULL or a writable fmi2FMUstate.
        let slot = match unsafe { ptr::out_arg(FMUstate) } {
            Ok(slot) => slot,
            Err(e) => return refused(inst, "fmi2GetFMUstate", "FMUstate", e),
        };
        let state = inst.save();
        // SAFETY: host contract: *slot is NULL or a state from us.
        unsafe { store_state(inst, "fmi2GetFMUstate", slot, state) }
    })
}

/// `fmi2SetFMUstate`: restore a saved state (phase included).
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetFMUstate(c: fmi2Component, FMUstate: fmi2FMUstate) -> fmi2Status {
    guarded!(c, "fmi2SetFMUstate", |inst| {
        // SAFETY: host contract: a state from us, not yet freed.
        match unsafe { state_arg(inst, "fmi2SetFMUstate", FMUstate) } {
            Some(s) => {
                let saved = s.state.clone();
                inst.restore(&saved)
            }
            None => fmi2Error,
        }
    })
}

/// `fmi2FreeFMUstate`: release a saved state of this instance and set
/// `*FMUstate` to NULL; in every state of the instance, also after a panic.
/// A state of another instance is refused (that instance frees it).
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeFMUstate(
    c: fmi2Component,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    // SAFETY: as in `guarded!`.
    let inst = unsafe { ptr::handle::<Instance>(c) };
    run_with(inst, "fmi2FreeFMUstate", true, |inst| {
        // SAFETY: host contract: NULL or a writable fmi2FMUstate.
        let slot = match unsafe { ptr::out_arg(FMUstate) } {
            Ok(slot) => slot,
            Err(e) => return refused(inst, "fmi2FreeFMUstate", "FMUstate", e),
        };
        if slot.is_null() {
            return fmi2OK;
        }
        // SAFETY: host contract: a state from us, not yet freed (the magic
        // number, cleared here, catches most second frees).
        if unsafe { state_arg(inst, "fmi2FreeFMUstate", *slot) }.is_none() {
            return fmi2Error;
        }
        if !inst.disown_state(*slot as usize) {
            inst.log.log(
                fmi2Error,
                "fmi2FreeFMUstate: FMUstate was created by another instance; free it with that \
                 instance (fmi2FreeInstance of it frees it too)",
            );
            return fmi2Error;
        }
        // SAFETY: as above; checked to be a live state of this instance.
        match unsafe { ptr::free_handle::<FmuState>(*slot) } {
            Ok(b) => drop(b),
            Err(e) => return state_refused(inst, "fmi2FreeFMUstate", e),
        }
        *slot = std::ptr::null_mut();
        fmi2OK
    })
}

/// `fmi2SerializedFMUstateSize`: bytes that `fmi2SerializeFMUstate` writes.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: fmi2Component,
    FMUstate: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    const F: &str = "fmi2SerializedFMUstateSize";
    guarded!(c, F, |inst| {
        // SAFETY: host contract: NULL or a writable size_t.
        let size = match unsafe { ptr::out_arg(size) } {
            Ok(size) => size,
            Err(e) => return refused(inst, F, "size", e),
        };
        // SAFETY: host contract: a state from us, not yet freed.
        let Some(s) = (unsafe { state_arg(inst, F, FMUstate) }) else {
            return fmi2Error;
        };
        match Instance::serialize(&s.state) {
            Ok(bytes) => *size = bytes.len(),
            Err(e) => {
                inst.log.log(fmi2Error, &format!("{F}: {e}"));
                return fmi2Error;
            }
        }
        fmi2OK
    })
}

/// `fmi2SerializeFMUstate`: write the state (JSON) into the host's buffer.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: fmi2Component,
    FMUstate: fmi2FMUstate,
    serializedState: *mut fmi2Byte,
    size: usize,
) -> fmi2Status {
    guarded!(c, "fmi2SerializeFMUstate", |inst| {
        // SAFETY: host contract: a state from us, not yet freed.
        let Some(s) = (unsafe { state_arg(inst, "fmi2SerializeFMUstate", FMUstate) }) else {
            return fmi2Error;
        };
        let bytes = match Instance::serialize(&s.state) {
            Ok(bytes) => bytes,
            Err(e) => {
                inst.log
                    .log(fmi2Error, &format!("fmi2SerializeFMUstate: {e}"));
                return fmi2Error;
            }
        };
        if size < bytes.len() {
            inst.log.log(
                fmi2Error,
                &format!(
                    "fmi2SerializeFMUstate: buffer of {size} bytes is too small; fmi2SerializedFMUstateSize says {}",
                    bytes.len()
                ),
            );
            return fmi2Error;
        }
        // SAFETY: host contract: `size` (>= bytes.len()) writable bytes.
        match unsafe { ptr::bytes_arg_mut(serializedState, bytes.len()) } {
            Ok(buf) => buf.copy_from_slice(&bytes),
            Err(e) => return refused(inst, "fmi2SerializeFMUstate", "serializedState", e),
        }
        fmi2OK
    })
}

/// `fmi2DeSerializeFMUstate`: a state from bytes written by
/// `fmi2SerializeFMUstate` of an instance of the same FMU.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: fmi2Component,
    serializedState: *const fmi2Byte,
    size: usize,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    const F: &str = "fmi2DeSerializeFMUstate";
    guarded!(c, F, |inst| {
        // SAFETY: host contract: NULL or a writable fmi2FMUstate.
        let slot = match unsafe { ptr::out_arg(FMUstate) } {
            Ok(slot) => slot,
            Err(e) => return refused(inst, F, "FMUstate", e),
        };
        // SAFETY: host contract: `size` readable bytes.
        let bytes = match unsafe { ptr::bytes_arg(serializedState, size) } {
            Ok(bytes) => bytes,
            Err(e) => return refused(inst, F, "serializedState", e),
        };
        let state = match inst.deserialize(bytes) {
            Ok(s) => s,
            Err(status) => return status,
        };
        // SAFETY: host contract: *slot is NULL or a state from us.
        unsafe { store_state(inst, F, slot, state) }
    })
}

/// `fmi2GetDirectionalDerivative`: not provided (fmi2Error).
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: fmi2Component,
    _vUnknown_ref: *const fmi2ValueReference,
    _nUnknown: usize,
    _vKnown_ref: *const fmi2ValueReference,
    _nKnown: usize,
    _dvKnown: *const fmi2Real,
    _dvUnknown: *mut fmi2Real,
) -> fmi2Status {
    guarded!(c, "fmi2GetDirectionalDerivative", |i| {
        i.unsupported(
            "fmi2GetDirectionalDerivative",
            "providesDirectionalDerivative is false",
        )
    })
}

// ---------------------------------------------------------------------------
// Co-simulation.

/// `fmi2SetRealInputDerivatives`: first and second derivatives of inputs over the
/// next communication steps (canInterpolateInputs is true).
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *const fmi2Real,
) -> fmi2Status {
    guarded!(c, "fmi2SetRealInputDerivatives", |inst| {
        const F: &str = "fmi2SetRealInputDerivatives";
        // SAFETY: host contract: nvr elements each.
        let slices = unsafe {
            (
                ptr::slice_arg(vr, nvr),
                ptr::slice_arg(order, nvr),
                ptr::slice_arg(value, nvr),
            )
        };
        let (vrs, orders, values) = match slices {
            (Ok(vrs), Ok(orders), Ok(values)) => (vrs, orders, values),
            (Err(e), _, _) | (_, Err(e), _) | (_, _, Err(e)) => {
                return refused(inst, F, "vr, order or value", e);
            }
        };
        inst.set_input_derivatives(vrs, orders, values)
    })
}

/// `fmi2GetRealOutputDerivatives`: not provided (maxOutputDerivativeOrder 0).
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _nvr: usize,
    _order: *const fmi2Integer,
    _value: *mut fmi2Real,
) -> fmi2Status {
    guarded!(c, "fmi2GetRealOutputDerivatives", |i| {
        i.unsupported(
            "fmi2GetRealOutputDerivatives",
            "maxOutputDerivativeOrder is 0",
        )
    })
}

/// `fmi2DoStep`: integrate from `currentCommunicationPoint` (the FMU's
/// time) by `communicationStepSize`; `fmi2Discard` with the state rolled
/// back when the solver cannot complete the step.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DoStep(
    c: fmi2Component,
    currentCommunicationPoint: fmi2Real,
    communicationStepSize: fmi2Real,
    _noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
) -> fmi2Status {
    guarded!(c, "fmi2DoStep", |i| {
        i.do_step(currentCommunicationPoint, communicationStepSize)
    })
}

/// `fmi2CancelStep`: steps are synchronous; nothing to cancel (fmi2Error).
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
    guarded!(c, "fmi2CancelStep", |i| {
        i.unsupported(
            "fmi2CancelStep",
            "steps are synchronous (canRunAsynchronuously is false)",
        )
    })
}

macro_rules! status_fn {
    ($(#[$doc:meta])* $name:ident, $ty:ty, |$inst:ident, $kind:ident, $value:ident| $body:expr) => {
        $(#[$doc])*
        ///
        /// # Safety
        /// Arguments as the FMI 2.0 standard requires.
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $name(c: fmi2Component, s: c_int, value: *mut $ty) -> fmi2Status {
            guarded!(c, stringify!($name), |$inst| {
                let Some($kind) = StatusKind::from_c(s) else {
                    $inst.log.log(
                        fmi2Error,
                        &format!("{}: {s} is not a valid fmi2StatusKind", stringify!($name)),
                    );
                    return fmi2Error;
                };
                // SAFETY: host contract: NULL or a writable value.
                let $value = match unsafe { ptr::out_arg(value) } {
                    Ok(v) => v,
                    Err(e) => return refused($inst, stringify!($name), "value", e),
                };
                $body
            })
        }
    };
}

status_fn!(
    /// `fmi2GetStatus`: `fmi2DoStepStatus` is always fmi2OK (synchronous
    /// steps); other kinds give fmi2Discard.
    fmi2GetStatus, fmi2Status, |inst, kind, value| match inst.status(kind) {
        Ok(s) => { *value = s; fmi2OK }
        Err(s) => s,
    }
);

status_fn!(
    /// `fmi2GetRealStatus`: `fmi2LastSuccessfulTime` is the FMU's time
    /// (after a discarded step: the start of that step).
    fmi2GetRealStatus, fmi2Real, |inst, kind, value| match inst.status_real(kind) {
        Ok(t) => { *value = t; fmi2OK }
        Err(s) => s,
    }
);

status_fn!(
    /// `fmi2GetIntegerStatus`: no integer status kinds (fmi2Discard).
    fmi2GetIntegerStatus, fmi2Integer, |inst, kind, value| {
        let _ = value;
        inst.unsupported_status("fmi2GetIntegerStatus", kind)
    }
);

status_fn!(
    /// `fmi2GetBooleanStatus`: `fmi2Terminated` is always false.
    fmi2GetBooleanStatus, fmi2Boolean, |inst, kind, value| match inst.status_boolean(kind) {
        Ok(b) => { *value = if b { FMI2_TRUE } else { FMI2_FALSE }; fmi2OK }
        Err(s) => s,
    }
);

status_fn!(
    /// `fmi2GetStringStatus`: no string status kinds (fmi2Discard).
    fmi2GetStringStatus, fmi2String, |inst, kind, value| {
        let _ = value;
        inst.unsupported_status("fmi2GetStringStatus", kind)
    }
);

// ---------------------------------------------------------------------------
// Model Exchange: not supported (fmi2Instantiate refuses fmi2ModelExchange,
// so these can only be reached with a co-simulation instance).

macro_rules! me_fn {
    ($name:ident ( $($arg:ident : $ty:ty),* )) => {
        /// Model Exchange function: not supported by this co-simulation FMU
        /// (fmi2Error with a log line).
        ///
        /// # Safety
        /// Arguments as the FMI 2.0 standard requires.
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $name(c: fmi2Component $(, $arg: $ty)*) -> fmi2Status {
            $(let _ = $arg;)*
            guarded!(c, stringify!($name), |i| {
                i.unsupported(stringify!($name), "this FMU supports co-simulation only")
            })
        }
    };
}

me_fn!(fmi2EnterEventMode());
me_fn!(fmi2NewDiscreteStates(eventInfo: *mut fmi2EventInfo));
me_fn!(fmi2EnterContinuousTimeMode());
me_fn!(fmi2CompletedIntegratorStep(
    noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
    enterEventMode: *mut fmi2Boolean,
    terminateSimulation: *mut fmi2Boolean
));
me_fn!(fmi2SetTime(time: fmi2Real));
me_fn!(fmi2SetContinuousStates(x: *const fmi2Real, nx: usize));
me_fn!(fmi2GetDerivatives(derivatives: *mut fmi2Real, nx: usize));
me_fn!(fmi2GetEventIndicators(eventIndicators: *mut fmi2Real, ni: usize));
me_fn!(fmi2GetContinuousStates(x: *mut fmi2Real, nx: usize));
me_fn!(fmi2GetNominalsOfContinuousStates(x_nominal: *mut fmi2Real, nx: usize));

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn panic_is_fatal_and_kills_the_instance() {
        use crate::mesh::builders::square_with_diagonal;
        use crate::scene::Scene;
        let scene = Scene::with_defaults("sq", square_with_diagonal(0.1, true, 1.0));
        let dir = std::env::temp_dir().join(format!("origami_fmu_guard_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bytes = super::super::resources::scene_bytes(&scene);
        std::fs::write(dir.join(super::super::resources::SCENE_FILE), &bytes).unwrap();
        let cb = fmi2CallbackFunctions {
            logger: None,
            allocateMemory: None,
            freeMemory: None,
            stepFinished: None,
            componentEnvironment: std::ptr::null_mut(),
        };
        let uri = super::super::resources::file_uri(&dir);
        let inst = Instance::instantiate(
            Logger::new(cb, "t", false),
            1,
            Some(&super::super::resources::guid(&bytes)),
            Some(&uri),
        )
        .expect("instantiates");
        let c = Box::into_raw(Box::new(inst)) as fmi2Component;
        // SAFETY: c is a live instance until fmi2FreeInstance; the last
        // call passes NULL, which guard refuses.
        unsafe {
            let s = guard(c, "test", |_| panic!("boom"));
            assert_eq!(s, fmi2Fatal);
            assert_eq!(guard(c, "test", |_| fmi2OK), fmi2Fatal);
            fmi2FreeInstance(c);
            assert_eq!(guard(std::ptr::null_mut(), "test", |_| fmi2OK), fmi2Error);
        }
    }
}
