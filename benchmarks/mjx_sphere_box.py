"""Reproduce MJX's sphere-box contact past a face's edge (docs/engines.md, Findings: "MJX marble-shot").

The marble shot's stick is a box 4 mm thick and 1 m long; its marbles (radius 8 mm) lie at its ends. Once the
struck stick turns, a marble's centre projects just past the end of the face it touches. C MuJoCo then puts the
contact on the closest point of the face's short end edge. MJX 3.17 (`collision_convex._sphere_convex`, which MJX
uses for SPHERE-BOX) takes that point from `math.closest_segment_point`, whose parameter is
``t = (pt - a).(b - a) / (|b - a|^2 + 1e-6)``: the absolute 1e-6 m^2 is 6 % of a 4 mm edge's 1.6e-5 m^2, so the
point slides 1.2e-4 m along the edge, the contact normal tilts 0.0147 rad out of the stick's plane and the depth
comes out 22 % short. The same in float32 and float64. The slide is |b - a| / 2 x 1e-6 / (|b - a|^2 + 1e-6):
on a 4 cm edge (`--half-width 0.02`) 1.2e-5 m, a tilt of 1.6e-3 rad.

This script needs only mujoco and the `mjx` extra (no rigidbench): it places a sphere 4 um into the box's long
face at several overhangs past the face's end and prints C MuJoCo's contact against MJX's.

    python benchmarks/mjx_sphere_box.py            # float64 (jax_enable_x64)
    python benchmarks/mjx_sphere_box.py --float32
    python benchmarks/mjx_sphere_box.py --scale 0.035    # the census draw's 3.5 cm stick: a 0.14 mm edge
"""

from __future__ import annotations

import argparse

import numpy as np

XML = """
<mujoco>
  <option gravity="0 0 0"/>
  <worldbody>
    <body name="stick"><freejoint/><geom type="box" size="{half_width} {half_length} {half_width}" mass="0.25"/></body>
    <body name="marble"><freejoint/><geom type="sphere" size="{radius}" mass="0.005"/></body>
  </worldbody>
</mujoco>
"""
DEPTH = 4e-6  # the marble's penetration into the face (m): the marble shot's contact at its default shot


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--float32", action="store_true", help="run MJX in float32 (default: float64)")
    parser.add_argument("--half-width", type=float, default=0.002, help="the box's half-thickness (m), default 0.002")
    parser.add_argument(
        "--scale", type=float, default=1.0, help="every length times this (the marble shot's stick length L in m)"
    )
    args = parser.parse_args()

    try:
        import jax
        from mujoco import mjx
    except ImportError:
        parser.exit(2, "mjx_sphere_box.py: needs MJX: pip install 'rigidbench[mjx]'\n")
    jax.config.update("jax_enable_x64", not args.float32)
    import mujoco

    scale = args.scale
    half_width, radius, depth = args.half_width * scale, 0.008 * scale, DEPTH * scale
    model = mujoco.MjModel.from_xml_string(XML.format(half_width=half_width, half_length=0.5 * scale, radius=radius))
    data = mujoco.MjData(model)
    forward = jax.jit(mjx.forward)
    mx = mjx.put_model(model)
    precision = "float32" if args.float32 else "float64"
    sizes = f"({half_width:g}, {0.5 * scale:g}, {half_width:g})"
    print(f"mujoco {mujoco.__version__}, MJX {precision}; box half-sizes {sizes} m, sphere radius {radius:g} m,")
    print(f"{depth:g} m into the box's +x face; its centre `overhang` past the face's end (y)")
    print(
        f"{'overhang (m)':>12}  {'C depth (m)':>11}  {'C normal':>28}  "
        f"{'MJX depth (m)':>13}  {'MJX normal':>28}  tilt (rad)"
    )
    for overhang in (-1e-3 * scale, 0.0, 1e-6 * scale, 1e-5 * scale, 1e-4 * scale):
        data.qpos[:] = [0, 0, 0, 1, 0, 0, 0, half_width + radius - depth, 0.5 * scale + overhang, 0, 1, 0, 0, 0]
        mujoco.mj_forward(model, data)
        contact = data.contact[0]
        mjx_data = forward(mx, mjx.put_data(model, data))
        found = mjx_data._impl.contact
        k = int(np.argmin(np.asarray(found.dist)))
        normal = np.asarray(found.frame)[k, 0]
        tilt = float(np.arccos(min(1.0, abs(float(np.dot(normal, contact.frame[:3]))))))
        print(
            f"{overhang:>12.0e}  {-contact.dist:>11.4g}  {np.array2string(contact.frame[:3], precision=5):>28}  "
            f"{-float(found.dist[k]):>13.4g}  {np.array2string(normal, precision=5):>28}  {tilt:.3g}"
        )


if __name__ == "__main__":
    main()
