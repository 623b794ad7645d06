"""Craig-Bampton component mode synthesis, orthogonalised (thesis section 6.2.2, 4.6.2).

The DOF are split into boundary DOF ``b`` (all six DOF of the interface nodes, e.g. the
32 suspension hard points) and interior DOF ``i``. The Craig-Bampton basis is

    T = [[I, 0], [Ψ_ib, Φ_i]],   Ψ_ib = −K_ii⁻¹ K_ib  (static constraint modes),

with ``Φ_i`` the lowest ``n_fixed`` fixed-interface normal modes (``K_ii φ = λ M_ii φ``).
The reduced matrices ``Tᵀ K T`` and ``Tᵀ M T`` are then diagonalised ("orthogonalised"):
their eigenvectors replace constraint and fixed-interface modes by boundary eigenvectors
and approximations of the free-free modes, each with a natural frequency. The six lowest
are the rigid-body modes and are removed, as in the thesis.
"""

import equinox as eqx
import jax.numpy as jnp
import jax.scipy.linalg as jsl
import numpy as np
from jaxtyping import Array, Float

from .._core import ParameterError
from ._modal import N_RIGID, check_mode_count, eigenvalue_to_hz, generalised_eigh


class CraigBampton(eqx.Module):
    """Result of :func:`craig_bampton`.

    Attributes:
        frequencies_hz: natural frequencies of the orthogonalised elastic modes (Hz), (n,).
        modes: those modes expanded to all DOF, mass-normalised, (n_dof, n).
        basis: the Craig-Bampton transformation ``T`` (rows: all DOF in global order;
            columns: boundary DOF then fixed-interface modes), (n_dof, n_b + n_fixed).
        fixed_interface_hz: frequencies of the fixed-interface modes (Hz), (n_fixed,).
    """

    frequencies_hz: Float[Array, " n"]
    modes: Float[Array, "dof n"]
    basis: Float[Array, "dof r"]
    fixed_interface_hz: Float[Array, " k"]


def boundary_dofs(node_indices: tuple[int, ...], n_dof: int) -> tuple[np.ndarray, np.ndarray]:
    """Boundary DOF (six per interface node) and interior DOF index arrays (static)."""
    b = np.asarray([6 * k + c for k in node_indices for c in range(6)], dtype=np.int64)
    i = np.setdiff1d(np.arange(n_dof), b)
    return b, i


def craig_bampton(
    K: Float[Array, "n n"],
    M: Float[Array, "n n"],
    interface_nodes: tuple[int, ...],
    n_modes: int,
    n_fixed: int = 20,
) -> CraigBampton:
    """Orthogonalised Craig-Bampton reduction with the given interface nodes.

    Args:
        K, M: global stiffness and mass matrices of a free (unconstrained) structure.
        interface_nodes: mesh-node indices of the boundary (master) nodes.
        n_modes: number of elastic orthogonalised modes returned.
        n_fixed: number of fixed-interface normal modes kept.

    Raises:
        ParameterError: no interface nodes, ``n_fixed`` out of range, or ``n_modes``
            larger than the reduced model's ``6 n_b + n_fixed − 6`` elastic modes.
    """
    n = K.shape[0]
    if not interface_nodes:
        raise ParameterError("Craig-Bampton needs at least one interface node (frame.interface is empty)")
    b, i = boundary_dofs(tuple(interface_nodes), n)
    check_mode_count(n_fixed, len(i), "interior DOF (fixed-interface modes)")
    check_mode_count(n_modes, len(b) + n_fixed - N_RIGID, "elastic Craig-Bampton modes")
    kii, kib = K[np.ix_(i, i)], K[np.ix_(i, b)]
    mii = M[np.ix_(i, i)]
    psi = -jsl.cho_solve(jsl.cho_factor(kii), kib)
    lam_i, phi_i = generalised_eigh(kii, mii)
    phi_i = phi_i[:, :n_fixed]
    nb = len(b)
    T = jnp.zeros((n, nb + n_fixed))
    T = T.at[b, np.arange(nb)].set(1.0)
    T = T.at[np.ix_(i, np.arange(nb))].set(psi)
    T = T.at[np.ix_(i, np.arange(nb, nb + n_fixed))].set(phi_i)
    kr = T.T @ K @ T
    mr = T.T @ M @ T
    lam, q = generalised_eigh(0.5 * (kr + kr.T), 0.5 * (mr + mr.T))
    sel = slice(N_RIGID, N_RIGID + n_modes)
    return CraigBampton(
        frequencies_hz=eigenvalue_to_hz(lam[sel]),
        modes=T @ q[:, sel],
        basis=T,
        fixed_interface_hz=eigenvalue_to_hz(lam_i[:n_fixed]),
    )
