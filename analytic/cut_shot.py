"""Closed forms for the rolling cut shot: a rolling cue ball hits an equal resting ball off-centre (docs/theory.md B4).

Pure numpy functions of SI values (house rule 2). Conventions: the table is the x-y plane, vectors are 2-D (x, y);
the cue ball rolls along +x at speed V before the impact (spin omega = z x v / R); the line of centres at the
touch makes the cut angle phi with +x, the cue ball passing on the +y side of the object ball, so the object ball
leaves along n = (cos phi, -sin phi) and the cue ball is deflected towards +y. Both balls are solid spheres of
radius R and mass M, I = gamma M R^2; the table has Coulomb friction mu (B2, B3); the ball-ball impact is
frictionless (its impulse J acts along the line of centres, through both centres, so it changes no spin).

The whole shot follows from the impulse J the object ball receives (J / M its velocity right after):

- right after the impact the cue ball has V x - J / M and its old spin: equal masses and an elastic central impact
  leave the two velocities at 90 degrees (C2), and both balls slip, by -J / M (cue) and +J / M (object);
- each slip is undone by Coulomb friction along a fixed direction (B3) in t_r = |J| / (M mu g (1 + 1/gamma)), and
  angular momentum about each ball's table contact point gives the rolling velocities
  ``v_cue = V x - J / (M (1 + gamma))`` and ``v_object = J / (M (1 + gamma))`` (the 5/7 rule for gamma = 2/5).

For the hard-sphere impact J / M = V cos(phi) n, and the cue ball's deflection from its first line is
``tan delta = sin phi cos phi / (gamma + sin^2 phi) = 5 sin phi cos phi / (2 cos^2 phi + 7 sin^2 phi)``, largest at
``tan phi = sqrt(gamma / (1 + gamma)) = sqrt(2/7)``: delta = 33.75 degrees at phi = 28.13 degrees (the "30 degree
rule"); the final angle between the two balls is ``arctan((1 + 1/gamma) tan phi) = arctan(3.5 tan phi)``.
Source: [D] (docs/theory.md B4).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from rigidbench.analytic.percussion import SOLID_SPHERE


def deflection(cut_angle: ArrayLike, gamma: float = SOLID_SPHERE) -> np.ndarray:
    """The rolling cue ball's deflection delta (rad) after a hard-sphere cut at `cut_angle` phi (docs/theory.md B4):
    ``tan delta = sin phi cos phi / (gamma + sin^2 phi)``, ``5 sin phi cos phi / (2 cos^2 phi + 7 sin^2 phi)`` for a
    solid ball."""
    phi = np.asarray(cut_angle, dtype=float)
    s, c = np.sin(phi), np.cos(phi)
    return np.arctan2(s * c, gamma + s * s)


def max_deflection(gamma: float = SOLID_SPHERE) -> tuple[float, float]:
    """The cut angle phi* (rad) of the largest deflection and that deflection (rad): ``tan phi* = sqrt(gamma / (1 +
    gamma))``, ``tan delta* = 1 / (2 sqrt(gamma (1 + gamma)))``; sqrt(2/7) and 33.75 degrees for a solid ball
    (docs/theory.md B4, the "30 degree rule")."""
    phi = math.atan(math.sqrt(gamma / (1.0 + gamma)))
    return phi, math.atan(0.5 / math.sqrt(gamma * (1.0 + gamma)))


def final_angle(cut_angle: ArrayLike, gamma: float = SOLID_SPHERE) -> np.ndarray:
    """Angle (rad) between the two rolling balls' velocities after a hard-sphere cut: ``arctan((1 + 1/gamma) tan
    phi)``, ``arctan(3.5 tan phi)`` for a solid ball (docs/theory.md B4)."""
    phi = np.asarray(cut_angle, dtype=float)
    return np.arctan2((1.0 + 1.0 / gamma) * np.sin(phi), np.cos(phi))


def object_impulse(speed: float, cm_angle: float) -> np.ndarray:
    """The object ball's velocity J / M (m/s, 2-D) right after an elastic central impact of equal masses that turns
    the relative velocity V x by the CM angle theta towards +y (docs/theory.md C2): ``(V / 2) (1 - cos theta,
    -sin theta)``. The hard sphere's theta = pi - 2 phi gives ``V cos phi (cos phi, -sin phi)``."""
    return 0.5 * speed * np.array([1.0 - math.cos(cm_angle), -math.sin(cm_angle)])


@dataclass(frozen=True)
class Skid:
    """A ball sliding on the table from t = 0 with velocity `velocity` and contact-point slip `slip` (2-D, m/s) under
    Coulomb friction mu, until it rolls (docs/theory.md B3: the slip keeps its direction, the centre runs on the
    parabola ``r(t) = v0 t - 1/2 mu g u_hat t^2``, and it rolls from ``t_r = |u0| / (mu g (1 + 1/gamma))`` at
    ``v_f = v0 - gamma / (1 + gamma) u0``)."""

    velocity: np.ndarray
    slip: np.ndarray
    mu: float
    g: float
    gamma: float = SOLID_SPHERE

    @property
    def time_to_roll(self) -> float:
        return float(np.hypot(*self.slip)) / (self.mu * self.g * (1.0 + 1.0 / self.gamma))

    @property
    def final_velocity(self) -> np.ndarray:
        return self.velocity - self.gamma / (1.0 + self.gamma) * self.slip

    def position(self, t: ArrayLike) -> np.ndarray:
        """Displacement (m), shape (len(t), 2), at times t >= 0 (s): the parabola, then rolling straight."""
        t = np.asarray(t, dtype=float)[:, None]
        t_r = self.time_to_roll
        size = float(np.hypot(*self.slip))
        direction = self.slip / size if size > 0 else np.zeros(2)
        ts = np.minimum(t, t_r)
        return self.velocity * ts - 0.5 * self.mu * self.g * direction * ts**2 + self.final_velocity * (t - ts)


@dataclass(frozen=True)
class CutShot:
    """The rolling cut shot from the object ball's impulse (module docstring; docs/theory.md B4, B2, B3, C2).

    Attributes
    ----------
    speed : float
        V (m/s), the rolling cue ball's speed before the impact.
    impulse : ndarray, shape (2,)
        J / M (m/s): the object ball's velocity right after the impact.
    cue_after, object_after : ndarray, shape (2,)
        Velocities (m/s) right after the impact: V x - J / M and J / M.
    cue, object : Skid
        Each ball's slide from the impact to rolling (B3).
    cue_final, object_final : ndarray, shape (2,)
        Rolling velocities (m/s): V x - J / (M (1 + gamma)) and J / (M (1 + gamma)).
    """

    speed: float
    impulse: np.ndarray
    mu: float
    g: float
    gamma: float

    @property
    def cue_after(self) -> np.ndarray:
        return np.array([self.speed, 0.0]) - self.impulse

    @property
    def object_after(self) -> np.ndarray:
        return np.array(self.impulse)

    @property
    def cue(self) -> Skid:
        return Skid(self.cue_after, -self.impulse, self.mu, self.g, self.gamma)

    @property
    def object(self) -> Skid:
        return Skid(self.object_after, np.array(self.impulse), self.mu, self.g, self.gamma)

    @property
    def cue_final(self) -> np.ndarray:
        return self.cue.final_velocity

    @property
    def object_final(self) -> np.ndarray:
        return self.object.final_velocity

    @property
    def deflection(self) -> float:
        """delta (rad): the cue ball's final direction from +x."""
        return float(math.atan2(self.cue_final[1], self.cue_final[0]))

    @property
    def object_direction(self) -> float:
        """zeta (rad): the object ball's direction below +x (phi for the hard sphere)."""
        return float(math.atan2(-self.impulse[1], self.impulse[0]))

    @property
    def opening_angle(self) -> float:
        """Angle (rad) between the two velocities right after the impact (pi/2 for any elastic central impact)."""
        return angle_between(self.cue_after, self.object_after)

    @property
    def final_angle(self) -> float:
        """Angle (rad) between the two rolling velocities."""
        return angle_between(self.cue_final, self.object_final)

    @property
    def time_to_roll(self) -> float:
        """The longer of the two slides (s); both are |J| / (M mu g (1 + 1/gamma))."""
        return max(self.cue.time_to_roll, self.object.time_to_roll)


def angle_between(a: ArrayLike, b: ArrayLike) -> float:
    """The angle (rad, in [0, pi]) between two 2-D vectors."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return float(math.atan2(abs(a[0] * b[1] - a[1] * b[0]), a[0] * b[0] + a[1] * b[1]))


def cut_shot(
    speed: float, cut_angle: float, mu: float, g: float, gamma: float = SOLID_SPHERE, *, cm_angle: float | None = None
) -> CutShot:
    """The rolling cut shot at cut angle phi (rad) and cue speed V (m/s) (docs/theory.md B4).

    `cm_angle` is the impact's CM scattering angle theta (rad): pi - 2 phi for hard spheres (the default); a soft
    contact's (C8, `scattering.soft_sphere_cm_angle`) turns the relative velocity by less.
    """
    theta = math.pi - 2.0 * cut_angle if cm_angle is None else cm_angle
    return CutShot(float(speed), object_impulse(speed, theta), float(mu), float(g), float(gamma))
