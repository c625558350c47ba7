//! The C types of the FMI 2.0 standard (`fmi2TypesPlatform.h`,
//! `fmi2FunctionTypes.h`), written by hand with `#[repr(C)]`.
//!
//! Enumerations that the host passes in (`fmi2Type`, `fmi2StatusKind`) are
//! plain `c_int` here: an out-of-range value in a Rust enum would be
//! undefined behaviour, so they are validated by [`Fmi2Type::from_c`] and
//! [`StatusKind::from_c`]. [`fmi2Status`] is only ever produced by us and
//! is a proper `#[repr(C)]` enum.
#![allow(non_camel_case_types, non_snake_case)]

use std::ffi::{c_char, c_int, c_uint, c_void};

/// Opaque instance handle (`fmi2Component`).
pub type fmi2Component = *mut c_void;
/// The host's environment pointer, passed back to every callback.
pub type fmi2ComponentEnvironment = *mut c_void;
/// Opaque saved-state handle (`fmi2FMUstate`).
pub type fmi2FMUstate = *mut c_void;
/// Value reference of a variable.
pub type fmi2ValueReference = c_uint;
/// Real value.
pub type fmi2Real = f64;
/// Integer value.
pub type fmi2Integer = c_int;
/// Boolean value: 0 is false, anything else true.
pub type fmi2Boolean = c_int;
/// One character of a string.
pub type fmi2Char = c_char;
/// A NUL-terminated string owned by whoever passed it.
pub type fmi2String = *const fmi2Char;
/// One byte of a serialized state.
pub type fmi2Byte = c_char;

/// `fmi2True`.
pub const FMI2_TRUE: fmi2Boolean = 1;
/// `fmi2False`.
pub const FMI2_FALSE: fmi2Boolean = 0;

/// Return status of every FMI function.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum fmi2Status {
    /// All well.
    fmi2OK = 0,
    /// Things are not quite right, but the computation can continue.
    fmi2Warning = 1,
    /// The step could not be completed; the state is as before it.
    fmi2Discard = 2,
    /// The call was rejected or failed; see the log.
    fmi2Error = 3,
    /// The instance is irreparably broken.
    fmi2Fatal = 4,
    /// Asynchronous step in progress (never returned here).
    fmi2Pending = 5,
}

impl fmi2Status {
    /// The FMI name of the status, for log lines.
    pub fn name(self) -> &'static str {
        match self {
            fmi2Status::fmi2OK => "fmi2OK",
            fmi2Status::fmi2Warning => "fmi2Warning",
            fmi2Status::fmi2Discard => "fmi2Discard",
            fmi2Status::fmi2Error => "fmi2Error",
            fmi2Status::fmi2Fatal => "fmi2Fatal",
            fmi2Status::fmi2Pending => "fmi2Pending",
        }
    }
}

/// `fmi2Type`, validated from the `c_int` the host passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fmi2Type {
    /// `fmi2ModelExchange` (0): not supported by this FMU.
    ModelExchange,
    /// `fmi2CoSimulation` (1).
    CoSimulation,
}

impl Fmi2Type {
    /// Validate a host value; `None` when it is neither 0 nor 1.
    pub fn from_c(v: c_int) -> Option<Fmi2Type> {
        match v {
            0 => Some(Fmi2Type::ModelExchange),
            1 => Some(Fmi2Type::CoSimulation),
            _ => None,
        }
    }
}

/// `fmi2StatusKind`, validated from the `c_int` the host passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StatusKind {
    /// `fmi2DoStepStatus` (0).
    DoStepStatus,
    /// `fmi2PendingStatus` (1).
    PendingStatus,
    /// `fmi2LastSuccessfulTime` (2).
    LastSuccessfulTime,
    /// `fmi2Terminated` (3).
    Terminated,
}

impl StatusKind {
    /// Validate a host value; `None` when it is not 0..=3.
    pub fn from_c(v: c_int) -> Option<StatusKind> {
        match v {
            0 => Some(StatusKind::DoStepStatus),
            1 => Some(StatusKind::PendingStatus),
            2 => Some(StatusKind::LastSuccessfulTime),
            3 => Some(StatusKind::Terminated),
            _ => None,
        }
    }
}

/// The logger callback. It is C-variadic: it is always called with the
/// format `"%s"` and the message as its single argument, so a `%` in a
/// message is never read as a conversion.
pub type fmi2CallbackLogger = Option<
    unsafe extern "C" fn(
        fmi2ComponentEnvironment,
        fmi2String, // instance name
        fmi2Status,
        fmi2String, // category
        fmi2String, // message (a printf format)
        ...
    ),
>;
/// `calloc`-like allocator of the host (never used by this FMU).
pub type fmi2CallbackAllocateMemory = Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>;
/// `free`-like deallocator of the host (never used by this FMU).
pub type fmi2CallbackFreeMemory = Option<unsafe extern "C" fn(*mut c_void)>;
/// Asynchronous step notification (never used by this FMU).
pub type fmi2StepFinished = Option<unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2Status)>;

/// The callbacks the host hands to `fmi2Instantiate`; copied by value.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct fmi2CallbackFunctions {
    /// Logger (may be null: then nothing is logged).
    pub logger: fmi2CallbackLogger,
    /// Allocator (unused: canNotUseMemoryManagementFunctions).
    pub allocateMemory: fmi2CallbackAllocateMemory,
    /// Deallocator (unused).
    pub freeMemory: fmi2CallbackFreeMemory,
    /// Asynchronous step callback (unused).
    pub stepFinished: fmi2StepFinished,
    /// Passed back as the first argument of every callback.
    pub componentEnvironment: fmi2ComponentEnvironment,
}

/// Event information of Model Exchange (only in the signatures of the ME
/// functions, which this FMU rejects).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct fmi2EventInfo {
    /// New discrete states needed.
    pub newDiscreteStatesNeeded: fmi2Boolean,
    /// Terminate simulation.
    pub terminateSimulation: fmi2Boolean,
    /// Nominals of continuous states changed.
    pub nominalsOfContinuousStatesChanged: fmi2Boolean,
    /// Values of continuous states changed.
    pub valuesOfContinuousStatesChanged: fmi2Boolean,
    /// Next event time defined.
    pub nextEventTimeDefined: fmi2Boolean,
    /// Next event time.
    pub nextEventTime: fmi2Real,
}
