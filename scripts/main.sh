#!/usr/bin/env bash
# Sets up, builds and runs the main job: the paper's "many small lights" scene rendered
# with optimal MIS (light + BSDF + uniform light-area sampling), then where optimal MIS
# wins: the two-lights scene with the balance heuristic against optimal-direct at equal
# samples, each image's error against a reference printed and the images written, all
# under out/. Only the command-line program is built, with the CPU back end alone (the
# GPU back end, the Python package and the fastest, link-time-optimised build come with
# scripts/setup.sh and `cargo build --release`: README.md).
set -euo pipefail
cd "$(dirname "$0")/.."
t0=$SECONDS
step() { echo "main: [$((SECONDS - t0)) s] $*" >&2; }
step "setting up (Rust's components)"
bash scripts/setup.sh --no-python --no-gpu --no-browser
[ -x "$HOME/.cargo/bin/cargo" ] && export PATH="$HOME/.cargo/bin:$PATH"
mkdir -p out
step "building frepray (optimised, CPU back end; about 3 minutes on 2 cores the first time)"
cargo build -p frepray-cli --no-default-features
B=target/debug/frepray
step "rendering scenes/many-lights.toml with optimal MIS (optimal-direct, 64 samples per pixel)"
$B render scenes/many-lights.toml -o out/many-lights.exr -o out/many-lights.png \
  --estimator optimal-direct --spp 64 --aovs depth,normal,albedo
step "where optimal MIS wins: scenes/two-lights.toml, balance against optimal-direct at 16 samples per pixel, 4 seeds each, against a 1024-sample reference"
$B experiment scenes/two-lights.toml --estimators balance,optimal-direct --spp 16 \
  --reference-spp 1024 --width 160 --height 120 --hide-emitters --quiet --out out/two-lights
# The table of summary.md: RMSE of each, and optimal-direct's Improvement over balance.
awk '/^\| Estimator/{t=1} t&&!/^\|/{exit} t' out/two-lights/summary.md >&2
for e in balance optimal-direct; do
  $B render scenes/two-lights.toml --estimator "$e" --spp 16 --hide-emitters --quiet \
    -o "out/two-lights-$e.png" 2>/dev/null
done
step "done: out/many-lights.png (and .exr with depth, normal, albedo); out/two-lights-balance.png and out/two-lights-optimal-direct.png side by side (16 samples per pixel each); out/two-lights/summary.md"
