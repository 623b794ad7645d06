"""Derived quantities of the chapter-3 vehicle (section 3.1) and the (λ, µ) parametrisation.

All lengths in m, masses in kg, stiffnesses in Nm/rad. The roll stiffness proportion is
λ = kF/(kF + kR) and the normalised chassis torsional stiffness µ = kC/(kF + kR).
"""

import equinox as eqx
from jaxtyping import Array, Float

from .._core import GRAVITY
from ..params import AnalyticVehicle, check
from ._checks import LAM, MU


def sprung_split(vehicle: AnalyticVehicle) -> tuple[Float[Array, ""], Float[Array, ""]]:
    """Front and rear parts of the sprung mass, msF = ms bs/l and msR = ms as/l (kg)."""
    l_s = vehicle.as_ + vehicle.bs
    return vehicle.ms * vehicle.bs / l_s, vehicle.ms * vehicle.as_ / l_s


def roll_arms(vehicle: AnalyticVehicle) -> tuple[Float[Array, ""], Float[Array, ""]]:
    """Heights of the front/rear sprung c.g. above their roll centres, dsF, dsR (m)."""
    return vehicle.hsF - vehicle.zF, vehicle.hsR - vehicle.zR


def roll_moments(vehicle: AnalyticVehicle) -> tuple[Float[Array, ""], Float[Array, ""]]:
    """Front and rear roll moment arms times mass, msF dsF and msR dsR (kg m)."""
    msF, msR = sprung_split(vehicle)
    dsF, dsR = roll_arms(vehicle)
    return msF * dsF, msR * dsR


def roll_moment_proportion(vehicle: AnalyticVehicle) -> Float[Array, ""]:
    """ζ = msF dsF / (msF dsF + msR dsR), the front share of the roll moment (section 3.1.2)."""
    mF, mR = roll_moments(vehicle)
    return mF / (mF + mR)


def total_roll_stiffness(vehicle: AnalyticVehicle) -> Float[Array, ""]:
    """kF + kR (Nm/rad)."""
    return vehicle.kF + vehicle.kR


def roll_stiffness_proportion(vehicle: AnalyticVehicle) -> Float[Array, ""]:
    """λ = kF / (kF + kR)."""
    return vehicle.kF / total_roll_stiffness(vehicle)


def normalised_torsional_stiffness(vehicle: AnalyticVehicle) -> Float[Array, ""]:
    """µ = kC / (kF + kR)."""
    return vehicle.kC / total_roll_stiffness(vehicle)


def with_distribution(vehicle: AnalyticVehicle, lam=None, mu=None) -> AnalyticVehicle:
    """Vehicle with roll stiffness proportion ``lam`` and/or normalised stiffness ``mu``.

    The total roll stiffness kF + kR is kept; kF = λ K, kR = (1 - λ) K, kC = µ K.
    ``None`` keeps the vehicle's own value. Differentiable in ``lam`` and ``mu``.
    λ must lie in [0, 1] and µ be > 0 (``ParameterError``; traced: ``eqx.error_if``).
    """
    k_total = total_roll_stiffness(vehicle)
    if lam is not None:
        lam = check("lam", lam, LAM)
        vehicle = eqx.tree_at(lambda v: (v.kF, v.kR), vehicle, (lam * k_total, (1.0 - lam) * k_total))
    if mu is not None:
        mu = check("mu", mu, MU)
        vehicle = eqx.tree_at(lambda v: v.kC, vehicle, mu * k_total)
    return vehicle


def roll_gradient(vehicle: AnalyticVehicle) -> Float[Array, ""]:
    """Rigid-chassis roll gradient φy = (msF dsF + msR dsR)/(kF + kR) (rad per m/s^2), eq. (3.9)."""
    mF, mR = roll_moments(vehicle)
    return (mF + mR) / total_roll_stiffness(vehicle)


def static_tyre_loads(vehicle: AnalyticVehicle) -> tuple[Float[Array, ""], Float[Array, ""]]:
    """Static vertical load of one front and one rear tyre (N)."""
    weight = vehicle.m * GRAVITY
    return weight * vehicle.b / (2.0 * vehicle.l), weight * vehicle.a / (2.0 * vehicle.l)
