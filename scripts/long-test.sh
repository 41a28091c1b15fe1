#!/usr/bin/env bash
# The long runs of the randomised differential tests, outside the test command: the
# geometry's random CSG trees (docs/geometry.md) with many more trees than `test.sh` tries.
# FREPRAY_CSG_TREES sets the count (default 20000 trees, 100 rays each: two million rays,
# about 20 minutes on 2 cores). Prints each test's tally; fails on any disagreement.
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x "$HOME/.cargo/bin/cargo" ] && export PATH="$HOME/.cargo/bin:$PATH"
export FREPRAY_CSG_TREES="${FREPRAY_CSG_TREES:-20000}"
cargo test -p frep --test csg_differential -- --nocapture
