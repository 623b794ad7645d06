"""Linear 4-DOF model at trim (eqs. 3.29-3.37): explicit matrices and autodiff linearisation.

State ``x = [Y, psi, phiF, phiR, v, r, pF, pR]`` (flexible chassis) or ``[Y, psi, phi, v, r,
p]`` (rigid chassis, φF = φR), input the steering-wheel angle δstw (rad); δ = δstw/kstw.
Units SI. Trim: straight running at speed ``u`` (m/s), zero lateral acceleration.
"""

import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from ..params import AnalyticVehicle
from ._checks import check_speed
from ._model import (
    FLEXIBLE,
    N_STATES,
    PF,
    PHIF,
    PHIR,
    PR,
    PSI,
    RIGID,
    RIGID_ROLL_MAP,
    R,
    V,
    Y,
    mass_matrix,
    vector_field,
)
from ._quantities import roll_moments
from ._roll_steer import axle_cornering_stiffness

LINEAR_STATE_NAMES = ("Y", "psi", "phiF", "phiR", "v", "r", "pF", "pR")
RIGID_STATE_NAMES = ("Y", "psi", "phi", "v", "r", "p")
#: Position of each linear state in the non-linear state vector of :mod:`._model`.
_TO_NONLINEAR = (Y, PSI, PHIF, PHIR, V, R, PF, PR)


def second_order_matrices(vehicle: AnalyticVehicle, speed):
    """M, T, K, D, Y of eqs. (3.31)-(3.35) for the flexible chassis (SI units), speed u > 0 (m/s)."""
    speed = check_speed(speed)
    mF, mR = roll_moments(vehicle)
    cF, cR = axle_cornering_stiffness(vehicle)
    a, b, u = vehicle.a, vehicle.b, speed
    kF, kR, kC, cC = vehicle.kF, vehicle.kR, vehicle.kC, vehicle.cC
    z = jnp.zeros_like(a)
    t_mat = jnp.stack([jnp.stack([z, u + z, z, z])] + [jnp.stack([z, z, z, z])] * 3)
    k_mat = jnp.stack(
        [
            jnp.stack([z, z, vehicle.epsF * cF, vehicle.epsR * cR]),
            jnp.stack([z, z, vehicle.epsF * cF * a, -vehicle.epsR * cR * b]),
            jnp.stack([z, z, -kC - kF, kC]),
            jnp.stack([z, z, kC, -kC - kR]),
        ]
    )
    d_mat = jnp.stack(
        [
            jnp.stack([-(cF + cR) / u, -vehicle.m * u - (cF * a - cR * b) / u, z, z]),
            jnp.stack([-(cF * a - cR * b) / u, -(cF * a**2 + cR * b**2) / u, z, z]),
            jnp.stack([z, mF * u, -cC - vehicle.cF, cC]),
            jnp.stack([z, mR * u, cC, -cC - vehicle.cR]),
        ]
    )
    y_vec = jnp.stack([cF, a * cF, z, z]) / vehicle.k_stw
    return mass_matrix(vehicle), t_mat, k_mat, d_mat, y_vec


def _first_order(m, t, k, d, y):
    n = m.shape[0]
    eye, zero = jnp.eye(n), jnp.zeros((n, n))
    lhs = jnp.block([[eye, zero], [zero, m]])
    a = jnp.linalg.solve(lhs, jnp.block([[t, eye], [k, d]]))
    b = jnp.linalg.solve(lhs, jnp.concatenate([jnp.zeros(n), y]))
    return a, b[:, None]


def state_space(vehicle: AnalyticVehicle, speed, rigid: bool = False):
    """Continuous-time (A, B) of eq. (3.37) from the thesis's explicit matrices.

    ``rigid=True`` returns the 6-state rigid-chassis model (projection φF = φR).
    B is per unit steering-wheel angle (rad).
    """
    m, t, k, d, y = second_order_matrices(vehicle, speed)
    if rigid:
        p = RIGID_ROLL_MAP
        m, t, k, d, y = p.T @ m @ p, jnp.linalg.pinv(p) @ t @ p, p.T @ k @ p, p.T @ d @ p, p.T @ y
    return _first_order(m, t, k, d, y)


def linearise(vehicle: AnalyticVehicle, speed, rigid: bool = False):
    """(A, B) by ``jax.jacfwd`` of the non-linear model (3.25-3.28) at straight-running trim.

    Same states and input as :func:`state_space`; the two must agree.
    """
    speed = check_speed(speed)
    variant = RIGID if rigid else FLEXIBLE
    index = jnp.asarray(_TO_NONLINEAR)

    def f(x, delta_stw):
        state = jnp.zeros(N_STATES).at[index].set(x)
        return vector_field(vehicle, state, speed, delta_stw / vehicle.k_stw, variant)[index]

    x0 = jnp.zeros(len(_TO_NONLINEAR))
    a, b = jax.jacfwd(f, argnums=(0, 1))(x0, jnp.asarray(0.0))
    if rigid:
        e = _rigid_embedding()
        pinv = jnp.linalg.pinv(e)
        return pinv @ a @ e, (pinv @ b)[:, None]
    return a, b[:, None]


def _rigid_embedding() -> Float[Array, "8 6"]:
    """x_flexible = E x_rigid (φF = φR = φ, pF = pR = p)."""
    p = RIGID_ROLL_MAP
    z = jnp.zeros((4, 3))
    return jnp.block([[p, z], [z, p]])


def dynamic_subsystem(a: Float[Array, "n n"], b: Float[Array, "n 1"]):
    """Drop the lateral position Y and yaw angle ψ (pure integrators) from (A, B)."""
    return a[2:, 2:], b[2:]
