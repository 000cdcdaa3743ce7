#!/usr/bin/env bash
# GPU check (session 2026-11-26e): MJX float32 on the GPU against the same on this machine's CPU, for two census draws
# whose float32 behaviour was measured on the 2-core CPU: a fast oblate free top (the world-frame momentum's secular
# drift) and a light projectile on a heavy target (the contact energy above its floor).
set -u
export PYTHONUNBUFFERED=1
OUT=${OUT:-/tmp/out}; mkdir -p "$OUT"
python3 -c "import tarfile; tarfile.open('.gpu2/site312.tar.xz').extractall('/tmp/site')" || exit 1
export PYTHONPATH=/tmp/site
python3 -m pip install -q --no-index --no-deps --no-build-isolation --no-compile --target /tmp/rb . 2>&1 | tail -2
export PYTHONPATH=/tmp/rb:/tmp/site
cd /tmp
(nvidia-smi -L; python3 -c "import mujoco, jax; print('mujoco', mujoco.__version__, 'jax', jax.__version__, jax.devices())") 2>&1 | tee "$OUT/versions.txt"
TOP="free-symmetric-top:oblate --set I1=0.0001061983074615631 --set I3=0.00021081192130827277 --set omega=-99.63942274979702,-98.15270726638914,-98.72056092387567"
HS="hard-spheres:light-projectile --set m1=7.530343740389547 --set m2=70085.63770378078 --set r1=0.00980404598357637 --set r2=0.0023823557427704667 --set speed=868.4182206075626 --set stiffness=1317296135715.702"
for dev in cuda:0 cpu; do
  for c in "$TOP" "$HS"; do
    echo "== $dev ${c%% *}"
    timeout 150 python3 -m rigidbench run $c --engine mjx --device $dev --json "$OUT/${dev%%:*}-${c%%:*}.json" 2>&1 | grep -v "^WARNING\|^\[" | grep "momentum-drift\|energy\|restitution\|passed"
  done
done
