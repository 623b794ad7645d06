"""Small dense linear solves that stay unbatched under ``jax.vmap``.

jaxlib 0.10.2 splits a batched LAPACK call (a vmapped Cholesky, LU or triangular solve)
over its CPU thread pool and waits for the parts; two such calls running at once can each
wait for the threads the other holds, and the process hangs with no CPU (seen with vmapped
steady states, sweeps and the fast car's batched step steers; native stacks in
docs/optimise.md). The solves here run a batch one system after the other inside the
compiled program (:func:`jax.custom_batching.sequential_vmap`: unbatched LAPACK calls never
use the pool), and differentiate as linear solves (:func:`jax.lax.custom_linear_solve`:
forward and reverse mode, the factorisation itself never differentiated). Unbatched they
are the plain LAPACK calls.
"""

import jax
import jax.scipy.linalg as jsl

_sequential = jax.custom_batching.sequential_vmap


@_sequential
def _cholesky(m):
    return jax.lax.linalg.cholesky(m)


@_sequential
def _cholesky_solve(factor, b):
    return jsl.cho_solve((factor, True), b)


@_sequential
def _lu_factor(a):
    return jsl.lu_factor(a)


@_sequential
def _lu_solve(lu, pivots, b):
    return jsl.lu_solve((lu, pivots), b)


@_sequential
def _lu_solve_transposed(lu, pivots, b):
    return jsl.lu_solve((lu, pivots), b, trans=1)


def spd_solve(m, b):
    """``m^-1 b`` for a symmetric positive definite ``m`` (n, n) and ``b`` (n,), by Cholesky."""
    factor = _cholesky(jax.lax.stop_gradient(m))
    return jax.lax.custom_linear_solve(lambda x: m @ x, b, lambda _, r: _cholesky_solve(factor, r), symmetric=True)


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
