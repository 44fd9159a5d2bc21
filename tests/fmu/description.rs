//! modelDescription.xml: missing fields are named, an unknown FMI version is refused,
//! variables found (FMI 3.0 descriptions: `fmi3.rs`).

use dsmcosim::fmu::{Causality, FmuError, ModelDescription, Value, VarKind, Variability};

use crate::fmu_build::fmus_dir;

fn msd_xml() -> String {
    std::fs::read_to_string(fmus_dir().join("msd.xml")).expect("tests/fmus/msd.xml")
}

#[test]
fn a_missing_guid_is_named() {
    let xml = msd_xml();
    let start = xml.find("guid=").expect("msd.xml has a guid");
    let end = start + xml[start..].find("}\"").expect("guid's end") + 2;
    let without = format!("{}{}", &xml[..start], &xml[end..]);
    match ModelDescription::parse(&without) {
        Err(e @ FmuError::Description { .. }) => {
            let text = e.to_string();
            assert!(text.contains("guid") && text.contains("missing"), "{text}");
        }
        other => panic!("expected a description error, got {other:?}"),
    }
}

#[test]
fn an_unknown_fmi_version_is_refused_with_its_version() {
    let xml = msd_xml().replace("fmiVersion=\"2.0\"", "fmiVersion=\"2.5\"");
    match ModelDescription::parse(&xml) {
        Err(e @ FmuError::UnsupportedVersion { .. }) => {
            let text = e.to_string();
            assert!(
                text.contains("'2.5'") && text.contains("not supported"),
                "{text}"
            );
        }
        other => panic!("expected the version refusal, got {other:?}"),
    }
}

#[test]
fn variables_are_found_by_name_with_their_attributes() {
    let d = ModelDescription::parse(&msd_xml()).expect("msd.xml parses");
    assert_eq!(d.fmi_version, "2.0");
    assert_eq!(d.model_name, "msd");
    assert_eq!(d.default_experiment_step, Some(0.001));
    let cs = d.co_simulation.as_ref().expect("co-simulation");
    assert_eq!(cs.model_identifier, "msd");
    assert!(cs.can_get_and_set_fmu_state && cs.can_serialize_fmu_state);
    assert!(cs.can_handle_variable_communication_step_size);
    assert!(!cs.can_be_instantiated_only_once_per_process);
    let k = d.variable("k").expect("k");
    assert_eq!(
        (
            k.value_reference,
            k.causality,
            k.variability,
            k.kind,
            k.start.clone()
        ),
        (
            1,
            Causality::Parameter,
            Variability::Fixed,
            VarKind::Real,
            Some(Value::Float(4.0))
        )
    );
    let f = d.variable("F").expect("F");
    assert_eq!(
        (f.causality, f.variability, f.start.clone()),
        (
            Causality::Input,
            Variability::Continuous,
            Some(Value::Float(0.0))
        )
    );
    let a = d.variable("a").expect("a");
    assert_eq!(
        (a.value_reference, a.causality, a.start.clone()),
        (8, Causality::Output, None)
    );
    assert!(d.variable("K").is_none(), "names are case-sensitive");
    assert_eq!(d.variables.len(), 9);
}
