#!/usr/bin/env bash
# The real-GPU check, run on a lent device machine over .device/ from
# scripts/device-pack.sh (see there): the adapter, the kernel twins and the GPU image
# tests against the CPU
# (FREPRAY_REQUIRE_GPU=1: no adapter is a failure), and `frepray bench --backend cpu,gpu`
# on both paper scenes at 320×240 and 16 spp with the stage plots. Everything goes under
# $OUT (default out/device): adapter.txt, tests-<binary>.txt, bench-<scene>.md,
# stages-<scene>.svg.
# `--quick` runs the bench alone at 64×48, 2 spp (a dry run on lavapipe).
set -uo pipefail
cd "$(dirname "$0")/.."
OUT="${OUT:-out/device}"
mkdir -p "$OUT"
quick=0
[ "${1:-}" = "--quick" ] && quick=1
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
# The test binary reads files by the path of the checkout it was built in.
root=$(cat .device/root)
if [ ! -e "$root/scenes" ]; then
    mkdir -p "$(dirname "$root")" && ln -sfn "$PWD" "$root"
fi
{
    nvidia-smi 2>&1 | head -15
    ./.device/frepray bench scenes/many-lights.toml --backend gpu --spp 1 --width 8 --height 8 2>&1 |
        grep -m1 '^GPU:'
} > "$OUT/adapter.txt"
cat "$OUT/adapter.txt"
if [ "$quick" = 0 ]; then
    # The twins first (seconds), then the images (minutes).
    for t in record_twin sums_twin sampler_twin bsdf_twin light_twin direct_image; do
        [ -x ".device/$t" ] || continue
        FREPRAY_REQUIRE_GPU=1 timeout 400 "./.device/$t" --test-threads 1 > "$OUT/tests-$t.txt" 2>&1
        echo "$t: $(grep -E 'test result' "$OUT/tests-$t.txt" || echo 'no result (timeout?)')"
        grep -E 'FAILED|panicked' "$OUT/tests-$t.txt" | head -5
    done
fi
size=(--width 320 --height 240 --spp 16)
[ "$quick" = 1 ] && size=(--width 64 --height 48 --spp 2)
for s in many-lights table; do
    ./.device/frepray bench "scenes/$s.toml" --backend cpu,gpu "${size[@]}" \
        --plot "$OUT/stages-$s.svg" > "$OUT/bench-$s.md" 2>&1
    cat "$OUT/bench-$s.md"
done
