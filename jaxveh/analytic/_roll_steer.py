"""Roll steer and understeer gradient, rigid (3.8-3.11) and flexible chassis (3.12-3.16).

Roll angles in rad, lateral acceleration ay in m/s^2, understeer gradients in rad/(m/s^2)
(multiply by ``RAD_PER_MS2_TO_DEG_PER_G`` for deg/g).
"""

import jax.numpy as jnp
from jaxtyping import Array, Float

from ..params import AnalyticVehicle
from ._quantities import (
    GRAVITY,
    normalised_torsional_stiffness,
    roll_gradient,
    roll_moment_proportion,
    roll_moments,
    roll_stiffness_proportion,
    static_tyre_loads,
)
from ._tyre import cornering_stiffness

#: Converts an understeer gradient from rad/(m/s^2) to deg/g.
RAD_PER_MS2_TO_DEG_PER_G = GRAVITY * 180.0 / jnp.pi


def axle_cornering_stiffness(vehicle: AnalyticVehicle) -> tuple[Float[Array, ""], Float[Array, ""]]:
    """Front and rear axle cornering stiffness CF, CR (N/rad) at the static loads."""
    fzF, fzR = static_tyre_loads(vehicle)
    tyre = vehicle.tyre
    return (
        2.0 * cornering_stiffness(tyre, fzF, tyre.scale_front),
        2.0 * cornering_stiffness(tyre, fzR, tyre.scale_rear),
    )


def roll_angles_flexible(vehicle: AnalyticVehicle, ay) -> tuple[Float[Array, ""], Float[Array, ""]]:
    """Steady-state front and rear roll angles φF, φR (rad) of a torsional chassis, eq. (3.13)."""
    mF, mR = roll_moments(vehicle)
    kF, kR, kC = vehicle.kF, vehicle.kR, vehicle.kC
    denom = kF * kR + kR * kC + kC * kF
    return (kC * (mF + mR) + kR * mF) / denom * ay, (kC * (mF + mR) + kF * mR) / denom * ay


def roll_angles_normalised(vehicle: AnalyticVehicle, ay) -> tuple[Float[Array, ""], Float[Array, ""]]:
    """φF, φR (rad) in the normalised form of eq. (3.14)."""
    lam = roll_stiffness_proportion(vehicle)
    mu = normalised_torsional_stiffness(vehicle)
    z = roll_moment_proportion(vehicle)
    phi = roll_gradient(vehicle) * ay
    denom = mu + lam - lam**2
    return (mu + (1.0 - lam) * z) / denom * phi, (mu + (1.0 - z) * lam) / denom * phi


def chassis_twist(vehicle: AnalyticVehicle, ay) -> Float[Array, ""]:
    """Chassis twist φC = φF - φR (rad), eq. (3.15).

    (3.15) is printed with (λ - ζ) in the numerator; the difference of the two lines of
    (3.14), which defines φC = φF - φR, gives (ζ - λ): a front-biased roll stiffness
    (λ > ζ) makes the front roll less than the rear. The consistent sign is used.
    """
    lam = roll_stiffness_proportion(vehicle)
    mu = normalised_torsional_stiffness(vehicle)
    z = roll_moment_proportion(vehicle)
    return (z - lam) / (mu + lam - lam**2) * roll_gradient(vehicle) * ay


def _tyre_term(vehicle: AnalyticVehicle) -> Float[Array, ""]:
    cF, cR = axle_cornering_stiffness(vehicle)
    return vehicle.m / vehicle.l * (vehicle.b / cF - vehicle.a / cR)


def understeer_gradient_rigid(vehicle: AnalyticVehicle) -> Float[Array, ""]:
    """Linear understeer gradient of a rigid chassis ku0 (rad per m/s^2), eq. (3.11)."""
    return _tyre_term(vehicle) - (vehicle.epsF - vehicle.epsR) * roll_gradient(vehicle)


def understeer_gradient(vehicle: AnalyticVehicle) -> Float[Array, ""]:
    """Linear understeer gradient with a torsional chassis ku (rad per m/s^2), eq. (3.16)."""
    lam = roll_stiffness_proportion(vehicle)
    mu = normalised_torsional_stiffness(vehicle)
    z = roll_moment_proportion(vehicle)
    denom = lam + mu - lam**2
    steer = (mu + (1.0 - lam) * z) / denom * vehicle.epsF - (mu + lam * (1.0 - z)) / denom * vehicle.epsR
    return _tyre_term(vehicle) - steer * roll_gradient(vehicle)


def understeer_summary(vehicle: AnalyticVehicle) -> dict[str, Float[Array, ""]]:
    """ku and ku0 in deg/g plus the roll gradient (deg/g) and twist gradient (deg/g)."""
    deg_per_g = RAD_PER_MS2_TO_DEG_PER_G
    return {
        "ku_deg_per_g": understeer_gradient(vehicle) * deg_per_g,
        "ku_rigid_deg_per_g": understeer_gradient_rigid(vehicle) * deg_per_g,
        "roll_gradient_deg_per_g": roll_gradient(vehicle) * deg_per_g,
        "twist_gradient_deg_per_g": chassis_twist(vehicle, 1.0) * deg_per_g,
    }
