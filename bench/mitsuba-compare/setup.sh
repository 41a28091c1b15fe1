#!/usr/bin/env bash
# Installs the peer for compare.py: Mitsuba 3 from PyPI in a virtual environment here
# (.venv, git-ignored), and Debian's libllvm19, which Dr.Jit loads at run time for the
# `llvm_ad_rgb` variant (without it only the scalar variants work).
set -euo pipefail
cd "$(dirname "$0")"
if ! dpkg -s libllvm19 >/dev/null 2>&1; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    apt-get update -qq >/dev/null
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libllvm19 >/dev/null
  else
    echo "setup: libllvm19 is missing; install it as root (apt-get install libllvm19)" >&2
    exit 1
  fi
fi
PYTHON="${PYTHON:-python3}"
# Python ≥ 3.11 for tomllib (compare.py reads the frepray scenes' resolution).
"$PYTHON" -c 'import sys; assert sys.version_info >= (3, 11), sys.version'
[ -x .venv/bin/python ] || "$PYTHON" -m venv .venv
# The versions measured in docs/benchmarks.md.
.venv/bin/python -m pip install -q --disable-pip-version-check \
  mitsuba==3.9.1 drjit==1.5.0 numpy==2.4.6
.venv/bin/python -c 'import mitsuba as mi; mi.set_variant("llvm_ad_rgb"); print("mitsuba", mi.__version__, "llvm_ad_rgb ok")'
