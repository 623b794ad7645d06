"""Steady-state cornering (skid-pad, section 3.3.2) by root finding, with implicit gradients.

On a circle of radius R (m) at lateral acceleration ay (m/s^2): u = sqrt(ay R), r = u/R,
pF = pR = 0. Unknowns ``w = [v, delta, phiF, phiR]`` (m/s, rad, rad, rad) solve
``M dv/dt = f = 0``; for a rigid chassis the roll equations are summed and φF = φR is added.
Optimistix's Newton solver with implicit-function adjoint gives exact derivatives of the
solution with respect to any vehicle parameter or ay.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import optimistix as optx
from jaxtyping import Array, Float

from ..params import AnalyticVehicle, Range, check
from ._checks import LATERAL_ACCELERATION
from ._model import N_STATES, PF, PHIF, PHIR, PR, R, V, Variant, generalised_forces, vector_field
from ._quantities import roll_gradient
from ._roll_steer import understeer_gradient, understeer_gradient_rigid

#: [v, r, pF, pR, phiF, phiR] = E @ [v, r, p, phi] for the rigid chassis.
_RIGID_EMBEDDING = ((1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 1, 0), (0, 0, 0, 1), (0, 0, 0, 1))

#: Newton tolerances on the unknowns (m/s and rad): far below any plotted resolution.
NEWTON_RTOL = 1e-10
NEWTON_ATOL = 1e-12
NEWTON_MAX_STEPS = 64
#: Skid-pad circle radius (m).
RADIUS = Range(0.0, low_open=True, what="skid-pad circle radius, m")


def _check_inputs(ay, radius):
    return check("ay", ay, LATERAL_ACCELERATION), check("radius", radius, RADIUS)


class SteadyState(eqx.Module):
    """Skid-pad trim: speed (m/s), yaw rate (rad/s), lateral velocity (m/s), road-wheel
    steer angle (rad), dynamic steer angle δd = δ - l/R (rad), roll angles (rad),
    and whether Newton's method converged."""

    ay: Float[Array, ""]
    speed: Float[Array, ""]
    yaw_rate: Float[Array, ""]
    v: Float[Array, ""]
    delta: Float[Array, ""]
    delta_dynamic: Float[Array, ""]
    phi_front: Float[Array, ""]
    phi_rear: Float[Array, ""]
    converged: Array
    stable: Array


def _state(w, r):
    return jnp.zeros(N_STATES).at[jnp.asarray([V, R, PHIF, PHIR])].set(jnp.stack([w[0], r, w[2], w[3]]))


def _residual(w, args):
    vehicle, ay, radius, variant = args
    speed = jnp.sqrt(ay * radius)
    r = speed / radius
    f = generalised_forces(vehicle, _state(w, r), speed, w[1], variant)
    if variant.flexible_roll:
        return f
    return jnp.stack([f[0], f[1], f[2] + f[3], w[2] - w[3]])


def _initial_guess(vehicle: AnalyticVehicle, ay, radius, variant: Variant):
    """Linear-range guess: roll from the roll gradient, δ = l/R + ku ay."""
    ku = understeer_gradient(vehicle) if variant.flexible_roll else understeer_gradient_rigid(vehicle)
    phi = roll_gradient(vehicle) * ay
    return jnp.stack([0.0 * ay, (vehicle.a + vehicle.b) / radius + ku * ay, phi, phi])


def skidpad_steady_state(
    vehicle: AnalyticVehicle, ay, variant: Variant, radius=50.0, throw: bool = True
) -> SteadyState:
    """Steady state on a circle of ``radius`` (m) at lateral acceleration ``ay`` (m/s^2).

    With ``throw=True`` a failed Newton solve (e.g. ay above the vehicle's grip limit)
    raises an error; with ``throw=False`` the result's ``converged`` flag says so.
    ``ay`` and ``radius`` must be > 0 (``ParameterError``; traced: ``eqx.error_if``).
    """
    ay, radius = _check_inputs(ay, radius)
    return _steady_state(vehicle, ay, variant, radius, throw)


def _steady_state(vehicle: AnalyticVehicle, ay, variant: Variant, radius, throw: bool) -> SteadyState:
    solver = optx.Newton(rtol=NEWTON_RTOL, atol=NEWTON_ATOL)
    sol = optx.root_find(
        _residual,
        solver,
        _initial_guess(vehicle, ay, radius, variant),
        args=(vehicle, ay, radius, variant),
        max_steps=NEWTON_MAX_STEPS,
        throw=throw,
    )
    w = sol.value
    speed = jnp.sqrt(ay * radius)
    converged = (sol.result == optx.RESULTS.successful) & jnp.all(jnp.isfinite(w))
    return SteadyState(
        ay=ay,
        speed=speed,
        yaw_rate=speed / radius,
        v=w[0],
        delta=w[1],
        delta_dynamic=w[1] - (vehicle.a + vehicle.b) / radius,
        phi_front=w[2],
        phi_rear=w[3],
        converged=converged,
        stable=_is_stable(vehicle, w, speed, radius, variant),
    )


def _is_stable(vehicle: AnalyticVehicle, w, speed, radius, variant: Variant) -> Array:
    """Whether the trim is asymptotically stable at fixed steer (all eigenvalues Re < 0).

    Beyond an axle's peak slip angle the steady-state equations keep having solutions,
    but on an unstable branch: those are not reachable skid-pad states.
    """
    idx = jnp.asarray([V, R, PF, PR, PHIF, PHIR])
    base = _state(w, speed / radius)

    def f(x):
        return vector_field(vehicle, base.at[idx].set(x), speed, w[1], variant)[idx]

    jac = jax.jacfwd(f)(base[idx])
    if not variant.flexible_roll:
        # Restrict to φF = φR, pF = pR (the rigid projection leaves a neutral twist direction).
        e = jnp.asarray(_RIGID_EMBEDDING, dtype=jnp.float64)
        jac = jnp.linalg.pinv(e) @ jac @ e
    return jnp.all(jnp.real(jnp.linalg.eigvals(jac)) < 0.0)


def steering_sensitivity(vehicle: AnalyticVehicle, ay, variant: Variant, radius=50.0) -> Float[Array, ""]:
    """1/ku = d ay / d δd (m/s^2 per rad) along the skid-pad curve, by implicit differentiation.

    ``ay`` (m/s^2) and ``radius`` (m) must be > 0.
    """
    ay, radius = _check_inputs(ay, radius)
    d_delta = jax.grad(lambda a: _steady_state(vehicle, a, variant, radius, True).delta)(ay)
    return 1.0 / d_delta


def _sensitivity_at(vehicle: AnalyticVehicle, state: SteadyState, variant: Variant, radius) -> Float[Array, ""]:
    """d ay/d δ at a solved steady state by the implicit function theorem, dw/day = -J⁻¹ ∂res/∂ay."""
    w = jnp.stack([state.v, state.delta, state.phi_front, state.phi_rear])
    jac_w = jax.jacfwd(lambda x: _residual(x, (vehicle, state.ay, radius, variant)))(w)
    jac_ay = jax.jacfwd(lambda a: _residual(w, (vehicle, a, radius, variant)))(state.ay)
    dw = -jnp.linalg.solve(jac_w, jac_ay)
    return 1.0 / dw[1]


def skidpad_sweep(vehicle: AnalyticVehicle, ay_values, variant: Variant, radius=50.0):
    """Steady states and steering sensitivities 1/ku (m/s^2 per rad) over an array of ay.

    One vmapped call. Points where Newton's method fails (ay above the grip limit) have
    ``converged = False`` and NaN values; points on the unstable branch beyond an axle's
    force peak have ``stable = False``. Callers select ``converged & stable`` points (the
    reports do, and give the highest such ay as the limit). Every ay and the radius must
    be > 0 (``ParameterError``; traced: ``eqx.error_if``).
    """
    ay_values, radius = _check_inputs(ay_values, radius)

    def one(ay):
        state = _steady_state(vehicle, ay, variant, radius, throw=False)
        sens = _sensitivity_at(vehicle, state, variant, radius)
        nan = jnp.nan
        state = jax.tree.map(lambda x: jnp.where(state.converged, x, nan) if x.dtype == jnp.float64 else x, state)
        state = eqx.tree_at(lambda s: s.stable, state, state.stable & state.converged)
        return state, jnp.where(state.converged, sens, nan)

    return jax.vmap(one)(ay_values)
