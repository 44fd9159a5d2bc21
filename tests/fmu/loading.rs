//! Loading: every test FMU loads; a missing platform binary, a missing function and a
//! model-exchange-only description are refused with what is missing.

use std::path::PathBuf;

use dsmcosim::fmu::{Fmu, FmuError};

use crate::fmu_build::{build_fmu, build_test_fmu, fmus_dir, write_zip, TEST_FMUS};

#[test]
fn every_test_fmu_loads_and_names_its_model() {
    let dir = tempfile::tempdir().expect("tempdir");
    for stem in TEST_FMUS {
        let path = build_test_fmu(stem, dir.path()).expect("build");
        let fmu = Fmu::load(stem, &path).unwrap_or_else(|e| panic!("{stem}: {e}"));
        assert_eq!(fmu.description().model_name, stem);
        assert!(
            fmu.resource_uri().starts_with("file:///"),
            "{}",
            fmu.resource_uri()
        );
        assert!(fmu.resource_uri().ends_with("/resources"));
        let bytes = std::fs::read(&path).expect("read");
        assert_eq!(fmu.hash(), blake3::hash(&bytes).to_hex().as_str());
    }
}

#[test]
fn an_fmu_without_this_platform_lists_the_platforms_it_has() {
    let dir = tempfile::tempdir().expect("tempdir");
    let dll = dir.path().join("msd.dll");
    std::fs::write(&dll, b"MZ not really").expect("write");
    let path = dir.path().join("win.fmu");
    let entries: Vec<(String, PathBuf)> = vec![
        ("modelDescription.xml".into(), fmus_dir().join("msd.xml")),
        ("binaries/win64/msd.dll".into(), dll),
    ];
    write_zip(&path, &entries).expect("zip");
    match Fmu::load("plant", &path) {
        Err(FmuError::NoBinary {
            available,
            ref wanted,
            ..
        }) if available == ["win64"] => {
            assert!(wanted.contains("linux64"), "{wanted}");
        }
        Err(e) => panic!("expected the platform error listing win64, got {e}"),
        Ok(_) => panic!("a win64-only FMU loaded on linux64"),
    }
    let text = Fmu::load("plant", &path)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        text.contains("'plant'") && text.contains("win64") && text.contains("linux64"),
        "{text}"
    );
}

#[test]
fn a_library_missing_a_function_is_refused_naming_it() {
    let dir = tempfile::tempdir().expect("tempdir");
    let src = dir.path().join("partial.c");
    std::fs::write(
        &src,
        "__attribute__((visibility(\"default\"))) const char *fmi2GetTypesPlatform(void) { return \"default\"; }\n\
         __attribute__((visibility(\"default\"))) const char *fmi2GetVersion(void) { return \"2.0\"; }\n",
    )
    .expect("write");
    let path = build_fmu(
        &src,
        &fmus_dir().join("msd.xml"),
        "msd",
        &dir.path().join("p.fmu"),
    )
    .expect("build");
    match Fmu::load("plant", &path) {
        Err(e @ FmuError::MissingSymbol { .. }) => {
            let text = e.to_string();
            assert!(
                text.contains("fmi2SetDebugLogging") && text.contains("'plant'"),
                "{text}"
            );
        }
        other => panic!("expected the missing-symbol error, got {other:?}"),
    }
}

#[test]
fn a_model_exchange_only_fmu_is_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let xml = std::fs::read_to_string(fmus_dir().join("pd.xml")).expect("pd.xml");
    let start = xml.find("<CoSimulation").expect("CoSimulation");
    let end = start + xml[start..].find("/>").expect("its end") + 2;
    let me = format!(
        "{}<ModelExchange modelIdentifier=\"pd\"/>{}",
        &xml[..start],
        &xml[end..]
    );
    let me_xml = dir.path().join("pd_me.xml");
    std::fs::write(&me_xml, me).expect("write");
    let path = build_fmu(
        &fmus_dir().join("pd.c"),
        &me_xml,
        "pd",
        &dir.path().join("me.fmu"),
    )
    .expect("build");
    match Fmu::load("ctl", &path) {
        Err(e @ FmuError::NotCoSimulation { .. }) => {
            assert!(e.to_string().contains("not a co-simulation FMU"), "{e}");
        }
        other => panic!("expected the not-co-simulation error, got {other:?}"),
    }
}
