"""Vertical tyre: linear spring and damper with lift-off, and rolling radii.

Table B.4: vertical stiffness 150 kN/m, damping 50 Ns/m (the ``.tir`` keys
``VERTICAL_STIFFNESS`` and ``VERTICAL_DAMPING``).
"""

from typing import TYPE_CHECKING

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

if TYPE_CHECKING:
    from ._model import MagicFormulaTyre

Scalar = Float[Array, ""]


def vertical_force(tyre: "MagicFormulaTyre", deflection: ArrayLike, deflection_rate: ArrayLike) -> Scalar:
    """Normal load [N] of a point-contact tyre, positive in compression.

    ``Fz = max(kz * rho + cz * rho_dot, 0)``: the tyre pushes, never pulls, so it lifts off
    as soon as spring plus damper would pull. The expression is continuous in both
    arguments (no jump at touch-down); a slightly negative deflection approached fast can
    give a small push (at most ``cz * rho_dot - kz * |rho|``), which is the price of
    continuity.

    Args:
        tyre: supplies ``vertical_stiffness`` kz [N/m] and ``vertical_damping`` cz [Ns/m].
        deflection: rho = unloaded radius - distance from wheel centre to road [m]
            (positive in contact).
        deflection_rate: d(rho)/dt [m/s].
    """
    rho = jnp.asarray(deflection, dtype=jnp.float64)
    rho_dot = jnp.asarray(deflection_rate, dtype=jnp.float64)
    return jnp.maximum(tyre.vertical_stiffness * rho + tyre.vertical_damping * rho_dot, 0.0)


def loaded_radius(tyre: "MagicFormulaTyre", fz: ArrayLike) -> Scalar:
    """Static loaded radius ``R0 - max(Fz, 0)/kz`` [m] of the linear vertical tyre."""
    fz = jnp.maximum(jnp.asarray(fz, dtype=jnp.float64), 0.0)
    return tyre.unloaded_radius - fz / tyre.vertical_stiffness


def effective_rolling_radius(tyre: "MagicFormulaTyre", fz: ArrayLike) -> Scalar:
    """MF 5.2 effective rolling radius ``Re`` [m] (forward speed / wheel spin rate).

    ``Re = R0 - rho_Fz0 * (DREFF * atan(BREFF * rho_d) + FREFF * rho_d)`` with
    ``rho_Fz0 = FNOMIN / kz`` and ``rho_d = rho / rho_Fz0``, ``rho = max(Fz, 0) / kz`` the
    static deflection. With BREFF = DREFF = FREFF = 0 it is the unloaded radius.
    """
    fz = jnp.maximum(jnp.asarray(fz, dtype=jnp.float64), 0.0)
    rho_fz0 = tyre.fnomin / tyre.vertical_stiffness
    rho_d = fz / tyre.fnomin
    return tyre.unloaded_radius - rho_fz0 * (tyre.dreff * jnp.arctan(tyre.breff * rho_d) + tyre.freff * rho_d)
