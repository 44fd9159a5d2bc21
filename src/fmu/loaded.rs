//! A loaded FMU: unpacked, described, its library open and its functions resolved.

use std::ffi::{CStr, CString};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

use libloading::Library;

use super::archive::{self, Unpacked};
use super::description::{CoSimulation, ModelDescription};
use super::instance::Instance;
use super::FmuError;
use super::{fmi2, fmi3};

/// The resolved function table of either FMI version.
#[derive(Clone, Copy)]
pub(crate) enum Api {
    /// An FMI 2.0 binary.
    Fmi2(fmi2::Functions),
    /// An FMI 3.0 binary.
    Fmi3(fmi3::Functions),
}

/// What instances and states share with their FMU, so that the library stays loaded and
/// the unpack directory stays on disk while any of them lives. Fields drop in order: the
/// library is closed before its directory is removed.
pub(crate) struct Loaded {
    /// The FMU's name (the scenario's node name), used in every message.
    pub(crate) name: String,
    /// The resolved functions; valid while `library` is loaded.
    pub(crate) api: Api,
    /// The description.
    pub(crate) description: ModelDescription,
    /// `file://` URI of `resources/`, NUL-terminated for C (FMI 2.0's
    /// `fmuResourceLocation`).
    pub(crate) resource_uri: CString,
    /// Path of `resources/` ending in the platform's separator, NUL-terminated for C
    /// (FMI 3.0's `resourcePath`, a plain path, not a URI).
    pub(crate) resource_path: CString,
    /// Live instances (for `canBeInstantiatedOnlyOncePerProcess`).
    pub(crate) instances: AtomicUsize,
    /// What every instance logged at warning and above ([`super::log`]).
    pub(crate) log: super::log::SharedLog,
    _library: Library,
    unpacked: Unpacked,
}

/// A loaded FMI 2.0 or FMI 3.0 co-simulation FMU; make instances with
/// [`Fmu::instantiate`].
pub struct Fmu {
    shared: Arc<Loaded>,
    path: PathBuf,
}

impl std::fmt::Debug for Fmu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Fmu")
            .field("name", &self.shared.name)
            .field("path", &self.path)
            .field("model", &self.shared.description.model_name)
            .field("hash", &self.hash())
            .finish_non_exhaustive()
    }
}

impl Fmu {
    /// Loads the FMU at `path` under the name `name` (the node it will be): unpacks it
    /// ([`archive::unpack`]), reads its description, requires co-simulation (FMI 2.0 or
    /// 3.0, by the description's `fmiVersion`), opens this platform's binary and resolves
    /// every function of that version the importer calls.
    pub fn load(name: &str, path: &Path) -> Result<Fmu, FmuError> {
        let unpacked = archive::unpack(path)?;
        let root = unpacked.root();
        let md_path = root.join("modelDescription.xml");
        let in_fmu = |e: FmuError| match e {
            FmuError::Description { field, message, .. } => FmuError::Description {
                file: format!("{}: modelDescription.xml", path.display()),
                field,
                message,
            },
            other => other,
        };
        let xml = std::fs::read_to_string(&md_path).map_err(|e| {
            in_fmu(FmuError::Description {
                file: String::new(),
                field: "(the file)".into(),
                message: format!("cannot be read: {e}"),
            })
        })?;
        let description = ModelDescription::parse(&xml).map_err(in_fmu)?;
        let Some(cs) = description.co_simulation.clone() else {
            return Err(FmuError::NotCoSimulation {
                fmu: name.to_string(),
                model: description.model_name.clone(),
            });
        };
        let v3 = description.is_fmi3();
        let library_path = binary(name, &root, &cs, v3)?;
        let library = open(name, &library_path)?;
        let (state, serialize) = (cs.can_get_and_set_fmu_state, cs.can_serialize_fmu_state);
        let api = if v3 {
            // SAFETY: the library is the FMU's FMI 3.0 binary, as its description says.
            let fns = unsafe { fmi3::Functions::load(&library, name, state, serialize) }?;
            // SAFETY: takes no argument and returns a static C string.
            let version = unsafe { c_text((fns.get_version)()) };
            check_text(name, "fmi3GetVersion", version, "3.0")?;
            Api::Fmi3(fns)
        } else {
            // SAFETY: the library is the FMU's FMI 2.0 binary, as its description says.
            let fns = unsafe { fmi2::Functions::load(&library, name, state, serialize) }?;
            // SAFETY: both functions take no argument and return a static C string.
            let version = unsafe { c_text((fns.get_version)()) };
            check_text(name, "fmi2GetVersion", version, "2.0")?;
            let platform = unsafe { c_text((fns.get_types_platform)()) };
            check_text(name, "fmi2GetTypesPlatform", platform, "default")?;
            Api::Fmi2(fns)
        };
        let resources = root.join("resources");
        let c_path = |what, text: String| {
            CString::new(text).map_err(|e| FmuError::NulByte {
                what,
                value: String::from_utf8_lossy(&e.into_vec()).replace('\0', "\\0"),
            })
        };
        let resource_uri = c_path("resource URI", file_uri(&resources))?;
        // FMI 3.0 asks for the path with a trailing separator, as FMPy passes it.
        let mut path_text = resources.to_string_lossy().into_owned();
        path_text.push(std::path::MAIN_SEPARATOR);
        let resource_path = c_path("resource path", path_text)?;
        Ok(Fmu {
            shared: Arc::new(Loaded {
                name: name.to_string(),
                api,
                description,
                resource_uri,
                resource_path,
                instances: AtomicUsize::new(0),
                log: super::log::SharedLog::default(),
                _library: library,
                unpacked,
            }),
            path: path.to_path_buf(),
        })
    }

    /// The FMU's name as given to [`Fmu::load`].
    pub fn name(&self) -> &str {
        &self.shared.name
    }

    /// The `.fmu` file it was loaded from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Its parsed `modelDescription.xml`.
    pub fn description(&self) -> &ModelDescription {
        &self.shared.description
    }

    /// The blake3 hash of the `.fmu` file (lower-case hex), for provenance records.
    pub fn hash(&self) -> &str {
        self.shared.unpacked.hash()
    }

    /// The `file://` URI of the unpacked `resources/` directory, as passed to
    /// `fmi2Instantiate` (no trailing slash, as FMPy passes it).
    pub fn resource_uri(&self) -> &str {
        self.shared.resource_uri.to_str().unwrap_or_default()
    }

    /// The path of the unpacked `resources/` directory with a trailing separator, as
    /// passed to `fmi3InstantiateCoSimulation` (FMI 3.0 takes a path, not a URI).
    pub fn resource_path(&self) -> &str {
        self.shared.resource_path.to_str().unwrap_or_default()
    }

    /// The messages its instances logged at warning and above, as summary.json keeps
    /// them ([`super::log`]): the kept ones and how many were not kept.
    pub fn messages(&self) -> (Vec<super::LogEntry>, u64) {
        let log = self.shared.log.lock().unwrap_or_else(|p| p.into_inner());
        (log.entries().to_vec(), log.not_kept())
    }

    /// Where the FMU is unpacked (removed when the FMU and all its instances are gone).
    pub fn unpack_dir(&self) -> PathBuf {
        self.shared.unpacked.root()
    }

    /// A new co-simulation instance called `instance_name`; `logging` turns the FMU's
    /// log messages to stderr on (`loggingOn`), off keeps it quiet.
    pub fn instantiate(&self, instance_name: &str, logging: bool) -> Result<Instance, FmuError> {
        let once = self
            .shared
            .description
            .co_simulation
            .as_ref()
            .is_some_and(|c| c.can_be_instantiated_only_once_per_process);
        // Count the instance before making it; `Instance` gives the count back when it
        // is freed or fails to be made.
        let before = self.shared.instances.fetch_add(1, Ordering::SeqCst);
        if once && before > 0 {
            self.shared.instances.fetch_sub(1, Ordering::SeqCst);
            return Err(FmuError::OnlyOnce {
                fmu: self.shared.name.clone(),
            });
        }
        Instance::new(Arc::clone(&self.shared), instance_name, logging)
    }
}

/// The binary for this host: `binaries/<platform>/<modelIdentifier>.<suffix>`, where
/// `<platform>` is FMI 2.0's name (`linux64`) or, for FMI 3.0, a tuple (`x86_64-linux`).
fn binary(fmu: &str, root: &Path, cs: &CoSimulation, v3: bool) -> Result<PathBuf, FmuError> {
    let id = &cs.model_identifier;
    let available = || {
        let mut v: Vec<String> = std::fs::read_dir(root.join("binaries"))
            .map(|rd| {
                rd.filter_map(|e| e.ok())
                    .filter(|e| e.path().is_dir())
                    .map(|e| e.file_name().to_string_lossy().into_owned())
                    .collect()
            })
            .unwrap_or_default();
        v.sort();
        v
    };
    let host = if v3 {
        fmi3::host_platform()
    } else {
        fmi2::host_platform()
    };
    let Some((platform, suffix)) = host else {
        return Err(FmuError::NoBinary {
            fmu: fmu.to_string(),
            wanted: format!(
                "none (FMI {} names no platform for {}-{})",
                if v3 { "3.0" } else { "2.0" },
                std::env::consts::ARCH,
                std::env::consts::OS
            ),
            available: available(),
        });
    };
    let rel = format!("binaries/{platform}/{id}.{suffix}");
    let path = root.join(&rel);
    if path.is_file() && !id.contains(['/', '\\']) {
        Ok(path)
    } else {
        Err(FmuError::NoBinary {
            fmu: fmu.to_string(),
            wanted: format!("{platform} ({rel})"),
            available: available(),
        })
    }
}

/// Opens the library; on Unix resolving every symbol now (`RTLD_NOW`), so a missing
/// dependency shows at load rather than mid-run, and keeping its symbols private
/// (`RTLD_LOCAL`), so two FMUs' `fmi2DoStep` never mix.
fn open(fmu: &str, path: &Path) -> Result<Library, FmuError> {
    let fail = |e: libloading::Error| FmuError::Library {
        fmu: fmu.to_string(),
        library: path.to_path_buf(),
        message: e.to_string(),
    };
    // SAFETY: loading runs the library's initializers: native code the user chose to
    // trust (module docs, "Trust").
    #[cfg(unix)]
    unsafe {
        use libloading::os::unix::{Library as Unix, RTLD_LOCAL, RTLD_NOW};
        Unix::open(Some(path), RTLD_NOW | RTLD_LOCAL)
            .map(Library::from)
            .map_err(fail)
    }
    #[cfg(not(unix))]
    unsafe {
        Library::new(path).map_err(fail)
    }
}

/// The text of a static C string (empty for null).
///
/// # Safety
/// `p` is null or NUL-terminated and lives long enough.
unsafe fn c_text(p: *const std::ffi::c_char) -> String {
    if p.is_null() {
        String::new()
    } else {
        // SAFETY: per the contract.
        unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
    }
}

/// `value` must be `expected`.
fn check_text(
    fmu: &str,
    function: &'static str,
    value: String,
    expected: &'static str,
) -> Result<(), FmuError> {
    if value == expected {
        Ok(())
    } else {
        Err(FmuError::BinaryMismatch {
            fmu: fmu.to_string(),
            function,
            value,
            expected,
        })
    }
}

/// `file://` URI of an absolute path, each byte outside RFC 3986's unreserved set, `/`
/// and `:` (a Windows drive) percent-encoded.
fn file_uri(path: &Path) -> String {
    let bytes = path.as_os_str().as_encoded_bytes();
    let mut s = String::from("file://");
    if !bytes.starts_with(b"/") {
        s.push('/');
    }
    for &b in bytes {
        match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'.' | b'_' | b'~' | b'/' | b':' => {
                s.push(b as char)
            }
            b'\\' => s.push('/'),
            _ => s.push_str(&format!("%{b:02X}")),
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_uris_escape_what_rfc_3986_reserves() {
        assert_eq!(
            file_uri(Path::new("/tmp/a b/résumé/resources")),
            "file:///tmp/a%20b/r%C3%A9sum%C3%A9/resources"
        );
    }
}
