"""An LU solve that stays unbatched under ``jax.vmap``, and shifted solves
``(I - s J) x = r`` by an eigendecomposition of ``J`` (the IMEX root finder's).

jaxlib 0.10.2 splits a batched LAPACK call (a vmapped Cholesky, LU or triangular solve)
over its CPU thread pool and waits for the parts; two such calls running at once can each
wait for the threads the other holds, and the process hangs with no CPU (seen with vmapped
steady states, sweeps and the fast car's batched step steers; native stacks in
docs/optimise.md). The solve here runs a batch one system after the other inside the
compiled program (:func:`jax.custom_batching.sequential_vmap`: unbatched LAPACK calls never
use the pool), and differentiate as linear solves (:func:`jax.lax.custom_linear_solve`:
forward and reverse mode, the factorisation itself never differentiated). Unbatched it is
the plain LAPACK call.

The same treatment of the fast car's Cholesky solve failed: the skid-pad program (a
Newton solve whose Jacobian is a vmapped forward-mode pass) then stopped at run time with
"No registered implementation for untyped custom call to lapack_dpotrf_ffi", so that solve
stays a plain batched LAPACK call (docs/manoeuvre.md, "Speed").
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.scipy.linalg as jsl
from jaxtyping import Array

_sequential = jax.custom_batching.sequential_vmap


@_sequential
def _lu_factor(a):
    return jsl.lu_factor(a)


@_sequential
def _lu_solve(lu, pivots, b):
    return jsl.lu_solve((lu, pivots), b)


@_sequential
def _lu_solve_transposed(lu, pivots, b):
    return jsl.lu_solve((lu, pivots), b, trans=1)


def lu_factor(a):
    """``(a, lu, pivots)``: ``a`` (n, n) and its LU factors, for :func:`lu_solve` (no
    derivative with respect to ``a``)."""
    a = jax.lax.stop_gradient(a)
    return (a, *_lu_factor(a))


def lu_solve(factors, b):
    """``a^-1 b`` from :func:`lu_factor`'s ``factors``; ``b`` (n,)."""
    a, lu, pivots = factors
    return jax.lax.custom_linear_solve(lambda x: a @ x, b, lambda _, r: _lu_solve(lu, pivots, r),
                                       transpose_solve=lambda _, r: _lu_solve_transposed(lu, pivots, r))


@_sequential
def _eig_with_inverse(a):
    values, vectors = jnp.linalg.eig(a)
    return values, vectors, jnp.linalg.inv(vectors)


class Diagonalised(eqx.Module):
    """A real matrix ``J`` (n, n) as ``V diag(eigenvalues) V^-1`` (complex), for solving
    ``(I - s J) x = r`` for any scalar ``s`` by two real matrix products and a diagonal
    scaling (:meth:`solve_shifted`): no factorisation per ``s``, no LAPACK call. Built by
    :func:`diagonalise`; ``error`` is the decomposition's own error, ``max |V diag(lam) V^-1
    - J|`` over ``max |J|`` (about 1e-13 on the fast car's Jacobians, whose eigenvectors'
    condition numbers are about 2e3; near 1 for a matrix that is not diagonalisable)."""

    matrix: Array  # J (n, n)
    eigenvalues: Array  # (n,) complex
    to_modal: Array  # (2n, n): real and imaginary parts of V^-1, stacked
    from_modal: Array  # (n, 2n): [Re V, -Im V]
    error: Array

    def solve_shifted(self, scale, r):
        """``(I - scale J)^-1 r`` for ``r`` (n,): linear in ``r`` (derivatives flow through
        ``r`` only; the decomposition and ``scale`` are constants)."""
        n = r.shape[0]
        w = self.to_modal @ r
        shift = jnp.asarray(jax.lax.stop_gradient(scale), self.eigenvalues.dtype)
        z = jax.lax.complex(w[:n], w[n:]) / (1.0 - shift * self.eigenvalues)
        return self.from_modal @ jnp.concatenate([z.real, z.imag])


def diagonalise(matrix) -> Diagonalised:
    """:class:`Diagonalised` of the real ``matrix`` (held out of differentiation): LAPACK's
    eigendecomposition, run one system at a time under ``vmap`` (module docs)."""
    matrix = jax.lax.stop_gradient(matrix)
    values, vectors, inverse = _eig_with_inverse(matrix)
    rebuilt = ((vectors * values[None, :]) @ inverse).real
    scale = jnp.max(jnp.abs(matrix))
    error = jnp.max(jnp.abs(rebuilt - matrix)) / jnp.where(scale > 0.0, scale, 1.0)
    return Diagonalised(matrix, values, jnp.concatenate([inverse.real, inverse.imag]),
                        jnp.concatenate([vectors.real, -vectors.imag], axis=1), error)
