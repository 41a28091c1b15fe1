#!/usr/bin/env python3
"""Cost per sample against the number of lights, per light-selection technique.

For each count N, writes scenes/many-lights.toml's objects with N small sphere lights of
unequal power (seeded, spread over the floor at heights 1.5-3.5, the total power that of
the original ten) and renders it with `T:1,bsdf:1` for each technique T, single-threaded;
prints MSamples/s and the time per sample relative to N = 10.

    python3 bench/lights/scaling.py target/release/frepray --counts 1,10,100,1000,10000 \
        --techniques light-power,light-spatial,light-bvh -- --spp 4 --width 160 --height 120

Arguments after `--` go to every `frepray render`. With `--backend gpu` among them the
rate is the GPU's: samples over the sum of its stage times (camera, shade, shadow and
continuation rays, by GPU timestamps), without the setup that compiles the kernels.

    python3 bench/lights/scaling.py target/release/frepray --counts 10,1000,10000 \
        --techniques light-bvh -- --backend gpu --spp 4 --width 80 --height 60

With `--instructions` each render runs under `valgrind --tool=callgrind`, counting only
the samples (`Integrator::sample`, and `Integrator::run_wave` with `--engine batched`),
not the scene's loading: instructions per sample, which a shared machine's load cannot
disturb, and their ratio to N = 10 (the CPU back end only).

    python3 bench/lights/scaling.py target/release/frepray --instructions \
        --counts 10,10000 --techniques light-power,light-bvh -- --spp 2 --width 80 --height 60"""

import argparse
import random
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def scene_text(n, seed=1):
    base = (ROOT / "scenes/many-lights.toml").read_text()
    # Everything before the first light; the lights are generated.
    head = base[: base.index("[[lights]]")]
    rng = random.Random(seed)
    weights = [rng.uniform(0.2, 5.0) for _ in range(n)]
    total = 1000.0
    out = [head]
    for w in weights:
        x, y, z = rng.uniform(-6, 6), rng.uniform(-6, 6), rng.uniform(1.5, 3.5)
        c = [round(rng.uniform(0.4, 1.0), 3) for _ in range(3)]
        out.append(
            f"[[lights]]\ntype = \"sphere\"\ncenter = [{x:.4f}, {y:.4f}, {z:.4f}]\n"
            f"radius = 0.04\ncolor = {c}\npower = {total * w / sum(weights):.6g}\n\n"
        )
    return "".join(out)


def msamples(binary, scene, technique, rest):
    with tempfile.TemporaryDirectory() as d:
        cmd = [binary, "render", str(scene), "--threads", "1", "--techniques",
               f"{technique}:1,bsdf:1", "-o", f"{d}/x.exr", *rest]
        out = subprocess.run(cmd, capture_output=True, text=True)
        if out.returncode != 0:
            sys.exit(f"{' '.join(cmd)} failed:\n{out.stderr[-2000:]}")
        g = re.search(r"GPU stages: camera rays ([0-9.]+) ms, shade ([0-9.]+) ms, "
                      r"shadow rays ([0-9.]+) ms, continuation rays ([0-9.]+) ms", out.stderr)
        n = re.search(r"([0-9]+) samples", out.stderr)
        if g and n:
            return int(n.group(1)) / (sum(float(x) for x in g.groups()) * 1e3)
        m = re.search(r"\(([0-9.]+) MSamples/s\)", out.stderr)
        if not m:
            sys.exit(f"no MSamples/s in:\n{out.stderr[-2000:]}")
        return float(m.group(1))


def instructions(binary, scene, technique, rest):
    """Instructions per sample of the render's samples (module docs)."""
    with tempfile.TemporaryDirectory() as d:
        cmd = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={d}/cg.out",
               "--toggle-collect=render::integrator::Integrator::sample",
               "--toggle-collect=render::integrator::Integrator::run_wave",
               binary, "render", str(scene), "--threads", "1", "--techniques",
               f"{technique}:1,bsdf:1", "-o", f"{d}/x.exr", *rest]
        out = subprocess.run(cmd, capture_output=True, text=True)
        if out.returncode != 0:
            sys.exit(f"{' '.join(cmd)} failed:\n{out.stderr[-2000:]}")
        ir = re.search(r"Collected : (\d+)", out.stderr)
        n = re.search(r"([0-9]+) samples", out.stderr)
        if not (ir and n):
            sys.exit(f"no instruction or sample count in:\n{out.stderr[-2000:]}")
        return int(ir.group(1)) / int(n.group(1))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("binary")
    p.add_argument("--counts", default="1,10,100,1000,10000")
    p.add_argument("--techniques", default="light-power,light-spatial,light-bvh")
    p.add_argument("--instructions", action="store_true",
                   help="instructions per sample under callgrind instead of MSamples/s")
    argv = sys.argv[1:]
    cut = argv.index("--") if "--" in argv else len(argv)
    a, rest = p.parse_args(argv[:cut]), argv[cut + 1:]
    counts = [int(c) for c in a.counts.split(",")]
    techs = a.techniques.split(",")
    rates = {}
    with tempfile.TemporaryDirectory() as d:
        for n in counts:
            scene = Path(d) / f"lights{n}.toml"
            scene.write_text(scene_text(n))
            for t in techs:
                if a.instructions:
                    rates[(n, t)] = instructions(a.binary, scene, t, rest)
                    print(f"{n} lights, {t}: {rates[(n, t)]:.0f} instructions a sample",
                          file=sys.stderr)
                else:
                    rates[(n, t)] = msamples(a.binary, scene, t, rest)
                    print(f"{n} lights, {t}: {rates[(n, t)]:.4g} MSamples/s", file=sys.stderr)
    print(f"render flags: {' '.join(rest)}; 1 thread; `T:1,bsdf:1`")
    what = "instructions a sample (/ N=10)" if a.instructions else "MSamples/s (time / N=10)"
    print("| lights | " + " | ".join(f"{t} {what}" for t in techs) + " |")
    print("|---:|" + "---|" * len(techs))
    for n in counts:
        cells = []
        for t in techs:
            r = rates[(n, t)]
            if a.instructions:
                rel = f" ({r / rates[(10, t)]:.2f}×)" if (10, t) in rates else ""
                cells.append(f"{r:.0f}{rel}")
            else:
                rel = f" ({rates[(10, t)] / r:.2f}×)" if (10, t) in rates else ""
                cells.append(f"{r:.4g}{rel}")
        print(f"| {n} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
