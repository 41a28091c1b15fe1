#!/usr/bin/env bash
# Prepares the real-GPU check for a lent device machine: the release `frepray` and the
# GPU test binary (`gpu_tests`: the kernel twins and the image tests), stripped, in
# .device/ (git-ignored), with Vulkan's loader package in .gl/ (the device machine
# reaches no package registry). Then, in one call carrying .device and .gl:
#
#   bash scripts/device-check.sh
#
# which unpacks the loader without root, reports what the machine lacks, runs the
# benches first and the tests while its time budget lasts, and writes everything under
# $OUT (docs/gpu.md, "On a real GPU").
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p .device .gl
cargo build --release -p frepray-cli
# The test binary cargo builds (its name carries a hash): the GPU images against the
# CPU's, and the kernel twins whose bit-equality lavapipe shows (a real GPU may fuse or
# reorder: what it does is a finding, not a failure to hide). The test profile is the
# optimised dev build the test command already made, not a second link-time optimised
# one: the tests' time is the GPU's.
cargo test --workspace --test gpu_tests --no-run --message-format=json 2>/dev/null |
    python3 -c 'import json,sys
for l in sys.stdin:
    m = json.loads(l)
    if m.get("reason") == "compiler-artifact" and m.get("executable"):
        print(m["target"]["name"], m["executable"])' |
    while read -r name bin; do strip -o ".device/$name" "$bin"; done
strip -o .device/frepray target/release/frepray
# The tests read scenes/sky.exr by the path they were built at: device-check.sh links it.
pwd > .device/root
if ! ls .gl/*.deb >/dev/null 2>&1; then
    o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64'
    mkdir -p /tmp/amd64/partial
    # shellcheck disable=SC2086
    apt-get $o update -qq && (cd .gl && apt-get $o download libvulkan1)
fi
du -sh .device .gl
