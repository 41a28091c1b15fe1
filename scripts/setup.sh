#!/usr/bin/env bash
# Installs what frepray needs on a fresh Debian machine of this project's kind.
# Rust (stable, with rustfmt and clippy) is expected on the machine; crates come from
# crates.io through cargo; Mesa's software Vulkan driver (lavapipe) from Debian, so that
# the GPU back end runs and is tested on machines without a GPU (../shared/GPU.md §11.1).
# The Python package: a virtual environment in .venv (Python ≥ 3.11) with the pinned
# tools of python/requirements-dev.txt (maturin, numpy, pytest, Ray), and frepray built
# into it by maturin (editable: python/frepray). Options:
#   --no-python   skip the Python package (the CLI alone renders the main job);
#   --no-gpu      skip Mesa's lavapipe (a CPU-only build needs no Vulkan driver);
#   --no-browser  skip Debian's Chromium and ChromeDriver (only `frepray view`'s browser
#                 tests use them);
#   --dev         build the extension in the dev profile (optimised, not across crates:
#                 the build `cargo test` shares, as scripts/test.sh wants) instead of
#                 release;
#   --venv-only   create .venv and stop (scripts/test.sh installs into it beside its
#                 build).
set -euo pipefail
cd "$(dirname "$0")/.."
python=1 gpu=1 browser=1 profile=--release venv_only=
for a in "$@"; do
  case $a in
    --no-python) python= ;;
    --no-gpu) gpu= ;;
    --no-browser) browser= ;;
    --dev) profile= ;;
    --venv-only) venv_only=1 ;;
    *) echo "setup: unknown option $a (expected --no-python, --no-gpu, --no-browser, --dev, --venv-only)" >&2; exit 2 ;;
  esac
done
if ! command -v cargo >/dev/null 2>&1; then
  if [ -x "$HOME/.cargo/bin/cargo" ]; then
    export PATH="$HOME/.cargo/bin:$PATH"
  else
    echo "setup: cargo not found; install Rust (rustup) first" >&2
    exit 1
  fi
fi
rustup component add rustfmt clippy >/dev/null 2>&1 || true

# lavapipe, at the versions GPU.md measured (Debian 12's main archive).
LAVAPIPE="mesa-vulkan-drivers=22.3.6-1+deb12u2 libvulkan1=1.3.239.0-1"
if [ -n "$gpu" ] && ! dpkg -s mesa-vulkan-drivers libvulkan1 >/dev/null 2>&1; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "setup: installing Mesa's lavapipe for the GPU tests" >&2
    apt-get update -qq >/dev/null
    # shellcheck disable=SC2086
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $LAVAPIPE >/dev/null \
      || DEBIAN_FRONTEND=noninteractive apt-get install -y -qq mesa-vulkan-drivers libvulkan1 >/dev/null
  else
    echo "setup: mesa-vulkan-drivers and libvulkan1 are missing; install them as root" \
      "(apt-get install mesa-vulkan-drivers libvulkan1) for the GPU tests" >&2
  fi
fi

# Headless Chromium and its WebDriver, for the browser tests of `frepray view`.
if [ -n "$browser" ] && ! { command -v chromium && command -v chromedriver; } >/dev/null 2>&1; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "setup: installing Chromium and ChromeDriver for the browser tests" >&2
    apt-get update -qq >/dev/null
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium chromium-driver >/dev/null
  else
    echo "setup: chromium and chromium-driver are missing; install them as root" \
      "(apt-get install chromium chromium-driver) for the browser tests" >&2
  fi
fi

[ -z "$python" ] && exit 0
PYTHON="${PYTHON:-python3}"
echo "setup: the Python package (.venv, built by maturin)" >&2
if [ ! -x .venv/bin/python ]; then
  "$PYTHON" -c 'import sys; assert sys.version_info >= (3, 11), sys.version' || {
    echo "setup: $PYTHON must be Python 3.11 or newer (set PYTHON=...)" >&2
    exit 1
  }
  "$PYTHON" -m venv .venv
fi
[ -n "$venv_only" ] && exit 0
.venv/bin/python -m pip install -q --disable-pip-version-check -r python/requirements-dev.txt
# shellcheck disable=SC2086
VIRTUAL_ENV="$PWD/.venv" .venv/bin/maturin develop -q $profile -m python/Cargo.toml
