"""Linearisation of the reduced equations of motion in minimal coordinates.

Minimal coordinates ``s`` (one per independent velocity) come from a local chart of the
constraint manifold at ``q0``: ``q(s)`` is ``q0 + B T R s`` projected back onto
``Phi = 0`` by Newton iterations in the dependent joint directions (the independent ones
held), so ``dq/ds = B T R`` at ``s = 0``. Their rates are ``s_dot = (dq/ds)^+ q_dot``; at an
equilibrium with ``z = 0`` this is ``s_dot = z``. The state ``x = [s, z]`` is linearised by
``jax.jacfwd`` of ``[s_dot, z_dot]`` at ``s = 0``: the matrices are exact derivatives of the
model, not finite differences.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from ._kinematics import velocity_matrix
from ._projection import Inputs, dynamics, projection
from ._simulate import project_coordinates
from ._system import System, SystemParams, checked_params

#: Newton iterations of the chart ``q(s)``: two give exact first and second derivatives at
#: ``s = 0`` (Newton converges quadratically), two more make the chart accurate near it.
CHART_ITERATIONS = 4


class Linearisation(eqx.Module):
    """``x_dot = A x + B w`` in minimal coordinates ``x = [s, z, aux]`` about a state
    (``n = 2 ndof + n_aux``).

    ``A`` (n x n); ``B`` (n x nw) for the external-force arguments ``w`` (empty when none);
    ``tangent`` = ``dq/ds`` (nq x ndof) maps minimal coordinates to ``q``.
    """

    A: Float[Array, "n n"]
    B: Float[Array, "n nw"]
    tangent: Float[Array, "nq ndof"]


def chart(system: System, params: SystemParams, q0, t=0.0, inputs: Inputs | None = None, aux=None):
    """``q(s)``: the constraint manifold near ``q0`` in minimal coordinates (see module)."""
    t = jnp.asarray(t, q0.dtype)
    basis = velocity_matrix(system, params, q0) @ projection(system, params, q0, t, inputs, 0.0, aux).R

    def q_of(s):
        return project_coordinates(system, params, q0 + basis @ s, t, inputs, CHART_ITERATIONS, aux)

    return q_of


def minimal_rates(system, params, q_of, s, z, aux, w, t=0.0, inputs=None, external=None, elements=(), with_args=False):
    """``[s_dot, z_dot, aux_dot]`` at minimal coordinates ``s`` of the chart ``q_of``."""
    qs = q_of(s)
    dyn = dynamics(system, params, qs, z, t, inputs, external, w if with_args else None, 0.0, elements, aux)
    jac = jax.jacfwd(q_of)(s)
    # full column rank; normal equations, not an SVD (whose derivative is undefined at the
    # repeated singular values of symmetric structures)
    s_dot = jnp.linalg.solve(jac.T @ jac, jac.T @ dyn.q_dot)
    return jnp.concatenate([s_dot, dyn.z_dot, dyn.aux_dot])


def linearise(
    system: System,
    params: SystemParams,
    q,
    z,
    t=0.0,
    inputs: Inputs | None = None,
    external=None,
    args=None,
    elements: tuple = (),
    aux=None,
) -> Linearisation:
    """Exact linearisation of eq. (5.61) at ``(q, z, aux, t)`` (``q`` assembled).

    ``external(q, v, t, args)`` as in :func:`dynamics`; ``B`` is the Jacobian with respect
    to ``args`` (a flat array of force inputs, e.g. a steering torque), empty when ``args``
    is None. ``elements`` / ``aux``: force elements and their states. Rheonomic inputs
    follow their law (open-loop: their time history at ``t``).
    """
    q, z = jnp.asarray(q, jnp.float64), jnp.asarray(z, jnp.float64)
    params = checked_params(system, params)
    t = jnp.asarray(t, q.dtype)
    aux = jnp.zeros((0,), q.dtype) if aux is None else jnp.asarray(aux, q.dtype)
    q_of = chart(system, params, q, t, inputs, aux)
    w0 = jnp.zeros((0,), q.dtype) if args is None else jnp.asarray(args, q.dtype)

    def rates(x, w):
        n = system.n_dof
        return minimal_rates(
            system, params, q_of, x[:n], x[n : 2 * n], x[2 * n :], w, t, inputs, external, elements, args is not None
        )

    x0 = jnp.concatenate([jnp.zeros((system.n_dof,), q.dtype), z, aux])
    a, b = jax.jacfwd(rates, argnums=(0, 1))(x0, w0)
    return Linearisation(A=a, B=b, tangent=jax.jacfwd(q_of)(jnp.zeros((system.n_dof,), q.dtype)))
