#!/usr/bin/env python3
"""Offline licence check of every crate the workspace builds on this platform (the
licence half of `cargo deny`; advisories need a network database and are not checked).

Reads `cargo metadata`, evaluates each package's SPDX licence expression against the
allow-list below and exits non-zero, naming the packages, if any expression cannot be
satisfied by allowed licences (or a package declares none)."""

import json
import re
import subprocess
import sys

# Permissive licences compatible with the workspace's MIT OR Apache-2.0.
ALLOWED = {
    "MIT", "Apache-2.0", "BSD-2-Clause", "BSD-3-Clause", "Zlib", "Unlicense", "0BSD",
    "ISC", "BSL-1.0", "Unicode-3.0", "Unicode-DFS-2016", "CC0-1.0",
}


def satisfiable(expr: str) -> bool:
    """Whether an SPDX expression (with the legacy '/' for OR) holds over ALLOWED."""
    tokens = re.findall(r"\(|\)|[A-Za-z0-9.+-]+|/", expr.replace(" WITH ", "+WITH+"))
    out = []
    for t in tokens:
        if t in ("(", ")"):
            out.append(t)
        elif t in ("OR", "/"):
            out.append(" or ")
        elif t == "AND":
            out.append(" and ")
        else:
            out.append(str(t.split("+WITH+")[0] in ALLOWED))
    try:
        return bool(eval("".join(out), {"__builtins__": {}}))  # noqa: S307 - tokens only
    except SyntaxError:
        return False


def main() -> int:
    host = subprocess.run(["rustc", "-vV"], capture_output=True, text=True, check=True).stdout
    triple = re.search(r"host: (\S+)", host).group(1)
    meta = json.loads(subprocess.run(
        ["cargo", "metadata", "--format-version", "1", "--filter-platform", triple],
        capture_output=True, text=True, check=True).stdout)
    used = {n["id"] for n in meta["resolve"]["nodes"]}
    bad = []
    for p in meta["packages"]:
        if p["id"] not in used:
            continue
        lic = p.get("license")
        if not lic or not satisfiable(lic):
            bad.append(f"{p['name']} {p['version']}: {lic or 'no licence declared'}")
    print(f"licences: {len(used)} packages checked, {len(bad)} not allowed")
    for b in bad:
        print("  " + b)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
