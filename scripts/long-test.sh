#!/usr/bin/env bash
# The long runs, outside the test command (scripts/test.sh):
# - every case of the GPU-against-CPU image comparisons (FREPRAY_LONG=1: all seven
#   estimators, per light under the sky map, every path and environment case; the test
#   command runs one case per integrator and estimator family), on lavapipe where there
#   is no GPU (about 5 minutes on 2 cores), and the direct kernels compiled with
#   runtime bounds checks against the unchecked ones (about 5 minutes more: lavapipe
#   compiles the checked kernels slowly);
# - the geometry's random CSG trees (docs/geometry.md) with many more trees than the test
#   command tries: FREPRAY_CSG_TREES sets the count (default 20000 trees, 100 rays each:
#   two million rays, about 20 minutes on 2 cores).
# Prints each test's tally; fails on any disagreement.
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x "$HOME/.cargo/bin/cargo" ] && export PATH="$HOME/.cargo/bin:$PATH"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
FREPRAY_LONG=1 FREPRAY_REQUIRE_GPU=1 cargo test -p gpu --test gpu_tests direct_image::
export FREPRAY_CSG_TREES="${FREPRAY_CSG_TREES:-20000}"
cargo test -p frep --test frep_tests csg_differential:: -- --nocapture
