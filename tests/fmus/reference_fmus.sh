#!/bin/sh
# The Modelica Reference FMUs (https://github.com/modelica/Reference-FMUs, BSD-2-Clause)
# in dsmcosim, against each model's own <Model>_out.csv. Not part of `cargo test`: it
# needs a checkout of that repository, which CI cannot download.
#
#   sh tests/fmus/reference_fmus.sh REFERENCE_FMUS_CHECKOUT DSMCOSIM_BINARY OUTDIR
#
# 1. Builds Feedthrough (FMI 2.0 and 3.0), Resource (2.0 and 3.0) and StateSpace (3.0)
#    as the checkout's CMakeLists.txt does (its sources with FMI_VERSION and
#    DISABLE_PREFIX, the description as modelDescription.xml, Resource's y.txt under
#    resources/), with the system C compiler, without cmake.
# 2. Runs each alone in dsmcosim at its _out.csv's output interval (build/merge_binaries.py
#    of that repository: 1 s; Feedthrough's csv holds rows every 0.1 s) with every output
#    traced, and compares every value of _out.csv with trace.csv: floats and integers
#    exactly, Booleans as 0/1, Strings and Binary as text, StateSpace's array y
#    ("1 2 3") with y[1] y[2] y[3].
# 3. Drives Feedthrough 3.0's inputs of every numeric type from dsmcosim's types3.fmu
#    (OUTDIR/types3.fmu, built by `cargo run --release --example build_fmus -- OUTDIR`
#    beforehand) over a channel, with String and Binary start values set on Feedthrough,
#    and checks that each Feedthrough output is the input it was given.
#
# Exit 0 when everything agrees.
set -e
REF=$(cd "$1" && pwd)
BIN=$2
OUT=$(mkdir -p "$3" && cd "$3" && pwd)

build() { # MODEL VERSION
    t=$(mktemp -d)
    if [ "$2" = 3 ]; then p=x86_64-linux; else p=linux64; fi
    mkdir -p "$t/binaries/$p" "$t/resources"
    (cd "$REF" && ${CC:-cc} -shared -fPIC -O2 -DFMI_VERSION="$2" -DDISABLE_PREFIX -Iinclude -I"$1" \
        -o "$t/binaries/$p/$1.so" "src/fmi$2Functions.c" src/cosimulation.c "$1/model.c" -lm)
    cp "$REF/$1/FMI$2.xml" "$t/modelDescription.xml"
    if [ -f "$REF/$1/y.txt" ]; then cp "$REF/$1/y.txt" "$t/resources/"; fi
    rm -f "$OUT/$1$2.fmu"
    (cd "$t" && zip -qr "$OUT/$1$2.fmu" .)
    rm -rf "$t"
}

alone() { # RUN MODEL VERSION NAME DURATION DT
    printf '{"name": "%s", "seed": 1, "duration": %s, "dt": %s, "output": {"decimation": 1},
  "fmus": [{"name": "%s", "path": "%s%s.fmu"}]}\n' "$1" "$5" "$6" "$4" "$2" "$3" > "$OUT/$1.json"
    "$BIN" validate "$OUT/$1.json" | grep 'output(s) read'
    "$BIN" run "$OUT/$1.json" --out "$OUT/$1" --force > /dev/null
}

build Feedthrough 2
build Feedthrough 3
build Resource 2
build Resource 3
build StateSpace 3
alone ft2 Feedthrough 2 F 2 0.1
alone ft3 Feedthrough 3 F 2 0.1
alone res2 Resource 2 R 1 1
alone res3 Resource 3 R 1 1
alone ss3 StateSpace 3 S 10 1

cat > "$OUT/drive.json" <<'EOF'
{"name": "drive", "seed": 1, "duration": 2, "dt": 0.1, "output": {"decimation": 1},
 "fmus": [{"name": "A", "path": "types3.fmu", "node": 1},
          {"name": "F", "path": "Feedthrough3.fmu", "node": 2,
           "start": {"String_input": "from dsmcosim, \"quoted\"", "Binary_input": "c0ffee"}}],
 "channels": [{"name": "wire", "tau": 0.1, "latency": 0.0}],
 "connections": [
  {"from": "A.f64_out", "to": "F.Float64_continuous_input", "channel": "wire"},
  {"from": "A.f32_out", "to": "F.Float32_continuous_input", "channel": "wire"},
  {"from": "A.i8_out", "to": "F.Int8_input", "channel": "wire"},
  {"from": "A.u8_out", "to": "F.UInt8_input", "channel": "wire"},
  {"from": "A.i16_out", "to": "F.Int16_input", "channel": "wire"},
  {"from": "A.u16_out", "to": "F.UInt16_input", "channel": "wire"},
  {"from": "A.i32_out", "to": "F.Int32_input", "channel": "wire"},
  {"from": "A.u32_out", "to": "F.UInt32_input", "channel": "wire"},
  {"from": "A.i64_out", "to": "F.Int64_input", "channel": "wire"},
  {"from": "A.u64_out", "to": "F.UInt64_input", "channel": "wire"},
  {"from": "A.bool_out", "to": "F.Boolean_input", "channel": "wire"}]}
EOF
"$BIN" run "$OUT/drive.json" --out "$OUT/drive" --force > /dev/null

python3 - "$REF" "$OUT" <<'EOF'
import csv
import sys

ref, out = sys.argv[1:3]
ok = True


def same(want, got):
    if want in ("true", "false"):
        return got == ("1" if want == "true" else "0")
    for kind in (int, float):
        try:
            return kind(want) == kind(got)
        except ValueError:
            pass
    return want.lower() == got.lower()


for run, model, fmu in [("ft2", "Feedthrough", "F"), ("ft3", "Feedthrough", "F"),
                        ("res2", "Resource", "R"), ("res3", "Resource", "R"),
                        ("ss3", "StateSpace", "S")]:
    want = list(csv.DictReader(open(f"{ref}/{model}/{model}_out.csv", newline="")))
    got = list(csv.DictReader(open(f"{out}/{run}/trace.csv", newline="")))
    compared, differ = 0, []
    for w, g in zip(want, got):
        if abs(float(w["time"]) - float(g["t"])) > 1e-9:
            differ.append(("time", w["time"], g["t"]))
        for c in w:
            if c == "time":
                continue
            if f"{fmu}.{c}[1]" in g:  # an array, "1 2 3" in the csv
                ws = w[c].split()
                pairs = [(x, g[f"{fmu}.{c}[{i + 1}]"]) for i, x in enumerate(ws)]
            elif f"{fmu}.{c}" in g:
                pairs = [(w[c], g[f"{fmu}.{c}"])]
            else:
                continue  # FMI 2.0's Feedthrough lacks FMI 3.0's types; the csv is shared
            for x, y in pairs:
                compared += 1
                if not same(x, y):
                    differ.append((c, x, y))
    ok = ok and not differ and len(want) == len(got)
    print(f"{run}: {len(got)} rows ({len(want)} in {model}_out.csv), {compared} values "
          f"compared, {len(differ)} differ {differ[:3]}")

rows = list(csv.DictReader(open(f"{out}/drive/trace.csv", newline="")))
pairs = [("f64_out", "Float64_continuous_output"), ("f32_out", "Float32_continuous_output"),
         ("i8_out", "Int8_output"), ("u8_out", "UInt8_output"), ("i16_out", "Int16_output"),
         ("u16_out", "UInt16_output"), ("i32_out", "Int32_output"),
         ("u32_out", "UInt32_output"), ("i64_out", "Int64_output"),
         ("u64_out", "UInt64_output"), ("bool_out", "Boolean_output")]
differ = [(k, a) for k in range(1, len(rows)) for a, f in pairs
          if rows[k]["F." + f] != rows[k - 1]["A." + a]]
texts = {rows[-1]["F.String_output"], rows[-1]["F.Binary_output"]}
ok = ok and not differ and texts == {'from dsmcosim, "quoted"', "c0ffee"}
print(f"drive: types3 into Feedthrough 3.0 over a channel, {len(rows)} rows, "
      f"{(len(rows) - 1) * len(pairs)} values compared (each output one step after the "
      f"input it was given), {len(differ)} differ; String and Binary start values "
      f"{sorted(texts)}")
sys.exit(0 if ok else 1)
EOF
