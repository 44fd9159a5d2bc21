#!/usr/bin/env bash
# Regenerates every stored run in results/ from its scenario and lists the digests that
# changed. Usage: results/regenerate.sh [--studies]   (from anywhere; builds the release
# binary)
#
# A stored run is a directory results/<dir>/ with a summary.json whose "scenario" key
# names an existing scenarios/<scenario>.json. Each is rerun into a fresh temporary
# directory beside it, which then replaces it whole: a file the new run no longer writes
# does not survive (the script names such files). A run that fails (exit code other than
# 0, or 3 for a run that diverged, whose trace up to the divergence is its result) leaves
# the stored directory untouched and stops the script. Directories ending in .new (left
# by `dsmcosim check`) are not stored runs. To add a stored run:
# `dsmcosim run scenarios/<name>.json --out results/<name>`. The longest stored run,
# results/grid64_tight/ (a 64×64 net at tight accuracy), takes about 2 min of it.
#
# --studies also regenerates the speed-accuracy studies (results/tradeoff/, with its
# subdirectories), the stability map (results/stability/), the coupling study
# (results/coupling/, and of the mechanisms in scenarios/mechanisms/ under
# results/coupling/mechanisms/) with the commands docs/accuracy.md and docs/guide.md give, and
# the sweeps behind the thesis-claim table (results/sweeps/dsm_size_*/, measure_*/ and
# seeds_*/, then the tables in results/README.md and results/claims.csv); they take
# minutes and their wall-time columns change on every run, so the default leaves them
# alone.
set -uo pipefail
cd "$(dirname "$0")/.."
studies=0
for arg in "$@"; do
  case "$arg" in
    --studies) studies=1 ;;
    -h|--help) sed -n '2,/^set /p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    *) echo "unknown argument: $arg (usage: results/regenerate.sh [--studies])" >&2; exit 2 ;;
  esac
done
cargo build --release --quiet || exit 1
# The FMU scenes (scenarios/fmu_*.json) read the test FMUs from scenarios/fmu/, built
# from tests/fmus/ (not in the repository: they are build products).
cargo run --release --quiet --example build_fmus -- scenarios/fmu >/dev/null || exit 1
bin=target/release/dsmcosim
key() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$1" "$2"; }
tmp=$(mktemp -d results/.regenerate.XXXXXX) || exit 1
# Each run goes to a directory beside the stored ones, at their depth: a run keeps its
# scenario's FMU paths relative to where it is written (docs/reference.md,
# scenario.json), so the move that replaces a stored run must not change its depth.
fresh="$tmp.run"
trap 'rm -rf "$tmp" "$fresh"' EXIT
found=0
for summary in results/*/summary.json; do
  [ -f "$summary" ] || continue
  dir=$(dirname "$summary")
  case "$dir" in *.new) continue ;; esac
  name=$(key "$summary" scenario) || { echo "$dir: unreadable summary.json"; exit 1; }
  scenario="scenarios/$name.json"
  if [ ! -f "$scenario" ]; then echo "$dir: skipped, no $scenario"; continue; fi
  found=1
  old=$(key "$summary" digest 2>/dev/null || echo none)
  rm -rf "$fresh" "$tmp/old"
  "$bin" run "$scenario" --out "$fresh" >/dev/null 2>"$tmp/stderr"
  code=$?
  if [ $code -ne 0 ] && [ $code -ne 3 ]; then
    echo "$dir: failed (exit $code), left as it was: $(cat "$tmp/stderr")"
    exit $code
  fi
  gone=$(comm -23 <(cd "$dir" && find . -type f | sort) <(cd "$fresh" && find . -type f | sort) \
    | sed 's|^\./||' | tr '\n' ' ')
  mv "$dir" "$tmp/old" && mv "$fresh" "$dir" || { echo "$dir: could not replace"; exit 1; }
  new=$(key "$summary" digest)
  if [ "$old" != "$new" ]; then line="$dir: digest changed $old -> $new"; else line="$dir: unchanged"; fi
  [ $code -eq 3 ] && line="$line (diverged, as a stored result)"
  [ -n "$gone" ] && line="$line; removed (no longer written): ${gone% }"
  echo "$line"
done
[ $found -eq 1 ] || echo "no stored runs found under results/"
# Distances of bodies 1 and 16 from the monolithic run (results/README.md, "Body
# errors"), from the stored traces just written.
for reading in thesis_reading sample_and_hold; do
  suffix=""; [ "$reading" = sample_and_hold ] && suffix=_hold
  online=""
  [ "$reading" = thesis_reading ] \
    && online="results/grid16_space_cp_online results/grid16_space_cp_ds2_online"
  # shellcheck disable=SC2086 # $online is a list of directories
  "$bin" distance results/grid16_monolithic results/grid16_space_cp_no_opt$suffix \
    results/grid16_space_cp$suffix results/grid16_space_cp_ds2$suffix $online --bodies 1,16 \
    --out "results/body_errors/$reading" >/dev/null \
    || { echo "results/body_errors/$reading: failed"; exit 1; }
  echo "results/body_errors/$reading: regenerated"
done
if [ $studies -eq 1 ]; then
  study() {
    local out=$1; shift
    "$bin" "$@" --out "$out" >/dev/null || { echo "$out: failed: $bin $* --out $out"; exit 1; }
    echo "$out: regenerated"
  }
  study results/tradeoff tradeoff scenarios/grid16_monolithic.json --duration 3
  study results/tradeoff/horizon_10s tradeoff scenarios/grid16_monolithic.json --duration 10
  study results/tradeoff/horizon_30s tradeoff scenarios/grid16_monolithic.json --duration 30
  study results/tradeoff/grid16_space_fixed tradeoff scenarios/grid16_space_fixed.json --duration 3
  study results/tradeoff/tdma4_space_fixed_hold tradeoff scenarios/tdma4_space_fixed_hold.json --duration 3
  study results/tradeoff/grid16_rk4 tradeoff scenarios/grid16_rk4.json --duration 3
  study results/tradeoff/grid64_tight_1s tradeoff scenarios/grid64_tight.json --duration 1
  study results/stability stability-map scenarios/grid16_monolithic.json --duration 12
  study results/coupling coupling scenarios/grid16_space_fixed.json
  for m in scenarios/mechanisms/*.json scenarios/hanging_chain.json; do
    study "results/coupling/mechanisms/$(basename "$m" .json)" coupling "$m"
  done
  # The sweeps behind the thesis-claim table (results/README.md; written by
  # scenarios/sweeps/make_thesis_claims.py): rerun from scratch, each point keeping its
  # summary.json and epochs.csv (stored: results/sweeps/.gitignore lets these in), then
  # the table is rewritten into results/README.md.
  # The seeds_* sweeps measure the table's verdicts over ten load phases (ideal
  # channels) or ten seeds (TDMA); measure_Ts varies the server's period.
  for s in dsm_size_cp dsm_size_cp_hold dsm_size_up measure_ramp measure_T10 \
    measure_tdma4 measure_tdma16 measure_Ts seeds_space_cp seeds_time_cp seeds_space_up \
    seeds_tdma4 seeds_tdma16; do
    rm -rf "results/sweeps/$s"
    "$bin" sweep "scenarios/sweeps/$s.json" --out "results/sweeps/$s" --keep summary \
      >/dev/null || { echo "results/sweeps/$s: failed"; exit 1; }
    echo "results/sweeps/$s: regenerated"
  done
  # The FMU loop's slot layouts (docs/fmi.md, "A networked control loop on TDMA").
  rm -rf results/sweeps/fmu_pd_tdma_layouts
  "$bin" sweep scenarios/sweeps/fmu_pd_tdma_layouts.json --out results/sweeps/fmu_pd_tdma_layouts \
    --keep summary >/dev/null 2>"$tmp/stderr" \
    || { echo "results/sweeps/fmu_pd_tdma_layouts: failed: $(cat "$tmp/stderr")"; exit 1; }
  echo "results/sweeps/fmu_pd_tdma_layouts: regenerated"
  python3 results/summarize_claims.py --write results/README.md \
    || { echo "results/README.md: claim table failed"; exit 1; }
fi
exit 0
