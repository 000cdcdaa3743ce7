#!/usr/bin/env bash
# GPU checks (session 2026-11-26d): Warp on the GPU for the first time (warp.so carried in two parts), and the
# gathered MJX census on the GPU. Run from the repository root on the device machine; results under $OUT.
set -u
export PYTHONUNBUFFERED=1
OUT=${OUT:-/tmp/out}; mkdir -p "$OUT"
R=$PWD
PART0=${PART0:-/root/gpu}
DEV=${DEV:-cuda:0}
SECONDS=0
python3 - <<'PY' || exit 1
import lzma, shutil, tarfile, glob, os
tarfile.open(".gpu2/site312.tar.xz").extractall("/tmp/site")
parts = sorted(glob.glob(os.environ.get("PART0", "/root/gpu") + "/warp.so.xz.part*")) + sorted(glob.glob(".gpu2/warp.so.xz.part*"))
print("parts", parts)
with open("/tmp/warp.so.xz", "wb") as f:
    for p in parts:
        f.write(open(p, "rb").read())
with lzma.open("/tmp/warp.so.xz") as src, open("/tmp/site/warp/bin/warp.so", "wb") as dst:
    shutil.copyfileobj(src, dst)
print("warp.so", os.path.getsize("/tmp/site/warp/bin/warp.so"))
PY
export PYTHONPATH=/tmp/site
python3 -m pip install -q --no-index --no-deps --no-build-isolation --no-compile --target /tmp/rb . 2>&1 | tail -2
export PYTHONPATH=/tmp/rb:/tmp/site
cd /tmp
echo "== [$SECONDS s] versions"
(nvidia-smi -L; nproc; python3 -c "
import warp as wp, mujoco, jax, numpy
wp.init()
import mujoco_warp
print('warp', wp.__version__, wp.get_cuda_devices(), 'mujoco', mujoco.__version__, 'jax', jax.__version__, jax.devices(), 'numpy', numpy.__version__)
") 2>&1 | tee "$OUT/versions.txt"
STAGES=${STAGES:-wvc}
WARP_CASES=${WARP_CASES:-pendulum heavy-top:nutation double-pendulum:released struck-stick hard-spheres:head-on}
[[ $STAGES == *w* ]] && echo "== [$SECONDS s] rigidbench run, Warp on $DEV" &&
timeout ${T1:-210} python3 -m rigidbench run $WARP_CASES \
  --engine warp --device "$DEV" --json "$OUT/gpu-warp.json" 2>&1 | grep -v "^WARNING" | tee "$OUT/gpu-warp.txt" | tail -70
[[ $STAGES == *v* ]] && echo "== [$SECONDS s] vector envs, Warp on $DEV" &&
timeout ${T2:-110} python3 "$R/benchmarks/vector_envs.py" --envs HeavyTop-v0 SimplePendulum-v0 --engines warp --device "$DEV" \
  --ns 1 64 1024 4096 --rounds 2 --seconds 1 --no-sync --json "$OUT/vector-gpu-warp.json" 2>&1 | grep -v "^WARNING" | tee "$OUT/vector-gpu-warp.txt"
[[ $STAGES == *c* ]] && echo "== [$SECONDS s] census double-pendulum, MJX float32 on $DEV (gathered)" &&
timeout ${T3:-100} python3 -m rigidbench census double-pendulum --n ${CN:-12} --seed 2 --engine mjx --device "$DEV" \
  --json "$OUT/gpu-mjx-census.json" 2>&1 | grep -v "^WARNING" | tail -25
echo "== [$SECONDS s] done"
