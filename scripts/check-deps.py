#!/usr/bin/env python3
"""The workspace's dependency arrows against DESIGN.md §3 ("Layout"): arrows point down
only, `cli, python → frepray → render, gpu → state → scene → frep, mis`; the front ends
import `frepray` alone; `render` and `gpu` stand side by side; crates of one layer never
import each other. Normal and build dependencies are checked (tests may compare the two
back ends, so dev-dependencies are not).

Arrows the layout does not allow yet but the code still has are listed in DEBT, each
with what removes it. The check fails on any other wrong arrow, and on a DEBT entry the
code no longer has (remove it from the list: the debt only shrinks).
Also the minimum Rust version: every member takes the workspace's `rust-version`, and no
locked dependency declares a higher one.
Reads `cargo metadata`; exits non-zero naming each problem.
"""

import json
import subprocess
import sys

# Layers, top to bottom (DESIGN.md §3).
LAYER = {
    "frepray-cli": 5, "frepray-py": 5,
    "frepray": 4,
    "render": 3, "gpu": 3,
    "state": 2,
    "scene": 1,
    "frep": 0, "mis": 0,
}
FRONT_ENDS = {"frepray-cli", "frepray-py"}

# Wrong arrows the code still has, and what removes each.
DEBT: dict = {}


def allowed(a: str, b: str) -> bool:
    """Whether `a` may depend on `b`: a lower layer, and for a front end `frepray` only."""
    if a in FRONT_ENDS:
        return b == "frepray"
    return LAYER[b] < LAYER[a]


def arrows(metadata: dict) -> set:
    """(crate, dependency) for every normal or build dependency inside the workspace."""
    members = [p for p in metadata["packages"] if p["id"] in set(metadata["workspace_members"])]
    names = {p["name"] for p in members}
    out = set()
    for p in members:
        for d in p["dependencies"]:
            if d["name"] in names and d["kind"] in (None, "build"):
                out.add((p["name"], d["name"]))
    return out


def check(found: set) -> list:
    """The problems: unknown crates, wrong arrows outside DEBT, DEBT entries gone."""
    problems = []
    for a, b in sorted(found):
        for c in (a, b):
            if c not in LAYER:
                problems.append(f"{c}: a crate DESIGN.md §3 does not place (add it to LAYER)")
        if a in LAYER and b in LAYER and not allowed(a, b) and (a, b) not in DEBT:
            problems.append(f"{a} → {b}: not allowed by DESIGN.md §3 (arrows point down only; "
                            "front ends import frepray alone)")
    for a, b in sorted(set(DEBT) - found):
        problems.append(f"{a} → {b} is gone: remove it from DEBT in scripts/check-deps.py")
    return problems


def version(v: str) -> tuple:
    """A `rust-version` as a comparable tuple (1.87 == 1.87.0)."""
    parts = [int(x) for x in v.split(".")]
    return tuple(parts + [0] * (3 - len(parts)))


def msrv(metadata: dict) -> list:
    """The problems with the minimum Rust version: a member whose `rust-version` is not
    the workspace's one, or a dependency declaring a higher one."""
    members = set(metadata["workspace_members"])
    ours = {p["rust_version"] for p in metadata["packages"] if p["id"] in members}
    if len(ours) != 1 or None in ours:
        return [f"members declare rust-version {sorted(map(str, ours))}: expected one, "
                "the workspace's (rust-version.workspace = true)"]
    (v,) = ours
    higher = [f"{p['name']} {p['version']} ({p['rust_version']})" for p in metadata["packages"]
              if p["id"] not in members and p.get("rust_version")
              and version(p["rust_version"]) > version(v)]
    return [f"rust-version {v} is below what dependencies need: {', '.join(higher)}"] if higher else []


def main() -> int:
    metadata = json.loads(subprocess.run(
        ["cargo", "metadata", "--format-version", "1"],
        check=True, capture_output=True, text=True).stdout)
    found = arrows(metadata)
    problems = check(found) + msrv(metadata)
    for p in problems:
        print(f"check-deps: {p}", file=sys.stderr)
    debt = sorted(set(DEBT) & found)
    print(f"check-deps: {len(found)} arrows, {len(debt)} still to remove "
          f"({', '.join(f'{a} → {b}' for a, b in debt)})", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
