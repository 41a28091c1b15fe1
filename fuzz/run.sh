#!/usr/bin/env bash
# Fuzzes frepray's readers: `fuzz/run.sh TARGET EXECS [SEED]` or `fuzz/run.sh all EXECS`.
# TARGET is frep, hf, vm, toml or json; EXECS a count (10_000_000 allowed). Builds the
# harness with LLVM SanitizerCoverage (inline 8-bit counters: stable codegen flags, no
# nightly, no libFuzzer), then prints one RESULT line per target: executions, corpus
# size, edges, crashes, hangs, peak memory. Exit status 1 when anything crashed or hung.
# --target keeps the flags off build scripts and proc macros (they run on the host).
set -euo pipefail
cd "$(dirname "$0")"
[ -x "$HOME/.cargo/bin/cargo" ] && export PATH="$HOME/.cargo/bin:$PATH"
[ $# -ge 2 ] || { echo "usage: $0 TARGET|all EXECS [SEED]" >&2; exit 2; }
host=$(rustc -vV | sed -n 's/^host: //p')
export RUSTFLAGS="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=3 \
-Cllvm-args=-sanitizer-coverage-inline-8bit-counters -Cdebug-assertions -Coverflow-checks"
cargo build --release --quiet --target "$host"
bin="target/$host/release/frepray-fuzz"
targets=("$1")
[ "$1" = all ] && targets=(frep hf vm toml json toml-resolve json-resolve)
status=0
for t in "${targets[@]}"; do
    "$bin" "$t" "$2" ${3:+"$3"} || status=1
done
exit $status
