#!/usr/bin/env bash
# The real-GPU check, run on a lent device machine over .device/ and .gl/ from
# scripts/device-pack.sh (see there), in one call:
#
#   bash scripts/device-check.sh            # or --quick: a dry run on lavapipe
#
# 1. What the machine has (preflight.txt): the GPU (nvidia-smi), the C library against
#    what the binaries need, the Vulkan loader, the Vulkan drivers (ICD manifests) and
#    the libraries NVIDIA's needs (libGLX_nvidia.so.0, libX11, libXext), each found or
#    named as missing. The loader comes from .gl/ unpacked into .gl/root (no root
#    needed); where no NVIDIA manifest is installed but its library is, one is written.
# 2. The benches first (seconds each): `frepray bench` of both paper scenes on the CPU,
#    then on the GPU, each alone, so that the CPU rows stay when the GPU fails; then both
#    side by side with the stage plots.
# 3. The kernel twins and the GPU image tests (FREPRAY_REQUIRE_GPU=1), while the time
#    budget lasts (BUDGET seconds from the start, default 540), the images last.
#    BENCH_SIZE="width height spp" sets the benches' size (320 240 16).
# Everything goes under $OUT (default out/device): preflight.txt, bench-<scene>-<backend>.md,
# bench-<scene>.md, stages-<scene>.svg, tests-<binary>.txt. Exits 0 once the report is
# written, whatever it found: the files say what worked.
set -uo pipefail
cd "$(dirname "$0")/.."
OUT="${OUT:-out/device}"
mkdir -p "$OUT"
start=$SECONDS
budget="${BUDGET:-540}"
quick=0
[ "${1:-}" = "--quick" ] && quick=1
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
bin=./.device/frepray

# The Vulkan loader from the packed .deb files, without root.
if ls .gl/*.deb >/dev/null 2>&1; then
    mkdir -p .gl/root
    for f in .gl/*.deb; do dpkg-deb -x "$f" .gl/root 2>/dev/null || dpkg -x "$f" .gl/root; done
    export LD_LIBRARY_PATH="$PWD/.gl/root/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
fi

# Where a library is: the loader's cache, the driver folders, or LD_LIBRARY_PATH.
find_lib() {
    local name=$1 d
    ldconfig -p 2>/dev/null | awk -v n="$name" '$1 == n { print $NF; exit }' | grep . && return 0
    for d in ${LD_LIBRARY_PATH//:/ } /usr/local/nvidia/lib64 /usr/local/nvidia/lib \
        /usr/lib/x86_64-linux-gnu /usr/lib64 /usr/lib; do
        [ -e "$d/$name" ] && { echo "$d/$name"; return 0; }
    done
    return 1
}

preflight() {
    echo "## GPU"
    if command -v nvidia-smi >/dev/null; then nvidia-smi 2>&1 | head -15; else echo "nvidia-smi: not found"; fi
    echo
    echo "## C library"
    echo "have: $(ldd --version 2>&1 | head -1)"
    local need
    need=$(objdump -T "$bin" 2>/dev/null | grep -o 'GLIBC_[0-9.]*' | sort -uV | tail -1)
    echo "the binaries need: ${need:-unknown (no objdump)}"
    echo
    echo "## Vulkan"
    local lib
    for lib in libvulkan.so.1 libGLX_nvidia.so.0 libX11.so.6 libXext.so.6; do
        if p=$(find_lib "$lib"); then echo "found   $lib: $p"; else echo "MISSING $lib"; fi
    done
    local manifests=() d f
    for d in /etc/vulkan/icd.d /usr/share/vulkan/icd.d /usr/local/share/vulkan/icd.d; do
        for f in "$d"/*.json; do [ -e "$f" ] && manifests+=("$f"); done
    done
    echo "driver manifests (ICD): ${manifests[*]:-none}"
    if ! grep -qs nvidia "${manifests[@]:-/dev/null}"; then
        if p=$(find_lib libGLX_nvidia.so.0); then
            mkdir -p .gl/icd
            printf '{"file_format_version": "1.0.0", "ICD": {"library_path": "%s", "api_version": "1.3.0"}}\n' \
                "$p" > .gl/icd/nvidia_icd.json
            export VK_DRIVER_FILES="$PWD/.gl/icd/nvidia_icd.json" VK_ICD_FILENAMES="$PWD/.gl/icd/nvidia_icd.json"
            echo "no NVIDIA manifest installed: wrote .gl/icd/nvidia_icd.json for $p"
        else
            echo "no NVIDIA Vulkan driver: no manifest and no libGLX_nvidia.so.0 (a compute-only driver install); the GPU rows will say which adapter was found, if any"
        fi
    fi
    echo
    echo "## The adapter frepray opens"
    "$bin" bench scenes/many-lights.toml --backend gpu --spp 1 --width 8 --height 8 2>&1 |
        grep -m1 -E '^GPU:|error' || echo "no GPU line (see the GPU bench files)"
}
preflight > "$OUT/preflight.txt" 2>&1
cat "$OUT/preflight.txt"

left() { echo $((budget - (SECONDS - start))); }

# BENCH_SIZE="width height spp" (320 240 16; --quick: 64 48 2).
default_size="320 240 16"
[ "$quick" = 1 ] && default_size="64 48 2"
read -r bw bh bn <<< "${BENCH_SIZE:-$default_size}"
size=(--width "$bw" --height "$bh" --spp "$bn")
gpu_ok=1
for s in many-lights table; do
    for b in cpu gpu; do
        timeout 120 "$bin" bench "scenes/$s.toml" --backend "$b" "${size[@]}" \
            > "$OUT/bench-$s-$b.md" 2>&1
        rc=$?
        echo "bench $s on the $b: rc $rc"
        cat "$OUT/bench-$s-$b.md"
        [ "$b" = gpu ] && [ "$rc" != 0 ] && gpu_ok=0
    done
done
if [ "$gpu_ok" = 1 ]; then
    for s in many-lights table; do
        timeout 180 "$bin" bench "scenes/$s.toml" --backend cpu,gpu "${size[@]}" \
            --plot "$OUT/stages-$s.svg" > "$OUT/bench-$s.md" 2>&1
        cat "$OUT/bench-$s.md"
    done
fi

if [ "$quick" = 0 ]; then
    # The test binaries read files by the path of the checkout they were built in.
    root=$(cat .device/root 2>/dev/null || echo)
    if [ -n "$root" ] && [ ! -e "$root/scenes" ]; then
        mkdir -p "$(dirname "$root")" && ln -sfn "$PWD" "$root"
    fi
    # The twins first (seconds), then the images (minutes), while the budget lasts.
    for t in gpu_tests; do
        [ -x ".device/$t" ] || { echo "$t: not packed"; continue; }
        for filter in device layout sampler_twin record_twin sums_twin bsdf_twin light_twin \
            env_twin quadric_twin perturbed_twin tape_twin direct_image; do
            l=$(left)
            if [ "$l" -lt 20 ]; then
                echo "$filter: skipped (the time budget is spent)"
                continue
            fi
            FREPRAY_REQUIRE_GPU=1 timeout "$l" ".device/$t" "$filter::" --test-threads 1 \
                > "$OUT/tests-$filter.txt" 2>&1
            echo "$filter: $(grep -E 'test result' "$OUT/tests-$filter.txt" || echo 'no result (timeout?)')"
            grep -E 'FAILED|panicked' "$OUT/tests-$filter.txt" | head -5
        done
    done
fi
echo "device check: $((SECONDS - start)) s; files in $OUT"
exit 0
