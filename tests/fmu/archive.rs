//! Unpacking: unsafe entries, caps counted on the bytes written, non-zip files, the
//! private directory and the archive's hash.

use std::path::{Path, PathBuf};

use dsmcosim::fmu::{unpack, unpack_with_limits, FmuError, Limits};

use crate::fmu_build::write_zip;

/// Writes `content` to `dir/name` and returns the path.
fn file(dir: &Path, name: &str, content: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, content).expect("write a fixture file");
    p
}

/// A zip at `dir/name` whose entries hold `content` each.
fn zip_of(dir: &Path, name: &str, entries: &[&str], content: &[u8]) -> PathBuf {
    let data = file(dir, "data.bin", content);
    let out = dir.join(name);
    let list: Vec<(String, PathBuf)> = entries
        .iter()
        .map(|e| (e.to_string(), data.clone()))
        .collect();
    write_zip(&out, &list).expect("write the zip");
    out
}

#[test]
fn an_entry_that_climbs_out_is_refused_by_name() {
    let dir = tempfile::tempdir().expect("tempdir");
    for evil in [
        "../evil",
        "a/../../evil",
        "resources/../modelDescription.xml",
    ] {
        let path = zip_of(
            dir.path(),
            "evil.fmu",
            &["modelDescription.xml", evil],
            b"x",
        );
        match unpack(&path) {
            Err(e @ FmuError::UnsafeEntry { .. }) => {
                assert!(e.to_string().contains(&format!("'{evil}'")), "{e}");
            }
            other => panic!("{evil}: expected the unsafe-entry refusal, got {other:?}"),
        }
    }
}

#[test]
fn a_symbolic_link_entry_is_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("link.fmu");
    let file = std::fs::File::create(&out).expect("create");
    let mut zip = zip::ZipWriter::new(file);
    let options = zip::write::SimpleFileOptions::default();
    zip.add_symlink("resources/passwd", "/etc/passwd", options)
        .expect("add a symlink entry");
    zip.finish().expect("finish");
    match unpack(&out) {
        Err(e @ FmuError::UnsafeEntry { .. }) => {
            let text = e.to_string();
            assert!(
                text.contains("resources/passwd") && text.contains("symbolic link"),
                "{text}"
            );
        }
        other => panic!("expected the symlink refusal, got {other:?}"),
    }
}

#[test]
fn caps_are_counted_on_the_bytes_written() {
    let dir = tempfile::tempdir().expect("tempdir");
    // Highly compressible: 100 kB of zeros deflate to a few hundred bytes.
    let zeros = vec![0u8; 100_000];
    let path = zip_of(
        dir.path(),
        "big.fmu",
        &["resources/a.bin", "resources/b.bin"],
        &zeros,
    );
    let loose = Limits::default();
    assert!(unpack_with_limits(&path, &loose).is_ok());

    let one = Limits {
        entry_bytes: 99_999,
        ..loose
    };
    match unpack_with_limits(&path, &one) {
        Err(e @ FmuError::CapExceeded { .. }) => {
            let text = e.to_string();
            assert!(
                text.contains("MAX_ENTRY_BYTES") && text.contains("resources/a.bin"),
                "{text}"
            );
        }
        other => panic!("entry cap: got {other:?}"),
    }
    let total = Limits {
        total_bytes: 150_000,
        ..loose
    };
    match unpack_with_limits(&path, &total) {
        Err(FmuError::CapExceeded { what, limit, .. }) => {
            assert!(what.contains("MAX_TOTAL_BYTES"), "{what}");
            assert_eq!(limit, 150_000);
        }
        other => panic!("total cap: got {other:?}"),
    }
    let count = Limits {
        entries: 1,
        ..loose
    };
    match unpack_with_limits(&path, &count) {
        Err(FmuError::CapExceeded { what, value, .. }) => {
            assert!(what.contains("MAX_ENTRIES"), "{what}");
            assert_eq!(value, 2);
        }
        other => panic!("entry count cap: got {other:?}"),
    }
    let size = std::fs::metadata(&path).expect("metadata").len();
    let archive = Limits {
        archive_bytes: size - 1,
        ..loose
    };
    match unpack_with_limits(&path, &archive) {
        Err(FmuError::CapExceeded { what, value, .. }) => {
            assert!(what.contains("MAX_ARCHIVE_BYTES"), "{what}");
            assert_eq!(value, size);
        }
        other => panic!("archive cap: got {other:?}"),
    }
}

#[test]
fn a_file_that_is_not_a_zip_is_refused_as_such() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = file(dir.path(), "plain.fmu", b"<fmiModelDescription/>");
    match unpack(&path) {
        Err(e @ FmuError::NotZip { .. }) => {
            let text = e.to_string();
            assert!(
                text.contains("plain.fmu") && text.contains("not a readable zip"),
                "{text}"
            );
        }
        other => panic!("expected the not-a-zip error, got {other:?}"),
    }
    let missing = dir.path().join("absent.fmu");
    assert!(matches!(unpack(&missing), Err(FmuError::Io { .. })));
}

#[test]
fn the_unpack_is_private_hashed_and_removed_on_drop() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = zip_of(
        dir.path(),
        "ok.fmu",
        &["modelDescription.xml", "resources/d/e.txt"],
        b"hello",
    );
    let unpacked = unpack(&path).expect("unpack");
    let root = unpacked.root();
    assert_eq!(
        std::fs::read(root.join("resources/d/e.txt")).expect("read"),
        b"hello"
    );
    let bytes = std::fs::read(&path).expect("read the archive");
    assert_eq!(unpacked.hash(), blake3::hash(&bytes).to_hex().as_str());
    use std::os::unix::fs::PermissionsExt;
    let private = root.parent().expect("the private directory");
    let mode = std::fs::metadata(private)
        .expect("metadata")
        .permissions()
        .mode();
    assert_eq!(mode & 0o777, 0o700, "mode {mode:o}");
    let entries: Vec<_> = std::fs::read_dir(private).expect("list").collect();
    assert_eq!(
        entries.len(),
        1,
        "only the unpacked tree remains, not the archive's copy"
    );
    drop(unpacked);
    assert!(!private.exists());
}
