#!/usr/bin/env python3
"""Side-by-side throughput of two frepray builds (A = before, B = after) on the same
scenes: `frepray bench` runs alternate A, B, A, B, … so that load on a shared machine hits
both alike; prints the median MSamples/s and MRays/s of each and the ratio B/A, with the
load average before and after.

    python3 bench/ab/ab.py --reps 3 OLD/frepray NEW/frepray -- \
        --estimator balance --spp 8 --width 160 --height 120 --techniques light:1,bsdf:1,light-area:1

Scenes default to the paper's two (scenes/many-lights.toml, scenes/table.toml)."""

import argparse
import os
import statistics
import subprocess
import sys


def run(binary, scene, extra):
    out = subprocess.run([binary, "bench", scene, *extra], capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"{binary} bench {scene} failed:\n{out.stderr}")
    # The first table's columns by name: `bench` has grown columns before (backend).
    rows, header = {}, None
    for line in out.stdout.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if header is None and "integrator" in cells and "MSamples/s" in cells:
            header = {name: k for k, name in enumerate(cells)}
            continue
        if header and len(cells) == len(header) and cells[header["integrator"]] in ("direct", "path"):
            rows[cells[header["integrator"]]] = (
                float(cells[header["MSamples/s"]]),
                float(cells[header["MRays/s"]]),
            )
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("a", help="the 'before' frepray binary")
    ap.add_argument("b", help="the 'after' frepray binary")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--scenes", nargs="*", default=["scenes/many-lights.toml", "scenes/table.toml"])
    ap.add_argument("extra", nargs=argparse.REMAINDER, help="after --: flags for `frepray bench`")
    args = ap.parse_args()
    extra = [x for x in args.extra if x != "--"]
    load0 = os.getloadavg()
    results = {}
    for scene in args.scenes:
        for _ in range(args.reps):
            for tag, binary in (("A", args.a), ("B", args.b)):
                for integ, v in run(binary, scene, extra).items():
                    results.setdefault((scene, integ, tag), []).append(v)
    load1 = os.getloadavg()
    print(f"load average before {load0[0]:.2f}, after {load1[0]:.2f}; {args.reps} runs each, alternating")
    print("| scene | integrator | A MSamples/s | B MSamples/s | B/A | A MRays/s | B MRays/s | B/A |")
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for scene in args.scenes:
        for integ in ("direct", "path"):
            a = results.get((scene, integ, "A"))
            b = results.get((scene, integ, "B"))
            if not a or not b:
                continue
            ms = [statistics.median(x[0] for x in r) for r in (a, b)]
            mr = [statistics.median(x[1] for x in r) for r in (a, b)]
            print(f"| {os.path.basename(scene)} | {integ} | {ms[0]:.4f} | {ms[1]:.4f} | "
                  f"{ms[1] / ms[0]:.2f} | {mr[0]:.4f} | {mr[1]:.4f} | {mr[1] / mr[0]:.2f} |")


if __name__ == "__main__":
    main()
