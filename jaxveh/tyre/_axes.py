"""Mapping between the tyre's ISO-W axes and the vehicle's axes.

The vehicle frame of jaxveh (Appendix B data, ``hard_points_vehicle_frame``) is ISO 8855:
x forward, y left, z up. The ISO-W (TYDEX W) tyre axes at the contact point are the same
directions rotated about z by the wheel's heading angle ``delta`` (steer plus toe, measured
from vehicle x towards vehicle y, i.e. positive to the left). No axis flips are needed:
only that yaw rotation, and the convention for camber:

- ISO-W inclination ``gamma`` is a right-handed rotation of the wheel plane about x: it is
  positive when the wheel top leans towards -y (right), and camber thrust pushes towards
  the lean (PVY3 < 0 in MF 5.2 files). So for a *left* wheel ``gamma = -camber`` and for a
  *right* wheel ``gamma = +camber`` (camber positive with the top leaning outboard, as in
  Appendix B).
- The normal load MF-Tyre uses is positive in compression; on the vehicle the road pushes
  up (+z) with that force.
"""

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._trig import sin_cos
from ..params import require
from ._base import TyreForces

Scalar = Float[Array, ""]


_SIDE_MESSAGE = "side must be +1 (left wheel) or -1 (right wheel)"


def inclination_angle(camber: ArrayLike, side: ArrayLike) -> Scalar:
    """ISO-W inclination [rad] from camber [rad] (top outboard positive); ``side`` = +1 left, -1 right.

    Any other ``side`` raises ``ParameterError`` (traced: ``eqx.error_if``).
    """
    side = jnp.asarray(side, dtype=jnp.float64)
    side = require(side, jnp.abs(side) != 1.0, _SIDE_MESSAGE)
    return -jnp.asarray(camber, dtype=jnp.float64) * side


def velocity_to_wheel(velocity: Float[Array, "3"], heading: ArrayLike) -> tuple[Scalar, Scalar]:
    """Road-plane velocity components ``(vx_w, vy_w)`` [m/s] along and across the wheel heading.

    Args:
        velocity: velocity of the contact point in vehicle axes (x fwd, y left, z up) [m/s].
        heading: wheel heading angle delta relative to vehicle x, positive left [rad].
    """
    s, c = sin_cos(heading)
    return c * velocity[0] + s * velocity[1], -s * velocity[0] + c * velocity[1]


def slip_velocities(
    velocity: Float[Array, "3"], heading: ArrayLike, omega: ArrayLike, rolling_radius: ArrayLike
) -> tuple[Scalar, Scalar, Scalar]:
    """``(vx_w, vsx, vsy)`` [m/s]: wheel-heading speed and ISO-W slip velocities.

    ``vsx = vx_w - omega * Re`` (omega: spin rate about the wheel axle, positive rolling
    forward [rad/s]; Re: effective rolling radius [m]); ``vsy = vy_w``.
    """
    vx_w, vy_w = velocity_to_wheel(velocity, heading)
    return vx_w, vx_w - omega * rolling_radius, vy_w


def forces_to_vehicle(
    forces: TyreForces, fz: ArrayLike, heading: ArrayLike
) -> tuple[Float[Array, "3"], Float[Array, "3"]]:
    """Force [N] and moment [Nm] of the road on the tyre, at the contact point, vehicle axes.

    Args:
        forces: ISO-W forces and moments from :func:`tyre_forces`.
        fz: normal load [N] (compression positive); the vertical component is
            ``max(fz, 0)`` upwards.
        heading: wheel heading delta [rad], positive left.
    """
    s, c = sin_cos(heading)
    fz_up = jnp.maximum(jnp.asarray(fz, dtype=jnp.float64), 0.0)
    force = jnp.stack([c * forces.fx - s * forces.fy, s * forces.fx + c * forces.fy, fz_up])
    moment = jnp.stack([c * forces.mx - s * forces.my, s * forces.mx + c * forces.my, forces.mz])
    return force, moment
