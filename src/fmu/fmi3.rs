//! The FMI 3.0 C API, bound by hand: its types, the log callback an importer passes to
//! `fmi3InstantiateCoSimulation`, and the co-simulation functions resolved by name from
//! the FMU's shared library.
//!
//! Hand-written for the same reasons as [`super::fmi2`]: the `fmi` crate generates its
//! bindings with bindgen at build time (libclang, clang-sys, a large dependency set) and
//! extracts archives without size caps, while the part of the ABI an importer needs is
//! small and fixed by the standard.
//!
//! What differs from FMI 2.0 at the ABI: no callback table and no memory callbacks (the
//! FMU allocates for itself), a log callback that is not variadic, `fmi3Boolean` is C's
//! one-byte `bool`, every getter and setter takes the number of values as well as the
//! number of references (they differ for arrays, whose elements follow each other),
//! there is no `fmi2SetupExperiment` (start and stop go to
//! `fmi3EnterInitializationMode`), and `fmi3DoStep` reports through out-parameters
//! whether the FMU wants the simulation to end.

use std::ffi::{c_char, c_void};

use libloading::Library;

use super::FmuError;

/// `fmi3Instance`: the FMU's opaque instance pointer.
pub type Instance = *mut c_void;
/// `fmi3InstanceEnvironment`: the importer's pointer handed back to its callback.
pub type InstanceEnvironment = *mut c_void;
/// `fmi3FMUState`: an opaque saved state.
pub type State = *mut c_void;
/// `fmi3ValueReference` (`uint32_t`).
pub type ValueReference = u32;
/// `fmi3Float64` (`double`).
pub type Float64 = f64;
/// `fmi3Int32` (`int32_t`).
pub type Int32 = i32;
/// `fmi3Int64` (`int64_t`): the ABI type of enumerations.
pub type Int64 = i64;
/// `fmi3String` (`const char *`).
pub type Str = *const c_char;
/// `fmi3Binary` (`const uint8_t *`).
pub type Binary = *const u8;
/// `fmi3Boolean` (C99 `bool`), passed as a byte: reading it as `u8` and testing for
/// non-zero never makes an invalid Rust `bool` from whatever the FMU wrote.
pub type Boolean = u8;
/// `fmi3Status` (a C enum, `int` at the ABI).
pub type Status = std::ffi::c_int;

/// `fmi3OK`.
pub const OK: Status = 0;
/// `fmi3Warning`.
pub const WARNING: Status = 1;
/// `fmi3Discard`.
pub const DISCARD: Status = 2;
/// `fmi3Error`.
pub const ERROR: Status = 3;
/// `fmi3Fatal`.
pub const FATAL: Status = 4;

/// The status's C name (`fmi3Error`); unknown values read `fmi3Status(out of range)`.
pub fn status_name(s: Status) -> &'static str {
    match s {
        OK => "fmi3OK",
        WARNING => "fmi3Warning",
        DISCARD => "fmi3Discard",
        ERROR => "fmi3Error",
        FATAL => "fmi3Fatal",
        _ => "fmi3Status(out of range)",
    }
}

/// `fmi3LogMessageCallback(env, status, category, message)`: not variadic in FMI 3.0,
/// so it is declared exactly as C declares it.
pub type LogMessage = unsafe extern "C" fn(
    env: InstanceEnvironment,
    status: Status,
    category: *const c_char,
    message: *const c_char,
);

/// The log callback: prints `[instance] status category: message` to stderr when the
/// instance's logging is on, and keeps and prints every message of status warning and
/// worse whether or not it is (`fmi2::LogTarget::message`). `env` is the instance's [`super::fmi2::LogTarget`] (shared
/// with FMI 2.0: it holds the instance's name, which FMI 3.0 no longer passes). Never
/// unwinds (a write error is ignored).
///
/// # Safety
/// `env` is null or points at a live `LogTarget`; the strings are null or
/// NUL-terminated, as FMI 3.0 requires of the FMU.
pub unsafe extern "C" fn log_message(
    env: InstanceEnvironment,
    status: Status,
    category: *const c_char,
    message: *const c_char,
) {
    // SAFETY: the instance made `env` from a `Box<LogTarget>` that outlives it.
    let Some(target) = (unsafe { env.cast::<super::fmi2::LogTarget>().as_ref() }) else {
        return;
    };
    // SAFETY (both): null or NUL-terminated by the caller's contract.
    let (category, message) = unsafe { (super::fmi2::text(category), super::fmi2::text(message)) };
    target.message(
        target.instance.clone(),
        (status, status_name(status)),
        category,
        message,
    );
}

/// `fmi3GetVersion`: a static C string.
pub type GetString = unsafe extern "C" fn() -> *const c_char;
/// `fmi3SetDebugLogging(inst, loggingOn, nCategories, categories)`.
pub type SetDebugLogging =
    unsafe extern "C" fn(Instance, Boolean, usize, *const *const c_char) -> Status;
/// `fmi3InstantiateCoSimulation(instanceName, instantiationToken, resourcePath, visible,
/// loggingOn, eventModeUsed, earlyReturnAllowed, requiredIntermediateVariables,
/// nRequiredIntermediateVariables, instanceEnvironment, logMessage, intermediateUpdate)`.
/// The intermediate-update callback is passed null, so its type is left opaque.
pub type InstantiateCoSimulation = unsafe extern "C" fn(
    *const c_char,
    *const c_char,
    *const c_char,
    Boolean,
    Boolean,
    Boolean,
    Boolean,
    *const ValueReference,
    usize,
    InstanceEnvironment,
    Option<LogMessage>,
    *const c_void,
) -> Instance;
/// `fmi3FreeInstance(inst)`.
pub type FreeInstance = unsafe extern "C" fn(Instance);
/// `fmi3EnterInitializationMode(inst, toleranceDefined, tolerance, startTime,
/// stopTimeDefined, stopTime)`.
pub type EnterInitializationMode =
    unsafe extern "C" fn(Instance, Boolean, Float64, Float64, Boolean, Float64) -> Status;
/// A call on the instance alone (`fmi3ExitInitializationMode`, `fmi3Terminate`, …).
pub type Call = unsafe extern "C" fn(Instance) -> Status;
/// `fmi3Get*(inst, vrs, nvr, values, nValues)`.
pub type GetValues<T> =
    unsafe extern "C" fn(Instance, *const ValueReference, usize, *mut T, usize) -> Status;
/// `fmi3Set*(inst, vrs, nvr, values, nValues)`.
pub type SetValues<T> =
    unsafe extern "C" fn(Instance, *const ValueReference, usize, *const T, usize) -> Status;
/// `fmi3GetBinary(inst, vrs, nvr, valueSizes, values, nValues)`.
pub type GetBinary = unsafe extern "C" fn(
    Instance,
    *const ValueReference,
    usize,
    *mut usize,
    *mut Binary,
    usize,
) -> Status;
/// `fmi3SetBinary(inst, vrs, nvr, valueSizes, values, nValues)`.
pub type SetBinary = unsafe extern "C" fn(
    Instance,
    *const ValueReference,
    usize,
    *const usize,
    *const Binary,
    usize,
) -> Status;
/// `fmi3GetFMUState(inst, &state)`.
pub type GetState = unsafe extern "C" fn(Instance, *mut State) -> Status;
/// `fmi3SetFMUState(inst, state)`.
pub type SetState = unsafe extern "C" fn(Instance, State) -> Status;
/// `fmi3FreeFMUState(inst, &state)`.
pub type FreeState = unsafe extern "C" fn(Instance, *mut State) -> Status;
/// `fmi3SerializedFMUStateSize(inst, state, &size)`.
pub type StateSize = unsafe extern "C" fn(Instance, State, *mut usize) -> Status;
/// `fmi3SerializeFMUState(inst, state, bytes, size)` (`fmi3Byte` is `uint8_t`).
pub type Serialize = unsafe extern "C" fn(Instance, State, *mut u8, usize) -> Status;
/// `fmi3DeserializeFMUState(inst, bytes, size, &state)`.
pub type Deserialize = unsafe extern "C" fn(Instance, *const u8, usize, *mut State) -> Status;
/// `fmi3DoStep(inst, currentCommunicationPoint, communicationStepSize,
/// noSetFMUStatePriorToCurrentPoint, &eventHandlingNeeded, &terminateSimulation,
/// &earlyReturn, &lastSuccessfulTime)`.
pub type DoStep = unsafe extern "C" fn(
    Instance,
    Float64,
    Float64,
    Boolean,
    *mut Boolean,
    *mut Boolean,
    *mut Boolean,
    *mut Float64,
) -> Status;

/// The functions this importer calls, resolved from the library. The state functions
/// are resolved only when the description declares the capability; the pointers are
/// valid while the [`Library`] they came from stays loaded (the owner keeps both).
#[derive(Clone, Copy)]
pub struct Functions {
    /// `fmi3GetVersion`.
    pub get_version: GetString,
    /// `fmi3SetDebugLogging`.
    pub set_debug_logging: SetDebugLogging,
    /// `fmi3InstantiateCoSimulation`.
    pub instantiate: InstantiateCoSimulation,
    /// `fmi3FreeInstance`.
    pub free_instance: FreeInstance,
    /// `fmi3EnterInitializationMode`.
    pub enter_initialization_mode: EnterInitializationMode,
    /// `fmi3ExitInitializationMode`.
    pub exit_initialization_mode: Call,
    /// `fmi3Terminate`.
    pub terminate: Call,
    /// `fmi3Reset`.
    pub reset: Call,
    /// `fmi3GetFloat64`.
    pub get_float64: GetValues<Float64>,
    /// `fmi3GetInt32`.
    pub get_int32: GetValues<Int32>,
    /// `fmi3GetInt64` (enumerations).
    pub get_int64: GetValues<Int64>,
    /// `fmi3GetBoolean`.
    pub get_boolean: GetValues<Boolean>,
    /// `fmi3SetFloat64`.
    pub set_float64: SetValues<Float64>,
    /// `fmi3SetInt32`.
    pub set_int32: SetValues<Int32>,
    /// `fmi3SetInt64` (enumerations).
    pub set_int64: SetValues<Int64>,
    /// `fmi3SetBoolean`.
    pub set_boolean: SetValues<Boolean>,
    /// The getters and setters of the other types, each resolved where the library
    /// exports it (every FMI 3.0 FMU must export them all, but one that lacks one loads;
    /// reading or setting that type is then refused naming the function).
    pub more: MoreValues,
    /// `fmi3DoStep`.
    pub do_step: DoStep,
    /// `fmi3GetFMUState`, `fmi3SetFMUState`, `fmi3FreeFMUState` when
    /// `canGetAndSetFMUState`.
    pub state: Option<(GetState, SetState, FreeState)>,
    /// `fmi3SerializedFMUStateSize`, `fmi3SerializeFMUState`, `fmi3DeserializeFMUState`
    /// when `canSerializeFMUState`.
    pub serialize: Option<(StateSize, Serialize, Deserialize)>,
}

/// A getter and a setter of one FMI 3.0 type, where the library exports both.
pub type GetSet<T> = Option<(GetValues<T>, SetValues<T>)>;

/// `fmi3Get*`/`fmi3Set*` of Float32, Int8 … UInt64 (but Int32 and Int64, which every
/// importer needs), String and Binary.
#[derive(Clone, Copy)]
pub struct MoreValues {
    /// `fmi3GetFloat32`, `fmi3SetFloat32`.
    pub float32: GetSet<f32>,
    /// `fmi3GetInt8`, `fmi3SetInt8`.
    pub int8: GetSet<i8>,
    /// `fmi3GetUInt8`, `fmi3SetUInt8`.
    pub uint8: GetSet<u8>,
    /// `fmi3GetInt16`, `fmi3SetInt16`.
    pub int16: GetSet<i16>,
    /// `fmi3GetUInt16`, `fmi3SetUInt16`.
    pub uint16: GetSet<u16>,
    /// `fmi3GetUInt32`, `fmi3SetUInt32`.
    pub uint32: GetSet<u32>,
    /// `fmi3GetUInt64`, `fmi3SetUInt64`.
    pub uint64: GetSet<u64>,
    /// `fmi3GetString`, `fmi3SetString`.
    pub string: GetSet<Str>,
    /// `fmi3GetBinary`, `fmi3SetBinary`.
    pub binary: Option<(GetBinary, SetBinary)>,
}

impl MoreValues {
    /// Resolves each pair that `library` exports.
    ///
    /// # Safety
    /// As [`Functions::load`].
    unsafe fn load(l: &Library, fmu: &str) -> MoreValues {
        use super::symbol as sym;
        // SAFETY (all): FMI 3.0 fixes each symbol's type as declared.
        unsafe {
            MoreValues {
                float32: sym(l, fmu, "fmi3GetFloat32")
                    .and_then(|g| Ok((g, sym(l, fmu, "fmi3SetFloat32")?)))
                    .ok(),
                int8: sym(l, fmu, "fmi3GetInt8")
                    .and_then(|g| Ok((g, sym(l, fmu, "fmi3SetInt8")?)))
                    .ok(),
                uint8: sym(l, fmu, "fmi3GetUInt8")
                    .and_then(|g| Ok((g, sym(l, fmu, "fmi3SetUInt8")?)))
                    .ok(),
                int16: sym(l, fmu, "fmi3GetInt16")
                    .and_then(|g| Ok((g, sym(l, fmu, "fmi3SetInt16")?)))
                    .ok(),
                uint16: sym(l, fmu, "fmi3GetUInt16")
                    .and_then(|g| Ok((g, sym(l, fmu, "fmi3SetUInt16")?)))
                    .ok(),
                uint32: sym(l, fmu, "fmi3GetUInt32")
                    .and_then(|g| Ok((g, sym(l, fmu, "fmi3SetUInt32")?)))
                    .ok(),
                uint64: sym(l, fmu, "fmi3GetUInt64")
                    .and_then(|g| Ok((g, sym(l, fmu, "fmi3SetUInt64")?)))
                    .ok(),
                string: sym(l, fmu, "fmi3GetString")
                    .and_then(|g| Ok((g, sym(l, fmu, "fmi3SetString")?)))
                    .ok(),
                binary: sym(l, fmu, "fmi3GetBinary")
                    .and_then(|g| Ok((g, sym(l, fmu, "fmi3SetBinary")?)))
                    .ok(),
            }
        }
    }
}

impl Functions {
    /// Resolves every function from `library`; `state` and `serialize` say whether the
    /// state functions are required. A missing one is [`FmuError::MissingSymbol`].
    ///
    /// # Safety
    /// `library` must be an FMI 3.0 binary: the symbols are taken to have the types
    /// above, which nothing at run time can check.
    pub unsafe fn load(
        library: &Library,
        fmu: &str,
        state: bool,
        serialize: bool,
    ) -> Result<Functions, FmuError> {
        use super::symbol as sym;
        // SAFETY (all): FMI 3.0 fixes each symbol's type as declared above.
        let l = library;
        unsafe {
            Ok(Functions {
                get_version: sym(l, fmu, "fmi3GetVersion")?,
                set_debug_logging: sym(l, fmu, "fmi3SetDebugLogging")?,
                instantiate: sym(l, fmu, "fmi3InstantiateCoSimulation")?,
                free_instance: sym(l, fmu, "fmi3FreeInstance")?,
                enter_initialization_mode: sym(l, fmu, "fmi3EnterInitializationMode")?,
                exit_initialization_mode: sym(l, fmu, "fmi3ExitInitializationMode")?,
                terminate: sym(l, fmu, "fmi3Terminate")?,
                reset: sym(l, fmu, "fmi3Reset")?,
                get_float64: sym(l, fmu, "fmi3GetFloat64")?,
                get_int32: sym(l, fmu, "fmi3GetInt32")?,
                get_int64: sym(l, fmu, "fmi3GetInt64")?,
                get_boolean: sym(l, fmu, "fmi3GetBoolean")?,
                set_float64: sym(l, fmu, "fmi3SetFloat64")?,
                set_int32: sym(l, fmu, "fmi3SetInt32")?,
                set_int64: sym(l, fmu, "fmi3SetInt64")?,
                set_boolean: sym(l, fmu, "fmi3SetBoolean")?,
                more: MoreValues::load(l, fmu),
                do_step: sym(l, fmu, "fmi3DoStep")?,
                state: if state {
                    Some((
                        sym(l, fmu, "fmi3GetFMUState")?,
                        sym(l, fmu, "fmi3SetFMUState")?,
                        sym(l, fmu, "fmi3FreeFMUState")?,
                    ))
                } else {
                    None
                },
                serialize: if serialize {
                    Some((
                        sym(l, fmu, "fmi3SerializedFMUStateSize")?,
                        sym(l, fmu, "fmi3SerializeFMUState")?,
                        sym(l, fmu, "fmi3DeserializeFMUState")?,
                    ))
                } else {
                    None
                },
            })
        }
    }
}

/// The FMI 3.0 platform tuples (`binaries/<tuple>/`) this loader knows, with their
/// library suffixes: one of them is this host's, the one it loads.
pub const PLATFORMS: [(&str, &str); 5] = [
    ("x86_64-linux", "so"),
    ("aarch64-linux", "so"),
    ("x86_64-darwin", "dylib"),
    ("aarch64-darwin", "dylib"),
    ("x86_64-windows", "dll"),
];

/// The FMI 3.0 platform tuple of this host (`x86_64-linux`) and its library suffix, or
/// `None` for a host not in [`PLATFORMS`].
pub fn host_platform() -> Option<(&'static str, &'static str)> {
    let tuple = if cfg!(all(target_os = "linux", target_arch = "x86_64")) {
        "x86_64-linux"
    } else if cfg!(all(target_os = "linux", target_arch = "aarch64")) {
        "aarch64-linux"
    } else if cfg!(all(target_os = "macos", target_arch = "x86_64")) {
        "x86_64-darwin"
    } else if cfg!(all(target_os = "macos", target_arch = "aarch64")) {
        "aarch64-darwin"
    } else if cfg!(all(target_os = "windows", target_arch = "x86_64")) {
        "x86_64-windows"
    } else {
        return None;
    };
    PLATFORMS.iter().copied().find(|(t, _)| *t == tuple)
}
