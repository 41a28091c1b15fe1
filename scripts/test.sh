#!/usr/bin/env bash
# Sets up and runs every check and test: formatting, clippy, the docs (warnings are
# errors: broken intra-doc links fail), the dependencies' licences, the crates'
# dependency arrows (DESIGN.md §3), the whole Rust test suite, then the Python package's
# tests (pytest, Ray on a local 2-CPU cluster) and its wheel, installed into a clean
# environment. The long comparisons are in scripts/long-test.sh.
#
# One build serves every step: clippy's lints run inside the test build (clippy-driver
# as the workspace's compiler, with `-D warnings`: what `cargo clippy --workspace
# --all-targets -- -D warnings` checks, without checking every crate a second time); the
# Python package is set up beside that build and compiles the extension on its
# dependencies (Cargo sees the environment maturin gives it, so pyo3 is built once);
# the docs build beside the tests, at a lower priority.
# Afterwards a plain `cargo build` recompiles the workspace's own crates once (the
# compiler differs).
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
# Background jobs stop with the script.
trap 'summary; kill $(jobs -p) 2>/dev/null || true' EXIT
logs=$(mktemp -d)
# Waits for a background job; on failure prints its log and fails.
await() {
  local pid=$1 log=$2 what=$3
  if ! wait "$pid"; then
    cat "$log" >&2
    echo "test: $what failed" >&2
    return 1
  fi
  cat "$log" >&2
}

step "setup (Rust components, lavapipe, Chromium, .venv)" bash scripts/setup.sh --venv-only
# CI builds a fresh clone once: incremental compilation's caches would only cost the
# time to write them (the workspace's crates from scratch 124.7–126.5 s against
# 134.3–137.1 s: docs/notebook/2026-12-07-test-time-probes.md). Set before any Cargo
# call, so that every build here shares it; a developer's run keeps them.
if [ -n "${CI:-}" ]; then
  export CARGO_INCREMENTAL=0
fi
[ -x "$HOME/.cargo/bin/cargo" ] && export PATH="$HOME/.cargo/bin:$PATH"
# What `maturin develop` sets for Cargo (maturin 1.16), so that pyo3's build script
# gives the tests' build and the extension's the same configuration.
py="$PWD/.venv/bin/python"
export VIRTUAL_ENV="$PWD/.venv" PYO3_PYTHON="$py" PYTHON_SYS_EXECUTABLE="$py" \
  PYO3_BUILD_EXTENSION_MODULE=1
PYO3_ENVIRONMENT_SIGNATURE=$("$py" -c 'import platform, struct, sys
print("%s-%d.%d-%dbit" % (platform.python_implementation().lower(), *sys.version_info[:2],
                          struct.calcsize("P") * 8))')
export PYO3_ENVIRONMENT_SIGNATURE
driver="$(rustc --print sysroot)/bin/clippy-driver"
if [ -x "$driver" ]; then
  export RUSTC_WORKSPACE_WRAPPER="$driver"
  export CLIPPY_ARGS="-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__"
  # The lints must fail the build: a crate with one warning-level clippy lint
  # (`useless_vec`) must not compile, and the same crate without it must.
  probe() {
    printf 'pub fn f() -> usize { let v = %s; v.len() }\n' "$1" > "$logs/probe.rs"
    "$driver" rustc --edition 2021 --crate-type lib --emit=metadata \
      -o "$logs/probe.rmeta" "$logs/probe.rs" > "$logs/probe.log" 2>&1
  }
  if probe 'vec![1u8]' || ! probe '[1u8]'; then
    cat "$logs/probe.log" >&2
    echo "test: clippy-driver did not turn a lint into an error; run cargo clippy" >&2
    exit 1
  fi
fi
# The Python package: pip (no compiler needed), then maturin, which waits for Cargo's
# lock and builds the extension on the dependencies the test build made.
bash scripts/setup.sh --dev --no-gpu --no-browser > "$logs/setup" 2>&1 &
python_setup=$!
step "cargo fmt --check" cargo fmt --all -- --check
if [ -n "${RUSTC_WORKSPACE_WRAPPER:-}" ]; then
  step "build every target, with clippy's lints" \
    cargo test --workspace --all-targets --no-run
else
  step "cargo clippy" cargo clippy --workspace --all-targets -- -D warnings
fi
# The docs beside the tests: once the first test binary runs, Cargo's lock is free (it
# is held while building); the docs reuse the build's proc macros and build scripts, and
# are niced so that they take what the tests leave idle.
(
  until grep -q '^ *Running ' "$logs/test" 2>/dev/null; do sleep 1; done
  env -u RUSTC_WORKSPACE_WRAPPER -u CLIPPY_ARGS RUSTDOCFLAGS="-D warnings" nice -n 10 \
    cargo doc --workspace --no-deps -q
) > "$logs/doc" 2>&1 &
docs=$!
step "licences" python3 scripts/check-licenses.py
step "dependency arrows (DESIGN.md §3)" python3 scripts/check-deps.py

# GPU tests fail, not skip, when no adapter is found (lavapipe comes with setup.sh);
# Mesa wants a private runtime directory, else it prints a harmless error per device.
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
# Examples and benchmarks were built above; doctests run in a second call.
run_tests() {
  env FREPRAY_REQUIRE_GPU=1 cargo test --workspace --lib --bins --tests 2>&1 | tee "$logs/test"
}
step "cargo test" run_tests
step "cargo doc (beside the tests)" await "$docs" "$logs/doc" "cargo doc"
step "cargo test --doc" cargo test --workspace --doc
step "the Python package (set up beside the build)" \
  await "$python_setup" "$logs/setup" "the Python package's setup"
step "pytest" .venv/bin/python -m pytest -q --doctest-modules python/tests python/frepray
# The wheel users install: packaged from the extension just built, installed into a
# clean virtual environment and run there (the quick start).
step "the wheel, in a clean environment" bash scripts/wheel.sh --dev --check --out "$logs/dist"
