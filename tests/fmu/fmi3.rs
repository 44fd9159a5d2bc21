//! FMI 3.0 co-simulation behind the same API: msd3 (msd.c's model in FMI 3.0 form)
//! against the closed form, against msd bit for bit, with saved states, in a loop with
//! the FMI 2.0 PD controller through the simulator, and its description and errors.

use std::path::{Path, PathBuf};

use dsmcosim::fmu::{
    Causality, Dimension, Fmu, FmuError, ModelDescription, StepEnd, Value, VarKind, Variability,
};
use serde_json::json;

use crate::closed_form;
use crate::cosim::{closed_loop, run};
use crate::fmu_build::{build_fmu, build_test_fmu, fmus_dir, write_zip};
use crate::fmus::{load, real, scratch, start, vr};
use crate::states;

fn msd3_xml() -> String {
    std::fs::read_to_string(fmus_dir().join("msd3.xml")).expect("tests/fmus/msd3.xml")
}

/// Builds msd3 from `xml` (a variant of msd3.xml) and `defines` (C lines put before
/// msd3.c) into `dir` and loads it as `name`.
fn variant(dir: &Path, xml: &str, defines: &str, name: &str) -> Result<Fmu, FmuError> {
    let xml_path = dir.join(format!("{name}.xml"));
    std::fs::write(&xml_path, xml).expect("write xml");
    let src = dir.join(format!("{name}.c"));
    let msd3 = fmus_dir().join("msd3.c");
    std::fs::write(
        &src,
        format!("{defines}\n#include \"{}\"\n", msd3.display()),
    )
    .expect("write c");
    let path = build_fmu(&src, &xml_path, "msd3", &dir.join(format!("{name}.fmu")))
        .unwrap_or_else(|e| panic!("building {name}: {e}"));
    Fmu::load(name, &path)
}

#[test]
fn msd3_matches_the_closed_form() {
    for f in [0.0, 2.0] {
        let worst = closed_form::check("msd3", f);
        assert!(worst <= 1e-9, "F = {f} N: {worst:e}");
    }
}

#[test]
fn msd3_and_msd_stepped_alike_give_the_same_bits() {
    let (fmu2, fmu3) = (load("msd", "plant2"), load("msd3", "plant3"));
    let params = [("m", 1.5), ("c", 0.3), ("v0", 0.5)];
    let mut a = start(&fmu2, "plant2", &params);
    let mut b = start(&fmu3, "plant3", &params);
    let (x2, x3) = (vr(&fmu2, "x"), vr(&fmu3, "x"));
    // Steps of varying size (1 ms, 0.25 ms, 2.5 ms) and a force that changes per step.
    let mut t = 0.0;
    for i in 0..3000u32 {
        let h = [1e-3, 2.5e-4, 2.5e-3][(i % 3) as usize];
        let force = (f64::from(i) * 0.01).sin();
        a.set_real(&[vr(&fmu2, "F")], &[force]).expect("msd F");
        b.set_real(&[vr(&fmu3, "F")], &[force]).expect("msd3 F");
        a.do_step(t, h)
            .unwrap_or_else(|e| panic!("msd step {i}: {e}"));
        b.do_step(t, h)
            .unwrap_or_else(|e| panic!("msd3 step {i}: {e}"));
        t += h;
        let (p, q) = (real(&a, x2), real(&b, x3));
        assert_eq!(
            p.to_bits(),
            q.to_bits(),
            "step {i} (t = {t} s): msd x = {p}, msd3 x = {q}"
        );
    }
    assert!((real(&b, x3) - 1.0).abs() > 0.1, "x must move");
    assert_eq!(
        b.time(),
        Some(t),
        "the instance's time is the last point reached"
    );
}

#[test]
fn msd3_restores_a_saved_state_bit_for_bit() {
    states::restoring_repeats("msd3");
}

#[test]
fn msd3_resumes_a_serialized_state_in_a_fresh_instance_bit_for_bit() {
    states::serialized_resumes("msd3");
}

#[test]
fn an_fmi3_description_parses_with_its_token_capabilities_and_variables() {
    let d = ModelDescription::parse(&msd3_xml()).expect("msd3.xml parses");
    assert_eq!(d.fmi_version, "3.0");
    assert!(d.is_fmi3());
    assert_eq!(d.model_name, "msd3");
    assert_eq!(d.guid, "{b3f1d6a2-7c4e-4f0a-9e21-5d8c3a6b7f03}");
    assert_eq!(d.default_experiment_step, Some(0.001));
    let cs = d.co_simulation.as_ref().expect("co-simulation");
    assert_eq!(cs.model_identifier, "msd3");
    assert!(cs.can_get_and_set_fmu_state && cs.can_serialize_fmu_state);
    assert!(cs.can_handle_variable_communication_step_size);
    assert!(!cs.can_be_instantiated_only_once_per_process);
    assert_eq!(d.variables.len(), 10);
    let time = d.variable("time").expect("time");
    assert_eq!(
        (time.value_reference, time.causality),
        (9, Causality::Independent)
    );
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
    let a = d.variable("a").expect("a");
    assert_eq!(
        (a.value_reference, a.causality, a.start.clone()),
        (8, Causality::Output, None)
    );

    // Every FMI 3.0 type loads as its own kind, keeping its element name, an array with
    // its dimensions; FMI 3.0's defaults (variability discrete except for floats) and its
    // extra causality are read, start values in their types' forms.
    let extra = r#"
    <Float32 name="f32" valueReference="20" causality="output"/>
    <Int8 name="i8" valueReference="21" causality="parameter" variability="fixed" start="3"/>
    <UInt64 name="u64" valueReference="22" causality="output"/>
    <Binary name="bin" valueReference="23" causality="output"/>
    <Clock name="tick" valueReference="24" causality="input"/>
    <Int32 name="n" valueReference="25" causality="structuralParameter" variability="fixed" start="7"/>
    <Boolean name="on" valueReference="26" causality="input" start="true"/>
    <Enumeration name="mode" declaredType="Modes" valueReference="27" causality="parameter" variability="tunable" start="2"/>
    <Float64 name="arr" valueReference="28" causality="output"><Dimension start="3"/></Float64>
  </ModelVariables>"#;
    let xml = msd3_xml().replace("  </ModelVariables>", extra);
    let d = ModelDescription::parse(&xml).expect("the extended description parses");
    let kind = |n: &str| d.variable(n).map(|v| v.kind);
    assert_eq!(kind("f32"), Some(VarKind::Float32));
    assert_eq!(kind("i8"), Some(VarKind::Int8));
    assert_eq!(kind("u64"), Some(VarKind::UInt64));
    assert_eq!(kind("bin"), Some(VarKind::Binary));
    assert_eq!(kind("tick"), Some(VarKind::Clock));
    assert_eq!(kind("arr"), Some(VarKind::Real));
    let type_name = |n: &str| d.variable(n).map(|v| v.type_name);
    assert_eq!(
        type_name("n"),
        Some("Int32"),
        "FMI 3.0's Int32 is not called Integer"
    );
    assert_eq!(type_name("arr"), Some("Float64"));
    let arr = d.variable("arr").expect("arr");
    assert_eq!(arr.dimensions, vec![Dimension::Fixed(3)]);
    assert_eq!(d.shape(arr).ok(), Some(vec![3]));
    assert_eq!(
        d.variable("i8").and_then(|v| v.start.clone()),
        Some(Value::Int(3))
    );
    let n = d.variable("n").expect("n");
    assert_eq!(
        (n.causality, n.kind, n.start.clone()),
        (
            Causality::StructuralParameter,
            VarKind::Integer,
            Some(Value::Int(7))
        )
    );
    let on = d.variable("on").expect("on");
    assert_eq!(
        (on.kind, on.variability, on.start.clone()),
        (
            VarKind::Boolean,
            Variability::Discrete,
            Some(Value::Bool(true))
        )
    );
    let mode = d.variable("mode").expect("mode");
    assert_eq!(
        (mode.kind, mode.start.clone()),
        (VarKind::Enumeration, Some(Value::Int(2)))
    );
    assert_eq!(
        d.variable("f32").map(|v| v.variability),
        Some(Variability::Continuous)
    );
}

#[test]
fn an_unknown_fmi_version_is_refused_and_an_fmi3_token_is_required() {
    let xml = msd3_xml().replace("fmiVersion=\"3.0\"", "fmiVersion=\"1.0\"");
    match ModelDescription::parse(&xml) {
        Err(e @ FmuError::UnsupportedVersion { .. }) => {
            let text = e.to_string();
            assert!(
                text.contains("'1.0'") && text.contains("not supported"),
                "{text}"
            );
        }
        other => panic!("expected the version refusal, got {other:?}"),
    }
    let xml = msd3_xml().replace("instantiationToken=", "guid=");
    let text = ModelDescription::parse(&xml)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        text.contains("instantiationToken") && text.contains("missing"),
        "{text}"
    );
}

#[test]
fn fmi3_errors_name_the_fmi3_function_status_and_capability() {
    let fmu = load("msd3", "plant");
    let mut inst = start(&fmu, "plant", &[]);
    inst.do_step(0.0, 0.5).expect("a first step");
    let err = inst
        .do_step(0.5, 0.0)
        .expect_err("a zero step is refused by msd3");
    assert!(
        matches!(
            err,
            FmuError::Status {
                status: "fmi3Error",
                ..
            }
        ),
        "{err:?}"
    );
    assert_eq!(
        err.to_string(),
        "FMU 'plant': fmi3DoStep returned fmi3Error at t = 0.5 s"
    );
    let err = inst
        .set_real(&[vr(&fmu, "m")], &[2.0])
        .expect_err("a fixed parameter after initialization");
    assert!(
        err.to_string()
            .contains("fmi3SetFloat64 returned fmi3Error"),
        "{err}"
    );
    // msd3 has no Int32 or Boolean variables: the FMI 3.0 getters are called and refuse.
    let mut i = [0];
    let err = inst.get_integer(&[99], &mut i).expect_err("no Int32");
    assert!(
        err.to_string().contains("fmi3GetInt32 returned fmi3Error"),
        "{err}"
    );
    let mut b = [false];
    let err = inst.get_boolean(&[99], &mut b).expect_err("no Boolean");
    assert!(
        err.to_string()
            .contains("fmi3GetBoolean returned fmi3Error"),
        "{err}"
    );

    // Without canGetAndSetFMUState the state calls are refused before the FMU is called,
    // naming FMI 3.0's flag and function.
    let dir = tempfile::tempdir().expect("tempdir");
    let xml = msd3_xml()
        .replace(
            "canGetAndSetFMUState=\"true\"",
            "canGetAndSetFMUState=\"false\"",
        )
        .replace(
            "canSerializeFMUState=\"true\"",
            "canSerializeFMUState=\"false\"",
        );
    let fmu = variant(dir.path(), &xml, "", "stateless").expect("load");
    let inst = start(&fmu, "stateless", &[]);
    match inst.get_state() {
        Err(e @ FmuError::CapabilityMissing { .. }) => {
            let text = e.to_string();
            assert!(
                text.contains("canGetAndSetFMUState") && text.contains("fmi3GetFMUState"),
                "{text}"
            );
        }
        other => panic!("get_state: expected the capability refusal, got {other:?}"),
    }
    match inst.deserialize_state(&[0; 8]) {
        Err(FmuError::CapabilityMissing {
            capability,
            function,
            ..
        }) => {
            assert_eq!(
                (capability, function),
                ("canGetAndSetFMUState", "fmi3DeserializeFMUState")
            );
        }
        other => panic!("deserialize_state: expected the capability refusal, got {other:?}"),
    }
}

#[test]
fn a_step_that_sets_terminate_simulation_is_a_stop_request_at_its_end() {
    let dir = tempfile::tempdir().expect("tempdir");
    let fmu = variant(
        dir.path(),
        &msd3_xml(),
        "#define MSD3_TERMINATE_AT 0.75",
        "ending",
    )
    .expect("load");
    let mut inst = start(&fmu, "plant", &[]);
    let h = 0.25;
    assert_eq!(
        inst.do_step(0.0, h).expect("step to 0.25 s"),
        StepEnd::Completed
    );
    assert_eq!(
        inst.do_step(0.25, h).expect("step to 0.5 s"),
        StepEnd::Completed
    );
    match inst
        .do_step(0.5, h)
        .expect("the step reaching 0.75 s asks to stop")
    {
        StepEnd::Stopped { reached, reason } => {
            assert_eq!(reached, 0.75, "the step completed before the request");
            assert_eq!(
                reason,
                "fmi3DoStep returned fmi3OK with terminateSimulation = true"
            );
        }
        other => panic!("expected a stop request, got {other:?}"),
    }
    assert_eq!(inst.time(), Some(0.75), "the completed step is reached");
}

/// A scenario of the msd3 variant that asks to stop at 0.75 s, run by `dsmcosim run`:
/// the run ends there normally, with that row, and says who stopped it.
#[test]
fn an_fmi3_stop_request_ends_the_run_normally_with_its_last_row() {
    let dir = crate::fmus::scratch("fmu-fmi3", "stop-request");
    variant(
        &dir,
        &msd3_xml(),
        "#define MSD3_TERMINATE_AT 0.75",
        "ending",
    )
    .expect("load");
    let scenario = serde_json::json!({
        "name": "ending", "seed": 1, "duration": 2.0, "dt": 0.05,
        "fmus": [{"name": "plant", "path": "ending.fmu", "trace": ["x"]}]
    });
    let path = dir.join("scenario.json");
    std::fs::write(&path, scenario.to_string()).unwrap();
    let out = dir.join("out");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_dsmcosim"))
        .args([
            "run",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .expect("run dsmcosim");
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert_eq!(o.status.code(), Some(0), "{stdout}{stderr}");
    let message = "stopped by FMU 'plant' at t = 0.75 s \
                   (fmi3DoStep returned fmi3OK with terminateSimulation = true)";
    assert!(stdout.contains(message), "{stdout}");
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let last = trace.lines().last().unwrap();
    assert!(
        last.starts_with("0.75,"),
        "the last row is the stop's: {last}"
    );
    let times: Vec<&str> = trace
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap())
        .collect();
    assert_eq!(
        times,
        ["0", "0.5", "0.75"],
        "every 10th step, and the stop's"
    );
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "stopped");
    assert_eq!(summary["stopped"]["fmu"], "plant");
    assert_eq!(summary["stopped"]["time"], 0.75);
    assert_eq!(summary["stopped"]["message"], message);
    assert_eq!(summary["steps"], 15);
}

#[test]
fn an_fmi3_fmu_without_this_platform_lists_the_tuples_it_has() {
    let dir = tempfile::tempdir().expect("tempdir");
    let dll = dir.path().join("msd3.dll");
    std::fs::write(&dll, b"MZ not really").expect("write");
    let path = dir.path().join("win.fmu");
    let entries: Vec<(String, PathBuf)> = vec![
        ("modelDescription.xml".into(), fmus_dir().join("msd3.xml")),
        ("binaries/x86_64-windows/msd3.dll".into(), dll),
    ];
    write_zip(&path, &entries).expect("zip");
    match Fmu::load("plant", &path) {
        Err(e @ FmuError::NoBinary { .. }) => {
            let text = e.to_string();
            assert!(
                text.contains("'plant'")
                    && text.contains("x86_64-windows")
                    && text.contains(&format!("{}-", std::env::consts::ARCH)),
                "{text}"
            );
        }
        other => panic!("expected the platform error, got {other:?}"),
    }
}

#[test]
fn an_fmi3_fmu_gets_a_resource_path_not_a_uri() {
    let fmu = load("msd3", "plant");
    let path = fmu.resource_path();
    assert!(
        path.starts_with('/') && path.ends_with("/resources/"),
        "{path}"
    );
    assert!(fmu.resource_uri().starts_with("file:///"));
}

/// The PD loop of `cosim.rs` with `plant` as given.
fn pd_loop(plant: &str) -> serde_json::Value {
    let dt = 1e-3;
    let mut v = closed_loop(dt, 3.0, (2.0 * dt, 1e-3), (dt, 2e-3));
    v["fmus"][0]["path"] = json!(plant);
    v
}

#[test]
fn an_fmi3_plant_and_an_fmi2_controller_loop_as_the_fmi2_pair_does() {
    let dir = scratch("fmu-fmi3", "loop");
    for stem in ["msd", "msd3", "pd"] {
        build_test_fmu(stem, &dir).unwrap_or_else(|e| panic!("{stem}.fmu: {e}"));
    }
    let (t2, x2, _) = run(&dir, &pd_loop("msd.fmu"), &["plant.x", "ctrl.u"]);
    let (t3, x3, _) = run(&dir, &pd_loop("msd3.fmu"), &["plant.x", "ctrl.u"]);
    assert_eq!(t2.len(), t3.len(), "row counts");
    assert!(t2.len() > 1000, "{} rows", t2.len());
    for (i, (a, b)) in x2[0].iter().zip(&x3[0]).enumerate() {
        assert_eq!(
            a.to_bits(),
            b.to_bits(),
            "plant.x at t = {} s: {a} vs {b}",
            t2[i]
        );
    }
    assert_eq!(x2[1], x3[1], "ctrl.u");
    // The loop does something: the controller pulls x from 1 m towards 0.
    let end = *x3[0].last().expect("rows");
    assert!(end.abs() < 0.5, "x(3 s) = {end}");
}

#[test]
fn fmi3_variables_of_other_types_are_refused_where_their_type_does_not_fit() {
    let dir = scratch("fmu-fmi3", "other-types");
    build_test_fmu("pd", &dir).expect("pd.fmu");
    let extra = r#"
    <Float32 name="y32" valueReference="20" causality="output"/>
    <Float64 name="arr" valueReference="21" causality="output"><Dimension start="3"/></Float64>
    <Int8 name="gain8" valueReference="22" causality="parameter" variability="fixed" start="1"/>
  </ModelVariables>"#;
    let xml = msd3_xml().replace("  </ModelVariables>", extra);
    let fmu = variant(&dir, &xml, "", "msd3").expect("a description with other types loads");
    drop(fmu);
    let mut base = pd_loop("msd3.fmu");
    base["fmus"][0]["trace"] = json!(["x", "v", "a"]);
    let scenario_error = |v: &serde_json::Value| {
        let path = dir.join("scenario.json");
        std::fs::write(&path, serde_json::to_string_pretty(v).expect("json")).expect("write");
        dsmcosim::scenario::load(&path)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    };
    // A Float32 output into the controller's Float64 input: two types, both named.
    let mut v = base.clone();
    v["connections"][0]["from"] = json!("plant.y32");
    let text = scenario_error(&v);
    assert_eq!(
        text,
        "connections[0]: FMU \"plant\" output \"y32\" (Float32) cannot feed FMU \"ctrl\" \
         input \"x\" (Real): a connection carries a value of one type unchanged (Real to \
         Real, Integer to Integer, Int64 to Int64, …; FMI 2.0's Real is FMI 3.0's Float64, \
         its Integer FMI 3.0's Int32)"
    );
    let mut v = base.clone();
    v["connections"][0]["from"] = json!("plant.arr");
    let text = scenario_error(&v);
    assert!(text.contains("\"arr\" is a Float64 array"), "{text}");
    // An Int8 start value out of its range is refused; in range it is accepted and set
    // through fmi3SetInt8, which msd3 (without Int8 variables) refuses, naming it.
    let mut v = base.clone();
    v["fmus"][0]["start"]["gain8"] = json!(200);
    let text = scenario_error(&v);
    assert!(
        text.contains("\"gain8\" is Int8: a whole number from -128 to 127 (got 200)"),
        "{text}"
    );
    let mut v = base.clone();
    v["fmus"][0]["start"]["gain8"] = json!(2);
    assert_eq!(
        scenario_error(&v),
        "",
        "an Int8 start value in range is accepted"
    );
    let path = dir.join("scenario.json");
    let s = dsmcosim::scenario::load(&path).expect("loads");
    let e = dsmcosim::run::run_with(&s, &dir.join("out-int8"), Default::default())
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        e.contains("fmi3SetInt8 returned fmi3Error"),
        "the start value reaches the Int8 setter: {e}"
    );
    // Unnamed, with `trace` listing Float64 outputs, they are left alone and the loop
    // runs.
    let (t, cols, _) = run(&dir, &base, &["plant.x", "plant.v", "plant.a"]);
    assert!(!t.is_empty() && cols[0].iter().all(|x| x.is_finite()));
}

#[test]
fn fmi3_enumerations_go_through_int64_and_int32_variables_through_int32() {
    // msd3 has neither: each call reaches the FMU function of its type, which refuses
    // and so names itself.
    let dir = tempfile::tempdir().expect("tempdir");
    let extra = r#"
    <Enumeration name="mode" declaredType="Modes" valueReference="30" causality="parameter" variability="fixed" start="1"/>
    <Int32 name="count" valueReference="31" causality="parameter" variability="fixed" start="0"/>
  </ModelVariables>"#;
    let xml = msd3_xml().replace("  </ModelVariables>", extra);
    let fmu = variant(dir.path(), &xml, "", "enums").expect("load");
    let mut inst = fmu.instantiate("enums", false).expect("instantiate");
    let set = |inst: &mut dsmcosim::fmu::Instance, r: u32| {
        inst.set_integer(&[r], &[2])
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    };
    assert!(set(&mut inst, 30).contains("fmi3SetInt64 returned fmi3Error"));
    assert!(set(&mut inst, 31).contains("fmi3SetInt32 returned fmi3Error"));
    let mut v = [0];
    let text = inst
        .get_integer(&[30], &mut v)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(text.contains("fmi3GetInt64 returned fmi3Error"), "{text}");
}
