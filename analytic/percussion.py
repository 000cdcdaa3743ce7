"""Closed forms for percussion: the struck free stick, the pivoted stick, a ball striking a stick, the cue ball.

Pure numpy/scipy functions of SI values; nothing here imports mujoco (house rule 2).

Conventions (docs/theory.md sections 6 and 7)
---------------------------------------
Stick: lies along +y with its centre of mass (CM) at the origin; s is the body coordinate along it. An impulse
``impulse`` (Pi) along +x at s = +h (``offset``) turns it clockwise seen from +z: omega_z = -Pi h / I. Moments of
inertia are about the CM unless the name says otherwise (``inertia_pivot``). docs/theory.md writes the uniform stick
with the *half*-length l (I = M l^2 / 3); the public parameter here is the full length L = 2 l (I = M L^2 / 12).

Ball: radius R, mass M, moment of inertia I = gamma M R^2 about any axis through its centre (gamma = 2/5 for a
solid sphere). Motion along +x on a table in the x-y plane; omega_y is the spin about +y, so the contact point
(at -R z from the centre) slips with u = v - R omega_y; rolling is u = 0 and topspin is omega_y > 0.
A cue impulse along +x at height h above the centre gives omega_y = Pi h / I (topspin for h > 0).

References
----------
[H] Harter, lecture slides Unit 6, Ch. 2 (seed 001): stick percussion, centre of percussion, cycloids,
    "practical poolhall application" (H = 7/10 of the diameter).
[W] Wilcox, *Modern Introductory Mechanics Part II* (seed 000), prob. 11.7 (equivalent length of a pendulum).
[T] docs/theory.md, entries P1-P6 (stick) and B1-B2 (billiard ball).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

SOLID_SPHERE = 2.0 / 5.0  # gamma = I / (M R^2), docs/theory.md B1

# ---------------------------------------------------------------------------------------------------------
# The free stick struck by an impulse (docs/theory.md P1-P3; [H] Fig. 2.4.1 slides)
# ---------------------------------------------------------------------------------------------------------


def uniform_rod_inertia(mass: float, length: float) -> float:
    """Moment of inertia (kg m^2) of a thin uniform rod about a transverse axis through its centre: M L^2 / 12.

    `length` is the full length L (docs/theory.md R3 writes it with the half-length l = L/2 as M l^2 / 3).
    """
    return mass * length**2 / 12.0


def centre_of_percussion(mass: float, inertia: float, offset: float) -> float:
    """Distance p (m) from the CM to the centre of percussion, on the far side from the blow: p = I / (M h).

    docs/theory.md P2 ([H]: "p = I/(Mh)"; for the uniform stick p = l^2 / (3 h)). The point s = -p is at rest just
    after an impulse at s = +h. A blow through the CM (h = 0) gives p = inf: no point of the body is at rest.
    """
    return inertia / (mass * offset) if offset != 0 else math.inf


@dataclass(frozen=True)
class StruckStick:
    """Planar motion of a free stick just after an impulse Pi along +x at s = +h (docs/theory.md P1-P3).

    Attributes
    ----------
    com_velocity : float
        V = Pi / M (m/s), along +x (P1).
    angular_velocity : float
        omega_z = -Pi h / I (rad/s); clockwise for h > 0 (P1).
    percussion_distance : float
        p = I / (M h) (m): the point s = -p is momentarily at rest (P2).
    cusp_period : float
        2 pi / |omega| = 2 pi I / (Pi h) (s): the point s = -p is at rest again at t_n = n cusp_period (P3).
    cusp_spacing : float
        2 pi p (m): distance along +x between successive cusps of its cycloid (P3).
    """

    com_velocity: float
    angular_velocity: float
    percussion_distance: float
    cusp_period: float
    cusp_spacing: float

    def point_velocity(self, s: float | np.ndarray) -> np.ndarray:
        """Velocity along +x (m/s) of the stick point at s just after the blow: V (1 + s h / rho^2) (P2)."""
        return self.com_velocity - self.angular_velocity * np.asarray(s, dtype=float)

    def cycloid(self, t: np.ndarray) -> np.ndarray:
        """Position (x, y) (m), shape (len(t), 2), of the point s = -p at time t after the blow (P3).

        x = p (theta - sin theta), y = -p cos theta with theta = |omega| t (the CM moves along y = 0).
        """
        theta = abs(self.angular_velocity) * np.asarray(t, dtype=float)
        p = self.percussion_distance
        return np.stack([p * (theta - np.sin(theta)), -p * np.cos(theta)], axis=-1)


def struck_stick(mass: float, inertia: float, impulse: float, offset: float) -> StruckStick:
    """The free stick after an impulse `impulse` (N s) along +x at `offset` h (m) from the CM (docs/theory.md P1-P3).

    Parameters
    ----------
    mass : float
        M (kg).
    inertia : float
        I (kg m^2) about the transverse axis z through the CM.
    impulse, offset : float
        Pi > 0 and h > 0.
    """
    omega = -impulse * offset / inertia
    p = centre_of_percussion(mass, inertia, offset)
    return StruckStick(
        com_velocity=impulse / mass,
        angular_velocity=omega,
        percussion_distance=p,
        cusp_period=2 * np.pi / abs(omega) if omega != 0 else math.inf,
        cusp_spacing=2 * np.pi * p,
    )


# ---------------------------------------------------------------------------------------------------------
# The pivoted stick (docs/theory.md P4)
# ---------------------------------------------------------------------------------------------------------


def pivot_reaction_impulse(mass: float, inertia_pivot: float, com_distance: float, strike: float, impulse: float):
    """Reaction impulse J (N s) of a frictionless pivot on a body struck perpendicularly (docs/theory.md P4).

    J = Pi (M d_cm d / I_O - 1), along the blow (negative: the pivot holds the body back).

    Parameters
    ----------
    inertia_pivot : float
        I_O (kg m^2), about the pivot axis.
    com_distance : float
        d_cm (m), pivot to CM.
    strike : float
        d (m), pivot to the line of the blow (measured along the same line as d_cm).
    """
    return impulse * (mass * com_distance * strike / inertia_pivot - 1.0)


def sweet_spot(mass: float, inertia_pivot: float, com_distance: float) -> float:
    """d* = I_O / (M d_cm) (m): the strike distance with no pivot reaction (docs/theory.md P4; [W] prob. 11.7).

    It is the centre of percussion referred to the pivot, d_cm + p, and the equivalent length of the physical
    pendulum; 2L/3 for a uniform rod pivoted at one end.
    """
    return inertia_pivot / (mass * com_distance)


# ---------------------------------------------------------------------------------------------------------
# A ball striking the free stick (docs/theory.md P5)
# ---------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class BallOnStick:
    """Velocities just after a point ball hits the resting free stick perpendicularly (docs/theory.md P5).

    Attributes
    ----------
    effective_mass : float
        M_eff = (1/M + h^2/I)^-1 (kg): the stick's inertia felt at the struck point.
    impulse : float
        Pi = (1 + e) m u M_eff / (m + M_eff) (N s), along +x on the stick.
    ball_velocity : float
        u' = u - Pi / m (m/s).
    stick : StruckStick
        The stick's motion after the impulse Pi (P1-P3 apply).
    """

    effective_mass: float
    impulse: float
    ball_velocity: float
    stick: StruckStick


def ball_on_stick(
    mass: float, inertia: float, offset: float, ball_mass: float, ball_speed: float, restitution: float = 1.0
) -> BallOnStick:
    """A point ball of mass m at speed u (+x) hits the stick at s = h with restitution e (docs/theory.md P5)."""
    m_eff = 1.0 / (1.0 / mass + offset**2 / inertia)
    impulse = (1.0 + restitution) * ball_mass * ball_speed * m_eff / (ball_mass + m_eff)
    return BallOnStick(
        effective_mass=m_eff,
        impulse=impulse,
        ball_velocity=ball_speed - impulse / ball_mass,
        stick=struck_stick(mass, inertia, impulse, offset),
    )


# ---------------------------------------------------------------------------------------------------------
# The cue ball (docs/theory.md B1, B2)
# ---------------------------------------------------------------------------------------------------------


def no_skid_height(radius: float, gamma: float = SOLID_SPHERE) -> float:
    """Height h = I / (M R) = gamma R above the centre at which a horizontal blow leaves no slip (docs/theory.md B1).

    2R/5 for a solid sphere: the line of the blow is at H = R + h = 7/10 of the diameter above the table ([H]).
    """
    return gamma * radius


def slip_after_impulse(radius: float, height: float, impulse_per_mass: float, gamma: float = SOLID_SPHERE) -> float:
    """Change of the contact slip u = v - R omega_y (m/s) from a horizontal impulse Pi at height h (docs/theory.md B1).

    du = (Pi / M) (1 - h M R / I) = (Pi / M) (1 - h / (gamma R)); zero at the no-skid height whatever the
    state before (the rolling ball stays rolling off a cushion of that height).
    """
    return impulse_per_mass * (1.0 - height / (gamma * radius))


@dataclass(frozen=True)
class SkidToRoll:
    """A ball sliding on a table with Coulomb friction until it rolls (docs/theory.md B2, B3 in one dimension).

    Attributes
    ----------
    speed, spin : float
        v0 (m/s) and omega_y0 (rad/s) at t = 0.
    slip : float
        u0 = v0 - R omega0 (m/s).
    time_to_roll : float
        t_r = |u0| / (mu g (1 + 1/gamma)); 2 |u0| / (7 mu g) for a solid sphere.
    final_speed : float
        v_f = (v0 + gamma R omega0) / (1 + gamma) = v0 - (2/7) u0: angular momentum about the contact point is
        conserved.
    skid_distance : float
        s = v0 t_r - 1/2 sgn(u0) mu g t_r^2 (m).
    energy_lost : float
        Fraction of the kinetic energy at t = 0 lost to sliding friction (2/7 for a centre strike).
    """

    radius: float
    mu: float
    g: float
    gamma: float
    speed: float
    spin: float
    slip: float
    time_to_roll: float
    final_speed: float
    skid_distance: float
    energy_lost: float

    @property
    def slip_rate(self) -> float:
        """du/dt while sliding (m/s^2): -sgn(u0) mu g (1 + 1/gamma) = -(7/2) mu g sgn(u0) for a solid sphere."""
        return -np.sign(self.slip) * self.mu * self.g * (1.0 + 1.0 / self.gamma)

    def state(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Distance x (m), speed v (m/s) and slip u (m/s) at times t >= 0 (s): sliding, then rolling."""
        t = np.asarray(t, dtype=float)
        ts = np.minimum(t, self.time_to_roll)
        decel = np.sign(self.slip) * self.mu * self.g
        v = self.speed - decel * ts
        x = self.speed * ts - 0.5 * decel * ts**2 + self.final_speed * (t - ts)
        u = self.slip + self.slip_rate * ts
        return x, v, u


def skid_to_roll(
    radius: float, mu: float, g: float, speed: float, spin: float, gamma: float = SOLID_SPHERE
) -> SkidToRoll:
    """The ball's slide with initial speed v0 (+x) and spin omega_y0 (docs/theory.md B2).

    Validity: point contact, constant Coulomb coefficient mu (sliding = static), no rolling or spinning
    resistance, table horizontal with gravity g.
    """
    slip = speed - radius * spin
    t_r = abs(slip) / (mu * g * (1.0 + 1.0 / gamma))
    v_f = (speed + gamma * radius * spin) / (1.0 + gamma)
    s = speed * t_r - 0.5 * np.sign(slip) * mu * g * t_r**2
    e0 = speed**2 + gamma * (radius * spin) ** 2  # 2 E / M
    e_f = (1.0 + gamma) * v_f**2
    return SkidToRoll(
        radius=radius,
        mu=mu,
        g=g,
        gamma=gamma,
        speed=speed,
        spin=spin,
        slip=slip,
        time_to_roll=t_r,
        final_speed=v_f,
        skid_distance=float(s),
        energy_lost=1.0 - e_f / e0 if e0 > 0 else 0.0,
    )


def cue_strike(
    radius: float, mu: float, g: float, speed: float, height: float, gamma: float = SOLID_SPHERE
) -> SkidToRoll:
    """A resting ball struck horizontally at `height` h above its centre, leaving with CoM speed v0 (docs/theory.md
    B1-B2).

    omega0 = Pi h / I = v0 h / (gamma R^2); u0 = v0 (1 - h / (gamma R)); for gamma = 2/5 the final speed is
    v_f = (5/7) v0 (1 + h / R).
    """
    spin = speed * height / (gamma * radius**2)
    return skid_to_roll(radius, mu, g, speed, spin, gamma)


# ---------------------------------------------------------------------------------------------------------
# The moving stick hitting a resting ball (docs/theory.md P5 seen from the stick; P6, the marble shot)
# ---------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class StickHitsBall:
    """A moving free stick hits a resting point ball at s, perpendicularly (docs/theory.md P5 in the stick's frame).

    Attributes
    ----------
    approach_speed : float
        Speed of the stick point s along +x before the impact, V - omega s (m/s) (P2).
    ball_velocity : float
        (1 + e) M_eff v_s / (m + M_eff) (m/s), along +x; zero if the point is not approaching (v_s <= 0).
    com_velocity, angular_velocity : float
        The stick's V (m/s) and omega_z (rad/s) after the impact.
    """

    approach_speed: float
    ball_velocity: float
    com_velocity: float
    angular_velocity: float


def stick_hits_ball(
    mass: float,
    inertia: float,
    com_velocity: float,
    angular_velocity: float,
    s: float,
    ball_mass: float,
    restitution: float = 1.0,
) -> StickHitsBall:
    """The stick (V, omega_z) hits a resting ball of mass m lying against the stick point s on its +x side.

    The impulse on the ball is J = (1 + e) m M_eff v_s / (m + M_eff) with M_eff = (1/M + s^2/I)^-1 (docs/theory.md
    P5, the relative speed being that of the stick point); the stick gets -J at s: V' = V - J/M,
    omega' = omega + J s / I.
    """
    v_s = com_velocity - angular_velocity * s
    if v_s <= 0:
        return StickHitsBall(v_s, 0.0, com_velocity, angular_velocity)
    m_eff = 1.0 / (1.0 / mass + s**2 / inertia)
    j = (1.0 + restitution) * ball_mass * m_eff * v_s / (ball_mass + m_eff)
    return StickHitsBall(v_s, j / ball_mass, com_velocity - j / mass, angular_velocity + j * s / inertia)
