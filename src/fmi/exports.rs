//! Every function of the FMI 2.0 standard, exported with its C name.
//!
//! Each body runs under [`guard`] (or `catch_unwind` directly for the
//! functions without an instance): a panic becomes `fmi2Fatal` plus a log
//! line and marks the instance dead; it never unwinds into the host. Null
//! pointers are rejected with `fmi2Error` before they are dereferenced.
//! The Model Exchange functions, directional derivatives, output
//! derivatives and `fmi2CancelStep` return `fmi2Error` with a log line.
#![allow(non_snake_case)]

use super::instance::{Instance, Logger, SavedState};
use super::types::*;
use std::ffi::{CStr, c_int};
use std::panic::{AssertUnwindSafe, catch_unwind};

use fmi2Status::*;

/// What an `fmi2FMUstate` points to: a saved state tagged with a magic
/// number, so that a foreign or freed pointer is (usually) detected.
struct FmuState {
    magic: u64,
    state: SavedState,
}

const STATE_MAGIC: u64 = 0x6f72_6967_616d_6931; // "origami1"

fn panic_message(p: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic".into()
    }
}

/// Run `body` on the instance behind `c`: null check, dead check, and
/// `catch_unwind` (a panic returns `fmi2Fatal`, logs, and kills the
/// instance).
pub fn guard(
    c: fmi2Component,
    function: &str,
    body: impl FnOnce(&mut Instance) -> fmi2Status,
) -> fmi2Status {
    if c.is_null() {
        return fmi2Error;
    }
    let inst = c as *mut Instance;
    // SAFETY: a non-null fmi2Component is, by the FMI contract, a pointer
    // returned by our fmi2Instantiate and not yet freed; the host never
    // calls into one instance from two threads at once.
    if unsafe { (*inst).dead } {
        let i = unsafe { &*inst };
        i.log.log(
            fmi2Fatal,
            &format!("{function}: the instance is dead after an internal error; only fmi2FreeInstance is allowed"),
        );
        return fmi2Fatal;
    }
    // SAFETY: as above; the reference does not outlive the closure.
    let result = catch_unwind(AssertUnwindSafe(|| body(unsafe { &mut *inst })));
    match result {
        Ok(s) => s,
        Err(p) => {
            let msg = panic_message(&*p);
            // SAFETY: as above; the closure's borrow has ended.
            let i = unsafe { &mut *inst };
            i.dead = true;
            let _ = catch_unwind(AssertUnwindSafe(|| {
                i.log.log(
                    fmi2Fatal,
                    &format!("{function}: internal error ({msg}); the instance is dead, free it"),
                )
            }));
            fmi2Fatal
        }
    }
}

/// A C string argument as `&str`; `None` for null or invalid UTF-8.
///
/// # Safety
/// `p` is null or points to a NUL-terminated string that outlives `'a`.
unsafe fn str_arg<'a>(p: fmi2String) -> Option<&'a str> {
    if p.is_null() {
        None
    } else {
        // SAFETY: by the caller's contract.
        unsafe { CStr::from_ptr(p) }.to_str().ok()
    }
}

/// A C array argument as a slice (empty for n = 0 even if `p` is null);
/// `None` for a null pointer with n > 0 or an impossible length.
///
/// # Safety
/// `p` is null or points to `n` valid elements that outlive `'a`.
unsafe fn slice_arg<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        Some(&[])
    } else if p.is_null() || n > isize::MAX as usize / std::mem::size_of::<T>().max(1) {
        None
    } else {
        // SAFETY: by the caller's contract.
        Some(unsafe { std::slice::from_raw_parts(p, n) })
    }
}

/// Like [`slice_arg`], mutable.
///
/// # Safety
/// `p` is null or points to `n` writable elements that outlive `'a`.
unsafe fn slice_arg_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        Some(&mut [])
    } else if p.is_null() || n > isize::MAX as usize / std::mem::size_of::<T>().max(1) {
        None
    } else {
        // SAFETY: by the caller's contract.
        Some(unsafe { std::slice::from_raw_parts_mut(p, n) })
    }
}

fn null_arg(inst: &Instance, function: &str, what: &str) -> fmi2Status {
    inst.log
        .log(fmi2Error, &format!("{function}: {what} is NULL"));
    fmi2Error
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
    if s.is_null() {
        null_arg(inst, function, "FMUstate");
        return None;
    }
    let st = s as *mut FmuState;
    // SAFETY: by the caller's contract.
    if unsafe { (*st).magic } != STATE_MAGIC {
        inst.log.log(
            fmi2Error,
            &format!("{function}: FMUstate was not created by this FMU or was freed"),
        );
        return None;
    }
    Some(unsafe { &mut *st })
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
    guard(c, "fmi2SetDebugLogging", |inst| {
        // SAFETY: host contract: nCategories strings.
        let Some(cats) = (unsafe { slice_arg(categories, nCategories) }) else {
            return null_arg(inst, "fmi2SetDebugLogging", "categories");
        };
        let mut names = Vec::with_capacity(cats.len());
        for &p in cats {
            // SAFETY: host contract: each is a C string.
            match unsafe { str_arg(p) } {
                Some(s) => names.push(s.to_string()),
                None => return null_arg(inst, "fmi2SetDebugLogging", "a category"),
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
    if functions.is_null() {
        return std::ptr::null_mut();
    }
    // SAFETY: non-null; copied by value, the host may free its struct.
    let callbacks = unsafe { *functions };
    let r = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: host contract: NUL-terminated strings or NULL.
        let name = unsafe { str_arg(instanceName) }.unwrap_or("");
        let log = Logger::new(callbacks, name, loggingOn != FMI2_FALSE);
        if instanceName.is_null() || name.is_empty() {
            log.log(
                fmi2Error,
                "fmi2Instantiate failed: instanceName is NULL, empty or not UTF-8",
            );
            return std::ptr::null_mut();
        }
        // SAFETY: as above.
        let guid = unsafe { str_arg(fmuGUID) };
        let resources = unsafe { str_arg(fmuResourceLocation) };
        match Instance::instantiate(log, fmuType, guid, resources) {
            Some(inst) => Box::into_raw(Box::new(inst)) as fmi2Component,
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

/// `fmi2FreeInstance`: release the instance (NULL is ignored).
///
/// # Safety
/// `c` is NULL or an instance from `fmi2Instantiate`, not freed before.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
    if c.is_null() {
        return;
    }
    // SAFETY: created by Box::into_raw in fmi2Instantiate.
    let b = unsafe { Box::from_raw(c as *mut Instance) };
    let _ = catch_unwind(AssertUnwindSafe(move || drop(b)));
}

// ---------------------------------------------------------------------------
// Initialization, termination, reset.

/// `fmi2SetupExperiment`: start time (any), stop time (recorded); the
/// tolerance is not used (parameter `solver.tolerance` sets it).
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
    guard(c, "fmi2SetupExperiment", |inst| {
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
    guard(c, "fmi2EnterInitializationMode", |i| {
        i.enter_initialization_mode()
    })
}

/// `fmi2ExitInitializationMode`: the model computes its initial state.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
    guard(c, "fmi2ExitInitializationMode", |i| {
        i.exit_initialization_mode()
    })
}

/// `fmi2Terminate`.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
    guard(c, "fmi2Terminate", |i| i.terminate())
}

/// `fmi2Reset`: back to the state right after `fmi2Instantiate`.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
    guard(c, "fmi2Reset", |i| i.reset())
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
    guard(c, "fmi2GetReal", |inst| {
        // SAFETY: host contract: nvr elements each.
        let (Some(vrs), Some(values)) = (unsafe { slice_arg(vr, nvr) }, unsafe {
            slice_arg_mut(value, nvr)
        }) else {
            return null_arg(inst, "fmi2GetReal", "vr or value");
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
    guard(c, "fmi2SetReal", |inst| {
        // SAFETY: host contract: nvr elements each.
        let (Some(vrs), Some(values)) = (unsafe { slice_arg(vr, nvr) }, unsafe {
            slice_arg(value, nvr)
        }) else {
            return null_arg(inst, "fmi2SetReal", "vr or value");
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

/// `fmi2GetInteger`: there are no Integer variables.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetInteger(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    nvr: usize,
    _value: *mut fmi2Integer,
) -> fmi2Status {
    guard(c, "fmi2GetInteger", |i| {
        no_variables_of_type(i, "fmi2GetInteger", nvr, "Integer")
    })
}

/// `fmi2GetBoolean`: there are no Boolean variables.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    nvr: usize,
    _value: *mut fmi2Boolean,
) -> fmi2Status {
    guard(c, "fmi2GetBoolean", |i| {
        no_variables_of_type(i, "fmi2GetBoolean", nvr, "Boolean")
    })
}

/// `fmi2GetString`: there are no String variables.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetString(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    nvr: usize,
    _value: *mut fmi2String,
) -> fmi2Status {
    guard(c, "fmi2GetString", |i| {
        no_variables_of_type(i, "fmi2GetString", nvr, "String")
    })
}

/// `fmi2SetInteger`: there are no Integer variables.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetInteger(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    nvr: usize,
    _value: *const fmi2Integer,
) -> fmi2Status {
    guard(c, "fmi2SetInteger", |i| {
        no_variables_of_type(i, "fmi2SetInteger", nvr, "Integer")
    })
}

/// `fmi2SetBoolean`: there are no Boolean variables.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    nvr: usize,
    _value: *const fmi2Boolean,
) -> fmi2Status {
    guard(c, "fmi2SetBoolean", |i| {
        no_variables_of_type(i, "fmi2SetBoolean", nvr, "Boolean")
    })
}

/// `fmi2SetString`: there are no String variables.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetString(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    nvr: usize,
    _value: *const fmi2String,
) -> fmi2Status {
    guard(c, "fmi2SetString", |i| {
        no_variables_of_type(i, "fmi2SetString", nvr, "String")
    })
}

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
    guard(c, "fmi2GetFMUstate", |inst| {
        if FMUstate.is_null() {
            return null_arg(inst, "fmi2GetFMUstate", "FMUstate");
        }
        let state = inst.save();
        // SAFETY: non-null out pointer (host contract).
        let slot = unsafe { &mut *FMUstate };
        if slot.is_null() {
            *slot = Box::into_raw(Box::new(FmuState {
                magic: STATE_MAGIC,
                state,
            })) as fmi2FMUstate;
        } else {
            // SAFETY: host contract: a state from an earlier call.
            match unsafe { state_arg(inst, "fmi2GetFMUstate", *slot) } {
                Some(old) => old.state = state,
                None => return fmi2Error,
            }
        }
        fmi2OK
    })
}

/// `fmi2SetFMUstate`: restore a saved state (phase included).
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetFMUstate(c: fmi2Component, FMUstate: fmi2FMUstate) -> fmi2Status {
    guard(c, "fmi2SetFMUstate", |inst| {
        // SAFETY: host contract.
        match unsafe { state_arg(inst, "fmi2SetFMUstate", FMUstate) } {
            Some(s) => {
                let saved = s.state.clone();
                inst.restore(&saved)
            }
            None => fmi2Error,
        }
    })
}

/// `fmi2FreeFMUstate`: release a saved state and set `*FMUstate` to NULL.
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeFMUstate(
    c: fmi2Component,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    guard(c, "fmi2FreeFMUstate", |inst| {
        if FMUstate.is_null() {
            return null_arg(inst, "fmi2FreeFMUstate", "FMUstate");
        }
        // SAFETY: non-null out pointer (host contract).
        let slot = unsafe { &mut *FMUstate };
        if slot.is_null() {
            return fmi2OK;
        }
        // SAFETY: host contract: a state from us, not yet freed.
        if unsafe { state_arg(inst, "fmi2FreeFMUstate", *slot) }.is_none() {
            return fmi2Error;
        }
        // SAFETY: created by Box::into_raw; clear the magic against reuse.
        let mut b = unsafe { Box::from_raw(*slot as *mut FmuState) };
        b.magic = 0;
        drop(b);
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
    guard(c, "fmi2SerializedFMUstateSize", |inst| {
        if size.is_null() {
            return null_arg(inst, "fmi2SerializedFMUstateSize", "size");
        }
        // SAFETY: host contract.
        let Some(s) = (unsafe { state_arg(inst, "fmi2SerializedFMUstateSize", FMUstate) }) else {
            return fmi2Error;
        };
        // SAFETY: non-null out pointer.
        unsafe { *size = Instance::serialize(&s.state).len() };
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
    guard(c, "fmi2SerializeFMUstate", |inst| {
        // SAFETY: host contract.
        let Some(s) = (unsafe { state_arg(inst, "fmi2SerializeFMUstate", FMUstate) }) else {
            return fmi2Error;
        };
        let bytes = Instance::serialize(&s.state);
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
        // SAFETY: host contract: `size` writable bytes.
        let Some(buf) = (unsafe { slice_arg_mut(serializedState as *mut u8, bytes.len()) }) else {
            return null_arg(inst, "fmi2SerializeFMUstate", "serializedState");
        };
        buf.copy_from_slice(&bytes);
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
    guard(c, "fmi2DeSerializeFMUstate", |inst| {
        if FMUstate.is_null() {
            return null_arg(inst, "fmi2DeSerializeFMUstate", "FMUstate");
        }
        // SAFETY: host contract: `size` readable bytes.
        let Some(bytes) = (unsafe { slice_arg(serializedState as *const u8, size) }) else {
            return null_arg(inst, "fmi2DeSerializeFMUstate", "serializedState");
        };
        let state = match inst.deserialize(bytes) {
            Ok(s) => s,
            Err(status) => return status,
        };
        // SAFETY: non-null out pointer.
        let slot = unsafe { &mut *FMUstate };
        if slot.is_null() {
            *slot = Box::into_raw(Box::new(FmuState {
                magic: STATE_MAGIC,
                state,
            })) as fmi2FMUstate;
        } else {
            // SAFETY: host contract: a state from an earlier call.
            match unsafe { state_arg(inst, "fmi2DeSerializeFMUstate", *slot) } {
                Some(old) => old.state = state,
                None => return fmi2Error,
            }
        }
        fmi2OK
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
    guard(c, "fmi2GetDirectionalDerivative", |i| {
        i.unsupported(
            "fmi2GetDirectionalDerivative",
            "providesDirectionalDerivative is false",
        )
    })
}

// ---------------------------------------------------------------------------
// Co-simulation.

/// `fmi2SetRealInputDerivatives`: first derivatives of inputs over the
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
    guard(c, "fmi2SetRealInputDerivatives", |inst| {
        // SAFETY: host contract: nvr elements each.
        let (Some(vrs), Some(orders), Some(values)) = (
            unsafe { slice_arg(vr, nvr) },
            unsafe { slice_arg(order, nvr) },
            unsafe { slice_arg(value, nvr) },
        ) else {
            return null_arg(inst, "fmi2SetRealInputDerivatives", "vr, order or value");
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
    guard(c, "fmi2GetRealOutputDerivatives", |i| {
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
    guard(c, "fmi2DoStep", |i| {
        i.do_step(currentCommunicationPoint, communicationStepSize)
    })
}

/// `fmi2CancelStep`: steps are synchronous; nothing to cancel (fmi2Error).
///
/// # Safety
/// Arguments as the FMI 2.0 standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
    guard(c, "fmi2CancelStep", |i| {
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
            guard(c, stringify!($name), |$inst| {
                let Some($kind) = StatusKind::from_c(s) else {
                    $inst.log.log(
                        fmi2Error,
                        &format!("{}: {s} is not a valid fmi2StatusKind", stringify!($name)),
                    );
                    return fmi2Error;
                };
                if value.is_null() {
                    return null_arg($inst, stringify!($name), "value");
                }
                // SAFETY: non-null out pointer (host contract).
                let $value = unsafe { &mut *value };
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
            guard(c, stringify!($name), |i| {
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
        let uri = format!("file://{}", dir.display());
        let inst = Instance::instantiate(
            Logger::new(cb, "t", false),
            1,
            Some(&super::super::resources::guid(&bytes)),
            Some(&uri),
        )
        .expect("instantiates");
        let c = Box::into_raw(Box::new(inst)) as fmi2Component;
        let s = guard(c, "test", |_| panic!("boom"));
        assert_eq!(s, fmi2Fatal);
        assert_eq!(guard(c, "test", |_| fmi2OK), fmi2Fatal);
        unsafe { fmi2FreeInstance(c) };
        assert_eq!(guard(std::ptr::null_mut(), "test", |_| fmi2OK), fmi2Error);
    }
}
