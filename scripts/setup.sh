#!/usr/bin/env bash
# Installs what frepray needs on a fresh Debian machine of this project's kind.
# Rust (stable, with rustfmt and clippy) is expected on the machine; crates come from
# crates.io through cargo. The Python package: a virtual environment in .venv (Python
# ≥ 3.11) with the pinned tools of python/requirements-dev.txt (maturin, numpy, pytest,
# Ray), and frepray built into it by maturin (release, editable: python/frepray).
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v cargo >/dev/null 2>&1; then
  if [ -x "$HOME/.cargo/bin/cargo" ]; then
    export PATH="$HOME/.cargo/bin:$PATH"
  else
    echo "setup: cargo not found; install Rust (rustup) first" >&2
    exit 1
  fi
fi
rustup component add rustfmt clippy >/dev/null 2>&1 || true

PYTHON="${PYTHON:-python3}"
if [ ! -x .venv/bin/python ]; then
  "$PYTHON" -c 'import sys; assert sys.version_info >= (3, 11), sys.version' || {
    echo "setup: $PYTHON must be Python 3.11 or newer (set PYTHON=...)" >&2
    exit 1
  }
  "$PYTHON" -m venv .venv
fi
.venv/bin/python -m pip install -q --disable-pip-version-check -r python/requirements-dev.txt
VIRTUAL_ENV="$PWD/.venv" .venv/bin/maturin develop -q --release -m python/Cargo.toml
