#!/usr/bin/env python3
"""Cost of each light-selection technique relative to light-power: renders alternate
across the techniques, 5 rounds, median wall time of each process (docs/light-selection.md).
Run from the repository root after `cargo build --release -p frepray-cli`."""
import subprocess, time, statistics, os
B="target/release/frepray"
base=["render","scenes/many-lights.toml","--integrator","direct","--estimator","balance","--spp","16","--width","64","--height","48","--hide-emitters","--threads","1","-o","/tmp/tr.exr"]
T=["light-power:1,bsdf:1","light-uniform:1,bsdf:1","light-spatial:1,bsdf:1","light-trained:1,bsdf:1","light#*:1,bsdf:1"]
times={t:[] for t in T}
print("load before", open("/proc/loadavg").read().split()[:3])
for rep in range(5):
    for t in T:
        t0=time.perf_counter(); subprocess.run([B,*base,"--techniques",t],check=True,capture_output=True); times[t].append(time.perf_counter()-t0)
print("load after", open("/proc/loadavg").read().split()[:3])
ref=statistics.median(times[T[0]])
for t in T:
    m=statistics.median(times[t]); print(f"| `{t}` | {m:.3f} | {m/ref:.2f} |")
