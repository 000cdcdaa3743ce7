"""Gyrocompass on a turning platform: the MuJoCo side of the scenario, and its gymnasium env.

Theory: docs/theory.md G1 (the exact hunting equation, its small-amplitude frequency and its large-amplitude period by
quadrature; H conserved), implemented in `rigidbench.analytic.gyrocompass`. Model: ``models/gyrocompass.xml``: a
platform hinged about n = (0, cos(lat), sin(lat)) (the Earth, turning at a scaled rate Omega), a gimbal hinged
about the platform's vertical (its angle is the azimuth alpha of the spin axis, from North towards East) and a
rotor hinged about the gimbal's horizontal y axis.

Three choices make the model the textbook one:

- The spin axis is held horizontal by the joint coordinates themselves (a hinge inside a hinge), not by a soft
  equality or a spring, so docs/theory.md G1's compliance note (an effective inertia I_t + I_g + H^2/K) does not apply:
  there is no K.
- The platform's rate stays constant because its moment of inertia I_p is huge. Its axis is a frictionless hinge, so
  I_p Omega + L_n is conserved, L_n the gyro's angular momentum along n (`analytic.gyrocompass.momentum_along_axis`);
  L_n swings by at most S over the hunting (`analytic.gyrocompass.platform_momentum_swing`), which moves the rate by
  at most S / I_p, and the platform's turning back as the gimbal turns lightens I_t + I_g by (I_t + I_g)
  sin^2(lat) / I_p. I_p follows the parameters (`GyroCompass.reference_settings`): max(S A / ((A - B) Omega d),
  (I_t + I_g) / d), d = PLATFORM_DRIFT = 1e-10, so both effects stay below 1e-10; every period tolerance carries
  both bounds, and the check ``platform-drift`` predicts the drift from the balance along the theory's trajectory.
- Every centre of mass is at the gimbal centre on the platform's axis: gravity exerts no torque and does no work,
  and is set to zero (a compass a radius off the Earth's axis sees a uniform acceleration of its pivot, which
  exerts no torque about a CoM at the pivot either).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import gymnasium as gym
import mujoco
import numpy as np

from rigidbench import signals
from rigidbench.analytic import gyrocompass as gc
from rigidbench.analytic.gyrocompass import Geometry, gyroscopic_roundoff  # noqa: F401 (their old import path)
from rigidbench.contract import UNRESOLVED_FRACTION, Case, Check, Derived, Domain, Scenario, Trajectory, round_step
from rigidbench.envs.base import ScenarioEnv
from rigidbench.envs.pendulums import frequency
from rigidbench.envs.rotor import require_rigid_body_inertia
from rigidbench.params import BodyInertia, Bound, Numeric, Param, Range, Value

PLATFORM, GIMBAL, ROTOR = "platform", "gimbal", "rotor"  # body and joint names (models/gyrocompass.xml)

# Reference timestep: dt = STEP_TURN / omega_max, rounded down to one digit (`round_step`), omega_max the hunting's
# fastest rate: max(omega_g, the azimuth's largest rate). RK4's relative frequency error is (omega dt)^4 / 120 <= 5e-12
# (measured 3e-12 at the default case). The platform's rate and the rotor's spin set no limit: the equations of
# motion in joint coordinates are autonomous (the platform's angle enters no force, its rate only as a coefficient),
# and the rotor is axisymmetric (its spin angle enters no force, its spin rate changes on the hunting's time scale).
STEP_TURN = 0.005
# Largest relative change of the platform's rate the derived platform inertia allows (module docstring).
PLATFORM_DRIFT = 1e-10
# North must be stable by a margin: omega_g^2 = A - B >= NORTH_MARGIN A. Closer to A = B the hunting frequency is a
# difference of nearly equal terms (relative round-off eps A / (A - B)) and the platform's drift is amplified by
# A / (A - B) in it.
NORTH_MARGIN = 0.01
# Double precision. MuJoCo computes the gyroscopic torque in world axes, from the rotor's spin chi' and its
# world-frame inertia, which round-off leaves axisymmetric only to ~eps: a torque error ~eps I chi'^2 against the
# restoring torque H Omega_perp sin(alpha) ~ I_a chi' Omega_perp sin(alpha), smallest at the turning point |a|. Its
# relative size rho = eps chi' / (Omega_perp sin|a|) sets a noise floor. Near the separatrix (|a| -> pi) the period
# also answers to the energy that noise moves by S = |d ln T / d ln a| (the quadrature's, ~5 at a = 3). Measured over
# 85 runs (80 census draws and five corners a review found: slow platforms near the pole, small rotors, heavy gimbals,
# a = 3): error / rho <= 0.020 S for the hunting period, <= 0.011 for the small-amplitude one, <= 0.012 for the mean
# azimuth (over the amplitude), <= 0.13 for the turning angle. Each tolerance adds ROUNDOFF_GAINS[check] x rho (x S for
# the hunting period), 2.3-2.8x above those, and rho is refused beyond ROUNDOFF_MAX (domain 'gyroscopic-round-off').
# (rho once took sin(min(|a|, pi/2)): 7x too small at a = 3, where the gains, 0.01-0.1, also fell short by 2x.)
ROUNDOFF_GAINS = {"hunting-period": 0.05, "small-amplitude-period": 0.03, "mean-azimuth": 0.03, "turning-angle": 0.3}
ROUNDOFF_MAX = 1e-5
ROUNDOFF = (
    "; + {gain:g} rho, rho = eps chi' / (Omega cos(lat) sin|a|) the relative round-off of MuJoCo's world-frame "
    "gyroscopic torque against the restoring one at the turning point (measured error / rho <= {measured:g} over 85 "
    "runs, census draws and corners; rho = 6.3e-11 .. 3e-13 in the cases)"
)
RUN_PERIODS = 4.25  # released at a turning point: 4.25 periods hold 17 zero crossings, 4 whole periods of each sign

_RK4 = (
    f"RK4 at omega_max dt <= {STEP_TURN:g} (reference_settings): relative frequency error (omega dt)^4/120 <= 5e-12 "
    "(measured 3e-12 at the default case); crossings cubic-interpolated, O(dt^4); + the platform's rate drift (<= "
    f"{PLATFORM_DRIFT:g} by the derived platform inertia, its bound from the compiled model added at run time)"
)
CHECKS = (
    Check(
        "hunting-period",
        "s",
        1e-9,
        "rel",
        _RK4 + "; 1e-9 leaves two decades" + ROUNDOFF.format(gain=0.05, measured=0.02) + " x S = |d ln T / d ln a| "
        "(the quadrature's; ~5 at a = 3, where the round-off moves the energy the period answers to)",
        "G1: T = 4 int_0^a dalpha / sqrt(2 (V(a) - V(alpha))), V = -A cos alpha - (B/2) sin^2 alpha (quadrature)",
    ),
    Check(
        "small-amplitude-period",
        "s",
        1e-9,
        "rel",
        "1e-9 for "
        + _RK4
        + "; + twice the terms beyond a^2 that the expected value neglects, |T(a)/T0 - 1 - shift| by the quadrature "
        "(added at run time; ~a^4/300 <= 4e-11 at |a| <= 0.01, the case's regime)"
        + ROUNDOFF.format(gain=0.03, measured=0.011),
        "G1: T0 = 2 pi / omega_g, omega_g^2 = Omega cos(lat) (H - I_t Omega cos(lat)) / (I_t + I_g), times 1 + the "
        "leading amplitude shift ((A - 4B)/(A - B)) a^2/16 (V's quartic term, as the pendulum's a^2/16, O1)",
    ),
    Check(
        "mean-azimuth",
        "rad",
        1e-9,
        "abs",
        "1e-9 of the amplitude (scaled at run time): the mean is a cubic-spline quadrature of alpha(t) between the "
        "first and last upward zero crossings (whole periods), O((omega dt)^4) ~ 1e-10 of the amplitude; RK4's "
        "phase error shifts whole periods, not the mean" + ROUNDOFF.format(gain=0.03, measured=0.012) + " (x a)",
        "G1: the spin axis hunts about the horizontal part of Omega (North for H > 0): V(alpha) is even",
    ),
    Check(
        "turning-angle",
        "rad",
        1e-8,
        "rel",
        "the first integral E = alpha'^2/2 + V(alpha) fixes the turning angle; RK4's error in it ~ (omega dt)^4 per "
        "period (measured <= 1e-10); the extremum is cubic-interpolated, O((omega dt)^4); + the platform drift"
        + ROUNDOFF.format(gain=0.3, measured=0.13),
        "G1: alpha'' = -dV/dalpha, released at rest: it turns at +-amplitude (E conserved)",
    ),
    Check(
        "momentum-drift",
        "1",
        1e-11,
        "abs",
        "RK4 keeps H = I_a (chi' + Omega cos(lat) cos alpha) to its truncation error, which falls as dt^4 in "
        "proportion to the share I_a Omega cos(lat) (1 - cos a) / H of H that moves between its two terms (1.3e-3 at "
        "the defaults, < 2 in the ranges): measured 6e-15 in the cases, up to 1.5e-12 over the ranges (a slow rotor, "
        "share ~1: 1.6e-13 at 0.57x the step); round-off up to 3.8e-12 (slow platforms, chi' accumulated each "
        "step); 1e-11 leaves 2.6x over the worst measured",
        "G1: H conserved (the bearing exerts no torque about the spin axis); max |H(t) - H(0)| / |H(0)|",
    ),
    Check(
        "platform-drift",
        "1",
        1e-3,
        "abs",
        "1e-3 of the predicted drift (scaled at run time): the prediction neglects the gyro's own Omega-dependent "
        "share of the moment about n, (I_t + I_g) / I_p <= 1e-10 of it, follows the theory's trajectory (within 1e-8 "
        "of MuJoCo's) and samples the maximum at 2000 points a period (<= 5e-6); + 10 sqrt(nstep) eps, the rate's "
        "rounding as each step adds its change to Omega (a random walk: the changes are thousands of ulps); the "
        "drift itself is <= 1e-10 by the derived platform inertia",
        "G1 assumes a constant platform rate; the platform keeps it to I_p Omega + L_n = const, L_n the gyro's "
        "angular momentum along n (analytic.gyrocompass.momentum_along_axis): max |Omega(t) - Omega(0)| / Omega(0)",
    ),
)
_ALL = ("hunting-period", "mean-azimuth", "turning-angle", "momentum-drift", "platform-drift")


@dataclass(frozen=True)
class PlatformLatitude:
    """Latitude lat (rad) of the site: the platform's hinge axis is n = (0, cos(lat), sin(lat)) in the local East,
    North, Up frame (docs/theory.md section 0), read back from the compiled joint axis."""

    joint: str = PLATFORM

    def apply(self, spec: mujoco.MjSpec, value: Value) -> None:
        lat = float(value)
        spec.joint(self.joint).axis = [0.0, math.cos(lat), math.sin(lat)]

    def read(self, model: mujoco.MjModel) -> Value:
        axis = model.jnt_axis[model.joint(self.joint).id]
        return float(math.atan2(axis[2], math.hypot(axis[0], axis[1])))


def _theory(p: Mapping[str, Any]) -> gc.Gyrocompass:
    """The closed form from requested parameters (the prediction reads the compiled model instead)."""
    omega_perp = p["Omega"] * math.cos(p["latitude"])
    h = gc.spin_momentum(p["I_axial"], p["spin_rate"], omega_perp, p["amplitude"])
    return gc.Gyrocompass(p["I_transverse"], p["I_gimbal"], h, omega_perp)


_omega_max = gc.fastest_rate


def _swing(theory: gc.Gyrocompass, omega: float, latitude: float, amplitude: float) -> float:
    return gc.platform_momentum_swing(
        theory.inertia_transverse,
        theory.inertia_gimbal,
        theory.spin_momentum,
        omega,
        latitude,
        amplitude,
        theory.max_rate(amplitude),
    )


def _north_seeking(p: Mapping[str, Any]) -> str | None:
    """Domain test: A - B >= NORTH_MARGIN A (North a stable equilibrium by a margin)."""
    theory = _theory(p)
    if theory.A > 0 and theory.A - theory.B >= NORTH_MARGIN * theory.A:
        return None
    return (
        f"I_axial = {p['I_axial']:g} kg m^2, spin_rate = {p['spin_rate']:g} rad/s, I_transverse = "
        f"{p['I_transverse']:g} kg m^2, Omega = {p['Omega']:g} rad/s, latitude = {p['latitude']:g} rad "
        f"(H = {theory.spin_momentum:.4g} kg m^2/s against I_t Omega cos(lat) = "
        f"{theory.inertia_transverse * theory.omega_perp:.4g} kg m^2/s)"
    )


def _roundoff(p: Mapping[str, Any]) -> str | None:
    """Domain test: rho <= ROUNDOFF_MAX (requested parameters; released at rest, the turning angle is |amplitude|)."""
    omega_perp = p["Omega"] * math.cos(p["latitude"])
    rho = gyroscopic_roundoff(p["spin_rate"], omega_perp, p["amplitude"])
    if rho <= ROUNDOFF_MAX:
        return None
    return (
        f"spin_rate = {p['spin_rate']:g} rad/s, Omega = {p['Omega']:g} rad/s, latitude = {p['latitude']:g} rad, "
        f"amplitude = {p['amplitude']:g} rad (rho = {rho:.2g})"
    )


DOMAINS = (
    Domain(
        "gyroscopic-round-off",
        "G1 (restoring torque H Omega cos(lat) sin(a))",
        f"rho = eps chi' / (Omega cos(lat) sin|a|) <= {ROUNDOFF_MAX:g}: MuJoCo computes the gyroscopic "
        "torque in world axes, from a spin chi' far faster than the platform, with a round-off ~eps I chi'^2 against "
        "the restoring torque I_a chi' Omega cos(lat) sin(a); the checks' tolerances carry a floor ~rho (their reasons "
        "say how much); beyond 1e-5 the turning angle's floor would pass 1e-6 (an engine limit: a spin 1e10 times "
        "faster than the platform's horizontal rate times the amplitude)",
        _roundoff,
    ),
    Domain(
        "north-seeking",
        "G1 (stable equilibrium)",
        f"omega_g^2 = A - B >= {NORTH_MARGIN:g} A, i.e. H - I_t Omega cos(lat) >= {NORTH_MARGIN:g} H: North is a "
        "stable equilibrium (for A <= B the rotor is too slow for the platform and there is no hunting about North), "
        "by a margin that keeps omega_g^2, a difference of A and B, resolved in double precision and the platform's "
        f"drift, amplified by A / (A - B) in it, below the tolerances; also cos(lat) > 0 (|latitude| < pi/2)",
        _north_seeking,
    ),
)


class GyroCompass(Scenario):
    """A fast rotor held horizontal by a gimbal free about the local vertical, on a platform turning at Omega about
    an axis at latitude lat: the spin axis hunts about North (docs/theory.md G1)."""

    slug = "gyrocompass"
    title = "Gyrocompass: north-seeking hunting on a turning platform"
    env_id = "rigidbench/Gyrocompass-v0"
    params = (
        Param(
            "Omega",
            "rad/s",
            "the platform's (the Earth's, scaled up) rate about its axis n = (0, cos(lat), sin(lat)), at t = 0",
            Range(1e-3, 5.0),
            Numeric("Omega"),
        ),
        Param(
            "latitude",
            "rad",
            "latitude lat of the site: n is tilted from the local vertical by pi/2 - lat (negative: southern)",
            Range(-1.5, 1.5),
            PlatformLatitude(),
        ),
        Param(
            "spin_rate",
            "rad/s",
            "the rotor's initial spin rate chi' about its axis, relative to the gimbal",
            Range(10.0, 1e4),
            Numeric("spin_rate"),
        ),
        Param(
            "amplitude",
            "rad",
            "initial azimuth alpha0 of the spin axis from North towards East, at rest relative to the platform",
            Range(1e-4, 3.0, magnitude=True),
            Numeric("amplitude"),
        ),
        Param(
            "I_transverse",
            "kg m^2",
            "the rotor's transverse principal moment I_t about its CM (body x and z)",
            Range(1e-4, 10.0),
            BodyInertia(ROTOR, (0, 2)),
        ),
        Param(
            "I_axial",
            "kg m^2",
            "the rotor's axial principal moment I_a about its CM (body y, the spin axis)",
            Range(1e-4, 20.0),
            BodyInertia(ROTOR, (1,)),
            within=Bound(
                "[I_transverse, 2 I_transverse] (a flywheel: 2 I_t is the triangle inequality I_a <= I_t + I_t of "
                "every rigid body; below I_t, a rod-like rotor, MuJoCo's world-frame gyroscopic torque carries a "
                "round-off ~eps I_t chi'^2 that reached 1e-6 of the restoring torque at I_t / I_a = 2500, measured)",
                lambda p: Range(p["I_transverse"], 2 * p["I_transverse"]),
                ("I_transverse",),
            ),
        ),
        Param(
            "I_gimbal",
            "kg m^2",
            "the gimbal's moment I_g about the vertical, about its centre (isotropic: its horizontal moments equal)",
            Range(1e-5, 10.0),
            BodyInertia(GIMBAL, (0, 1, 2)),
        ),
    )
    cases = (
        Case(
            "small-hunting",
            "released 0.005 rad from North at latitude 45 deg: hunting at omega_g (period 0.43 s), T0 (1 + 1.6e-6)",
            {"amplitude": 0.005},
            ("small-amplitude-period", *_ALL),
            ranges={"amplitude": Range(1e-4, 0.01, magnitude=True)},
            regime="the small-amplitude period 2 pi / omega_g (1 + ((A - 4B)/(A - B)) a^2/16) neglects terms ~a^4 / "
            "300, below 4e-11 at |a| <= 0.01 (their exact size, by the quadrature, is in the tolerance)",
        ),
        Case(
            "large-hunting",
            "released 2.5 rad from North (143 deg) at latitude 45 deg: period 1.64 T0 by quadrature",
            {"amplitude": 2.5},
            _ALL,
        ),
        Case(
            "high-latitude",
            "released 1 rad from North at latitude 75 deg: cos(lat) = 0.26 slows the hunting by sqrt(0.707 / 0.259) = "
            "1.65, the amplitude by 7 % more (period 0.76 s)",
            {"amplitude": 1.0, "latitude": 1.309},
            _ALL,
        ),
    )
    checks = CHECKS
    domains = DOMAINS

    def validate(self, params: Mapping[str, Any]) -> None:
        require_rigid_body_inertia(
            params["I_transverse"], params["I_axial"], params["I_transverse"], "I_transverse, I_axial, I_transverse"
        )

    def reference_settings(self, params: Mapping[str, Any]) -> dict[str, Derived]:
        theory = _theory(params)
        amplitude = abs(float(params["amplitude"]))
        omega_max = _omega_max(theory, amplitude)
        h = round_step(STEP_TURN / omega_max)
        swing = _swing(theory, params["Omega"], params["latitude"], amplitude)
        gain = theory.A / (theory.A - theory.B)
        by_rate = swing * gain / (params["Omega"] * PLATFORM_DRIFT)
        by_reaction = theory.inertia_azimuth / PLATFORM_DRIFT
        inertia = max(by_rate, by_reaction)
        return {
            "timestep": Derived(
                h,
                f"{STEP_TURN:g} rad / omega_max, omega_max = max(omega_g, the azimuth's rate through North) = "
                f"{omega_max:.6g} rad/s, rounded down to one digit: {h:.1g} s (RK4 frequency error "
                f"(omega dt)^4/120 <= {STEP_TURN**4 / 120:.1e})",
            ),
            "platform_inertia": Derived(
                inertia,
                f"max(S A / ((A - B) Omega d), (I_t + I_g) / d), d = {PLATFORM_DRIFT:g}: "
                f"max({swing:.4g} x {gain:.4g} / ({params['Omega']:.4g} d), {theory.inertia_azimuth:.4g} / d) = "
                f"{inertia:.4g} kg m^2. S is the swing "
                "of the gyro's angular momentum along the platform's axis: the platform's rate moves by <= d of "
                "itself; and the platform's reaction to the gimbal's own turning (its axis is sin(lat) along n) "
                "lightens I_t + I_g by (I_t + I_g) sin^2(lat) / I_p <= d",
            ),
        }

    def apply_derived(self, spec: mujoco.MjSpec, name: str, value: float) -> None:
        if name != "platform_inertia":
            super().apply_derived(spec, name, value)
            return
        spec.body(PLATFORM).inertia = [value, value, value]

    def check_model(self, model: mujoco.MjModel) -> None:
        geometry(model)  # refuses a rotor that is not axisymmetric or a gimbal whose horizontal moments differ

    def initial_state(self, model: mujoco.MjModel, data: mujoco.MjData, params: Mapping[str, Any]) -> None:
        j = _joints(model)
        data.qpos[:] = 0.0
        data.qvel[:] = 0.0
        data.qpos[j.gimbal_q] = params["amplitude"]
        data.qvel[j.platform_v] = params["Omega"]
        data.qvel[j.rotor_v] = params["spin_rate"]

    def precision_domain(
        self, model: mujoco.MjModel, data: mujoco.MjData, prediction: Mapping[str, Any], precision: str
    ) -> str | None:
        """Refused where rho at the engine's eps reaches `UNRESOLVED_FRACTION`: the gyroscopic torque's round-off is
        that share of the restoring torque, beyond the floors' linear gains (a Warp census draw at rho = 1.5 ran
        its hunting period 18 % long against a linear floor of 8 %)."""
        eps = float(np.finfo(np.dtype(precision)).eps)
        rho = prediction["_rho"] * eps / float(np.finfo(float).eps)
        if rho < UNRESOLVED_FRACTION:
            return None
        return (
            f"rho = eps chi' / (Omega cos(lat) sin|a|) = {rho:.3g} at eps = {eps:.3g}: the gyroscopic torque's "
            f"round-off is {rho:.3g} of the restoring torque (resolvable: below {UNRESOLVED_FRACTION:g})"
        )

    def predict(self, model: mujoco.MjModel, data: mujoco.MjData) -> dict[str, Any]:
        g = geometry(model)
        j = _joints(model)
        omega = float(data.qvel[j.platform_v])
        azimuth0 = float(data.qpos[j.gimbal_q])
        rate0 = float(data.qvel[j.gimbal_v])
        omega_perp = omega * g.horizontal
        h = gc.spin_momentum(g.inertia_axial, float(data.qvel[j.rotor_v]), omega_perp, azimuth0 - g.north)
        theory = gc.Gyrocompass(g.inertia_transverse, g.inertia_gimbal, h, omega_perp)
        amplitude = theory.turning_angle(azimuth0 - g.north, rate0)
        period = theory.period(amplitude)
        shift = theory.small_amplitude_shift(amplitude)
        small = 2 * np.pi / theory.hunting_frequency * (1 + shift)
        beyond = abs(period / (2 * np.pi / theory.hunting_frequency) - 1 - shift)  # the quadrature's a^4 and higher
        swing = gc.platform_momentum_swing(
            g.inertia_transverse, g.inertia_gimbal, h, omega, g.latitude, amplitude, theory.max_rate(amplitude)
        )
        drift = swing / (g.inertia_platform * abs(omega))
        gain = abs((theory.A - 2 * theory.B) / (theory.A - theory.B))  # d ln(omega_g^2) / d ln(Omega)
        # The platform turns back as the gimbal turns (the gimbal axis has sin(lat) along n): I_t + I_g is lightened
        # by (I_t + I_g) sin^2(lat) / I_p, and the period by half that.
        reaction = theory.inertia_azimuth * np.sin(g.latitude) ** 2 / g.inertia_platform
        period_drift = 0.5 * (gain * drift + reaction)
        # The platform's rate along the theory's trajectory: I_p Omega + L_n conserved.
        eps = float(np.finfo(float).eps)
        t = np.linspace(0.0, RUN_PERIODS * period, int(2000 * RUN_PERIODS) + 1)
        alpha_t, rate_t = theory.trajectory(t, azimuth0 - g.north, rate0)
        along = gc.momentum_along_axis(g.inertia_transverse, g.inertia_gimbal, h, omega, g.latitude, alpha_t, rate_t)
        predicted_drift = float(np.abs(along - along[0]).max() / (g.inertia_platform * abs(omega)))
        nstep = round(RUN_PERIODS * period / model.opt.timestep)
        rho = gyroscopic_roundoff(float(data.qvel[j.rotor_v]), omega_perp, amplitude)
        # The hunting period's sensitivity to the amplitude (and so to the energy the round-off moves)
        sensitivity = gc.period_sensitivity(theory, amplitude)
        scale = {"hunting-period": max(1.0, sensitivity)}
        floor = {name: gain_ * rho * scale.get(name, 1.0) for name, gain_ in ROUNDOFF_GAINS.items()}
        return {
            "_theory": theory,
            "_geometry": g,
            "_azimuth0": azimuth0,
            "_rate0": rate0,
            "_amplitude": amplitude,
            "_omega": omega,
            "hunting-period": period,
            "small-amplitude-period": small,
            "mean-azimuth": g.north,
            "turning-angle": amplitude,
            "momentum-drift": 0.0,
            "platform-drift": predicted_drift,
            "_rho": rho,
            # The same floors on a float32 engine (`Scenario._roundoff_check`): rho is eps times chi' / (Omega_perp
            # sin a), so each floor in units of the precision's eps.
            "_roundoff_eps": {
                name: floor[name] / eps * (amplitude if name == "mean-azimuth" else 1.0) for name in ROUNDOFF_GAINS
            },
            "_roundoff_eps_rule": "gain x rho, rho = eps chi' / (Omega cos(lat) sin|a|) (x S, the period's sensitivity "
            "to the amplitude, for the hunting period): the gyroscopic "
            "torque's round-off against the restoring torque, proportional to the precision's eps; the gains are "
            "the float64 floors'",
            "_tolerance": {
                "hunting-period": self.check("hunting-period").tolerance + period_drift + floor["hunting-period"],
                "small-amplitude-period": 2 * beyond
                + self.check("small-amplitude-period").tolerance
                + period_drift
                + floor["small-amplitude-period"],
                "mean-azimuth": (self.check("mean-azimuth").tolerance + floor["mean-azimuth"]) * amplitude,
                "turning-angle": self.check("turning-angle").tolerance + drift + reaction + floor["turning-angle"],
                "platform-drift": self.check("platform-drift").tolerance * predicted_drift
                + 10 * math.sqrt(nstep) * eps,
            },
        }

    def duration(self, prediction: Mapping[str, Any]) -> float:
        return RUN_PERIODS * prediction["hunting-period"]

    def measure(self, model: mujoco.MjModel, traj: Trajectory, prediction: Mapping[str, Any]) -> dict[str, float]:
        j = _joints(model)
        g = prediction["_geometry"]
        t = traj.time
        alpha = traj.qpos[:, j.gimbal_q] - g.north
        rate = traj.qvel[:, j.gimbal_v]
        omega = traj.qvel[:, j.platform_v]
        h = g.inertia_axial * (traj.qvel[:, j.rotor_v] + omega * g.horizontal * np.cos(alpha))
        _, maxima = signals.extrema(t, alpha, rate, "max")
        _, minima = signals.extrema(t, alpha, rate, "min")
        turning = np.abs(np.concatenate([[alpha[0]], maxima, minima]))
        amplitude = prediction["turning-angle"]
        period = 2 * np.pi / frequency(t, alpha)
        return {
            "hunting-period": period,
            "small-amplitude-period": period,
            "mean-azimuth": g.north + mean_over_periods(t, alpha),
            "turning-angle": float(turning[np.argmax(np.abs(turning - amplitude))]),
            "momentum-drift": signals.max_relative_drift(h),
            "platform-drift": signals.max_relative_drift(omega),
        }


def mean_over_periods(t: np.ndarray, alpha: np.ndarray) -> float:
    """Time average (rad) of `alpha` between its first and last upward zero crossings (whole periods): a cubic
    spline's exact integral, error O(h^4). NaN with fewer than two upward crossings."""
    from scipy.interpolate import CubicSpline

    up = signals.crossings(t, alpha, 1)
    if len(up) < 2:
        return float("nan")
    return float(CubicSpline(t, alpha).integrate(up[0], up[-1]) / (up[-1] - up[0]))


def _moment(model: mujoco.MjModel, body: int, axis_body: np.ndarray) -> float:
    """Moment of inertia (kg m^2) of `body` about the unit axis `axis_body` (body frame) through its CM."""
    frame = np.empty(9)
    mujoco.mju_quat2Mat(frame, model.body_iquat[body])
    axis_inertial = frame.reshape(3, 3).T @ (axis_body / np.linalg.norm(axis_body))
    return float(np.sum(model.body_inertia[body] * axis_inertial**2))


def geometry(model: mujoco.MjModel) -> Geometry:
    """Read the gyrocompass' moments and axes from the compiled model (body frames at rest: the model's own).

    Raises
    ------
    ValueError
        If the rotor is not axisymmetric about its spin axis, or the gimbal's horizontal moments differ (docs/theory.md
        G1 assumes both: otherwise an azimuth-dependent torque of order (difference) Omega^2 enters).
    """
    j = _joints(model)
    axis = {name: model.jnt_axis[getattr(j, name + "_id")] for name in (PLATFORM, GIMBAL, ROTOR)}
    rotor, gimbal, platform = (model.body(name).id for name in (ROTOR, GIMBAL, PLATFORM))
    # Joint axes in the platform frame (the gimbal and rotor frames coincide with it at zero joint angles).
    q_g, q_r = model.body_quat[gimbal], model.body_quat[rotor]
    up = -_rotate(q_g, axis[GIMBAL])  # the gimbal turns about -up: its angle is the azimuth towards East
    spin0 = _rotate(q_g, _rotate(q_r, axis[ROTOR]))  # the spin axis at zero gimbal angle
    latitude, horizontal, north = gc.axes_geometry(axis[PLATFORM], up, spin0)
    spin_local = axis[ROTOR] / np.linalg.norm(axis[ROTOR])
    trans = np.cross(spin_local, np.eye(3)[np.argmin(np.abs(spin_local))])
    trans /= np.linalg.norm(trans)
    trans2 = np.cross(spin_local, trans)
    i_t1, i_t2 = _moment(model, rotor, trans), _moment(model, rotor, trans2)
    if abs(i_t1 - i_t2) > 1e-12 * max(i_t1, i_t2):
        raise ValueError(
            f"scenario 'gyrocompass': the rotor's transverse moments {i_t1:g}, {i_t2:g} kg m^2 differ;"
            f" docs/theory.md G1 "
            "needs a rotor symmetric about its spin axis"
        )
    gimbal_axis = axis[GIMBAL] / np.linalg.norm(axis[GIMBAL])
    gh = np.cross(gimbal_axis, np.eye(3)[np.argmin(np.abs(gimbal_axis))])
    gh /= np.linalg.norm(gh)
    i_h1, i_h2 = _moment(model, gimbal, gh), _moment(model, gimbal, np.cross(gimbal_axis, gh))
    if abs(i_h1 - i_h2) > 1e-12 * max(i_h1, i_h2):
        raise ValueError(
            f"scenario 'gyrocompass': the gimbal's horizontal moments {i_h1:g}, {i_h2:g} kg m^2 differ;"
            f" docs/theory.md G1 "
            "takes them equal (else an azimuth-dependent torque (difference) Omega^2 cos^2(lat) sin 2 alpha / 2 enters)"
        )
    return Geometry(
        inertia_axial=_moment(model, rotor, spin_local),
        inertia_transverse=i_t1,
        inertia_gimbal=_moment(model, gimbal, gimbal_axis),
        inertia_platform=_moment(model, platform, axis[PLATFORM]),
        latitude=latitude,
        horizontal=horizontal,
        north=north,
    )


def _rotate(quat: np.ndarray, v: np.ndarray) -> np.ndarray:
    out = np.empty(3)
    mujoco.mju_rotVecQuat(out, np.asarray(v, dtype=float), np.asarray(quat, dtype=float))
    return out


@dataclass(frozen=True)
class _Joints:
    platform_id: int
    gimbal_id: int
    rotor_id: int
    platform_v: int
    gimbal_q: int
    gimbal_v: int
    rotor_v: int


def _joints(model: mujoco.MjModel) -> _Joints:
    ids = [model.joint(name).id for name in (PLATFORM, GIMBAL, ROTOR)]
    return _Joints(
        *ids,
        platform_v=int(model.jnt_dofadr[ids[0]]),
        gimbal_q=int(model.jnt_qposadr[ids[1]]),
        gimbal_v=int(model.jnt_dofadr[ids[1]]),
        rotor_v=int(model.jnt_dofadr[ids[2]]),
    )


class GyrocompassEnv(ScenarioEnv):
    """``rigidbench/Gyrocompass-v0``: the gyrocompass' hunting about North, scored against theory every step.

    Description
        A rotor spinning about a horizontal axis held by a gimbal that turns freely about the local vertical, on a
        platform turning at Omega about n = (0, cos(lat), sin(lat)) (East, North, Up). With zero action it is the
        textbook gyrocompass (docs/theory.md G1): the spin axis hunts about North, ``(I_t + I_g) alpha'' = -H Omega
        cos(lat) sin(alpha) + I_t Omega^2 cos^2(lat) sin(alpha) cos(alpha)``, at ``omega_g^2 = Omega cos(lat) (H -
        I_t Omega cos(lat)) / (I_t + I_g)`` for small amplitudes.

    Observation Space
        Box(-inf, inf, (6,)), float64: qpos then qvel of the joints ``platform``, ``gimbal``, ``rotor``:

        ==== ============================================================= ====== ==================
        idx  quantity                                                      unit   MuJoCo source
        ==== ============================================================= ====== ==================
        0    platform angle about n                                        rad    qpos ``platform``
        1    azimuth alpha of the spin axis from North towards East        rad    qpos ``gimbal``
        2    rotor spin angle chi relative to the gimbal                   rad    qpos ``rotor``
        3    platform rate Omega                                           rad/s  qvel ``platform``
        4    azimuth rate alpha'                                           rad/s  qvel ``gimbal``
        5    rotor spin rate chi'                                          rad/s  qvel ``rotor``
        ==== ============================================================= ====== ==================

    Action Space
        Box(-1, 1, (1,)), float32, normalised: ``action_scale = 0.1`` N m times it is a torque about the gimbal's
        axis (positive turns the spin axis towards East), through ``qfrc_applied``; out-of-range actions are
        clipped. Zero action = the textbook problem.

    Rewards
        ``reward = -|alpha - alpha_theory(t)| / amplitude``, alpha_theory the exact hunting equation integrated
        from the simulated initial state; ``info["measured"]["azimuth"]`` and ``info["predicted"]["azimuth"]`` hold
        both (rad). Each step's deviation counts up to ``DEVIATION_CAP`` = 10 (rewards >= -10).

    Starting State
        ``alpha = amplitude``, at rest relative to the platform; platform rate ``Omega``; rotor spin ``spin_rate``.
        Deterministic.

    Episode End
        Truncated after 4.25 hunting periods (the validation run's duration); terminated on divergence.
        The diverged step pays -10 for itself and for each step left, the worst the rest could score: blowing
        up the simulation never pays (`ScenarioEnv`).

    Arguments
        ``case`` (small-hunting, large-hunting, high-latitude), ``params`` (Omega, latitude, spin_rate,
        amplitude, I_transverse, I_axial, I_gimbal), ``profile``, ``integrator``, ``timestep``, ``frame_skip``
        (default 10: ten derived steps, 3 ms at the default case), ``render_mode``.

    Version History
        v0: initial version.
    """

    scenario_cls = GyroCompass
    observables = ("azimuth",)
    max_torque: ClassVar[float] = 0.1

    def define_observation_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-np.inf, np.inf, shape=(6,), dtype=np.float64)

    def define_action_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-self.max_torque, self.max_torque, shape=(1,), dtype=np.float64)

    def load(self, case: str, params) -> None:
        super().load(case, params)
        j = _joints(self.model)
        self._gimbal_q, self._gimbal_v = j.gimbal_q, j.gimbal_v
        self._north = self.prediction["_geometry"].north
        self._scale = float(self.prediction["_amplitude"])
        self.start_views()

    def bind_views(self) -> None:
        self._qfrc = self._data.qfrc_applied

    def observe(self) -> np.ndarray:
        obs = np.empty(6)
        mujoco.mj_getState(self.model, self._data, obs, mujoco.mjtState.mjSTATE_QPOS | mujoco.mjtState.mjSTATE_QVEL)
        return obs

    def apply_action(self, action: np.ndarray) -> None:
        self._qfrc[self._gimbal_v] = action.item()

    def theory(self, t: np.ndarray) -> np.ndarray:
        p = self.prediction
        north = p["_geometry"].north
        alpha = p["_theory"].azimuth(np.asarray(t) - self._time0, p["_azimuth0"] - north, p["_rate0"])
        return (alpha + north)[:, None]

    def measured(self, obs: np.ndarray) -> list[float]:
        return [float(obs[self._gimbal_q])]

    def deviation(self, measured: list[float], predicted: list[float]) -> float:
        return abs(measured[0] - predicted[0]) / self._scale

    def observe_batch(self, worlds) -> np.ndarray:
        return np.concatenate([worlds.qpos, worlds.qvel], axis=1)

    def apply_actions(self, actions: np.ndarray, worlds) -> None:
        worlds.qfrc_applied[:, self._gimbal_v] = actions[:, 0]

    def measured_batch(self, obs: np.ndarray) -> np.ndarray:
        return obs[:, self._gimbal_q : self._gimbal_q + 1]

    def deviation_batch(self, measured: np.ndarray, predicted: np.ndarray) -> np.ndarray:
        return np.abs(measured[:, 0] - predicted[:, 0]) / self._scale
