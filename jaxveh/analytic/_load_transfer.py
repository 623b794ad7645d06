"""Lateral load transfer distribution, rigid (3.2-3.4) and with a torsional chassis (3.5-3.7).

Per-wheel load transfers ΔFz (N) are the load gained by the outer wheel and lost by the
inner one; ay is the lateral acceleration (m/s^2). χ = ΔFzF/ΔFz with ΔFz = m hG ay / t.
"""

import jax
from jaxtyping import Array, Float

from ..params import AnalyticVehicle
from ._quantities import (
    normalised_torsional_stiffness,
    roll_moment_proportion,
    roll_moments,
    roll_stiffness_proportion,
    sprung_split,
    with_distribution,
)


def load_transfer_rigid(vehicle: AnalyticVehicle, ay) -> tuple[Float[Array, ""], Float[Array, ""]]:
    """Front and rear per-wheel lateral load transfer (N) of a rigid chassis, eq. (3.4)."""
    msF, msR = sprung_split(vehicle)
    mF, mR = roll_moments(vehicle)
    lam = roll_stiffness_proportion(vehicle)
    sprung = mF + mR
    front = lam * sprung + vehicle.zF * msF + vehicle.huF * vehicle.muF
    rear = (1.0 - lam) * sprung + vehicle.zR * msR + vehicle.huR * vehicle.muR
    return front * ay / vehicle.t, rear * ay / vehicle.t


def load_transfer_flexible(vehicle: AnalyticVehicle, ay) -> tuple[Float[Array, ""], Float[Array, ""]]:
    """Front and rear per-wheel lateral load transfer (N) with chassis torsional stiffness, eq. (3.5).

    The chassis spring kC acts in series with the opposite axle's roll stiffness.
    """
    msF, msR = sprung_split(vehicle)
    mF, mR = roll_moments(vehicle)
    kF, kR, kC = vehicle.kF, vehicle.kR, vehicle.kC
    kR_series = kR * kC / (kR + kC)
    kF_series = kF * kC / (kF + kC)
    front = kF * mF / (kF + kR_series) + kF_series * mR / (kF_series + kR)
    rear = kR_series * mF / (kF + kR_series) + kR * mR / (kF_series + kR)
    front = front + vehicle.zF * msF + vehicle.huF * vehicle.muF
    rear = rear + vehicle.zR * msR + vehicle.huR * vehicle.muR
    return front * ay / vehicle.t, rear * ay / vehicle.t


def chi_rigid(vehicle: AnalyticVehicle) -> Float[Array, ""]:
    """Lateral load transfer proportion χ0 of a rigid chassis, eq. (3.3)."""
    front, _ = load_transfer_rigid(vehicle, 1.0)
    return front / _total_transfer_per_ay(vehicle)


def chi_from_transfer(vehicle: AnalyticVehicle) -> Float[Array, ""]:
    """χ = ΔFzF/ΔFz evaluated from the load transfers of eq. (3.5)."""
    front, _ = load_transfer_flexible(vehicle, 1.0)
    return front / _total_transfer_per_ay(vehicle)


def chi(vehicle: AnalyticVehicle) -> Float[Array, ""]:
    """Lateral load transfer proportion χ with a torsional chassis, closed form eq. (3.6)."""
    msF, msR = sprung_split(vehicle)
    mF, mR = roll_moments(vehicle)
    lam = roll_stiffness_proportion(vehicle)
    mu = normalised_torsional_stiffness(vehicle)
    denom = lam**2 - lam - mu
    mh = vehicle.m * vehicle.hG
    return (
        (lam**2 - (mu + 1.0) * lam) / denom * mF / mh
        - mu * lam / denom * mR / mh
        + vehicle.zF * msF / mh
        + vehicle.huF * vehicle.muF / mh
    )


def chi_sensitivity(vehicle: AnalyticVehicle, rigid: bool = False) -> Float[Array, ""]:
    """χλ = ∂χ/∂λ at the vehicle's λ, by ``jax.grad`` (total roll stiffness and µ held)."""
    chi_fn = chi_rigid if rigid else chi

    def chi_of_lam(lam):
        return chi_fn(with_distribution(vehicle, lam=lam))

    return jax.grad(chi_of_lam)(roll_stiffness_proportion(vehicle))


def zeta(vehicle: AnalyticVehicle) -> Float[Array, ""]:
    """ζ, the λ at which chassis stiffness does not change χ, eq. (3.7)."""
    return roll_moment_proportion(vehicle)


def _total_transfer_per_ay(vehicle: AnalyticVehicle) -> Float[Array, ""]:
    return vehicle.m * vehicle.hG / vehicle.t


def load_transfer_summary(vehicle: AnalyticVehicle) -> dict[str, Float[Array, ""]]:
    """χ, χ0, ζ, ∂χ/∂λ (flexible and rigid), λ and µ of a vehicle, as a dict of scalars."""
    return {
        "chi": chi(vehicle),
        "chi_rigid": chi_rigid(vehicle),
        "zeta": zeta(vehicle),
        "dchi_dlam": chi_sensitivity(vehicle),
        "dchi_dlam_rigid": chi_sensitivity(vehicle, rigid=True),
        "lam": roll_stiffness_proportion(vehicle),
        "mu": normalised_torsional_stiffness(vehicle),
    }


