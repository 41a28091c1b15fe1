#!/usr/bin/env bash
# Fuzzes frepray's readers: `fuzz/run.sh TARGET EXECS [SEED]` or `fuzz/run.sh all EXECS`.
# TARGET is frep, hf, vm, toml, json, toml-resolve, json-resolve or state (render-state
# files); EXECS a count (10_000_000 allowed). Builds the harness with LLVM
# SanitizerCoverage (inline 8-bit counters: stable codegen flags, no nightly, no
# libFuzzer), then prints one RESULT line per target: executions, corpus size, edges,
# crashes, hangs, peak memory. Exit status 1 when anything crashed or hung.
# `fuzz/run.sh selftest 1` checks that each guard (panic, hang, memory, stack) works;
# FUZZ_MAX_SECONDS=N stops each target after N seconds, as does SIGTERM or Ctrl-C (the
# summary says how far it got).
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
if [ "$1" = selftest ]; then
    # Each guard on an input made to trip it: the input must be saved and reported.
    rm -rf crashes/selftest hangs/selftest
    exec 2>/dev/null # the shell's own "Aborted" and "Segmentation fault" lines
    for k in panic slow memory stack; do
        if (FUZZ_SELFTEST=$k "$bin" selftest 1 >/dev/null 2>&1) 2>/dev/null; then
            echo "guard $k: not caught"; exit 1
        fi
        grep -qrx "$k" crashes/selftest hangs/selftest || { echo "guard $k: input not saved"; exit 1; }
        echo "guard $k: caught, input saved"
    done
    exit 0
fi
targets=("$1")
[ "$1" = all ] && targets=(frep hf vm toml json toml-resolve json-resolve state)
status=0
for t in "${targets[@]}"; do
    "$bin" "$t" "$2" ${3:+"$3"} || status=1
done
exit $status
