#!/usr/bin/env bash
# Sets up and runs every check and test: formatting, clippy, the docs (warnings are
# errors: broken intra-doc links fail), the dependencies' licences, the whole Rust test
# suite, then the Python package's tests (pytest, Ray on a local 2-CPU cluster).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
[ -x "$HOME/.cargo/bin/cargo" ] && export PATH="$HOME/.cargo/bin:$PATH"
cargo fmt --all -- --check
cargo clippy --workspace --all-targets -- -D warnings
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps
python3 scripts/check-licenses.py
# GPU tests fail, not skip, when no adapter is found (lavapipe comes with setup.sh);
# Mesa wants a private runtime directory, else it prints a harmless error per device.
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
FREPRAY_REQUIRE_GPU=1 cargo test --workspace
.venv/bin/python -m pytest -q --doctest-modules python/tests python/frepray
