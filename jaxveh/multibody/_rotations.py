"""Rotation matrices, skew operator and angular-velocity maps (thesis eqs. 5.2-5.9).

A rotation sequence is a string of three axis letters applied in order: ``"zyx"`` is the
yaw-pitch-roll (Tait-Bryan) sequence of eq. (5.5), ``A = Rz(psi) Ry(theta) Rx(phi)``; ``"zxy"``
is the toe-camber-spin sequence of the uprights and wheels (section 6.1.2). The three angles
are stored in the order the rotations are applied (for ``"zyx"``: yaw, pitch, roll), which is
the reverse of the thesis's ``[phi, theta, psi]`` listing of eq. (5.1).
"""

import jax.numpy as jnp
from jaxtyping import Array, Float

from .._trig import sin_cos

SEQUENCES = ("zyx", "zxy", "xyz", "xzy", "yxz", "yzx")
_AXIS = {"x": 0, "y": 1, "z": 2}


def skew(a: Float[Array, "3"]) -> Float[Array, "3 3"]:
    """Skew-symmetric matrix ``ã`` with ``ã b = a x b``."""
    z = jnp.zeros((), a.dtype)
    return jnp.stack(
        [jnp.stack([z, -a[2], a[1]]), jnp.stack([a[2], z, -a[0]]), jnp.stack([-a[1], a[0], z])]
    )


def elementary(axis: int, angle: Float[Array, ""]) -> Float[Array, "3 3"]:
    """Rotation by ``angle`` (rad) about coordinate axis ``axis`` (0 = x, 1 = y, 2 = z)."""
    s, c = sin_cos(angle)
    o, z = jnp.ones_like(c), jnp.zeros_like(c)
    if axis == 0:
        rows = [[o, z, z], [z, c, -s], [z, s, c]]
    elif axis == 1:
        rows = [[c, z, s], [z, o, z], [-s, z, c]]
    else:
        rows = [[c, -s, z], [s, c, z], [z, z, o]]
    return jnp.stack([jnp.stack(r) for r in rows])


def rotation_matrix(sequence: str, angles: Float[Array, "3"]) -> Float[Array, "3 3"]:
    """Body-to-global rotation ``A = R_a(angles[0]) R_b(angles[1]) R_c(angles[2])`` (eq. 5.5)."""
    a, b, c = (_AXIS[k] for k in sequence)
    return elementary(a, angles[0]) @ elementary(b, angles[1]) @ elementary(c, angles[2])


def angular_velocity_matrix(sequence: str, angles: Float[Array, "3"]) -> Float[Array, "3 3"]:
    """``Gr`` with body-frame angular velocity ``omega = Gr @ angles_dot`` (eq. 5.9 for ``"zyx"``).

    Singular when the middle angle is +-pi/2 (gimbal lock), as the thesis notes.
    """
    a, b, c = (_AXIS[k] for k in sequence)
    eye = jnp.eye(3, dtype=angles.dtype)
    r2t, r3t = elementary(b, angles[1]).T, elementary(c, angles[2]).T
    return jnp.stack([r3t @ r2t @ eye[a], r3t @ eye[b], eye[c]], axis=1)


def axis_angle(axis: Float[Array, "3"], angle: Float[Array, ""]) -> Float[Array, "3 3"]:
    """Rodrigues rotation by ``angle`` (rad) about the unit vector ``axis``."""
    k = skew(axis)
    s, c = sin_cos(angle)
    return jnp.eye(3, dtype=axis.dtype) + s * k + (1.0 - c) * (k @ k)
