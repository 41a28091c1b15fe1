#!/usr/bin/env bash
# Builds frepray's Python wheel: one abi3 wheel for CPython 3.8 and newer on this
# platform, installable with `pip install dist/frepray-*.whl` without Rust.
#   bash scripts/wheel.sh            release build (link-time optimised) into dist/
#   bash scripts/wheel.sh --dev      the dev profile (optimised per crate; the build the
#                                    test command already made, so it only packages)
#   bash scripts/wheel.sh --check    also install the wheel into a clean virtual
#                                    environment and run the quick start there, from
#                                    outside the source tree (the test command does this)
#   --out DIR                        where the wheel goes (default dist/)
set -euo pipefail
cd "$(dirname "$0")/.."
profile=--release check= out=dist
while [ $# -gt 0 ]; do
  case $1 in
    --dev) profile= ;;
    --check) check=1 ;;
    --out) out=$2; shift ;;
    *) echo "wheel: unknown option $1 (expected --dev, --check, --out DIR)" >&2; exit 2 ;;
  esac
  shift
done
[ -x "$HOME/.cargo/bin/cargo" ] && export PATH="$HOME/.cargo/bin:$PATH"
# maturin from .venv, at the version python/requirements-dev.txt pins.
bash scripts/setup.sh --no-gpu --no-browser --venv-only
pin=$(grep '^maturin==' python/requirements-dev.txt)
.venv/bin/python -m pip install -q --disable-pip-version-check "$pin"
mkdir -p "$out"
# The extension's build environment, as `maturin develop` gives it (scripts/test.sh).
export VIRTUAL_ENV="$PWD/.venv"
# shellcheck disable=SC2086
.venv/bin/maturin build -q $profile -m python/Cargo.toml --out "$out" >&2
wheel=$(ls -t "$out"/frepray-*.whl | head -1)
echo "wheel: $wheel" >&2
[ -z "$check" ] && exit 0

# A clean environment with nothing but the wheel and what it declares (numpy).
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"${PYTHON:-python3}" -m venv "$tmp/venv"
"$tmp/venv/bin/python" -m pip install -q --disable-pip-version-check "$wheel"
scene="$PWD/scenes/many-lights.toml"
(
  cd "$tmp"
  "$tmp/venv/bin/python" - "$scene" "$tmp" <<'EOF'
# The README's quick start, from the installed wheel.
import os, sys
import frepray
root = os.path.realpath(sys.argv[2])
assert os.path.realpath(frepray.__file__).startswith(root), frepray.__file__
scene = frepray.load(sys.argv[1])
state = frepray.render(scene, spp=2, estimator="optimal-direct", seed=1, width=32, height=24)
img = state.image()
assert img.shape == (24, 32, 3) and img.mean() > 0, (img.shape, img.mean())
state.write_exr(os.path.join(root, "quick.exr"))
attrs = frepray.exr_attributes(os.path.join(root, "quick.exr"))
assert attrs["frepray.estimator"] == "optimal-direct", attrs
print(f"wheel: installed and rendered ({img.shape[1]}x{img.shape[0]}, mean {img.mean():.4f})",
      file=sys.stderr)
EOF
)
