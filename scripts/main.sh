#!/usr/bin/env bash
# Sets up, builds and runs the main job: the paper's "many small lights" scene rendered
# with optimal MIS (light + BSDF + uniform light-area sampling), written to out/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
[ -x "$HOME/.cargo/bin/cargo" ] && export PATH="$HOME/.cargo/bin:$PATH"
mkdir -p out
cargo build --release -p frepray-cli
./target/release/frepray render scenes/many-lights.toml -o out/many-lights.exr \
  -o out/many-lights.png --mis optimal-direct --spp 64 --aovs depth,normal,albedo
echo "wrote out/many-lights.exr (R, G, B + AOVs) and out/many-lights.png"
