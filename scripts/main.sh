#!/usr/bin/env bash
# Sets up, builds and runs the main job: the paper's "many small lights" scene rendered
# with optimal MIS (light + BSDF + uniform light-area sampling), written to out/. Only
# the CLI is built (the Python package is built by scripts/test.sh or setup.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
step() { echo "main: $* ($(date +%T))" >&2; }
step "setting up (Rust components, Mesa's lavapipe)"
bash scripts/setup.sh --no-python
[ -x "$HOME/.cargo/bin/cargo" ] && export PATH="$HOME/.cargo/bin:$PATH"
mkdir -p out
step "building the CLI (release, optimised across crates: minutes on a first build)"
cargo build --release -p frepray-cli
step "rendering scenes/many-lights.toml with optimal MIS"
./target/release/frepray render scenes/many-lights.toml -o out/many-lights.exr \
  -o out/many-lights.png --mis optimal-direct --spp 64 --aovs depth,normal,albedo
step "done: out/many-lights.exr (R, G, B + AOVs) and out/many-lights.png"
