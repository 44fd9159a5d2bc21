//! Every FMI type traced (issue 44): `types.fmu` (`tests/fmus/types.c`, an output of
//! every FMI 2.0 type) and `types3.fmu` (`tests/fmus/types3.c`, every FMI 3.0 type but
//! Clock, a Float64 array sized by a structural parameter and an Int32 array of fixed
//! size). Each trace column is compared with the value the C code computes, written out
//! here again from its formulas; integers are compared as integers (an Int64 or UInt64
//! never through an `f64`), floats bit for bit, Strings and Binary values as text.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::{json, Value};

use crate::fmu_build::{build_fmu, build_test_fmu, fmus_dir};
use crate::fmus::scratch;

/// The communication step and the number of steps of every scene here.
const DT: f64 = 0.1;
const STEPS: i64 = 10;

/// Builds types.fmu and types3.fmu into `dir` (once).
fn build(dir: &Path) {
    for stem in ["types", "types3"] {
        if !dir.join(format!("{stem}.fmu")).exists() {
            build_test_fmu(stem, dir).unwrap_or_else(|e| panic!("{stem}.fmu: {e}"));
        }
    }
}

/// A scene of `fmus` (each `{"name", "path", …}`) for `STEPS` steps of `DT`, one row
/// per step; with connections, over the channel `wire` (sampled every step, no latency).
fn scene(fmus: Value, connections: Value) -> Value {
    let mut v = json!({
        "name": "types", "seed": 1, "duration": DT * STEPS as f64, "dt": DT,
        "output": {"decimation": 1},
        "fmus": fmus
    });
    if connections.as_array().is_some_and(|c| !c.is_empty()) {
        v["channels"] = json!([{"name": "wire", "tau": DT, "latency": 0.0}]);
        v["connections"] = connections;
    }
    v
}

/// `dsmcosim` with `args`.
fn dsmcosim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dsmcosim"))
        .args(args)
        .output()
        .expect("run dsmcosim")
}

/// Writes `v` as `dir/<name>.json` and runs it into `dir/<name>`: the process's output
/// and the output directory.
fn run(dir: &Path, name: &str, v: &Value) -> (Output, PathBuf) {
    let path = dir.join(format!("{name}.json"));
    std::fs::write(&path, serde_json::to_string_pretty(v).unwrap()).unwrap();
    let out = dir.join(name);
    let _ = std::fs::remove_dir_all(&out);
    let o = dsmcosim(&[
        "run",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    (o, out)
}

/// Runs `v`, which must succeed: trace.csv's header, its rows (fields unquoted), its
/// raw text, and the run's digest.
fn traced(dir: &Path, name: &str, v: &Value) -> (Vec<String>, Vec<Vec<String>>, String, String) {
    let (o, out) = run(dir, name, v);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let text = std::fs::read_to_string(out.join("trace.csv")).expect("trace.csv");
    let mut r = csv::Reader::from_reader(text.as_bytes());
    let head = r.headers().unwrap().iter().map(str::to_string).collect();
    let rows = r
        .records()
        .map(|rec| rec.unwrap().iter().map(str::to_string).collect())
        .collect();
    let summary: Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let digest = summary["digest"].as_str().expect("digest").to_string();
    (head, rows, text, digest)
}

/// The column `name` of `rows` under `head`.
fn column(head: &[String], rows: &[Vec<String>], name: &str) -> Vec<String> {
    let i = head
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name} in {head:?}"));
    rows.iter().map(|r| r[i].clone()).collect()
}

/// Asserts that column `name` holds `want(k)` at row k (time k·DT), compared by `same`.
fn check(
    head: &[String],
    rows: &[Vec<String>],
    name: &str,
    want: impl Fn(i64) -> String,
    same: impl Fn(&str, &str) -> bool,
) {
    let got = column(head, rows, name);
    assert_eq!(got.len() as i64, STEPS + 1, "{name}: one row per step");
    for (k, g) in got.iter().enumerate() {
        let w = want(k as i64);
        assert!(same(g, &w), "{name} at row {k}: got {g:?}, want {w:?}");
    }
}

/// Same integer (parsed exactly, as i128).
fn int_eq(a: &str, b: &str) -> bool {
    matches!((a.parse::<i128>(), b.parse::<i128>()), (Ok(x), Ok(y)) if x == y)
}

/// Same f64, bit for bit.
fn f64_eq(a: &str, b: &str) -> bool {
    matches!((a.parse::<f64>(), b.parse::<f64>()), (Ok(x), Ok(y)) if x.to_bits() == y.to_bits())
}

/// Same f32, bit for bit (a Float32 column's text parses back to the FMU's f32).
fn f32_eq(a: &str, b: &str) -> bool {
    matches!((a.parse::<f32>(), b.parse::<f32>()), (Ok(x), Ok(y)) if x.to_bits() == y.to_bits())
}

fn text_eq(a: &str, b: &str) -> bool {
    a == b
}

/// The start values the FMI 2.0 scene gives `types.fmu`, one per type.
const S2: &str = "x\"y, z";

#[test]
fn every_fmi2_output_type_is_traced_exactly() {
    let dir = scratch("fmu-types", "fmi2");
    build(&dir);
    let v = scene(
        json!([{"name": "t", "path": "types.fmu",
                "start": {"r_p": 0.25, "i_p": -7, "b_p": true, "s_p": S2, "e_p": 3}}]),
        json!([]),
    );
    let (head, rows, text, _) = traced(&dir, "fmi2", &v);
    // The default trace: every output, of every type, in description order.
    assert_eq!(
        head[1..],
        ["t.r_out", "t.i_out", "t.b_out", "t.s_out", "t.e_out"],
        "{head:?}"
    );
    // Row k holds the outputs after k steps (n = k), the inputs at their starts (0).
    check(
        &head,
        &rows,
        "t.r_out",
        |n| (0.25 * n as f64 + 0.0).to_string(),
        f64_eq,
    );
    check(&head, &rows, "t.i_out", |n| (-7 + n).to_string(), int_eq);
    check(
        &head,
        &rows,
        "t.b_out",
        |n| u8::from(n % 2 == 0).to_string(),
        text_eq,
    );
    check(&head, &rows, "t.s_out", |n| format!("{S2} #{n}"), text_eq);
    check(
        &head,
        &rows,
        "t.e_out",
        |n| (1 + (3 - 1 + n) % 3).to_string(),
        int_eq,
    );
    // The String column is CSV-quoted (it holds a comma and a quote).
    assert!(text.contains(",\"x\"\"y, z #4\","), "{text}");
}

/// The FMI 3.0 scene's start values, one per type (the 64-bit ones beyond any f64's
/// exact integers).
fn types3_start() -> Value {
    json!({
        "f64_p": 0.75, "f32_p": 0.3, "i8_p": -110, "u8_p": 251, "i16_p": 32000,
        "u16_p": 65000, "i32_p": -2000000000, "u32_p": 4294967291u64,
        "i64_p": 9007199254740995i64, "u64_p": 18446744073709551557u64,
        "bool_p": true, "str_p": "é, \"q\"", "bin_p": "0a0B", "enum_p": 1
    })
}

#[test]
fn every_fmi3_output_type_and_array_is_traced_exactly() {
    let dir = scratch("fmu-types", "fmi3");
    build(&dir);
    let v = scene(
        json!([{"name": "u", "path": "types3.fmu", "start": types3_start()}]),
        json!([]),
    );
    let (head, rows, _, _) = traced(&dir, "fmi3", &v);
    let names: Vec<&str> = head[1..].iter().map(String::as_str).collect();
    assert_eq!(
        names,
        [
            "u.f64_out",
            "u.f32_out",
            "u.i8_out",
            "u.u8_out",
            "u.i16_out",
            "u.u16_out",
            "u.i32_out",
            "u.u32_out",
            "u.i64_out",
            "u.u64_out",
            "u.bool_out",
            "u.str_out",
            "u.bin_out",
            "u.enum_out",
            "u.y[1]",
            "u.y[2]",
            "u.y[3]",
            "u.z[1]",
            "u.z[2]"
        ]
    );
    // types3.c's formulas with these parameters, n = k at row k, inputs at 0.
    check(
        &head,
        &rows,
        "u.f64_out",
        |n| (0.75 * n as f64 + 0.0).to_string(),
        f64_eq,
    );
    check(
        &head,
        &rows,
        "u.f32_out",
        |n| (0.3f32 * n as f32).to_string(),
        f32_eq,
    );
    check(&head, &rows, "u.i8_out", |n| (-110 - n).to_string(), int_eq);
    check(
        &head,
        &rows,
        "u.u8_out",
        |n| 251u8.wrapping_add(n as u8).to_string(),
        int_eq,
    );
    check(
        &head,
        &rows,
        "u.i16_out",
        |n| (32000 - 7 * n).to_string(),
        int_eq,
    );
    check(
        &head,
        &rows,
        "u.u16_out",
        |n| 65000u16.wrapping_add(1000 * n as u16).to_string(),
        int_eq,
    );
    check(
        &head,
        &rows,
        "u.i32_out",
        |n| (-2000000000 + n).to_string(),
        int_eq,
    );
    check(
        &head,
        &rows,
        "u.u32_out",
        |n| 4294967291u32.wrapping_add(n as u32).to_string(),
        int_eq,
    );
    check(
        &head,
        &rows,
        "u.i64_out",
        |n| (9007199254740995i64 + n).to_string(),
        int_eq,
    );
    check(
        &head,
        &rows,
        "u.u64_out",
        |n| (18446744073709551557u64 - n as u64).to_string(),
        int_eq,
    );
    check(
        &head,
        &rows,
        "u.bool_out",
        |n| u8::from(n % 2 == 0).to_string(),
        text_eq,
    );
    check(
        &head,
        &rows,
        "u.str_out",
        |n| format!("é, \"q\" #{n}"),
        text_eq,
    );
    check(
        &head,
        &rows,
        "u.bin_out",
        |n| format!("0a0b{:02x}", n),
        text_eq,
    );
    check(
        &head,
        &rows,
        "u.enum_out",
        |n| (1 + n % 3).to_string(),
        int_eq,
    );
    for i in 1..=3 {
        check(
            &head,
            &rows,
            &format!("u.y[{i}]"),
            |n| (0.75 * i as f64 + n as f64).to_string(),
            f64_eq,
        );
    }
    check(&head, &rows, "u.z[1]", |n| n.to_string(), int_eq);
    check(&head, &rows, "u.z[2]", |n| (2 * n).to_string(), int_eq);
    // The 64-bit columns are written as integers: no exponent, no fraction.
    let i64s = column(&head, &rows, "u.i64_out");
    assert_eq!(i64s[0], "9007199254740995");
    assert_eq!(column(&head, &rows, "u.u64_out")[3], "18446744073709551554");
}

#[test]
fn outputs_of_any_type_are_asked_for_by_name_and_validate_counts_them_all() {
    let dir = scratch("fmu-types", "by-name");
    build(&dir);
    let v = scene(
        json!([{"name": "u", "path": "types3.fmu", "trace": ["str_out", "y", "u64_out"]}]),
        json!([]),
    );
    let (head, rows, _, _) = traced(&dir, "by-name", &v);
    assert_eq!(
        head[1..],
        ["u.u64_out", "u.str_out", "u.y[1]", "u.y[2]", "u.y[3]"],
        "description order"
    );
    check(
        &head,
        &rows,
        "u.str_out",
        |n| format!("a, \"b\" #{n}"),
        text_eq,
    );
    // `validate` counts every output it reads, whatever its type: 14 scalars and the
    // two arrays of types3; the 5 of types.
    let v = scene(
        json!([{"name": "u", "path": "types3.fmu"}, {"name": "t", "path": "types.fmu"}]),
        json!([]),
    );
    let path = dir.join("validate.json");
    std::fs::write(&path, v.to_string()).unwrap();
    let o = dsmcosim(&["validate", path.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{stdout}");
    assert!(stdout.contains("16 output(s) read"), "{stdout}");
    assert!(stdout.contains("5 output(s) read"), "{stdout}");
}

#[test]
fn the_digest_is_deterministic_and_sees_a_64_bit_integer_an_f64_cannot() {
    let dir = scratch("fmu-types", "digest");
    build(&dir);
    let with = |i64_p: i64| {
        let mut start = types3_start();
        start["i64_p"] = json!(i64_p);
        scene(
            json!([{"name": "u", "path": "types3.fmu", "start": start}]),
            json!([]),
        )
    };
    let (_, _, text_a, a) = traced(&dir, "a", &with(9007199254740993));
    let (_, _, text_b, b) = traced(&dir, "b", &with(9007199254740993));
    assert_eq!(a, b, "the same scene, the same digest");
    assert_eq!(text_a, text_b, "the same trace, byte for byte");
    // 2^53 + 1 and 2^53 are one f64: the digest tells them apart.
    assert_eq!(9007199254740993i64 as f64, 9007199254740992i64 as f64);
    let (_, _, _, c) = traced(&dir, "c", &with(9007199254740992));
    assert_ne!(a, c, "an Int64 output is in the digest as an integer");
    // So is a String: one character of its parameter changes the digest.
    let mut v = with(9007199254740993);
    v["fmus"][0]["start"]["str_p"] = json!("é, \"r\"");
    let (_, _, _, d) = traced(&dir, "d", &v);
    assert_ne!(a, d, "a String output is in the digest");
}

#[test]
fn integer_boolean_and_real_outputs_connect_exactly_where_the_types_agree() {
    let dir = scratch("fmu-types", "connect");
    build(&dir);
    // A (FMI 3.0) feeds B (FMI 3.0) its Int32, Int64, Boolean and Float64 outputs; C
    // (FMI 2.0) feeds D (FMI 3.0) its Integer output, which FMI 3.0 calls Int32.
    let v = scene(
        json!([
            {"name": "A", "path": "types3.fmu", "node": 1},
            {"name": "B", "path": "types3.fmu", "node": 2},
            {"name": "C", "path": "types.fmu", "node": 3},
            {"name": "D", "path": "types3.fmu", "node": 3}
        ]),
        json!([
            {"from": "A.i32_out", "to": "B.i32_in", "channel": "wire"},
            {"from": "A.i64_out", "to": "B.i64_in", "channel": "wire"},
            {"from": "A.bool_out", "to": "B.bool_in", "channel": "wire"},
            {"from": "A.f64_out", "to": "B.f64_in", "channel": "wire"},
            {"from": "C.i_out", "to": "D.i32_in", "channel": "wire"}
        ]),
    );
    let (head, rows, _, _) = traced(&dir, "connect", &v);
    let ints = |name: &str| -> Vec<i128> {
        column(&head, &rows, name)
            .iter()
            .map(|s| s.parse().unwrap())
            .collect()
    };
    let (a32, b32) = (ints("A.i32_out"), ints("B.i32_out"));
    let (a64, b64) = (ints("A.i64_out"), ints("B.i64_out"));
    let (c, d32) = (ints("C.i_out"), ints("D.i32_out"));
    let (abool, bbool) = (ints("A.bool_out"), ints("B.bool_out"));
    let (af, bf) = (
        column(&head, &rows, "A.f64_out"),
        column(&head, &rows, "B.f64_out"),
    );
    // Row 0: B's inputs at their starts. Row k ≥ 1: B stepped from row k-1 on what A
    // published there (sampled every step, no latency: the co-simulation's one-step lag).
    let i64_p = 9007199254740993i128;
    assert_eq!(b64[0], i64_p);
    for k in 1..=STEPS as usize {
        let n = k as i128;
        assert_eq!(b32[k], 1000 + a32[k - 1] + n, "B.i32_out at row {k}");
        assert_eq!(b64[k], i64_p + a64[k - 1] + n, "B.i64_out at row {k}");
        assert_eq!(d32[k], 1000 + c[k - 1] + n, "D.i32_out at row {k}");
        let held = abool[k - 1] != 0;
        assert_eq!(bbool[k] != 0, held ^ (k % 2 == 1), "B.bool_out at row {k}");
        let want = 0.5 * k as f64 + af[k - 1].parse::<f64>().unwrap();
        assert_eq!(
            bf[k].parse::<f64>().unwrap().to_bits(),
            want.to_bits(),
            "row {k}"
        );
    }
    // B's Int64 output is near 2^54, where an f64 holds only even numbers: it is odd on
    // every other row, so nothing passed through an f64.
    assert!(b64.iter().any(|x| x % 2 == 1) && b64[STEPS as usize] > 1 << 54);
}

#[test]
fn a_run_of_typed_outputs_resumed_from_any_checkpoint_ends_with_the_same_digest_and_trace() {
    use dsmcosim::kernel::SimTime;
    use dsmcosim::run::{resume, run_with, RunOptions};
    let dir = scratch("fmu-types", "checkpoint");
    build(&dir);
    // Every type traced (Strings and Binary included) and Int64, Int32, Boolean values
    // in flight between two FMUs: a checkpoint holds them all, typed.
    let v = scene(
        json!([
            {"name": "A", "path": "types3.fmu", "node": 1, "start": types3_start()},
            {"name": "B", "path": "types3.fmu", "node": 2},
            {"name": "C", "path": "types.fmu", "node": 2}
        ]),
        json!([
            {"from": "A.i64_out", "to": "B.i64_in", "channel": "wire"},
            {"from": "A.i32_out", "to": "B.i32_in", "channel": "wire"},
            {"from": "A.bool_out", "to": "B.bool_in", "channel": "wire"},
            {"from": "C.i_out", "to": "A.i32_in", "channel": "wire"}
        ]),
    );
    let path = dir.join("scenario.json");
    std::fs::write(&path, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    let s = dsmcosim::scenario::load(&path).unwrap_or_else(|e| panic!("scenario: {e}"));
    let opts = RunOptions {
        checkpoint_every: SimTime::from_secs_f64(0.3),
        ..RunOptions::default()
    };
    let full = run_with(&s, &dir.join("full"), opts).expect("run");
    let plain = run_with(&s, &dir.join("plain"), RunOptions::default()).expect("run");
    assert_eq!(full.digest, plain.digest);
    let mut cps: Vec<PathBuf> = std::fs::read_dir(dir.join("full/checkpoints"))
        .expect("checkpoints")
        .map(|e| e.unwrap().path())
        .collect();
    cps.sort();
    assert_eq!(cps.len(), 3, "{cps:?}");
    let trace = std::fs::read(dir.join("full/trace.csv")).unwrap();
    for (i, cp) in cps.iter().enumerate() {
        let out = dir.join(format!("resumed{i}"));
        let r = resume(cp, &out, RunOptions::default()).expect("resume");
        assert_eq!(r.digest, full.digest, "resumed from {}", cp.display());
        assert_eq!(std::fs::read(out.join("trace.csv")).unwrap(), trace);
    }
}

/// Runs `v` expecting a refusal: exit 2, the message on stderr, nothing written, no
/// panic.
fn refused(dir: &Path, name: &str, v: &Value) -> String {
    let (o, out) = run(dir, name, v);
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{name}: {stderr}");
    assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    assert!(!out.exists(), "{name}: a refused scene writes nothing");
    stderr
}

#[test]
fn mismatched_types_and_untyped_values_are_refused_naming_both_ends() {
    let dir = scratch("fmu-types", "refused");
    build(&dir);
    let pair = |from: &str, to: &str| {
        scene(
            json!([
                {"name": "A", "path": "types3.fmu", "node": 1},
                {"name": "B", "path": "types3.fmu", "node": 2},
                {"name": "C", "path": "types.fmu", "node": 2}
            ]),
            json!([{"from": from, "to": to, "channel": "wire"}]),
        )
    };
    let e = refused(&dir, "int-to-real", &pair("A.i32_out", "B.f64_in"));
    assert!(
        e.contains(
            "connections[0]: FMU \"A\" output \"i32_out\" (Int32) cannot feed FMU \"B\" \
             input \"f64_in\" (Float64)"
        ),
        "{e}"
    );
    let e = refused(&dir, "i64-to-i32", &pair("A.i64_out", "B.i32_in"));
    assert!(
        e.contains("\"i64_out\" (Int64) cannot feed FMU \"B\" input \"i32_in\" (Int32)"),
        "{e}"
    );
    let e = refused(&dir, "real-to-bool", &pair("C.r_out", "B.bool_in"));
    assert!(
        e.contains(
            "FMU \"C\" output \"r_out\" (Real) cannot feed FMU \"B\" input \"bool_in\" (Boolean)"
        ),
        "{e}"
    );
    let e = refused(&dir, "string", &pair("A.str_out", "B.i32_in"));
    assert!(
        e.contains("connections[0].from: FMU \"A\": \"str_out\" is a String; connections and costs take numbers and Booleans"),
        "{e}"
    );
    let e = refused(&dir, "array", &pair("A.y", "B.f64_in"));
    assert!(e.contains("\"y\" is a Float64 array"), "{e}");
    // Start values are refused by type, naming it and what it takes.
    let one = |start: Value| {
        scene(
            json!([{"name": "A", "path": "types3.fmu", "start": start}]),
            json!([]),
        )
    };
    let e = refused(&dir, "str-number", &one(json!({"str_p": 5})));
    assert!(
        e.contains("fmus[0].start.str_p: FMU \"A\": \"str_p\" is String: a JSON string"),
        "{e}"
    );
    let e = refused(&dir, "bin-hex", &one(json!({"bin_p": "0g"})));
    assert!(
        e.contains("\"bin_p\" is Binary: a string of hex bytes"),
        "{e}"
    );
    let e = refused(&dir, "u8-range", &one(json!({"u8_p": 256})));
    assert!(
        e.contains("\"u8_p\" is UInt8: a whole number from 0 to 255 (got 256)"),
        "{e}"
    );
    let e = refused(&dir, "u64-negative", &one(json!({"u64_p": -1})));
    assert!(e.contains("\"u64_p\" is UInt64"), "{e}");
    let e = refused(&dir, "structural", &one(json!({"n_y": 4})));
    assert!(e.contains("causality StructuralParameter"), "{e}");
}

#[test]
fn an_array_beyond_the_size_limit_is_refused_before_anything_is_allocated() {
    let dir = scratch("fmu-types", "too-large");
    let xml = std::fs::read_to_string(fmus_dir().join("types3.xml")).unwrap();
    let big = dsmcosim::fmu::MAX_ARRAY_ELEMENTS + 1;
    let xml = xml.replace(
        r#"name="n_y" valueReference="15" causality="structuralParameter" variability="fixed" start="3""#,
        &format!(
            r#"name="n_y" valueReference="15" causality="structuralParameter" variability="fixed" start="{big}""#
        ),
    );
    assert!(xml.contains(&format!("start=\"{big}\"")));
    let xml_path = dir.join("types3.xml");
    std::fs::write(&xml_path, xml).unwrap();
    build_fmu(
        &fmus_dir().join("types3.c"),
        &xml_path,
        "types3",
        &dir.join("types3.fmu"),
    )
    .expect("types3.fmu with a large n_y");
    let v = scene(
        json!([{"name": "u", "path": "types3.fmu", "trace": ["y"]}]),
        json!([]),
    );
    let e = refused(&dir, "big", &v);
    assert!(
        e.contains("fmus[0].trace: FMU \"u\": output \"y\"")
            && e.contains("more than MAX_ARRAY_ELEMENTS = 65536 elements (a dimension of 65537)"),
        "{e}"
    );
}

#[test]
fn types3_start_values_read_in_their_types_forms() {
    use dsmcosim::fmu::{Dimension, ModelDescription, Value};
    let xml = std::fs::read_to_string(fmus_dir().join("types3.xml")).unwrap();
    let d = ModelDescription::parse(&xml).expect("types3.xml parses");
    let start = |n: &str| d.variable(n).and_then(|v| v.start.clone());
    assert_eq!(start("f32_p"), Some(Value::Float32(0.1)));
    assert_eq!(start("i64_p"), Some(Value::Int(9007199254740993)));
    assert_eq!(start("u64_p"), Some(Value::UInt(u64::MAX)));
    assert_eq!(start("str_p"), Some(Value::Text("a, \"b\"".into())));
    assert_eq!(start("bin_p"), Some(Value::Bytes(vec![0x00, 0xff])));
    assert_eq!(start("enum_p"), Some(Value::Int(2)));
    let y = d.variable("y").expect("y");
    assert_eq!(
        (y.type_name, y.dimensions.clone()),
        ("Float64", vec![Dimension::Parameter(15)])
    );
    assert_eq!(d.shape(y).ok(), Some(vec![3]), "n_y's start value");
    // Without a start, a structural parameter cannot size an array.
    let no_start = xml.replace(
        r#"variability="fixed" start="3"/>"#,
        r#"variability="fixed"/>"#,
    );
    let d = ModelDescription::parse(&no_start).expect("parses");
    let e = d
        .shape(d.variable("y").expect("y"))
        .err()
        .map(|e| e.to_string());
    assert_eq!(
        e.as_deref(),
        Some(
            "modelDescription.xml: Float64 'y'/Dimension: its size is UInt64 'n_y' \
             (valueReference 15), which has no whole non-negative start value"
        )
    );
}

#[test]
fn a_multi_dimensional_array_names_its_elements_row_major_from_1() {
    use dsmcosim::fmu::{Value, VarKind};
    use dsmcosim::scenario::model::FmuVar;
    let var = |shape: Vec<usize>| FmuVar {
        name: "A".into(),
        vr: 7,
        kind: VarKind::Real,
        traced: true,
        start: Value::Float(0.0),
        shape,
    };
    assert_eq!(
        var(vec![2, 3]).element_names(),
        ["A[1,1]", "A[1,2]", "A[1,3]", "A[2,1]", "A[2,2]", "A[2,3]"]
    );
    assert_eq!(var(vec![3]).element_names(), ["A[1]", "A[2]", "A[3]"]);
    assert_eq!(var(vec![]).element_names(), ["A"]);
    assert!(var(vec![2, 0]).element_names().is_empty());
}

#[test]
fn a_string_past_max_value_bytes_stops_the_run_naming_the_fmu_function_and_variable() {
    let dir = scratch("fmu-types", "long-string");
    let max = dsmcosim::fmu::MAX_VALUE_BYTES;
    for (bytes, name) in [(max, "at-cap"), (max + 1, "past-cap")] {
        let src = dir.join(format!("{name}.c"));
        let c = format!(
            "#define TYPES3_STRING_BYTES {bytes}\n#include \"{}\"\n",
            fmus_dir().join("types3.c").display()
        );
        std::fs::write(&src, c).unwrap();
        let fmu = dir.join(format!("{name}.fmu"));
        build_fmu(&src, &fmus_dir().join("types3.xml"), "types3", &fmu)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    let one = |path: &str| {
        scene(
            json!([{"name": "u", "path": path, "trace": ["str_out"]}]),
            json!([]),
        )
    };
    // At the cap, the whole string is traced.
    let (_, rows, _, _) = traced(&dir, "ok", &one("at-cap.fmu"));
    assert!(rows
        .iter()
        .all(|r| r[1].len() == max && r[1].bytes().all(|b| b == b'x')));
    // One byte more: exit 3, the FMU, the function and the value reference named.
    let (o, _) = run(&dir, "too-long", &one("past-cap.fmu"));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{stderr}");
    assert!(
        stderr.contains(
            "MAX_VALUE_BYTES (a value FMU 'u' gave through fmi3GetString for value reference \
             31) exceeds its cap of 1048576"
        ),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}
