"""Generalised symmetric eigenproblems with safe derivatives; free-free modal truncation.

``K φ = λ M φ`` is solved by a Cholesky factor ``M = L Lᵀ`` and a dense symmetric
eigen-decomposition of ``L⁻¹ K L⁻ᵀ``. Modes are mass-normalised (``Φᵀ M Φ = I``).

Repeated eigenvalues. The derivative of an eigenvector inside a cluster of (numerically)
equal eigenvalues is not defined: any rotation within the cluster is an eigenbasis.
:func:`safe_eigh` uses first-order perturbation theory with the coupling factor
``1/(λ_j − λ_i)`` replaced by zero whenever ``|λ_j − λ_i| <= DEGENERACY_RTOL (|λ_i| + |λ_j|)``
(the six rigid-body modes, or the equal bending pairs of a circular tube). Eigenvalue
derivatives are then ``diag(Vᵀ dA V)``: exact for simple eigenvalues, and inside a cluster
their sum (the cluster trace) is exact. Eigenvector derivatives are exact for simple
eigenvalues; in a cluster the arbitrary in-cluster rotation is fixed to zero. Gradients are
therefore finite everywhere (never NaN/inf); quantities invariant to rotations inside a
cluster (frequencies of simple modes, cluster sums, static responses) are exact.
"""

import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._core import ParameterError

#: Relative eigenvalue gap below which two eigenvalues count as repeated (see module doc).
DEGENERACY_RTOL = 1e-6
#: Number of rigid-body modes of an unconstrained, connected 3D frame.
N_RIGID = 6


@jax.custom_jvp
def safe_eigh(a: Float[Array, "n n"]) -> tuple[Float[Array, " n"], Float[Array, "n n"]]:
    """Eigenvalues (ascending) and orthonormal eigenvectors of symmetric ``a``,
    with finite derivatives at repeated eigenvalues (module docstring)."""
    w, v = jnp.linalg.eigh(a)
    return w, v


@safe_eigh.defjvp
def _safe_eigh_jvp(primals, tangents):
    (a,), (da,) = primals, tangents
    w, v = safe_eigh(a)
    vdv = v.T @ (0.5 * (da + da.T)) @ v
    gap = w[None, :] - w[:, None]
    size = jnp.abs(w)[None, :] + jnp.abs(w)[:, None]
    degenerate = jnp.abs(gap) <= DEGENERACY_RTOL * size
    f = jnp.where(degenerate, 0.0, 1.0 / jnp.where(degenerate, 1.0, gap))
    return (w, v), (jnp.diagonal(vdv), v @ (f * vdv))


def generalised_eigh(
    K: Float[Array, "n n"], M: Float[Array, "n n"]
) -> tuple[Float[Array, " n"], Float[Array, "n n"]]:
    """All eigenpairs of ``K φ = λ M φ`` (``M`` positive definite): ``λ`` (rad²/s²)
    ascending and mass-normalised ``Φ`` (columns)."""
    L = jnp.linalg.cholesky(M)
    Linv_K = jax.scipy.linalg.solve_triangular(L, K, lower=True)
    A = jax.scipy.linalg.solve_triangular(L, Linv_K.T, lower=True)
    w, y = safe_eigh(0.5 * (A + A.T))
    phi = jax.scipy.linalg.solve_triangular(L.T, y, lower=False)
    return w, phi


def eigenvalue_to_hz(w: Float[Array, " n"]) -> Float[Array, " n"]:
    """Natural frequency (Hz) from an eigenvalue ω² (rad²/s²); 0 for ω² <= 0, with a
    finite derivative there (double-where)."""
    pos = w > 0.0
    return jnp.where(pos, jnp.sqrt(jnp.where(pos, w, 1.0)), 0.0) / (2.0 * jnp.pi)


def check_mode_count(n_modes: int, available: int, what: str = "free-free elastic modes") -> None:
    """Raise ``ParameterError`` if ``n_modes`` is not in ``1..available``."""
    if isinstance(n_modes, bool) or not isinstance(n_modes, int) or not 1 <= n_modes <= available:
        raise ParameterError(
            f"n_modes = {n_modes!r} is out of range: the model has {available} {what}; "
            f"allowed 1 <= n_modes <= {available}"
        )


def free_free_modes(
    K: Float[Array, "n n"], M: Float[Array, "n n"], n_modes: int
) -> tuple[Float[Array, " m"], Float[Array, "n m"]]:
    """Modal truncation: the ``n_modes`` lowest elastic free-free modes.

    The six rigid-body (zero-energy) modes are removed. Returns natural frequencies (Hz)
    and mass-normalised mode shapes (columns, global DOF order).

    Raises:
        ParameterError: ``n_modes`` larger than the number of elastic modes (``6n − 6``).
    """
    check_mode_count(n_modes, K.shape[0] - N_RIGID)
    w, phi = generalised_eigh(K, M)
    sel = slice(N_RIGID, N_RIGID + n_modes)
    return eigenvalue_to_hz(w[sel]), phi[:, sel]


def rigid_body_modes(xyz: Float[Array, "n 3"]) -> Float[Array, "n6 6"]:
    """Six rigid-body displacement fields (columns): translations x, y, z, then small
    rotations about the global axes through the origin (m, rad per unit amplitude)."""
    n = xyz.shape[0]
    eye = jnp.eye(3)
    cols = []
    for c in range(3):
        t = jnp.zeros((n, 6)).at[:, c].set(1.0)
        cols.append(t.reshape(-1))
    for c in range(3):
        trans = jnp.cross(jnp.broadcast_to(eye[c], xyz.shape), xyz)
        rot = jnp.broadcast_to(eye[c], xyz.shape)
        cols.append(jnp.concatenate([trans, rot], axis=1).reshape(-1))
    return jnp.stack(cols, axis=1)
