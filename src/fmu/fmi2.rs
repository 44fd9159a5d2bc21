//! The FMI 2.0 C API, bound by hand: its types, the callback table an importer passes to
//! `fmi2Instantiate`, and the co-simulation functions resolved by name from the FMU's
//! shared library.
//!
//! Why not the `fmi` crate: fmi 0.8 generates its bindings with bindgen at build time,
//! which needs libclang (not on a fresh machine) and pulls in clang-sys, bindgen and a
//! large zip feature set, and it extracts archives without size caps. The part of the
//! ABI an importer needs is small and fixed by the standard, so it is written out here.

use std::ffi::{c_char, c_int, c_void, CStr};
use std::io::Write;

use libloading::Library;

use super::FmuError;

/// `fmi2Component`: the FMU's opaque instance pointer.
pub type Component = *mut c_void;
/// `fmi2ComponentEnvironment`: the importer's pointer handed back to its callbacks.
pub type ComponentEnvironment = *mut c_void;
/// `fmi2FMUstate`: an opaque saved state.
pub type State = *mut c_void;
/// `fmi2ValueReference` (`unsigned int`).
pub type ValueReference = u32;
/// `fmi2Real` (`double`).
pub type Real = f64;
/// `fmi2Integer` (`int`).
pub type Integer = c_int;
/// `fmi2Boolean` (`int`, `fmi2True` = 1, `fmi2False` = 0).
pub type Boolean = c_int;
/// `fmi2Status` (a C enum, `int` at the ABI).
pub type Status = c_int;

/// `fmi2OK`.
pub const OK: Status = 0;
/// `fmi2Warning`.
pub const WARNING: Status = 1;
/// `fmi2Discard`.
pub const DISCARD: Status = 2;
/// `fmi2Error`.
pub const ERROR: Status = 3;
/// `fmi2Fatal`.
pub const FATAL: Status = 4;
/// `fmi2Pending`.
pub const PENDING: Status = 5;
/// `fmi2LastSuccessfulTime`, the `fmi2StatusKind` asked of `fmi2GetRealStatus`.
pub const LAST_SUCCESSFUL_TIME: c_int = 2;
/// `fmi2Terminated`, the `fmi2StatusKind` asked of `fmi2GetBooleanStatus`.
pub const TERMINATED: c_int = 3;
/// `fmi2CoSimulation`, the `fmi2Type` passed to `fmi2Instantiate` (`fmi2ModelExchange` is 0).
pub const CO_SIMULATION: c_int = 1;

/// The status's C name (`fmi2Error`); unknown values read `fmi2Status(out of range)`.
pub fn status_name(s: Status) -> &'static str {
    match s {
        OK => "fmi2OK",
        WARNING => "fmi2Warning",
        DISCARD => "fmi2Discard",
        ERROR => "fmi2Error",
        FATAL => "fmi2Fatal",
        PENDING => "fmi2Pending",
        _ => "fmi2Status(out of range)",
    }
}

/// `fmi2CallbackLogger`, declared with its five fixed parameters only.
///
/// In C it is variadic (`..., fmi2String message, ...)`: `message` is a printf format).
/// Stable Rust cannot define a variadic function, so ours takes the fixed five. That is
/// sound enough on the ABIs FMI 2.0 platforms use (x86-64 System V and Windows x64,
/// i386 cdecl, AArch64 AAPCS and Apple's variant): the named arguments travel exactly
/// as for a non-variadic call (registers, then stack, in order), the variadic ones come
/// after them, and the caller cleans the stack, so a callee that reads only the named
/// ones reads them correctly and ignores the rest. The price: format arguments are not
/// substituted; the message is printed as written.
pub type Logger = unsafe extern "C" fn(
    env: ComponentEnvironment,
    instance: *const c_char,
    status: Status,
    category: *const c_char,
    message: *const c_char,
);

/// `fmi2CallbackFunctions`, in the standard's field order.
#[repr(C)]
pub struct CallbackFunctions {
    /// `logger`.
    pub logger: Option<Logger>,
    /// `allocateMemory(nobj, size)`: zeroed memory, as `calloc`.
    pub allocate_memory: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
    /// `freeMemory(obj)`, as `free`.
    pub free_memory: Option<unsafe extern "C" fn(*mut c_void)>,
    /// `stepFinished(env, status)`: only for asynchronous `fmi2DoStep`, which dsmcosim
    /// does not use; null.
    pub step_finished: Option<unsafe extern "C" fn(ComponentEnvironment, Status)>,
    /// `componentEnvironment`: points at the instance's [`LogTarget`].
    pub component_environment: ComponentEnvironment,
}

/// What the logger needs to know about the instance that calls it; boxed by the
/// instance so its address is stable for the instance's life.
#[derive(Debug)]
pub struct LogTarget {
    /// The instance's name, the prefix of every message.
    pub instance: String,
    /// Print every message (`loggingOn` of `fmi2Instantiate`); off: only those of
    /// status warning and worse, which are always printed and kept.
    pub on: bool,
    /// The FMU's name, for the printed warnings.
    pub fmu: String,
    /// Where messages of status warning and worse are kept ([`super::log`]).
    pub log: super::log::SharedLog,
}

impl LogTarget {
    /// One message the FMU logged with `status` (its C name `status_name`): printed
    /// when logging is on, and if of status warning or worse kept and, the first time,
    /// printed as a warning ([`super::log::keep`]).
    pub(crate) fn message(
        &self,
        instance: String,
        (status, status_name): (Status, &'static str),
        category: String,
        message: String,
    ) {
        if self.on {
            let _ = writeln!(
                std::io::stderr(),
                "[{instance}] {status_name} {category}: {message}"
            );
        }
        // The codes OK, Warning, Discard, Error, Fatal are the same in FMI 2.0 and 3.0:
        // everything but OK (an out-of-range status too) is a warning or worse.
        if status != OK {
            let entry = (instance, status_name, category, message);
            super::log::keep(&self.log, &self.fmu, entry, self.on);
        }
    }
}

/// The text of a C string the FMU passed (empty for null).
///
/// # Safety
/// `p` is null or NUL-terminated.
pub(crate) unsafe fn text(p: *const c_char) -> String {
    if p.is_null() {
        String::new()
    } else {
        // SAFETY: non-null and NUL-terminated by the caller's contract.
        unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
    }
}

/// The logger: prints `[instance] status category: message` to stderr when the
/// instance's logging is on, and keeps and prints every message of status warning and
/// worse whether or not it is (`LogTarget::message`). Never unwinds (a write error is
/// ignored).
///
/// # Safety
/// `env` is null or points at a live [`LogTarget`]; the strings are null or
/// NUL-terminated, as FMI 2.0 requires of the FMU.
pub unsafe extern "C" fn log_message(
    env: ComponentEnvironment,
    instance: *const c_char,
    status: Status,
    category: *const c_char,
    message: *const c_char,
) {
    // SAFETY: the instance made `env` from a `Box<LogTarget>` that outlives it.
    let Some(target) = (unsafe { env.cast::<LogTarget>().as_ref() }) else {
        return;
    };
    // SAFETY (all three): null or NUL-terminated by the caller's contract.
    let name = if instance.is_null() {
        target.instance.clone()
    } else {
        unsafe { text(instance) }
    };
    let (category, message) = unsafe { (text(category), text(message)) };
    target.message(name, (status, status_name(status)), category, message);
}

/// The callback table for an instance whose logger target is `env`.
pub fn callbacks(env: *mut LogTarget) -> CallbackFunctions {
    CallbackFunctions {
        logger: Some(log_message),
        allocate_memory: Some(libc::calloc),
        free_memory: Some(libc::free),
        step_finished: None,
        component_environment: env.cast(),
    }
}

/// `fmi2GetTypesPlatform`, `fmi2GetVersion`: a static C string.
pub type GetString = unsafe extern "C" fn() -> *const c_char;
/// `fmi2SetDebugLogging(c, loggingOn, nCategories, categories)`.
pub type SetDebugLogging =
    unsafe extern "C" fn(Component, Boolean, usize, *const *const c_char) -> Status;
/// `fmi2Instantiate(name, type, guid, resourceLocation, functions, visible, loggingOn)`.
pub type Instantiate = unsafe extern "C" fn(
    *const c_char,
    c_int,
    *const c_char,
    *const c_char,
    *const CallbackFunctions,
    Boolean,
    Boolean,
) -> Component;
/// `fmi2FreeInstance(c)`.
pub type FreeInstance = unsafe extern "C" fn(Component);
/// `fmi2SetupExperiment(c, toleranceDefined, tolerance, start, stopDefined, stop)`.
pub type SetupExperiment =
    unsafe extern "C" fn(Component, Boolean, Real, Real, Boolean, Real) -> Status;
/// A call on the component alone (`fmi2Terminate`, `fmi2Reset`, …).
pub type Call = unsafe extern "C" fn(Component) -> Status;
/// `fmi2Get*(c, vr, nvr, value)`.
pub type GetValues<T> =
    unsafe extern "C" fn(Component, *const ValueReference, usize, *mut T) -> Status;
/// `fmi2Set*(c, vr, nvr, value)`.
pub type SetValues<T> =
    unsafe extern "C" fn(Component, *const ValueReference, usize, *const T) -> Status;
/// `fmi2GetFMUstate(c, &state)`.
pub type GetState = unsafe extern "C" fn(Component, *mut State) -> Status;
/// `fmi2SetFMUstate(c, state)`.
pub type SetState = unsafe extern "C" fn(Component, State) -> Status;
/// `fmi2FreeFMUstate(c, &state)`.
pub type FreeState = unsafe extern "C" fn(Component, *mut State) -> Status;
/// `fmi2SerializedFMUstateSize(c, state, &size)`.
pub type StateSize = unsafe extern "C" fn(Component, State, *mut usize) -> Status;
/// `fmi2SerializeFMUstate(c, state, bytes, size)`.
pub type Serialize = unsafe extern "C" fn(Component, State, *mut c_char, usize) -> Status;
/// `fmi2DeSerializeFMUstate(c, bytes, size, &state)`.
pub type Deserialize = unsafe extern "C" fn(Component, *const c_char, usize, *mut State) -> Status;
/// `fmi2GetRealStatus(c, kind, &value)` (`fmi2StatusKind` is a C enum, `int`).
pub type GetRealStatus = unsafe extern "C" fn(Component, c_int, *mut Real) -> Status;
/// `fmi2GetBooleanStatus(c, kind, &value)`.
pub type GetBooleanStatus = unsafe extern "C" fn(Component, c_int, *mut Boolean) -> Status;
/// `fmi2DoStep(c, t, h, noSetFMUStatePriorToCurrentPoint)`.
pub type DoStep = unsafe extern "C" fn(Component, Real, Real, Boolean) -> Status;

/// The functions this importer calls, resolved from the library. The state functions
/// are resolved only when the description declares the capability; the pointers are
/// valid while the [`Library`] they came from stays loaded (the owner keeps both).
#[derive(Clone, Copy)]
pub struct Functions {
    /// `fmi2GetTypesPlatform`.
    pub get_types_platform: GetString,
    /// `fmi2GetVersion`.
    pub get_version: GetString,
    /// `fmi2SetDebugLogging`.
    pub set_debug_logging: SetDebugLogging,
    /// `fmi2Instantiate`.
    pub instantiate: Instantiate,
    /// `fmi2FreeInstance`.
    pub free_instance: FreeInstance,
    /// `fmi2SetupExperiment`.
    pub setup_experiment: SetupExperiment,
    /// `fmi2EnterInitializationMode`.
    pub enter_initialization_mode: Call,
    /// `fmi2ExitInitializationMode`.
    pub exit_initialization_mode: Call,
    /// `fmi2Terminate`.
    pub terminate: Call,
    /// `fmi2Reset`.
    pub reset: Call,
    /// `fmi2GetReal`.
    pub get_real: GetValues<Real>,
    /// `fmi2GetInteger`.
    pub get_integer: GetValues<Integer>,
    /// `fmi2GetBoolean`.
    pub get_boolean: GetValues<Boolean>,
    /// `fmi2SetReal`.
    pub set_real: SetValues<Real>,
    /// `fmi2SetInteger`.
    pub set_integer: SetValues<Integer>,
    /// `fmi2SetBoolean`.
    pub set_boolean: SetValues<Boolean>,
    /// `fmi2GetString` and `fmi2SetString`: every FMI 2.0 FMU must export them, but an
    /// FMU without them loads; reading or setting a String of it is then refused
    /// naming the missing function.
    pub string: Option<(GetValues<*const c_char>, SetValues<*const c_char>)>,
    /// `fmi2DoStep`.
    pub do_step: DoStep,
    /// `fmi2GetRealStatus` and `fmi2GetBooleanStatus`, asked after a step returned
    /// `fmi2Discard` whether the FMU wants the simulation to end and how far it got.
    /// Every FMI 2.0 co-simulation FMU must export them, but they are not required here:
    /// without them a discarded step is an error, as it was before they were asked.
    pub status: Option<(GetRealStatus, GetBooleanStatus)>,
    /// `fmi2GetFMUstate`, `fmi2SetFMUstate`, `fmi2FreeFMUstate` when
    /// `canGetAndSetFMUstate`.
    pub state: Option<(GetState, SetState, FreeState)>,
    /// `fmi2SerializedFMUstateSize`, `fmi2SerializeFMUstate`, `fmi2DeSerializeFMUstate`
    /// when `canSerializeFMUstate`.
    pub serialize: Option<(StateSize, Serialize, Deserialize)>,
}

impl Functions {
    /// Resolves every function from `library`; `state` and `serialize` say whether the
    /// state functions are required. A missing one is [`FmuError::MissingSymbol`].
    ///
    /// # Safety
    /// `library` must be an FMI 2.0 binary: the symbols are taken to have the types
    /// above, which nothing at run time can check.
    pub unsafe fn load(
        library: &Library,
        fmu: &str,
        state: bool,
        serialize: bool,
    ) -> Result<Functions, FmuError> {
        use super::symbol as sym;
        // SAFETY (all): FMI 2.0 fixes each symbol's type as declared above.
        let l = library;
        unsafe {
            Ok(Functions {
                get_types_platform: sym(l, fmu, "fmi2GetTypesPlatform")?,
                get_version: sym(l, fmu, "fmi2GetVersion")?,
                set_debug_logging: sym(l, fmu, "fmi2SetDebugLogging")?,
                instantiate: sym(l, fmu, "fmi2Instantiate")?,
                free_instance: sym(l, fmu, "fmi2FreeInstance")?,
                setup_experiment: sym(l, fmu, "fmi2SetupExperiment")?,
                enter_initialization_mode: sym(l, fmu, "fmi2EnterInitializationMode")?,
                exit_initialization_mode: sym(l, fmu, "fmi2ExitInitializationMode")?,
                terminate: sym(l, fmu, "fmi2Terminate")?,
                reset: sym(l, fmu, "fmi2Reset")?,
                get_real: sym(l, fmu, "fmi2GetReal")?,
                get_integer: sym(l, fmu, "fmi2GetInteger")?,
                get_boolean: sym(l, fmu, "fmi2GetBoolean")?,
                set_real: sym(l, fmu, "fmi2SetReal")?,
                set_integer: sym(l, fmu, "fmi2SetInteger")?,
                set_boolean: sym(l, fmu, "fmi2SetBoolean")?,
                string: sym(l, fmu, "fmi2GetString")
                    .and_then(|g| Ok((g, sym(l, fmu, "fmi2SetString")?)))
                    .ok(),
                do_step: sym(l, fmu, "fmi2DoStep")?,
                status: sym(l, fmu, "fmi2GetRealStatus")
                    .and_then(|r| Ok((r, sym(l, fmu, "fmi2GetBooleanStatus")?)))
                    .ok(),
                state: if state {
                    Some((
                        sym(l, fmu, "fmi2GetFMUstate")?,
                        sym(l, fmu, "fmi2SetFMUstate")?,
                        sym(l, fmu, "fmi2FreeFMUstate")?,
                    ))
                } else {
                    None
                },
                serialize: if serialize {
                    Some((
                        sym(l, fmu, "fmi2SerializedFMUstateSize")?,
                        sym(l, fmu, "fmi2SerializeFMUstate")?,
                        sym(l, fmu, "fmi2DeSerializeFMUstate")?,
                    ))
                } else {
                    None
                },
            })
        }
    }
}

/// The FMI 2.0 platform folder of this host and its library suffix, or `None` where
/// FMI 2.0 names no platform (e.g. Linux on AArch64).
pub fn host_platform() -> Option<(&'static str, &'static str)> {
    if cfg!(all(target_os = "linux", target_arch = "x86_64")) {
        Some(("linux64", "so"))
    } else if cfg!(all(target_os = "linux", target_arch = "x86")) {
        Some(("linux32", "so"))
    } else if cfg!(target_os = "macos") {
        // FMI 2.0 has only darwin64; tools put universal (x86-64 + arm64) binaries there.
        Some(("darwin64", "dylib"))
    } else if cfg!(all(target_os = "windows", target_arch = "x86_64")) {
        Some(("win64", "dll"))
    } else if cfg!(all(target_os = "windows", target_arch = "x86")) {
        Some(("win32", "dll"))
    } else {
        None
    }
}
