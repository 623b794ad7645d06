"""Non-linear 4-DOF vehicle of section 3.3.1 (eqs. 3.17-3.28) with a torsional chassis.

State (array of 9, SI units): ``[v, r, pF, pR, phiF, phiR, X, Y, psi]`` — lateral velocity
(m/s) and yaw rate (rad/s) in the vehicle frame, front/rear roll rates (rad/s) and roll
angles (rad), position of the reference point in the ground frame (m) and yaw angle (rad).
Longitudinal speed ``u`` (m/s) is constant. The road-wheel steer angle δ (rad) is an input.

Equations of motion (3.26) are written as ``M dv/dt = f`` with M of eq. (3.31); the thesis's
typeset (3.26) prints ``v + ru - ar`` in the front roll equation where M (3.31) and the
derivation need ``v + ru + ar`` (lateral acceleration at the front axle); M is used.

A :class:`Variant` selects, as in Fig. 3.6, whether chassis compliance acts on the lateral
load transfer (eq. 3.5 instead of 3.4) and on the roll dynamics (two roll angles instead of
one: the rigid chassis is the projection φF = φR of the same equations).
"""

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from ..params import AnalyticVehicle
from ._load_transfer import load_transfer_flexible, load_transfer_rigid
from ._quantities import roll_moments, static_tyre_loads
from ._tyre import axle_force

STATE_NAMES = ("v", "r", "pF", "pR", "phiF", "phiR", "X", "Y", "psi")
N_STATES = len(STATE_NAMES)
V, R, PF, PR, PHIF, PHIR, X, Y, PSI = range(N_STATES)


class Variant(eqx.Module):
    """Which effects of chassis compliance the model includes (static flags)."""

    flexible_load_transfer: bool = eqx.field(static=True)
    flexible_roll: bool = eqx.field(static=True)


#: The four model variants of Fig. 3.6, by name.
VARIANTS = {
    "rigid": Variant(False, False),
    "flexible_load_transfer": Variant(True, False),
    "flexible_roll_steer": Variant(False, True),
    "flexible": Variant(True, True),
}
RIGID = VARIANTS["rigid"]
FLEXIBLE = VARIANTS["flexible"]


def get_variant(name: str) -> Variant:
    """Variant by name; raises ``ValueError`` naming the allowed names."""
    if name not in VARIANTS:
        raise ValueError(f"variant must be one of {sorted(VARIANTS)}, got {name!r}")
    return VARIANTS[name]


def mass_matrix(vehicle: AnalyticVehicle) -> Float[Array, "4 4"]:
    """Mass matrix M of eq. (3.31) on the velocities [v, r, pF, pR] (SI)."""
    mF, mR = roll_moments(vehicle)
    a, b = vehicle.a, vehicle.b
    zero = jnp.zeros_like(a)
    return jnp.stack(
        [
            jnp.stack([vehicle.m, zero, -mF, -mR]),
            jnp.stack([zero, vehicle.Jz, -a * mF, b * mR]),
            jnp.stack([-mF, -a * mF, vehicle.JrF, zero]),
            jnp.stack([-mR, b * mR, zero, vehicle.JrR]),
        ]
    )


def slip_angles(vehicle: AnalyticVehicle, state, speed, delta):
    """Axle slip angles αF, αR (rad), eq. (3.28), with roll steer (3.8)."""
    v, r = state[V], state[R]
    delta_f = delta + vehicle.epsF * state[PHIF]
    delta_r = vehicle.epsR * state[PHIR]
    return delta_f - (v + vehicle.a * r) / speed, delta_r - (v - vehicle.b * r) / speed


def axle_forces(vehicle: AnalyticVehicle, state, speed, delta, variant: Variant):
    """Front and rear axle lateral forces (N), eq. (3.27), load transfer at ay = r u."""
    alpha_f, alpha_r = slip_angles(vehicle, state, speed, delta)
    ay = state[R] * speed
    transfer = load_transfer_flexible if variant.flexible_load_transfer else load_transfer_rigid
    dfz_f, dfz_r = transfer(vehicle, ay)
    fz_f, fz_r = static_tyre_loads(vehicle)
    tyre = vehicle.tyre
    return (
        axle_force(tyre, alpha_f, fz_f, dfz_f, tyre.scale_front),
        axle_force(tyre, alpha_r, fz_r, dfz_r, tyre.scale_rear),
    )


def generalised_forces(vehicle: AnalyticVehicle, state, speed, delta, variant: Variant) -> Float[Array, "4"]:
    """Right-hand side f of ``M dv/dt = f`` (N, Nm), eq. (3.26)."""
    fy_f, fy_r = axle_forces(vehicle, state, speed, delta, variant)
    mF, mR = roll_moments(vehicle)
    r, p_f, p_r, phi_f, phi_r = state[R], state[PF], state[PR], state[PHIF], state[PHIR]
    twist_moment = vehicle.kC * (phi_f - phi_r) + vehicle.cC * (p_f - p_r)
    return jnp.stack(
        [
            fy_f + fy_r - vehicle.m * r * speed,
            vehicle.a * fy_f - vehicle.b * fy_r,
            mF * r * speed - vehicle.kF * phi_f - vehicle.cF * p_f - twist_moment,
            mR * r * speed - vehicle.kR * phi_r - vehicle.cR * p_r + twist_moment,
        ]
    )


#: Velocity map of the rigid chassis: [v, r, pF, pR] = RIGID_ROLL_MAP @ [v, r, p].
RIGID_ROLL_MAP = jnp.asarray([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])


def accelerations(mass: Float[Array, "4 4"], forces: Float[Array, "4"], variant: Variant) -> Float[Array, "4"]:
    """dv/dt from ``M dv/dt = f``; for a rigid chassis, the projection on φF = φR."""
    if variant.flexible_roll:
        return jnp.linalg.solve(mass, forces[:, None])[:, 0]
    t = RIGID_ROLL_MAP
    return t @ jnp.linalg.solve(t.T @ mass @ t, (t.T @ forces)[:, None])[:, 0]


def vector_field(vehicle: AnalyticVehicle, state, speed, delta, variant: Variant) -> Float[Array, "9"]:
    """Time derivative of the state (eqs. 3.25, 3.26) at constant speed ``u`` (m/s)."""
    dv = accelerations(mass_matrix(vehicle), generalised_forces(vehicle, state, speed, delta, variant), variant)
    v, psi = state[V], state[PSI]
    kinematics = jnp.stack(
        [
            state[PF],
            state[PR],
            speed * jnp.cos(psi) - v * jnp.sin(psi),
            speed * jnp.sin(psi) + v * jnp.cos(psi),
            state[R],
        ]
    )
    return jnp.concatenate([dv, kinematics])


def lateral_acceleration(vehicle: AnalyticVehicle, state, speed, delta, variant: Variant) -> Float[Array, ""]:
    """Lateral acceleration of the reference point, dv/dt + r u (m/s^2)."""
    return vector_field(vehicle, state, speed, delta, variant)[V] + state[R] * speed
