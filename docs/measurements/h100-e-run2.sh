#!/usr/bin/env bash
# GPU check 2 (session 2026-11-26e): the light projectile's momentum on MJX float32 with JAX's default matmul precision
# (TF32 on an H100) and with "highest"; and --device cpu on the GPU machine (the device fix).
set -u
export PYTHONUNBUFFERED=1
OUT=${OUT:-/tmp/out}; mkdir -p "$OUT"
python3 -c "import tarfile; tarfile.open('.gpu2/site312.tar.xz').extractall('/tmp/site')" || exit 1
export PYTHONPATH=/tmp/site
python3 -m pip install -q --no-index --no-deps --no-build-isolation --no-compile --target /tmp/rb . 2>&1 | tail -2
export PYTHONPATH=/tmp/rb:/tmp/site
cd /tmp
HS="hard-spheres:light-projectile --set m1=7.530343740389547 --set m2=70085.63770378078 --set r1=0.00980404598357637 --set r2=0.0023823557427704667 --set speed=868.4182206075626 --set stiffness=1317296135715.702"
for prec in default highest; do
  echo "== cuda:0 matmul precision $prec"
  if [ $prec = highest ]; then export JAX_DEFAULT_MATMUL_PRECISION=highest; fi
  timeout 140 python3 -m rigidbench run $HS --engine mjx --device cuda:0 --json "$OUT/cuda-hs-$prec.json" 2>&1 | grep -v "^WARNING\|^\[" | grep "momentum\|energy\|restitution\|passed"
done
unset JAX_DEFAULT_MATMUL_PRECISION
echo "== cpu (the device fix)"
timeout 140 python3 -m rigidbench run $HS pendulum:one-radian --engine mjx --device cpu --json "$OUT/cpu-hs.json" 2>&1 | grep -v "^WARNING\|^\[" | grep "momentum\|energy\|restitution\|passed\|ERROR"
