"""Static and steady-state equilibrium (trim) by Newton root finding in minimal coordinates.

Unknowns: the minimal coordinates ``s`` of the chart at ``q_guess`` (see :mod:`._linear`),
the independent velocities ``z`` and the auxiliary states, except those the caller holds;
equations: ``z_dot = 0`` and ``aux_dot = 0``. A static equilibrium holds every velocity at
zero; a steady state holds chosen velocities (e.g. a forward speed) and chosen coordinates
that drift without changing the forces (e.g. a position or a heading: "ignorable"
coordinates). Optimistix's Newton solver with its implicit-function adjoint gives exact
gradients of the trim with respect to the parameters without differentiating the iterations.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jaxtyping import Array, Float

from ._errors import MultibodyError
from ._linear import chart, minimal_rates
from ._system import System, SystemParams, checked_params


class TrimError(MultibodyError):
    """The equilibrium solve did not converge."""


class Trim(eqx.Module):
    """An equilibrium: coordinates ``q``, independent velocities ``z``, auxiliary states
    ``aux``, the largest remaining ``z_dot`` / ``aux_dot`` (``residual``), and ``ok``."""

    q: Float[Array, " nq"]
    z: Float[Array, " ndof"]
    aux: Float[Array, " na"]
    residual: Float[Array, ""]
    ok: Array


#: Newton stops when the largest acceleration / state rate falls below this (SI units).
TRIM_ATOL = 1e-10


def _count(n, hold, what):
    hold = tuple(int(k) for k in hold)
    if any(k < 0 or k >= n for k in hold) or len(set(hold)) != len(hold):
        raise ValueError(f"{what} must be distinct indices in [0, {n}), got {hold}")
    return np.setdiff1d(np.arange(n), np.asarray(hold, dtype=int))


def trim(
    system: System,
    params: SystemParams,
    q_guess,
    z_guess=None,
    aux_guess=None,
    *,
    hold_s: tuple[int, ...] = (),
    hold_z: tuple[int, ...] | None = None,
    t=0.0,
    inputs=None,
    external=None,
    args=None,
    elements: tuple = (),
    max_steps: int = 64,
    throw: bool = True,
) -> Trim:
    """Solve ``z_dot = 0``, ``aux_dot = 0`` for an equilibrium near ``q_guess`` (assembled).

    ``hold_z``: independent velocities held at ``z_guess`` (default all: a static
    equilibrium with ``z = z_guess``, usually zero); ``hold_s``: minimal coordinates held
    (their indices follow the independent velocities). The free unknowns must number
    ``ndof + n_aux``: for each velocity set free, hold one coordinate. With ``throw`` a
    failed solve raises (:class:`TrimError` for concrete values, a run-time error under
    ``jit``). Differentiable in ``params`` by the implicit function theorem.
    """
    q_guess = jnp.asarray(q_guess, jnp.float64)
    params = checked_params(system, params)
    n = system.n_dof
    z_guess = jnp.zeros((n,)) if z_guess is None else jnp.asarray(z_guess, jnp.float64)
    n_aux = sum(len(e.aux_names) for e in elements)
    aux_guess = jnp.zeros((n_aux,)) if aux_guess is None else jnp.asarray(aux_guess, jnp.float64)
    free_s = _count(n, hold_s, "hold_s")
    free_z = _count(n, tuple(range(n)) if hold_z is None else hold_z, "hold_z")
    if free_s.size + free_z.size != n:
        raise ValueError(
            f"trim needs as many free unknowns as equations: {free_s.size} free coordinates + {free_z.size} free "
            f"velocities must equal {n} (the number of independent velocities); hold one coordinate per free velocity"
        )
    t = jnp.asarray(t, q_guess.dtype)
    q_of = chart(system, params, q_guess, t, inputs, aux_guess)

    def unpack(x):
        s = jnp.zeros((n,), q_guess.dtype).at[free_s].set(x[: free_s.size])
        z = z_guess.at[free_z].set(x[free_s.size : free_s.size + free_z.size])
        return s, z, x[free_s.size + free_z.size :]

    def residual(x, p):
        s, z, aux = unpack(x)
        rates = minimal_rates(system, p, q_of, s, z, aux, args, t, inputs, external, elements, args is not None)
        return rates[n:]  # z_dot and aux_dot

    x0 = jnp.concatenate([jnp.zeros((free_s.size,)), z_guess[free_z], aux_guess])
    solver = optx.Newton(rtol=0.0, atol=TRIM_ATOL)
    sol = optx.root_find(residual, solver, x0, params, max_steps=max_steps, throw=False)
    s, z, aux = unpack(sol.value)
    res = jnp.max(jnp.abs(residual(sol.value, params)), initial=0.0)
    ok = (sol.result == optx.RESULTS.successful) & jnp.isfinite(res)
    result = Trim(q=q_of(s), z=z, aux=aux, residual=res, ok=ok)
    if not throw:
        return result
    if not isinstance(ok, jax.core.Tracer):
        if not bool(ok):
            raise TrimError(
                f"equilibrium not found: largest acceleration/state rate {float(res):.3e} after {max_steps} Newton "
                "steps; give a closer guess, or check that the held coordinates and velocities leave a "
                "non-singular problem"
            )
        return result
    return eqx.tree_at(lambda r: r.q, result, eqx.error_if(result.q, ~ok, "equilibrium (trim) not found"))
