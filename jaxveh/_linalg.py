"""Small linear solves that never put a batched LAPACK call in a vmapped program.

jaxlib 0.10.2 splits a batched LAPACK call (a vmapped Cholesky, LU or triangular solve)
over its CPU thread pool and waits for the parts; two such calls running at once can each
wait for the threads the other holds, and the process hangs with no CPU (seen with vmapped
steady states, sweeps and the fast car's batched step steers; native stacks in
docs/optimise.md). Two remedies:

- :func:`lu_factor` / :func:`lu_solve` (the IMEX root finder's): a batch runs one system
  after the other inside the compiled program (:func:`jax.custom_batching.sequential_vmap`:
  unbatched LAPACK calls never use the pool), differentiated as linear solves
  (:func:`jax.lax.custom_linear_solve`: forward and reverse mode, the factorisation itself
  never differentiated). Unbatched it is the plain LAPACK call.
- :func:`spd_solve` (the fast car's mass-matrix solve): a Cholesky factorisation unrolled
  into elementwise operations, no LAPACK at all. Treating that solve as the LU (a
  sequential LAPACK Cholesky) failed: the skid-pad program, whose Newton Jacobian is a
  vmapped forward-mode pass, stopped at run time with "No registered implementation for
  untyped custom call to lapack_dpotrf_ffi".
"""

import jax
import jax.scipy.linalg as jsl

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


def spd_solve(a, b):
    """``a^-1 b`` for a small symmetric positive definite ``a`` (n, n) and ``b`` (n,), by a
    Cholesky factorisation unrolled into elementwise operations: no LAPACK call, so nothing
    for the thread pool under ``jax.vmap`` (see the module docs), and any order of autodiff.
    Meant for n up to about 20 (the program grows as n^2)."""
    n = a.shape[-1]
    rows = jax.numpy.arange(n)
    columns = []  # columns of the factor L (zeros above the diagonal)
    for j in range(n):
        v = a[:, j]
        for k in range(j):
            v = v - columns[k] * columns[k][j]
        columns.append(jax.numpy.where(rows >= j, v / jax.numpy.sqrt(v[j]), 0.0))
    y = []
    for i in range(n):  # L y = b
        acc = b[i]
        for k in range(i):
            acc = acc - columns[k][i] * y[k]
        y.append(acc / columns[i][i])
    x = [None] * n
    for i in reversed(range(n)):  # L^T x = y
        acc = y[i]
        for k in range(i + 1, n):
            acc = acc - columns[i][k] * x[k]
        x[i] = acc / columns[i][i]
    return jax.numpy.stack(x)
