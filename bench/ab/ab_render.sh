#!/bin/bash
# Side-by-side single-thread throughput of frepray builds: `frepray render SCENE
# --integrator I --spp N --threads 1` for each scene and build in turn, REPS rounds
# (alternating, so that load on a shared machine hits every build alike); prints each
# build's median and best MSamples/s per scene and their ratios to the first build.
#
#   bash bench/ab/ab_render.sh REPS SPP INTEGRATOR "SCENE ..." BIN_A BIN_B [BIN ...]
#
# A scene is a name in bench/mitsuba-compare/scenes/ or scenes/ (without .toml), or a
# path. The image goes to a temporary file, removed at the end.
set -euo pipefail
[ $# -ge 6 ] || { sed -n 2,9p "$0"; exit 2; }
REPS=$1 SPP=$2 INT=$3 SCENES=$4
shift 4
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
scene_file() {
  for f in "$1" "$ROOT/bench/mitsuba-compare/scenes/$1.toml" "$ROOT/scenes/$1.toml"; do
    [ -f "$f" ] && { echo "$f"; return; }
  done
  echo "no scene '$1'" >&2
  exit 2
}
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
for _ in $(seq "$REPS"); do
  for s in $SCENES; do
    f=$(scene_file "$s")
    for b in "$@"; do
      v=$("$b" render "$f" --integrator "$INT" --spp "$SPP" --threads 1 -o "$OUT/x.exr" 2>&1 |
        grep -o '[0-9.]* MSamples/s' | cut -d' ' -f1)
      echo "$s $b $v"
    done
  done
done > "$OUT/runs.txt"
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
python3 - "$OUT/runs.txt" "$@" <<'PY'
import statistics as st, sys
runs, bins = {}, sys.argv[2:]
for line in open(sys.argv[1]):
    s, b, v = line.split()
    runs.setdefault(s, {}).setdefault(b, []).append(float(v))
print("| scene | build | median MSamples/s | best | median / first | best / first |")
print("| --- | --- | ---: | ---: | ---: | ---: |")
for s, by in runs.items():
    m0, b0 = st.median(by[bins[0]]), max(by[bins[0]])
    for b in bins:
        m, x = st.median(by[b]), max(by[b])
        print(f"| {s} | {b} | {m:.3f} | {x:.3f} | {m / m0:.3f} | {x / b0:.3f} |")
PY
