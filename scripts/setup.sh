#!/usr/bin/env bash
# Installs what frepray needs on a fresh Debian machine of this project's kind.
# Rust (stable, with rustfmt and clippy) is expected on the machine; everything else
# comes from crates.io through cargo.
set -euo pipefail
if ! command -v cargo >/dev/null 2>&1; then
  if [ -x "$HOME/.cargo/bin/cargo" ]; then
    export PATH="$HOME/.cargo/bin:$PATH"
  else
    echo "setup: cargo not found; install Rust (rustup) first" >&2
    exit 1
  fi
fi
rustup component add rustfmt clippy >/dev/null 2>&1 || true
