"""An LU solve that stays unbatched under ``jax.vmap`` (the IMEX solver's stage solves).

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
