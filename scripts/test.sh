#!/usr/bin/env bash
# Sets up and runs every check and test: formatting, clippy, the docs (warnings are
# errors: broken intra-doc links fail), the dependencies' licences, the crates'
# dependency arrows (DESIGN.md §3), the whole Rust test suite, then the Python package's
# tests (pytest, Ray on a local 2-CPU cluster). The long comparisons are in
# scripts/long-test.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
# Each step's wall time goes to stderr, and a summary at the end.
times=()
step() {
  local name=$1 t0=$SECONDS
  shift
  echo "test: $name" >&2
  "$@"
  times+=("$(printf '%5d s  %s' $((SECONDS - t0)) "$name")")
}
summary() { [ ${#times[@]} -gt 0 ] && printf 'test: %s\n' "${times[@]}" >&2; }
trap summary EXIT
step "setup (lavapipe, .venv with the Python package)" bash scripts/setup.sh --dev
[ -x "$HOME/.cargo/bin/cargo" ] && export PATH="$HOME/.cargo/bin:$PATH"
step "cargo fmt --check" cargo fmt --all -- --check
step "cargo clippy" cargo clippy --workspace --all-targets -- -D warnings
step "cargo doc" env RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps
step "licences" python3 scripts/check-licenses.py
step "dependency arrows (DESIGN.md §3)" python3 scripts/check-deps.py
# GPU tests fail, not skip, when no adapter is found (lavapipe comes with setup.sh);
# Mesa wants a private runtime directory, else it prints a harmless error per device.
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
# Examples are not built here (clippy checked them); doctests run in a second call.
step "cargo test" env FREPRAY_REQUIRE_GPU=1 cargo test --workspace --lib --bins --tests
step "cargo test --doc" cargo test --workspace --doc
step "pytest" .venv/bin/python -m pytest -q --doctest-modules python/tests python/frepray
