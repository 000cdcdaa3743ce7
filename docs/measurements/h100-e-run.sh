#!/usr/bin/env bash
# The GPU checks of session 2026-11-26 (e) on the lent H100: the commands run there, one call per STAGE in this order
# (the calls themselves filtered the printed rows differently; the JSON files are theirs):
#   STAGE=1  MJX float32 on the GPU: the fast oblate top (world-frame momentum) and the light projectile (contact)
#   STAGE=2  the light projectile with JAX's default matmul precision (TF32) and with "highest"
#   STAGE=3  --device cpu on the GPU machine, after the device fix
#   STAGE=4  the light projectile after the matmul-precision fix, nothing set
# Carried: .gpu2/site312.tar.xz (every wheel but Warp's, see h100-run.sh) and this script. Results under $OUT.
set -u
export PYTHONUNBUFFERED=1
OUT=${OUT:-/tmp/out}; mkdir -p "$OUT"
python3 -c "import tarfile; tarfile.open('.gpu2/site312.tar.xz').extractall('/tmp/site')" || exit 1
export PYTHONPATH=/tmp/site
python3 -m pip install -q --no-index --no-deps --no-build-isolation --no-compile --target /tmp/rb . 2>&1 | tail -2
export PYTHONPATH=/tmp/rb:/tmp/site
cd /tmp
TOP="free-symmetric-top:oblate --set I1=0.0001061983074615631 --set I3=0.00021081192130827277 --set omega=-99.63942274979702,-98.15270726638914,-98.72056092387567"
HS="hard-spheres:light-projectile --set m1=7.530343740389547 --set m2=70085.63770378078 --set r1=0.00980404598357637 --set r2=0.0023823557427704667 --set speed=868.4182206075626 --set stiffness=1317296135715.702"
run() { timeout 150 python3 -m rigidbench run "$@" 2>&1 | grep -v "^WARNING\|^\[" | tail -16; }
case ${STAGE:-1} in
  1) run $TOP --engine mjx --device cuda:0 --json "$OUT/cuda-free-symmetric-top.json"
     run $HS --engine mjx --device cuda:0 --json "$OUT/cuda-hard-spheres.json" ;;
  2) run $HS --engine mjx --device cuda:0 --json "$OUT/cuda-hs-default.json"
     JAX_DEFAULT_MATMUL_PRECISION=highest run $HS --engine mjx --device cuda:0 --json "$OUT/cuda-hs-highest.json" ;;
  3) run pendulum:one-radian --engine mjx --device cpu --json "$OUT/cpu-pendulum.json" ;;
  4) unset JAX_DEFAULT_MATMUL_PRECISION
     run $HS --engine mjx --device cuda:0 --json "$OUT/cuda-hs-fixed.json" ;;
esac
