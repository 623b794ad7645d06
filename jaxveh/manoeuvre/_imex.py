"""IMEX integration of the fast car (docs/manoeuvre.md, "Solvers").

The car's vector field is split into a linear part taken implicitly, its Jacobian at the
start ``J0 (x - x0)`` over every state, and the rest, ``f(x) - J0 (x - x0)``, taken
explicitly by Diffrax's additive Runge-Kutta method ``KenCarp4``; the two parts add up to
the exact vector field. The stiff motions of the car (the chassis modes at up to 525 rad/s,
the tyres' relaxation at speed / relaxation length, wheel hop and wheel spin) are close to
linear about the start, so the explicit remainder is no longer stiff and the step follows
the manoeuvre.

The implicit stage equations are then affine in the unknown, so one Newton step solves
them exactly: :class:`AffineRootFinder` factorises their Jacobian once per step (Diffrax
computes it at the second stage and reuses it for the others, ``KenCarp4`` having one
diagonal coefficient) and takes one step per stage, where Optimistix's Newton would
re-linearise and iterate to a tolerance, and Diffrax's chord method (``VeryChord``) was
seen to reject tens of thousands of steps at rtol 1e-4 on this car.
"""

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import optimistix as optx
from jax.flatten_util import ravel_pytree

from .._linalg import lu_factor, lu_solve


class _AffineState(eqx.Module):
    lu: tuple
    steps: jax.Array


class AffineRootFinder(optx.AbstractRootFinder):
    """Root finder for an affine function ``fn(y) = A y + b``: the LU factors of ``A`` (the
    Jacobian at the initial point, by forward mode) and one Newton step, which is exact up to
    round-off. Only for affine functions: nothing checks the residual afterwards (the
    implicit part of :func:`linearised_split` is affine by construction)."""

    rtol: float = 0.0  # unused: one step is exact (the fields Optimistix's root finders have)
    atol: float = 0.0
    norm: object = optx.max_norm

    def init(self, fn, y, args, options, f_struct, aux_struct, tags):
        if "init_state" in options:  # Diffrax's Jacobian of an earlier stage of the step
            return options["init_state"]
        flat, unravel = ravel_pytree(y)
        jacobian = jax.jacfwd(lambda x: ravel_pytree(fn(unravel(x), args)[0])[0])(flat)
        return _AffineState(lu_factor(jacobian), jnp.asarray(0))

    def step(self, fn, y, args, options, state, tags):
        del options, tags
        fx, aux = fn(y, args)
        flat, unravel = ravel_pytree(y)
        return unravel(flat - lu_solve(state.lu, ravel_pytree(fx)[0])), _AffineState(state.lu, state.steps + 1), aux

    def terminate(self, fn, y, args, options, state, tags):
        del fn, y, args, options, tags
        return state.steps >= 1, optx.RESULTS.successful

    def postprocess(self, fn, y, aux, args, options, state, tags, result):
        del fn, args, options, state, tags, result
        return y, aux, {}


def linearised_split(field, y0) -> diffrax.MultiTerm:
    """``(explicit, implicit)`` Diffrax terms of ``field(t, y, args)`` for an IMEX solver:
    the implicit part is the field's linearisation at ``(0, y0)`` over every state,
    ``J0 (y - y0)``, the explicit part the rest, so the two add up to ``field``."""
    x0, unravel = ravel_pytree(y0)
    jacobian = jax.jacfwd(lambda x: ravel_pytree(field(0.0, unravel(x), None))[0])(x0)

    def implicit(t, y, args):
        return unravel(jacobian @ (ravel_pytree(y)[0] - x0))

    def explicit(t, y, args):
        return jax.tree.map(jnp.subtract, field(t, y, args), implicit(t, y, args))

    return diffrax.MultiTerm(diffrax.ODETerm(explicit), diffrax.ODETerm(implicit))


def imex_solver() -> diffrax.KenCarp4:
    """``KenCarp4`` (4th order, L-stable implicit part) with :class:`AffineRootFinder`, for
    the terms of :func:`linearised_split`."""
    return diffrax.KenCarp4(root_finder=AffineRootFinder())
