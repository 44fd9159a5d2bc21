//! FMI 2.0 and FMI 3.0 co-simulation FMUs: unpack, describe, load and drive them
//! (issue 31).
//!
//! An FMU (Functional Mock-up Unit) is a zip archive holding a model in the FMI standard's
//! form: `modelDescription.xml` (the model's variables and capabilities), one compiled
//! shared library per platform under `binaries/<platform>/`, and optional `resources/`.
//! A co-simulation FMU brings its own solver: the importer sets inputs, calls
//! `fmi2DoStep(t, h)` (`fmi3DoStep`) and reads outputs at the communication points.
//!
//! Both versions are driven through the same [`Instance`] methods: [`Fmu::load`] reads
//! `fmiVersion` and resolves the FMI 2.0 ([`fmi2`]) or FMI 3.0 ([`fmi3`]) functions, and
//! each method calls its version's function.
//!
//! ```text
//!   plant.fmu ─archive::unpack─▶ private 0700 temp dir ─description::ModelDescription::parse─▶
//!   ─Fmu::load (dlopen binaries/linux64/<id>.so, resolve fmi2*;
//!               FMI 3.0: binaries/x86_64-linux/<id>.so, resolve fmi3*)─▶ Fmu ─instantiate─▶ Instance
//!
//!   Instance: setup_experiment → enter/exit_initialization_mode
//!             → { set_real/integer/boolean → do_step(t, h) → get_* } … → terminate
//!             get_state / set_state / serialize_state / deserialize_state where declared
//! ```
//!
//! # Trust
//!
//! An FMU's binary is native code that the user chose to run: it is loaded into this
//! process and runs with the tool's rights; nothing sandboxes it. The archive is unpacked
//! defensively (no path leaves the private directory, no symbolic links, size caps counted
//! on the bytes actually written: [`archive`]), but the library itself is trusted. A
//! crash inside it (a `SIGSEGV`, say) is not a Rust panic and cannot be caught: it kills
//! the process by that signal. Nothing half-written is left behind because dsmcosim
//! writes its outputs atomically at the end of a run.
//!
//! # Errors
//!
//! Every failure is an [`FmuError`]; every FMI call's status is checked, and `fmi2Discard`,
//! `fmi2Error`, `fmi2Fatal` and `fmi2Pending` (FMI 3.0: `fmi3Discard`, `fmi3Error`,
//! `fmi3Fatal`) become [`FmuError::Status`], except a step by which the FMU asks to end
//! the simulation ([`StepEnd::Stopped`]). What an FMU logs at warning and above is
//! printed and kept ([`log`]). What this loader supports: FMI 2.0 and 3.0,
//! co-simulation, on the platforms FMI 2.0 names (`linux64`, `linux32`, `darwin64`,
//! `win64`, `win32`) and the FMI 3.0 platform tuples of [`fmi3::PLATFORMS`]
//! (`x86_64-linux`, `aarch64-linux`, `x86_64-darwin`, `aarch64-darwin`,
//! `x86_64-windows`).

pub mod archive;
pub mod description;
pub mod fmi2;
pub mod fmi3;
pub mod instance;
pub mod loaded;
pub mod log;
pub mod value;

use std::path::PathBuf;

pub use archive::{unpack, unpack_with_limits, Limits, Unpacked};
pub use description::{
    Causality, CoSimulation, Dimension, ModelDescription, ScalarVariable, VarKind, Variability,
    MAX_ARRAY_ELEMENTS,
};
pub use instance::{FmuState, Instance, StepEnd};
pub use loaded::Fmu;
pub use log::{FmuLog, LogEntry};
pub use value::{Value, MAX_VALUE_BYTES};

/// Everything that can go wrong while unpacking, describing, loading or driving an FMU.
#[derive(Debug, thiserror::Error)]
pub enum FmuError {
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The operating-system error.
        #[source]
        source: std::io::Error,
    },
    /// The `.fmu` file is not a readable zip archive.
    #[error("{}: not an FMU: not a readable zip archive ({message})", path.display())]
    NotZip {
        /// The file given as an FMU.
        path: PathBuf,
        /// What the zip reader reported.
        message: String,
    },
    /// An entry of the archive could not be read (corrupt data, a bad checksum).
    #[error("archive entry '{entry}': {source}")]
    Entry {
        /// The entry's name as stored in the archive.
        entry: String,
        /// The read or write error.
        #[source]
        source: std::io::Error,
    },
    /// An entry would be written outside the unpack directory, or is a symbolic link.
    #[error("archive entry '{entry}' refused: {reason}")]
    UnsafeEntry {
        /// The entry's name as stored in the archive.
        entry: String,
        /// Why it is refused.
        reason: &'static str,
    },
    /// A size or count cap of [`archive`] was exceeded.
    #[error("{what} exceeds its cap of {limit} ({value} counted)")]
    CapExceeded {
        /// Which cap (its constant's name) and what it measured.
        what: String,
        /// The count or byte total reached when the unpack stopped.
        value: u64,
        /// The cap.
        limit: u64,
    },
    /// `modelDescription.xml` is missing, not XML, or lacks or malforms a field.
    #[error("{file}: {field}: {message}")]
    Description {
        /// The description file (inside which FMU, where known).
        file: String,
        /// The element or attribute at fault (`fmiModelDescription@guid`).
        field: String,
        /// What is wrong, with the offending value.
        message: String,
    },
    /// The FMU is of an FMI version this loader does not read.
    #[error(
        "fmiVersion '{version}': FMI {version} is not supported by this loader \
         (it reads FMI 2.0 and FMI 3.0 co-simulation FMUs)"
    )]
    UnsupportedVersion {
        /// The `fmiVersion` attribute.
        version: String,
    },
    /// The FMU has no `<CoSimulation>` element (model exchange only).
    #[error("FMU '{fmu}' (model '{model}') is not a co-simulation FMU: its modelDescription.xml has no <CoSimulation> element")]
    NotCoSimulation {
        /// The FMU's name in the scenario.
        fmu: String,
        /// The `modelName` attribute.
        model: String,
    },
    /// The FMU carries no binary for this host's platform.
    #[error(
        "FMU '{fmu}' has no binary for this platform: wanted {wanted}; it has binaries for: {}",
        if available.is_empty() { "none".to_string() } else { available.join(", ") }
    )]
    NoBinary {
        /// The FMU's name in the scenario.
        fmu: String,
        /// The platform folder and file wanted (`binaries/linux64/msd.so`,
        /// `binaries/x86_64-linux/msd3.so`).
        wanted: String,
        /// The subdirectories of `binaries/` the FMU has, sorted.
        available: Vec<String>,
    },
    /// The shared library could not be loaded (`dlopen` failed).
    #[error("FMU '{fmu}': cannot load {}: {message}", library.display())]
    Library {
        /// The FMU's name in the scenario.
        fmu: String,
        /// The shared library's path inside the unpack directory.
        library: PathBuf,
        /// What the dynamic loader reported.
        message: String,
    },
    /// A function the importer needs is not exported by the FMU's library.
    #[error("FMU '{fmu}': its library does not export {symbol}")]
    MissingSymbol {
        /// The FMU's name in the scenario.
        fmu: String,
        /// The C function name (`fmi2DoStep`, `fmi3DoStep`).
        symbol: &'static str,
    },
    /// The binary reports another FMI version (or FMI 2.0 types platform) than its
    /// description's.
    #[error("FMU '{fmu}': {function} returned '{value}', expected '{expected}'")]
    BinaryMismatch {
        /// The FMU's name in the scenario.
        fmu: String,
        /// `fmi2GetVersion`, `fmi2GetTypesPlatform` or `fmi3GetVersion`.
        function: &'static str,
        /// What it returned.
        value: String,
        /// What the standard requires.
        expected: &'static str,
    },
    /// An FMI call returned `fmi2Discard`, `fmi2Error`, `fmi2Fatal` or `fmi2Pending`
    /// (FMI 3.0: `fmi3Discard`, `fmi3Error` or `fmi3Fatal`).
    #[error(
        "FMU '{fmu}': {function} returned {status}{}",
        time.map(|t| format!(" at t = {t} s")).unwrap_or_default()
    )]
    Status {
        /// The FMU instance's name.
        fmu: String,
        /// The FMI function called.
        function: &'static str,
        /// The simulated time of the call [s], where one applies.
        time: Option<f64>,
        /// The status returned (`fmi2Error`, `fmi3Error`).
        status: &'static str,
    },
    /// An earlier call returned `fmi2Fatal` (`fmi3Fatal`): the standard allows no further
    /// call.
    #[error("FMU '{fmu}': {function} not called: an earlier call returned {status}")]
    Unusable {
        /// The FMU instance's name.
        fmu: String,
        /// The FMI function refused.
        function: &'static str,
        /// The fatal status's C name (`fmi2Fatal`, `fmi3Fatal`).
        status: &'static str,
    },
    /// An FMI 3.0 enumeration's value (an `Int64` at the ABI) does not fit the `i32` of
    /// [`Instance::get_integer`].
    #[error("FMU '{fmu}': {function} gave {value} for value reference {value_reference}, outside the 32-bit integers")]
    OutOfRange {
        /// The FMU instance's name.
        fmu: String,
        /// The FMI function (`fmi3GetInt64`).
        function: &'static str,
        /// The variable's value reference.
        value_reference: u32,
        /// The value read.
        value: i64,
    },
    /// A value an FMU gave (or was to be given) is not one of its variable's type: a
    /// null String or Binary pointer, a value outside the type's range.
    #[error("FMU '{fmu}': {function}, value reference {value_reference}: {message}")]
    BadValue {
        /// The FMU instance's name.
        fmu: String,
        /// The FMI function.
        function: &'static str,
        /// The variable's value reference.
        value_reference: u32,
        /// What is wrong with the value.
        message: String,
    },
    /// The FMU's description does not declare a capability the call needs; the FMU was
    /// not called.
    #[error("FMU '{fmu}': {function} refused: its modelDescription.xml does not declare {capability}=\"true\"")]
    CapabilityMissing {
        /// The FMU's name.
        fmu: String,
        /// The capability flag (`canGetAndSetFMUstate`, `canSerializeFMUstate`; in FMI 3.0
        /// `canGetAndSetFMUState`, `canSerializeFMUState`).
        capability: &'static str,
        /// The FMI function that was not called.
        function: &'static str,
    },
    /// `fmi2Instantiate` (`fmi3InstantiateCoSimulation`) returned a null instance.
    #[error("FMU '{fmu}': {function} returned null for instance '{instance}'")]
    NullInstance {
        /// The FMU's name.
        fmu: String,
        /// `fmi2Instantiate` or `fmi3InstantiateCoSimulation`.
        function: &'static str,
        /// The instance name passed.
        instance: String,
    },
    /// `fmi2GetFMUstate` or `fmi2DeSerializeFMUstate` (or their FMI 3.0 counterparts)
    /// returned success and a null state.
    #[error("FMU '{fmu}': {function} returned a null FMU state")]
    NullState {
        /// The FMU's name.
        fmu: String,
        /// The FMI function.
        function: &'static str,
    },
    /// A second instance of an FMU that declares `canBeInstantiatedOnlyOncePerProcess`.
    #[error(
        "FMU '{fmu}' declares canBeInstantiatedOnlyOncePerProcess and already has an instance"
    )]
    OnlyOnce {
        /// The FMU's name.
        fmu: String,
    },
    /// A call's argument slices differ in length.
    #[error("FMU '{fmu}': {function} given {refs} value references and {values} values")]
    LengthMismatch {
        /// The FMU instance's name.
        fmu: String,
        /// The FMI function.
        function: &'static str,
        /// Number of value references.
        refs: usize,
        /// Number of values.
        values: usize,
    },
    /// A state was passed to an instance other than the one that made it.
    #[error("FMU '{fmu}': {function} given a state of another instance")]
    ForeignState {
        /// The FMU instance's name.
        fmu: String,
        /// The FMI function.
        function: &'static str,
    },
    /// A name passed to C contains a NUL byte.
    #[error("{what} '{value}' contains a NUL byte")]
    NulByte {
        /// What the string is (`instance name`).
        what: &'static str,
        /// The string, NUL shown as `\0`.
        value: String,
    },
}

/// Resolves the symbol `name` of an FMU's `library` to a copy of its function pointer;
/// a missing one is [`FmuError::MissingSymbol`] naming it (both FMI versions' tables
/// load through this).
///
/// # Safety
/// `T` must be the symbol's true type, which nothing at run time can check.
pub(crate) unsafe fn symbol<T: Copy>(
    library: &libloading::Library,
    fmu: &str,
    name: &'static str,
) -> Result<T, FmuError> {
    // SAFETY: the caller vouches for the type.
    unsafe { library.get::<T>(name.as_bytes()) }
        .map(|s| *s)
        .map_err(|_| FmuError::MissingSymbol {
            fmu: fmu.to_string(),
            symbol: name,
        })
}
