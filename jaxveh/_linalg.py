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

The IMEX solver's stages solve ``(I - s A) x = b`` with one matrix ``A`` per segment and one
shift ``s`` per step (:func:`shifted_factor`, :func:`shifted_solve`). Unbatched that is an LU
factorisation per step and two triangular solves per stage (LAPACK). Under ``jax.vmap`` the
members' factorisations and solves one after the other cost more than the car's field
itself in a batch, so there each member's ``A`` is decomposed once per segment, ``A = V
diag(lambda) V^-1`` (:func:`spectral_form`), and a stage solve is two matrix-vector products,
batched: ``x = V diag(1 / (1 - s lambda)) V^-1 b`` (docs/manoeuvre.md, "Solvers"). A member
whose decomposition is refused (a defective or ill-conditioned ``V``) sends the batch back to
the LU loop. An unbatched program never computes the decomposition
(:func:`jax.custom_batching.custom_vmap` picks the path).

The same treatment of the fast car's Cholesky solve failed: the skid-pad program (a
Newton solve whose Jacobian is a vmapped forward-mode pass) then stopped at run time with
"No registered implementation for untyped custom call to lapack_dpotrf_ffi", so that solve
stays a plain batched LAPACK call (docs/manoeuvre.md, "Speed").
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.scipy.linalg as jsl
from jaxtyping import Array, Bool, Float, Int

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


# ---- shifted systems (I - s A) x = b: one A, many shifts (the IMEX solver's stages) ---------


class Spectral(eqx.Module):
    """``A = V diag(lambda) V^-1`` in real arrays, for batched solves of ``(I - s A) x = b``
    with matrix-vector products only: ``left = [Re V^-1; Im V^-1]`` (2n, n), ``right =
    [Re V, -Im V]`` (n, 2n), ``values = [Re lambda, Im lambda]`` (2, n), and ``usable`` (the
    decomposition reproduces ``A`` and ``V`` is well conditioned; else the LU path runs)."""

    left: Float[Array, "2n n"]
    right: Float[Array, "n 2n"]
    values: Float[Array, "2 n"]
    usable: Bool[Array, ""]


#: Largest ``|V|_F |V^-1|_F / n`` (a condition number's estimate) for which the spectral path
#: solves: its relative error is about that times the round-off.
SPECTRAL_CONDITION = 1e6
#: Largest ``|V diag(lambda) V^-1 - A|_F / |A|_F`` for which the spectral path solves.
SPECTRAL_RESIDUAL = 1e-10


def _eigen(a) -> Spectral:
    """The spectral form of one matrix (LAPACK's ``geev``, unbatched), with its checks."""
    n = a.shape[0]
    values, vectors = jnp.linalg.eig(a)
    inverse = jnp.linalg.inv(vectors)
    rebuilt = (vectors * values[None, :]) @ inverse
    scale = jnp.maximum(jnp.linalg.norm(a), jnp.finfo(a.dtype).tiny)
    residual = jnp.linalg.norm(rebuilt - a.astype(rebuilt.dtype)) / scale
    condition = jnp.linalg.norm(vectors) * jnp.linalg.norm(inverse) / n
    usable = jnp.isfinite(condition) & (condition < SPECTRAL_CONDITION) & (residual < SPECTRAL_RESIDUAL)
    return Spectral(left=jnp.concatenate([inverse.real, inverse.imag]),
                    right=jnp.concatenate([vectors.real, -vectors.imag], axis=1),
                    values=jnp.stack([values.real, values.imag]), usable=usable)


def empty_spectral(a) -> Spectral:
    """A spectral form of ``a``'s shape that is not ``usable`` (the LU path solves)."""
    n = a.shape[-1]
    return Spectral(left=jnp.zeros((2 * n, n), a.dtype), right=jnp.zeros((n, 2 * n), a.dtype),
                    values=jnp.zeros((2, n), a.dtype), usable=jnp.zeros((), bool))


@jax.custom_batching.custom_vmap
def _spectral_form(a):
    return empty_spectral(a)


@_spectral_form.def_vmap
def _spectral_form_batched(axis_size, in_batched, a):
    del axis_size
    if not in_batched[0]:
        out = empty_spectral(a)
        return out, jax.tree.map(lambda _: False, out)
    out = jax.lax.map(_eigen, a)
    return out, jax.tree.map(lambda _: True, out)


def _spectral_apply(spectral: Spectral, shift, b, transposed):
    """``(I - shift A)^-1 b`` (or its transpose's) from the spectral form (one system)."""
    n = b.shape[0]
    lam_re, lam_im = spectral.values
    den_re, den_im = 1.0 - shift * lam_re, -shift * lam_im
    norm = den_re**2 + den_im**2
    d_re, d_im = den_re / norm, -den_im / norm
    if transposed:  # (I - s A)^-T = V^-T D V^T
        c = spectral.right.T @ b
        c_re, c_im = c[:n], -c[n:]
    else:
        c = spectral.left @ b
        c_re, c_im = c[:n], c[n:]
    e_re, e_im = c_re * d_re - c_im * d_im, c_re * d_im + c_im * d_re
    if transposed:
        return spectral.left.T @ jnp.concatenate([e_re, -e_im])
    return spectral.right @ jnp.concatenate([e_re, e_im])


def _broadcast(args, in_batched, axis_size):
    return jax.tree.map(lambda x, b: x if b else jnp.broadcast_to(x, (axis_size,) + jnp.shape(x)), args,
                        tuple(in_batched))


@jax.custom_batching.custom_vmap
def _shifted_lu(a, usable):
    del usable
    return jsl.lu_factor(a)


@_shifted_lu.def_vmap
def _shifted_lu_batched(axis_size, in_batched, a, usable):
    a, usable = _broadcast((a, usable), in_batched, axis_size)

    def skip(a):
        return jnp.zeros_like(a), jnp.zeros(a.shape[:2], jnp.int32)

    out = jax.lax.cond(jnp.all(usable), skip, lambda a: jax.lax.map(jsl.lu_factor, a), a)
    return out, (True, True)


def _make_shifted_solve(transposed: bool):
    @jax.custom_batching.custom_vmap
    def solve(lu, pivots, spectral, shift, b):
        del spectral, shift
        return jsl.lu_solve((lu, pivots), b, trans=int(transposed))

    @solve.def_vmap
    def solve_batched(axis_size, in_batched, lu, pivots, spectral, shift, b):
        lu, pivots, spectral, shift, b = _broadcast((lu, pivots, spectral, shift, b), in_batched, axis_size)

        def by_lu(args):
            lu, pivots, _, _, b = args
            return jax.lax.map(lambda x: jsl.lu_solve((x[0], x[1]), x[2], trans=int(transposed)), (lu, pivots, b))

        def by_spectral(args):
            _, _, spectral, shift, b = args
            return jax.vmap(lambda s, h, x: _spectral_apply(s, h, x, transposed))(spectral, shift, b)

        args = (lu, pivots, spectral, shift, b)
        return jax.lax.cond(jnp.all(spectral.usable), by_spectral, by_lu, args), True

    return solve


_shifted_solve = _make_shifted_solve(False)
_shifted_solve_transposed = _make_shifted_solve(True)


class ShiftedFactors(eqx.Module):
    """``I - shift A`` factorised for :func:`shifted_solve` (see :func:`shifted_factor`)."""

    matrix: Float[Array, "n n"]
    shift: Float[Array, ""]
    spectral: Spectral
    lu: Float[Array, "n n"]
    pivots: Int[Array, " n"]


def spectral_form(matrix) -> Spectral:
    """``matrix``'s spectral form for :func:`shifted_factor`, computed only where the program
    is batched (under ``jax.vmap``: one unbatched LAPACK ``geev`` per member, in a loop); an
    unbatched program gets an empty form (not ``usable``), and its solves use LU, which is
    faster there. No derivative (``matrix`` is held out of differentiation)."""
    return _spectral_form(jax.lax.stop_gradient(matrix))


def shifted_factor(matrix, spectral: Spectral, shift) -> ShiftedFactors:
    """``I - shift matrix`` ready for :func:`shifted_solve` (no derivative with respect to
    ``matrix``, ``spectral`` or ``shift``). Unbatched: its LU factors (LAPACK). Under
    ``jax.vmap``, where every member's ``spectral`` is ``usable``: nothing (the solves are
    matrix-vector products with the spectral form); else the members' LU factors, one after
    the other (a batched LAPACK call can hang jaxlib's thread pool, module docs)."""
    matrix, spectral, shift = jax.lax.stop_gradient((matrix, spectral, shift))
    a = jnp.eye(matrix.shape[-1], dtype=matrix.dtype) - shift * matrix
    lu, pivots = _shifted_lu(a, spectral.usable)
    return ShiftedFactors(matrix=matrix, shift=shift, spectral=spectral, lu=lu, pivots=pivots)


def shifted_solve(factors: ShiftedFactors, b):
    """``(I - shift matrix)^-1 b`` from :func:`shifted_factor`; ``b`` (n,). Differentiable in
    ``b`` (forward and reverse mode, as a linear solve)."""
    f = factors

    def solve(_, r):
        return _shifted_solve(f.lu, f.pivots, f.spectral, f.shift, r)

    def solve_transposed(_, r):
        return _shifted_solve_transposed(f.lu, f.pivots, f.spectral, f.shift, r)

    return jax.lax.custom_linear_solve(lambda x: x - f.shift * (f.matrix @ x), b, solve,
                                       transpose_solve=solve_transposed)
