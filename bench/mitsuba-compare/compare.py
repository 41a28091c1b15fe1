#!/usr/bin/env python3
"""frepray against Mitsuba 3 on the same scenes: do the images agree, and how fast is each?

    bash bench/mitsuba-compare/setup.sh        # once: venv with Mitsuba, libllvm19
    cargo build --release -p frepray-cli
    bench/mitsuba-compare/.venv/bin/python bench/mitsuba-compare/compare.py [--quick]

Each scene (scenes/NAME.toml for frepray, scenes.py's NAME() for Mitsuba) is rendered
with `direct` and `path` by frepray, Mitsuba `scalar_rgb` and Mitsuba `llvm_ad_rgb`, in
turn, once per seed (so that load on a shared machine hits all three alike). The renders
of one renderer are independent, which gives each pixel's variance, hence z-scores of
the difference of two renderers' means, per pixel and per block of pixels (where noise
averages out and a bias does not). Mitsuba `scalar_rgb` against `llvm_ad_rgb` is the
control: the same estimator twice shows how often |z| > 4 happens by noise alone. A pair
disagrees if the image means differ by more than 1 % (and 3 standard errors) in a
channel, or if |z| > 4 is more than twice as common as in the control (plus 0.1 % of
pixels, 1 % of blocks). Throughput is the median over the seeds (Mitsuba's scene loading
and LLVM kernel compilation untimed, as frepray's statistics leave out its loading);
MRays/s is frepray's own count (Mitsuba does not report rays). Every timed render starts
after a pause (--settle, 0.1 s): Dr.Jit's worker threads keep spinning for a few
milliseconds after a Mitsuba render returns, and a render started at once shares the
cores with them (frepray measured right after `llvm_ad_rgb` ran slower than after a 20 ms
pause: settle.py; docs/notebook/2026-12-01-cpu-speed-round-4.md).

Mean images and |z| maps (0 black, 8 and above white) are written to --out.
`--g2 correlated` gives Mitsuba's rough conductors frepray's height-correlated G2 (g2.py);
with many samples (`--downscale 4 --seeds 16 --spp 1024`) that is what it takes for the
conductor scene to agree.
"""

import argparse
import os
import re
import statistics
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import drjit as dr
import mitsuba as mi
import numpy as np

import g2
import scenes

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
VARIANTS = ("scalar_rgb", "llvm_ad_rgb")
RENDERERS = ("frepray",) + VARIANTS
STATS = re.compile(r"(direct|path): ([\d.]+) s on (?:\d+ threads?|the GPU), (\d+) samples "
                   r"\(([\d.]+) MSamples/s\); rays: ([\d.]+) MRays/s")


def mitsuba_integrator(kind, max_depth, media=False):
    if media:
        # Mitsuba's volumetric path tracer (spectral MIS over the channels, as frepray's
        # free flight); its `direct` has no media, so media scenes render `path` only.
        return {"type": "volpathmis", "max_depth": max_depth + 1, "rr_depth": 1000}
    if kind == "direct":
        # One draw of each technique, power heuristic: frepray's `--estimator power` with
        # techniques bsdf:1, light-uniform:1 (Mitsuba picks an emitter uniformly).
        return {"type": "direct", "emitter_samples": 1, "bsdf_samples": 1}
    # Mitsuba's max_depth counts path segments (2 = direct lighting), frepray's counts
    # shaded vertices (1 = direct lighting). Russian roulette off in both.
    return {"type": "path", "max_depth": max_depth + 1, "rr_depth": 1000}


def run_frepray(binary, toml, kind, spp, seed, threads, w, h, out):
    cmd = [str(binary), "render", str(toml), "--integrator", kind, "--spp", str(spp),
           "--seed", str(seed), "--threads", str(threads), "--width", str(w),
           "--height", str(h), "-o", str(out)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{p.stderr}")
    m = STATS.search(p.stdout + p.stderr)
    if not m:
        sys.exit(f"no statistics in the output of {' '.join(cmd)}:\n{p.stdout}{p.stderr}")
    seconds, samples, mrays = float(m[2]), int(m[3]), float(m[5])
    img = np.array(mi.Bitmap(str(out)), dtype=np.float64)[..., :3]
    return img, samples / seconds / 1e6, mrays


def run_mitsuba(variant, scene, integrator, spp, seed):
    mi.set_variant(variant)
    t = time.perf_counter()
    img = mi.render(scene, integrator=integrator, spp=spp, seed=seed)
    img = np.array(img, dtype=np.float64)  # waits for the LLVM kernels
    seconds = time.perf_counter() - t
    h, w, _ = img.shape
    return img, w * h * spp / seconds / 1e6


def write(path, img):
    # Synchronous: mi.util.write_bitmap's default background write hung the process.
    mi.Bitmap(np.ascontiguousarray(img, dtype=np.float32)).write(str(path))


def zscores(a, b):
    """Per-element z-scores of the difference of the means over seeds (axis 0)."""
    k = a.shape[0]
    se = np.sqrt((a.var(0, ddof=1) + b.var(0, ddof=1)) / k)
    d = a.mean(0) - b.mean(0)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(se > 0, d / se, np.where(d == 0, 0.0, np.inf))


def blocks(x, n):
    """Means of n × n pixel blocks of (seeds, h, w, 3) renders (edges cropped)."""
    s, h, w, c = x.shape
    x = x[:, : h - h % n, : w - w % n]
    return x.reshape(s, h // n, n, w // n, n, c).mean((2, 4))


def agreement(a, b, block):
    """a, b: (seeds, h, w, 3) renders of two renderers. Returns the relative difference
    of the image means per channel with its standard error, the z-scores per pixel and
    per block of block × block pixels (where noise averages out and a bias does not)."""
    ia, ib = a.mean((1, 2)), b.mean((1, 2))  # image mean per seed
    ref = ib.mean(0)
    rel = (ia.mean(0) - ref) / ref
    rel_se = np.sqrt((ia.var(0, ddof=1) + ib.var(0, ddof=1)) / a.shape[0]) / ref
    return rel, rel_se, zscores(a, b), zscores(blocks(a, block), blocks(b, block))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="3 seeds × 4 spp: a smoke test")
    ap.add_argument("--seeds", type=int, default=8, help="independent renders each (≥ 3)")
    ap.add_argument("--spp", type=int, default=16, help="samples per pixel of each render")
    ap.add_argument("--scenes", nargs="*", default=list(scenes.SCENES))
    ap.add_argument("--integrators", nargs="*", default=["direct", "path"])
    ap.add_argument("--downscale", type=int, default=1,
                    help="divide the scenes' resolution by this (more spp per pixel)")
    ap.add_argument("--block", type=int, default=8, help="block size of the block z-scores")
    ap.add_argument("--g2", choices=["separable", "correlated"], default="separable",
                    help="Mitsuba's rough conductors with their own G2 (separable) or "
                    "frepray's (height-correlated, g2.py: a Python plugin, slow in scalar_rgb)")
    ap.add_argument("--threads", type=int, default=os.cpu_count())
    ap.add_argument("--settle", type=float, default=0.1,
                    help="seconds to wait before each timed render, so that the last "
                    "renderer's spinning worker threads are idle (module docs)")
    ap.add_argument("--frepray", default=ROOT / "target/release/frepray")
    ap.add_argument("--out", default=HERE / "out", type=Path)
    args = ap.parse_args()
    if args.quick:
        args.seeds, args.spp = 3, 4
    if args.seeds < 3:
        sys.exit("--seeds must be at least 3 (variances, medians)")
    args.out.mkdir(parents=True, exist_ok=True)
    dr.set_thread_count(args.threads)
    if args.g2 == "correlated":
        scenes.CONDUCTOR = "roughconductor_g2corr"
        for v in VARIANTS:
            mi.set_variant(v)
            g2.register()

    load0 = os.getloadavg()
    t0 = time.time()
    perf, rows = {}, []
    for name in args.scenes:
        toml = HERE / "scenes" / f"{name}.toml"
        desc = tomllib.loads(toml.read_text())
        w, h = (n // args.downscale for n in desc["camera"]["resolution"])
        max_depth = desc["render"]["max_depth"]
        loaded = {}
        for v in VARIANTS:
            mi.set_variant(v)
            loaded[v] = mi.load_dict(scenes.SCENES[name](mi, w, h, args.spp))
        media = "media" in desc
        kinds = [k for k in args.integrators if not (media and k == "direct")]
        for kind in kinds:
            integ = {}
            for v in VARIANTS:
                mi.set_variant(v)
                integ[v] = mi.load_dict(mitsuba_integrator(kind, max_depth, media))
                # Untimed: LLVM compiles its kernels on the first render (cached after).
                run_mitsuba(v, loaded[v], integ[v], args.spp, 10_000)
            imgs = {r: [] for r in RENDERERS}
            for seed in range(args.seeds):
                exr = args.out / f"{name}-{kind}-frepray-{seed}.exr"
                time.sleep(args.settle)
                img, ms, mr = run_frepray(args.frepray, toml, kind, args.spp, seed,
                                          args.threads, w, h, exr)
                imgs["frepray"].append(img)
                perf.setdefault((name, kind, "frepray"), []).append((ms, mr))
                for v in VARIANTS:
                    time.sleep(args.settle)
                    img, ms = run_mitsuba(v, loaded[v], integ[v], args.spp, seed)
                    imgs[v].append(img)
                    perf.setdefault((name, kind, v), []).append((ms, None))
            stacks = {r: np.stack(x) for r, x in imgs.items()}
            for r, s in stacks.items():
                write(args.out / f"{name}-{kind}-{r}-mean.exr", s.mean(0))
            for a, b in (("frepray", "scalar_rgb"), ("frepray", "llvm_ad_rgb"),
                         ("llvm_ad_rgb", "scalar_rgb")):
                rel, rel_se, z, zb = agreement(stacks[a], stacks[b], args.block)
                # |z| of the worst channel, 0 → black, ≥ 8 → white.
                zmap = np.clip(np.abs(z).max(-1, keepdims=True) / 8, 0, 1)
                write(args.out / f"{name}-{kind}-z-{a}-{b}.exr", np.repeat(zmap, 3, -1))
                rows.append((name, kind, a, b, rel, rel_se, float(np.mean(np.abs(z) > 4)),
                             float(np.mean(np.abs(zb) > 4))))
    load1 = os.getloadavg()

    print(f"\n{args.seeds} seeds × {args.spp} spp per renderer, {args.threads} threads, "
          f"{args.settle} s pause before each, "
          f"{time.time() - t0:.0f} s; load average before {load0[0]:.2f} "
          f"({load0[1]:.2f}, {load0[2]:.2f}), after {load1[0]:.2f} "
          f"({load1[1]:.2f}, {load1[2]:.2f})\n")
    print(f"Agreement: image mean of a − b relative to b's, ± its standard error; share of "
          f"|z| > 4 over pixels × channels and over {args.block}² blocks × channels:\n")
    print("| scene | integrator | a | b | mean R | mean G | mean B | pixels \\|z\\| > 4 | "
          "blocks \\|z\\| > 4 |")
    print("| --- | --- | --- | --- | ---: | ---: | ---: | ---: | ---: |")
    fails, unresolved = [], []
    for name, kind, a, b, rel, rel_se, fp, fb in rows:
        cells = " | ".join(f"{100 * r:+.2f} ± {100 * s:.2f} %"
                           for r, s in zip(rel, rel_se, strict=True))
        print(f"| {name} | {kind} | {a} | {b} | {cells} | {100 * fp:.3f} % | "
              f"{100 * fb:.2f} % |")
        # Agree: within 1 % with 3 standard errors to spare. Differ: off by more than 1 %
        # and by more than 3 standard errors. Otherwise too noisy to tell (--quick).
        if np.any((np.abs(rel) > 0.01) & (np.abs(rel) > 3 * rel_se)):
            fails.append(f"{name} {kind}: {a} and {b} image means differ by more than 1 %")
        elif np.any(np.abs(rel) + 3 * rel_se > 0.01):
            unresolved.append(f"{name} {kind}: {a}-{b} means: noise too large to tell 1 %")
    control = {(n, k): (fp, fb) for n, k, a, _, _, _, fp, fb in rows if a == "llvm_ad_rgb"}
    for name, kind, a, b, _, _, fp, fb in rows:
        # Noise alone gives the control's rate (the same estimator twice); a difference
        # in what the renderers estimate adds to it.
        cp, cb = control[(name, kind)]
        if a == "frepray" and (fp > 2 * cp + 1e-3 or fb > 2 * cb + 1e-2):
            fails.append(f"{name} {kind}: |z| > 4 on {100 * fp:.3f} % of {a}-{b} pixels, "
                         f"{100 * fb:.2f} % of blocks; control {100 * cp:.3f} %, "
                         f"{100 * cb:.2f} %")

    print("\nThroughput (median over the seeds; MRays/s is frepray's count):\n")
    print("| scene | integrator | frepray MSamples/s | MRays/s | scalar_rgb MSamples/s | "
          "llvm_ad_rgb MSamples/s | frepray/scalar_rgb | frepray/llvm_ad_rgb |")
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for name in args.scenes:
        for kind in args.integrators:
            if (name, kind, "frepray") not in perf:
                continue  # `direct` of a media scene
            f = perf[(name, kind, "frepray")]
            fs, fr = statistics.median(x[0] for x in f), statistics.median(x[1] for x in f)
            s = statistics.median(x[0] for x in perf[(name, kind, "scalar_rgb")])
            ll = statistics.median(x[0] for x in perf[(name, kind, "llvm_ad_rgb")])
            print(f"| {name} | {kind} | {fs:.3f} | {fr:.3f} | {s:.3f} | {ll:.3f} | "
                  f"{fs / s:.3f} | {fs / ll:.3f} |")
    print()
    for u in unresolved:
        print("UNRESOLVED:", u)
    for f in fails:
        print("DISAGREE:", f)
    if fails and args.g2 == "separable":
        print("note: rough conductors differ by the Smith G2 form (Mitsuba separable, frepray "
              "height-correlated); --g2 correlated aligns it (docs/benchmarks.md)")
    if fails:
        print(f"{len(fails)} disagreement(s)")
    elif unresolved:
        print(f"no disagreement found, but {len(unresolved)} mean(s) too noisy to tell 1 %")
    else:
        print("images agree")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
