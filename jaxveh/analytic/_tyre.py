"""Simplified Magic Formula of eq. (3.27): lateral force of one tyre, no camber, no combined slip.

    Fy = D sin(C atan(B α - E (B α - atan(B α))))
    D  = µ(Fz) Fz,  µ(Fz) = µ0 (1 + dµ (Fz - Fz0)/Fz0)
    BCD = Cα(Fz) = s k_α Fz0 sin(2 atan(Fz / (r Fz0)))

α is the slip angle (rad), Fz the tyre load (N), Fy positive when α is positive. ``s`` is the
axle's cornering stiffness scale. Coefficients are a documented choice (docs/assumptions.md).
"""

import jax.numpy as jnp
from jaxtyping import Array, Float

from ..params import AxleTyre

#: Loads below this (N) are treated as lift-off: the force fades to zero smoothly.
MIN_LOAD = 1.0


def cornering_stiffness(tyre: AxleTyre, fz, scale) -> Float[Array, ""]:
    """Cornering stiffness Cα = ∂Fy/∂α at α = 0 of one tyre (N/rad) at load ``fz`` (N)."""
    fz = jnp.maximum(fz, 0.0)
    return scale * tyre.k_alpha * tyre.fz0 * jnp.sin(2.0 * jnp.arctan(fz / (tyre.fz_peak_ratio * tyre.fz0)))


def lateral_force(tyre: AxleTyre, alpha, fz, scale) -> Float[Array, ""]:
    """Lateral force of one tyre (N) at slip angle ``alpha`` (rad) and load ``fz`` (N).

    For fz <= MIN_LOAD the load is clipped to MIN_LOAD and the force scaled by fz/MIN_LOAD
    (zero for fz <= 0), so the force is continuous and finite through lift-off.
    """
    fz_eff = jnp.maximum(fz, MIN_LOAD)
    mu = tyre.mu0 * (1.0 + tyre.dmu * (fz_eff - tyre.fz0) / tyre.fz0)
    d = mu * fz_eff
    c = tyre.shape
    b = cornering_stiffness(tyre, fz_eff, scale) / (c * d)
    e = tyre.curvature
    ba = b * alpha
    fy = d * jnp.sin(c * jnp.arctan(ba - e * (ba - jnp.arctan(ba))))
    lift_off = jnp.clip(fz / MIN_LOAD, 0.0, 1.0)
    return fy * lift_off


def axle_force(tyre: AxleTyre, alpha, fz_static, dfz, scale) -> Float[Array, ""]:
    """Axle lateral force (N), eq. (3.27): f(α, Fzs + dFz) + f(α, Fzs - dFz)."""
    return lateral_force(tyre, alpha, fz_static + dfz, scale) + lateral_force(tyre, alpha, fz_static - dfz, scale)
