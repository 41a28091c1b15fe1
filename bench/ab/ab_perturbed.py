#!/usr/bin/env python3
"""Wall-clock time of two builds of the perturbed-quadric benchmark (A = before,
B = after) at one count of perturbations: each run is one untimed-by-itself pass of the
benchmark's 256x256 rays (`PERTURBED_ONE_PASS=N`), timed from outside as a whole process;
runs alternate A, B, B, A, … so that load on a shared machine hits both alike. Prints
the median and the least time of each and the ratios A/B (above 1: B is faster), with
the load average before and after.

    cargo bench -p frep --bench perturbed --no-run   # prints the binary's path
    python3 bench/ab/ab_perturbed.py --n 4096 --reps 12 OLD/perturbed-HASH NEW/perturbed-HASH

The time includes starting the process and building the BVH (a few milliseconds), so
small N says little; at 4096 the rays take most of it (about 0.13 s of 0.15 s)."""

import argparse
import os
import statistics
import subprocess
import time


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("a", help="the 'before' benchmark binary")
    ap.add_argument("b", help="the 'after' benchmark binary")
    ap.add_argument("--n", default="4096", help="perturbations (default 4096)")
    ap.add_argument("--reps", type=int, default=10, help="runs of each (default 10)")
    args = ap.parse_args()
    env = dict(os.environ, PERTURBED_ONE_PASS=args.n)
    times = {args.a: [], args.b: []}
    load0 = os.getloadavg()
    for r in range(args.reps):
        for binary in (args.a, args.b) if r % 2 == 0 else (args.b, args.a):
            start = time.perf_counter()
            subprocess.run([binary], env=env, stdout=subprocess.DEVNULL, check=True)
            times[binary].append(time.perf_counter() - start)
    load1 = os.getloadavg()
    (ma, mb) = (statistics.median(times[args.a]), statistics.median(times[args.b]))
    (la, lb) = (min(times[args.a]), min(times[args.b]))
    print(f"N = {args.n}, {args.reps} runs each")
    print(f"A: median {ma:.4f} s, least {la:.4f} s")
    print(f"B: median {mb:.4f} s, least {lb:.4f} s")
    print(f"A/B: median {ma / mb:.3f}, least {la / lb:.3f}")
    print(f"load average before {load0[0]:.2f}, after {load1[0]:.2f}")


if __name__ == "__main__":
    main()
