#!/usr/bin/env python3
"""How long Mitsuba's worker threads disturb a render started after `mi.render` returns:
renders the diffuse scene with `llvm_ad_rgb`, waits, then times a frepray render of the
same scene (its own MSamples/s), for each wait in turn (why compare.py has --settle).

    bench/mitsuba-compare/.venv/bin/python bench/mitsuba-compare/settle.py [--reps 3]
"""

import argparse
import re
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import compare  # noqa: E402  (sets up Mitsuba and Dr.Jit)
import scenes  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--waits", type=float, nargs="*", default=[0, 0.02, 0.05, 0.1, 0.2])
    ap.add_argument("--frepray", default=compare.ROOT / "target/release/frepray")
    args = ap.parse_args()
    mi, dr = compare.mi, compare.dr
    dr.set_thread_count(2)
    mi.set_variant("llvm_ad_rgb")
    scene = mi.load_dict(scenes.SCENES["diffuse"](mi, 160, 120, 16))
    integ = mi.load_dict(compare.mitsuba_integrator("direct", 4))
    compare.run_mitsuba("llvm_ad_rgb", scene, integ, 16, 1)  # compiles the kernels
    out = HERE / "out" / "settle.exr"
    out.parent.mkdir(parents=True, exist_ok=True)
    cmd = [str(args.frepray), "render", str(HERE / "scenes/diffuse.toml"), "--spp", "16",
           "--threads", "2", "-o", str(out)]
    results = {w: [] for w in args.waits}
    for _ in range(args.reps):
        for w in args.waits:
            compare.run_mitsuba("llvm_ad_rgb", scene, integ, 16, 2)
            time.sleep(w)
            p = subprocess.run(cmd, capture_output=True, text=True, check=True)
            results[w].append(float(re.search(r"\(([0-9.]+) MSamples/s", p.stdout + p.stderr)[1]))
    print("| wait after the Mitsuba render | frepray MSamples/s |\n| ---: | --- |")
    for w, v in results.items():
        print(f"| {w * 1000:.0f} ms | {', '.join(f'{x:.2f}' for x in sorted(v))} |")


if __name__ == "__main__":
    main()
