"""Suspension rates from the kinematics: installation ratios of the push-rod spring and the
rocker, wheel rates, ride rates and frequencies, roll stiffness per axle and the roll
stiffness distribution λ, and spring / anti-roll-bar rates that reach chosen targets.

The installation ratios are exact derivatives (``jax.jvp``) of the push-rod chain of
:mod:`._pushrod` driven by the quarter car's kinematics (:mod:`._corner`) with respect to
the wheel-centre vertical travel. With ``dl_s/dz`` (spring) and ``dθ/dz`` (rocker) at a
travel and the spring's static force ``F_s`` (N, compression; the preload carrying the
car), an axle of track ``t`` has (small motions):

    wheel rate      k_w = k_s (dl_s/dz)^2 - F_s d²l_s/dz²                     (N/m)
    ride rate       k_r = k_w k_t / (k_w + k_t)     (tyre vertical stiffness k_t in series)
    ride frequency  f = sqrt(k_r / m_c) / 2π        (m_c the sprung mass on the corner)
    roll stiffness  K = k_w t^2 / 2 + k_arb (dθ/dz)^2 t^2                     (N m/rad)

the anti-roll bar being a torsion spring ``k_arb`` (N m/rad) between the left and right
rockers: heave does not twist it, roll twists it by ``(dθ/dz) t φ``. The second term of the
wheel rate is the linkage's geometric stiffness: a rising-rate push-rod linkage
(``d²l_s/dz² < 0``) makes a preloaded spring stiffer at the wheel (about +10 % on the
default car). Roll stiffness here is
the suspension's (rigid tyres), as ``k_F``, ``k_R`` of chapter 3 (Appendix A).
"""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._core import ParameterError, is_concrete
from ..multibody import marker_positions
from ..params import HARD_POINT_NAMES, load_vehicle_data
from ._corner import quarter_car, quarter_car_kinematics, quarter_car_wheel_centre, quarter_car_with_hard_points
from ._pushrod import point_d, rocker_angle, rocker_geometry, spring_length, wishbone_geometry

_AXLES = ("front", "rear")


class InstallationRatios(eqx.Module):
    """One corner's ratios at a wheel travel: ``spring`` = dl_s/dz (m/m, negative when the
    spring shortens in bump), ``spring_curvature`` = d²l_s/dz² (1/m), ``rocker`` = dθ/dz
    (rad/m), and there the spring length l_s (m) and the rocker angle θ (rad, 0 at design)."""

    spring: Float[Array, ""]
    spring_curvature: Float[Array, ""]
    rocker: Float[Array, ""]
    spring_length: Float[Array, ""]
    rocker_angle: Float[Array, ""]


def _axle(axle: str) -> str:
    if axle not in _AXLES:
        raise ParameterError(f"axle = {axle!r} is not allowed: choose 'front' or 'rear'")
    return axle


def installation_ratios(axle: str = "front", data=None, bump=0.0) -> InstallationRatios:
    """Installation ratios of the left corner of ``axle`` at wheel-centre travel ``bump``
    (m, positive up relative to the chassis), zero rack. One compilation serves both axles
    (their quarter cars have one structure; the axle's hard points and wheel centre are
    data)."""
    data = load_vehicle_data() if data is None else data
    # the structure from the shipped data, the (possibly traced) hard points as leaves
    system, params = quarter_car(None, _axle(axle))
    hp = (data.hard_points_front if axle == "front" else data.hard_points_rear).points
    return _installation_ratios(system, params, hp, quarter_car_wheel_centre(data, axle),
                                jnp.asarray(bump, jnp.float64))


@eqx.filter_jit
def _installation_ratios(system, params, hp, wheel_centre, bump) -> InstallationRatios:
    params = quarter_car_with_hard_points(system, params, hp, wheel_centre)
    xa, xb, xc, xd, xp, xq, xr, xs, xt = (hp[HARD_POINT_NAMES.index(n)] for n in "ABCDPQRST")
    wishbone = wishbone_geometry(xa, xb, xc, xd)
    rocker = rocker_geometry(xp, xq, xr, xs, xd)
    c_index = system.point_index("C")

    def chain(z):
        q, _ = quarter_car_kinematics(system, params, z, 0.0, wheel_centre=wheel_centre, throw=False)
        x_c = marker_positions(system, params, q, jnp.zeros(1))[c_index]
        theta = rocker_angle(rocker, point_d(xa, xb, x_c, wishbone))
        return spring_length(rocker, xt, theta), theta

    def first(z):
        return jax.jvp(chain, (z,), (jnp.ones_like(z),))

    ((length, theta), (d_length, d_theta)), (_, (dd_length, _)) = jax.jvp(first, (bump,), (jnp.ones_like(bump),))
    return InstallationRatios(spring=d_length, spring_curvature=dd_length, rocker=d_theta, spring_length=length,
                              rocker_angle=theta)


class AxleRates(eqx.Module):
    """Rates of one axle (per corner unless said): ``wheel_rate`` and ``ride_rate`` (N/m),
    ``ride_frequency`` (Hz), ``roll_stiffness`` (N m/rad, the axle) and its parts from the
    springs and the anti-roll bar."""

    wheel_rate: Float[Array, ""]
    ride_rate: Float[Array, ""]
    ride_frequency: Float[Array, ""]
    roll_stiffness: Float[Array, ""]
    roll_stiffness_springs: Float[Array, ""]
    roll_stiffness_arb: Float[Array, ""]

    @property
    def roll_stiffness_nm_per_deg(self):
        return self.roll_stiffness * math.pi / 180.0


def axle_rates(ratios: InstallationRatios, spring_rate, arb_rate, track, tyre_rate, corner_sprung_mass,
               spring_preload=0.0) -> AxleRates:
    """The module's formulas: spring rate (N/m), anti-roll-bar rate (N m/rad), track (m),
    tyre vertical stiffness (N/m), sprung mass on one corner (kg), static spring force
    (N, compression)."""
    wheel = spring_rate * ratios.spring**2 - spring_preload * ratios.spring_curvature
    ride = wheel * tyre_rate / (wheel + tyre_rate)
    springs = wheel * track**2 / 2.0
    arb = arb_rate * (ratios.rocker * track) ** 2
    return AxleRates(
        wheel_rate=wheel,
        ride_rate=ride,
        ride_frequency=jnp.sqrt(ride / corner_sprung_mass) / (2.0 * math.pi),
        roll_stiffness=springs + arb,
        roll_stiffness_springs=springs,
        roll_stiffness_arb=arb,
    )


def roll_stiffness_distribution(front: AxleRates, rear: AxleRates) -> Float[Array, ""]:
    """λ = K_front / (K_front + K_rear)."""
    return front.roll_stiffness / (front.roll_stiffness + rear.roll_stiffness)


def corner_sprung_masses(data=None) -> tuple[Float[Array, ""], Float[Array, ""]]:
    """Sprung mass on one front and one rear corner (kg): ``m_s b / 2 l`` and ``m_s a / 2 l``."""
    data = load_vehicle_data() if data is None else data
    wheelbase = data.a + data.b
    return data.sprung.mass * data.b / (2.0 * wheelbase), data.sprung.mass * data.a / (2.0 * wheelbase)


def design_rates(ratios: InstallationRatios, ride_frequency, roll_stiffness, track, tyre_rate, corner_sprung_mass,
                 spring_preload=0.0):
    """``(spring_rate N/m, arb_rate N m/rad)`` giving one axle the ride frequency (Hz) and the
    roll stiffness (N m/rad) with the static spring force ``spring_preload`` (N): the spring
    from the ride rate, the bar for the rest of the roll stiffness. Raises ``ParameterError``
    when the springs alone are stiffer in roll than the target (the bar would need a
    negative rate) or the ride rate needs an infinite wheel rate."""
    ride = corner_sprung_mass * (2.0 * math.pi * ride_frequency) ** 2
    if is_concrete(ride) and float(ride) >= float(tyre_rate):
        raise ParameterError(
            f"ride_frequency = {float(ride_frequency):.3g} Hz needs a ride rate of {float(ride):.4g} N/m, "
            f"not below the tyre's {float(tyre_rate):.4g} N/m: choose a lower frequency"
        )
    wheel = ride * tyre_rate / (tyre_rate - ride)
    springs = wheel * track**2 / 2.0
    if is_concrete(springs) and float(springs) > float(roll_stiffness):
        raise ParameterError(
            f"roll_stiffness = {float(roll_stiffness) * math.pi / 180:.4g} N m/deg is below the springs' own "
            f"{float(springs) * math.pi / 180:.4g} N m/deg at {float(ride_frequency):.3g} Hz: allowed only with a "
            "negative anti-roll-bar rate; lower the ride frequency or raise the roll stiffness"
        )
    spring = (wheel + spring_preload * ratios.spring_curvature) / ratios.spring**2
    return spring, (roll_stiffness - springs) / (ratios.rocker * track) ** 2
