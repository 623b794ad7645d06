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

from ._projection import Inputs, dynamics, projection
from ._simulate import project_coordinates
from ._kinematics import velocity_matrix
from ._system import System, SystemParams, checked_params

#: Newton iterations of the chart ``q(s)``: two give exact first and second derivatives at
#: ``s = 0`` (Newton converges quadratically), two more make the chart accurate near it.
CHART_ITERATIONS = 4


class Linearisation(eqx.Module):
    """``x_dot = A x + B w`` in minimal coordinates ``x = [s, z]`` (n = 2 ndof) about a state.

    ``A`` (n x n); ``B`` (n x nw) for the external-force arguments ``w`` (empty when none);
    ``tangent`` = ``dq/ds`` (nq x ndof) maps minimal coordinates to ``q``.
    """

    A: Float[Array, "n n"]
    B: Float[Array, "n nw"]
    tangent: Float[Array, "nq ndof"]


def chart(system: System, params: SystemParams, q0, t=0.0, inputs: Inputs | None = None):
    """``q(s)``: the constraint manifold near ``q0`` in minimal coordinates (see module)."""
    t = jnp.asarray(t, q0.dtype)
    basis = velocity_matrix(system, params, q0) @ projection(system, params, q0, t, inputs).R

    def q_of(s):
        return project_coordinates(system, params, q0 + basis @ s, t, inputs, CHART_ITERATIONS)

    return q_of


def linearise(
    system: System,
    params: SystemParams,
    q,
    z,
    t=0.0,
    inputs: Inputs | None = None,
    external=None,
    args=None,
) -> Linearisation:
    """Exact linearisation of eq. (5.61) at ``(q, z, t)`` (``q`` assembled).

    ``external(q, v, t, args)`` as in :func:`dynamics`; ``B`` is the Jacobian with respect
    to ``args`` (a flat array of force inputs, e.g. a steering torque), empty when ``args``
    is None. Rheonomic inputs are held at their time history.
    """
    q, z = jnp.asarray(q, jnp.float64), jnp.asarray(z, jnp.float64)
    params = checked_params(system, params)
    t = jnp.asarray(t, q.dtype)
    q_of = chart(system, params, q, t, inputs)
    w0 = jnp.zeros((0,), q.dtype) if args is None else jnp.asarray(args, q.dtype)

    def rates(s, zz, w):
        qs = q_of(s)
        dyn = dynamics(system, params, qs, zz, t, inputs, external, None if args is None else w)
        jac = jax.jacfwd(q_of)(s)
        s_dot = jnp.linalg.solve(jac.T @ jac, jac.T @ dyn.q_dot)  # full column rank; no SVD (its
        # derivative is undefined at the repeated singular values of symmetric structures)
        return jnp.concatenate([s_dot, dyn.z_dot])

    s0 = jnp.zeros((system.n_dof,), q.dtype)
    a_s, a_z, b = jax.jacfwd(rates, argnums=(0, 1, 2))(s0, z, w0)
    return Linearisation(A=jnp.concatenate([a_s, a_z], axis=1), B=b, tangent=jax.jacfwd(q_of)(s0))
