#!/usr/bin/env bash
# GPU check 4 (session 2026-11-26e): the light projectile on MJX float32 on the H100 after the matmul-precision fix,
# no JAX_DEFAULT_MATMUL_PRECISION set: rigidbench's programs run "highest".
set -u
OUT=${OUT:-/tmp/out}; mkdir -p "$OUT"
python3 -c "import tarfile; tarfile.open('.gpu2/site312.tar.xz').extractall('/tmp/site')" || exit 1
export PYTHONPATH=/tmp/site
python3 -m pip install -q --no-index --no-deps --no-build-isolation --no-compile --target /tmp/rb . 2>&1 | tail -2
export PYTHONPATH=/tmp/rb:/tmp/site
cd /tmp
unset JAX_DEFAULT_MATMUL_PRECISION
HS="hard-spheres:light-projectile --set m1=7.530343740389547 --set m2=70085.63770378078 --set r1=0.00980404598357637 --set r2=0.0023823557427704667 --set speed=868.4182206075626 --set stiffness=1317296135715.702"
timeout 150 python3 -m rigidbench run $HS --engine mjx --device cuda:0 --json "$OUT/cuda-hs-fixed.json" 2>&1 | grep -v "^WARNING\|^\[" | grep "momentum\|target-energy\|passed"
python3 -c "import json; print(json.load(open('$OUT/cuda-hs-fixed.json'))['results'][0]['settings']['matmul_precision'])"
