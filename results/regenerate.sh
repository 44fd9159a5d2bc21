#!/usr/bin/env bash
# Regenerates every stored run in results/ from its scenario and lists the digests that
# changed. Usage: results/regenerate.sh   (from anywhere; builds the release binary)
set -uo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet || exit 1
bin=target/release/dsmcosim
runs="grid16_monolithic grid16_space_fixed grid16_time_fixed"
changed=0
for name in $runs; do
  old=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['digest'])" "results/$name/summary.json" 2>/dev/null || echo none)
  "$bin" run "scenarios/$name.json" --out "results/$name" >/dev/null
  code=$?
  # Exit code 3 is a run that diverged: its trace up to the divergence is the result.
  if [ $code -ne 0 ] && [ $code -ne 3 ]; then echo "$name: failed (exit $code)"; exit $code; fi
  new=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['digest'])" "results/$name/summary.json")
  if [ "$old" != "$new" ]; then echo "$name: digest changed $old -> $new"; changed=1; else echo "$name: unchanged"; fi
done
exit 0
