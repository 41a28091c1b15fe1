#!/usr/bin/env python3
"""Overhead of each MIS estimator over the balance heuristic by instruction count, which a
shared, noisy machine cannot disturb: every render runs single-threaded under
`valgrind --tool=callgrind` and the instructions of a 1×1, 1-spp render of the same scene
(loading, setup) are subtracted. Overhead = Ir(estimator) / Ir(balance) − 1 at equal spp.

    python3 bench/overhead/overhead.py target/release/frepray scenes/many-lights.toml \
        --techniques light:1,bsdf:1 light:1,bsdf:1,light-area:1 \
        --estimators optimal-direct,optimal-progressive -- --width 32 --height 24 --spp 16

Arguments after `--` go to every `frepray render` (not the 1×1 baseline's size)."""

import argparse
import re
import subprocess
import sys
import tempfile


def instructions(binary, scene, args):
    with tempfile.TemporaryDirectory() as d:
        cmd = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={d}/cg.out",
               binary, "render", scene, "--threads", "1", "-o", f"{d}/x.exr", *args]
        out = subprocess.run(cmd, capture_output=True, text=True)
        if out.returncode != 0:
            sys.exit(f"{' '.join(cmd)} failed:\n{out.stderr[-2000:]}")
        m = re.search(r"Collected : (\d+)", out.stderr)
        if not m:
            sys.exit(f"no instruction count in callgrind's output:\n{out.stderr[-2000:]}")
        return int(m.group(1))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("binary")
    p.add_argument("scene")
    p.add_argument("--techniques", nargs="+", required=True, help="technique lists")
    p.add_argument("--estimators", default="optimal-direct,optimal-progressive")
    argv = sys.argv[1:]
    cut = argv.index("--") if "--" in argv else len(argv)
    a, rest = p.parse_args(argv[:cut]), argv[cut + 1:]
    print(f"scene {a.scene}; render flags: {' '.join(rest)}")
    print("| techniques | T | estimator | instructions (render − setup) | overhead vs balance |")
    print("|---|---|---|---|---|")
    for tech in a.techniques:
        parts = tech.split(",")
        # `light#*` is one technique per light: T depends on the scene.
        t = len(parts) if "light#*" not in parts else f"lights + {len(parts) - 1}"

        common = ["--techniques", tech]
        setup = instructions(a.binary, a.scene, [*common, "--estimator", "balance", "--width", "1",
                                                 "--height", "1", "--spp", "1"])
        base = instructions(a.binary, a.scene, [*common, "--estimator", "balance", *rest]) - setup
        print(f"| {tech} | {t} | balance | {base} | 0 |", flush=True)
        for est in a.estimators.split(","):
            ir = instructions(a.binary, a.scene, [*common, "--estimator", est, *rest]) - setup
            print(f"| {tech} | {t} | {est} | {ir} | {100 * (ir / base - 1):+.2f} % |",
                  flush=True)


if __name__ == "__main__":
    main()
