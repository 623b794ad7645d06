"""Implicit-explicit (IMEX) split of the equations of motion for stiff elastic modes.

The modal coordinates of flexible bodies oscillate at tens of hertz (the FSAE chassis:
40-86 Hz with the suspension attached), so an explicit solver's step is bounded by
stability, not accuracy. The elastic and damping forces ``-(K p + D p_dot)`` are linear;
they go to the implicit part of an additive Runge-Kutta method (Diffrax ``KenCarp``) as

    p_dot = z_p,        z_dot = -G (K p + D z_p),        G = Mr0^-1 E,

with ``Mr0`` the reduced mass matrix ``R^T T^T M T R`` at the initial state and ``E`` the
columns of ``z`` that hold the modal velocities. Everything else, including the difference
between the exact ``Mr(q)^-1`` and the frozen ``Mr0^-1``, stays explicit: the explicit part is
the full vector field minus this linear one, so the split changes the integration error,
never the equations. ``Mr`` changes by a few per cent over a manoeuvre (suspension travel,
steer; the velocities of a free root body are in its own axes, so ``Mr`` does not turn with
it).
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ._projection import dynamics
from ._system import System, SystemParams


def modal_rows(system: System) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """``(q rows, z rows)`` of every flexible body's modal coordinates and velocities.

    Raises ``ValueError`` when the system has no modes or a modal velocity is not
    independent (the split needs ``p_dot`` in ``z``)."""
    q_rows, z_rows = [], []
    for i, name in enumerate(system.body_names):
        for k in range(system.n_modes[i]):
            y = system.y_index(name, f"p{k}_dot")
            if y not in system.independent:
                raise ValueError(
                    f"implicit_modes needs every modal velocity among the independent velocities; "
                    f"{name}.p{k}_dot is dependent (declare it with add_independent)"
                )
            q_rows.append(system.q_index(name, f"p{k}"))
            z_rows.append(system.independent.index(y))
    if not q_rows:
        raise ValueError("implicit_modes needs a flexible body with modes; the system has none")
    return tuple(q_rows), tuple(z_rows)


class ModalImplicitPart(eqx.Module):
    """The linear implicit part ``f_I(t, state, args)`` of the IMEX split (see module)."""

    q_rows: tuple[int, ...] = eqx.field(static=True)
    z_rows: tuple[int, ...] = eqx.field(static=True)
    stiffness: Float[Array, "nm nm"]  # block diagonal over the flexible bodies
    damping: Float[Array, "nm nm"]
    gain: Float[Array, "ndof nm"]  # Mr0^-1 E

    def __call__(self, t, state, args):
        del t, args
        q_rows, z_rows = np.asarray(self.q_rows, int), np.asarray(self.z_rows, int)
        p, p_dot = state.q[q_rows], state.z[z_rows]
        q_dot = jnp.zeros_like(state.q).at[q_rows].set(p_dot)
        z_dot = -self.gain @ (self.stiffness @ p + self.damping @ p_dot)
        return type(state)(q_dot, z_dot, jnp.zeros_like(state.aux))


def _modal_matrices(system: System, params: SystemParams, dtype):
    """Block-diagonal ``K`` and ``D`` of the flexible bodies, from their elastic forces
    (linear in ``(p, p_dot)``, so the Jacobian is exact)."""
    k_blocks, d_blocks = [], []
    for i in range(system.n_bodies):
        n = system.n_modes[i]
        if n:
            zero = jnp.zeros((n,), dtype)
            k_neg, d_neg = jax.jacfwd(params.bodies[i].elastic, argnums=(0, 1))(zero, zero)
            k_blocks.append(-k_neg)
            d_blocks.append(-d_neg)
    return jax.scipy.linalg.block_diag(*k_blocks), jax.scipy.linalg.block_diag(*d_blocks)


def modal_implicit_part(
    system: System, params: SystemParams, q0, z0, t0, inputs=None, external=None, args=None, elements=(), aux0=None,
    kappa=0.0,
) -> ModalImplicitPart:
    """The implicit part at the (assembled) initial state ``(q0, z0, aux0, t0)``."""
    q_rows, z_rows = modal_rows(system)
    mass = dynamics(system, params, q0, z0, t0, inputs, external, args, kappa, elements, aux0).mass_matrix
    stiffness, damping = _modal_matrices(system, params, q0.dtype)
    select = jnp.zeros((system.n_dof, len(z_rows)), q0.dtype).at[np.asarray(z_rows), np.arange(len(z_rows))].set(1.0)
    return ModalImplicitPart(q_rows, z_rows, stiffness, damping, jnp.linalg.solve(mass, select))
