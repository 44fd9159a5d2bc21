//! Builds a test FMU from a C source and a model description: compiles the source with
//! the system C compiler into a shared library and zips it with the description in the
//! layout of the description's FMI version (`modelDescription.xml` and
//! `binaries/linux64/<id>.so` for FMI 2.0, `binaries/x86_64-linux/<id>.so` for FMI 3.0).
//! Shared by `tests/fmu` and `examples/build_fmus.rs`.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The test FMUs under `tests/fmus/`: each `<stem>.c` with its `<stem>.xml`; the stem
/// is also the model identifier. `msd3` is msd in FMI 3.0 form; `types` and `types3`
/// have an output of every FMI 2.0 and FMI 3.0 type (and arrays, in FMI 3.0).
pub const TEST_FMUS: [&str; 7] = ["msd", "pd", "faulty", "msd3", "quirks", "types", "types3"];

/// Where a test reads shipped scenario `file` from: the file itself, or, for a scene with
/// FMUs (which reads `fmu/*.fmu` beside it, built for users by `cargo run --example
/// build_fmus -- scenarios/fmu` and absent from a plain checkout), a copy of it in
/// `scratch` beside the test FMUs built into `scratch/fmu/`.
#[allow(dead_code)] // not every includer reads shipped scenarios
pub fn beside_test_fmus(file: &Path, scratch: &Path) -> Result<PathBuf, String> {
    let text = std::fs::read_to_string(file).map_err(|e| format!("{}: {e}", file.display()))?;
    let v: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", file.display()))?;
    if v.get("fmus").is_none() {
        return Ok(file.to_path_buf());
    }
    let dir = scratch.join("fmu");
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    for stem in TEST_FMUS {
        if !dir.join(format!("{stem}.fmu")).exists() {
            build_test_fmu(stem, &dir)?;
        }
    }
    let copy = scratch.join(file.file_name().ok_or("a scenario file has a name")?);
    std::fs::write(&copy, text).map_err(|e| format!("{}: {e}", copy.display()))?;
    Ok(copy)
}

/// Builds the test FMU `stem` (one of [`TEST_FMUS`]) as `<dir>/<stem>.fmu`.
pub fn build_test_fmu(stem: &str, dir: &Path) -> Result<PathBuf, String> {
    let src = fmus_dir().join(format!("{stem}.c"));
    let xml = fmus_dir().join(format!("{stem}.xml"));
    build_fmu(&src, &xml, stem, &dir.join(format!("{stem}.fmu")))
}

/// `tests/fmus/` of this checkout.
pub fn fmus_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fmus")
}

/// Builds `out` (a `.fmu`) from the C file `src` and the description `xml`: compiles with
/// `$CC` (default `cc`) `-shared -fPIC -O2 -std=c99 -Wall -Werror` in a private temporary
/// directory, with the source's directory on the include path, then zips. The binary's
/// folder follows the description's `fmiVersion`: FMI 3.0 names platforms by tuples
/// (`x86_64-linux`), FMI 2.0 by its own names (`linux64`). Returns `out`.
pub fn build_fmu(
    src: &Path,
    xml: &Path,
    model_identifier: &str,
    out: &Path,
) -> Result<PathBuf, String> {
    let text = std::fs::read_to_string(xml).map_err(|e| format!("{}: {e}", xml.display()))?;
    let fmi3 = text.contains("fmiVersion=\"3.0\"");
    let (platform, suffix) = match (cfg!(target_os = "macos"), fmi3) {
        (true, false) => ("darwin64", "dylib"),
        (true, true) if cfg!(target_arch = "aarch64") => ("aarch64-darwin", "dylib"),
        (true, true) => ("x86_64-darwin", "dylib"),
        (false, false) => ("linux64", "so"),
        (false, true) if cfg!(target_arch = "aarch64") => ("aarch64-linux", "so"),
        (false, true) => ("x86_64-linux", "so"),
    };
    let tmp = tempfile::tempdir().map_err(|e| format!("temporary directory: {e}"))?;
    let lib = tmp.path().join(format!("{model_identifier}.{suffix}"));
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let include = src.parent().unwrap_or(Path::new("."));
    let output = Command::new(&cc)
        .args(["-shared", "-fPIC", "-O2", "-std=c99", "-Wall", "-Werror"])
        .arg("-I")
        .arg(include)
        .arg("-o")
        .arg(&lib)
        .arg(src)
        .arg("-lm")
        .output()
        .map_err(|e| format!("cannot run the C compiler '{cc}': {e}"))?;
    if !output.status.success() {
        return Err(format!(
            "{cc} failed on {}: {}\n{}",
            src.display(),
            output.status,
            String::from_utf8_lossy(&output.stderr)
        ));
    }
    let entries = [
        ("modelDescription.xml".to_string(), xml.to_path_buf()),
        (
            format!("binaries/{platform}/{model_identifier}.{suffix}"),
            lib,
        ),
    ];
    write_zip(out, &entries)?;
    Ok(out.to_path_buf())
}

/// Writes a zip at `out` whose entries are `(name in the archive, file to store)`,
/// deflated.
pub fn write_zip(out: &Path, entries: &[(String, PathBuf)]) -> Result<(), String> {
    let file = File::create(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let mut zip = zip::ZipWriter::new(file);
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        // A fixed time (the format's epoch, 1980-01-01) instead of now: the same sources
        // build the same bytes, so an FMU's hash in summary.json is reproducible.
        .last_modified_time(zip::DateTime::default())
        .unix_permissions(0o644);
    for (name, path) in entries {
        let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        zip.start_file(name.as_str(), options)
            .and_then(|()| zip.write_all(&bytes).map_err(Into::into))
            .map_err(|e| format!("{}: entry {name}: {e}", out.display()))?;
    }
    zip.finish()
        .map_err(|e| format!("{}: {e}", out.display()))?;
    Ok(())
}
