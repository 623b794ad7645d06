"""The tyre concept: what a vehicle model needs from any tyre model."""

import abc
from typing import NamedTuple

import equinox as eqx
from jaxtyping import Array, ArrayLike, Float

Scalar = Float[Array, ""]


class TyreForces(NamedTuple):
    """Tyre forces [N] and moments [Nm] at the contact point, ISO-W axes."""

    fx: Scalar
    fy: Scalar
    mx: Scalar
    my: Scalar
    mz: Scalar


class AbstractTyre(eqx.Module):
    """A tyre model: steady-state forces from slips, relaxation lengths, vertical tyre.

    Conventions of every implementation: ISO-W axes and slips (see ``docs/tyre.md``), SI
    units, one operating point per call (``jax.vmap`` for batches).
    """

    @abc.abstractmethod
    def forces(self, fz: ArrayLike, kappa: ArrayLike, alpha: ArrayLike, gamma: ArrayLike, vx: ArrayLike) -> TyreForces:
        """Forces and moments at load ``fz`` [N], slips ``kappa`` [-], ``alpha`` [rad],
        inclination ``gamma`` [rad], wheel speed ``vx`` [m/s]."""

    @abc.abstractmethod
    def relaxation_lengths(self, fz: ArrayLike, gamma: ArrayLike) -> tuple[Scalar, Scalar]:
        """``(sigma_kappa, sigma_alpha)`` [m] at load ``fz`` and inclination ``gamma``."""

    @abc.abstractmethod
    def vertical_force(self, deflection: ArrayLike, deflection_rate: ArrayLike) -> Scalar:
        """Normal load [N] (compression positive, zero when lifted off)."""

    @abc.abstractmethod
    def effective_rolling_radius(self, fz: ArrayLike) -> Scalar:
        """Effective rolling radius [m] at load ``fz``."""
