#!/usr/bin/env bash
set -u
OUT=${OUT:-/tmp/out}; mkdir -p "$OUT"
python3 -c "import tarfile; tarfile.open('.gpu2/site312.tar.xz').extractall('/tmp/site')" || exit 1
export PYTHONPATH=/tmp/site
python3 -m pip install -q --no-index --no-deps --no-build-isolation --no-compile --target /tmp/rb . 2>&1 | tail -2
export PYTHONPATH=/tmp/rb:/tmp/site
cd /tmp
timeout 150 python3 -m rigidbench run pendulum:one-radian --engine mjx --device cpu --json "$OUT/cpu-pendulum.json" 2>&1 | grep -v "^WARNING" | tail -8
