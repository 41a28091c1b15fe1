#!/usr/bin/env bash
# Sets up, builds and runs the main job, writing into out/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
[ -x "$HOME/.cargo/bin/cargo" ] && export PATH="$HOME/.cargo/bin:$PATH"
mkdir -p out
cargo build --release -p frepray
./target/release/frepray check ../shared/models/fidget/colonnade.vm
./target/release/frepray render ../shared/models/fidget/colonnade.vm -o out/colonnade.png --width 512 --height 512
./target/release/frepray render models/examples/bumpy.frep -o out/bumpy.exr --width 512 --height 512
