#!/usr/bin/env bash
# Regenerates every stored run in results/ from its scenario and lists the digests that
# changed. Usage: results/regenerate.sh   (from anywhere; builds the release binary)
#
# A stored run is a directory results/<dir>/ with a summary.json whose "scenario" key
# names an existing scenarios/<scenario>.json; it is rerun into the same directory.
# Directories ending in .new (left by `dsmcosim check`) are not stored runs. To add a
# stored run: `dsmcosim run scenarios/<name>.json --out results/<name>`.
set -uo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet || exit 1
bin=target/release/dsmcosim
key() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$1" "$2"; }
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
  "$bin" run "$scenario" --out "$dir" >/dev/null
  code=$?
  # Exit code 3 is a run that diverged: its trace up to the divergence is the result.
  if [ $code -ne 0 ] && [ $code -ne 3 ]; then echo "$dir: failed (exit $code)"; exit $code; fi
  new=$(key "$summary" digest)
  if [ "$old" != "$new" ]; then echo "$dir: digest changed $old -> $new"; else echo "$dir: unchanged"; fi
done
[ $found -eq 1 ] || echo "no stored runs found under results/"
exit 0
