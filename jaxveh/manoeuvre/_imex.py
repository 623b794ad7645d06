"""IMEX integration of the fast car (docs/manoeuvre.md, "Solvers").

The car's vector field is split into a linear part taken implicitly, its Jacobian at the
start ``J0 (x - x0)`` over every state (a forward difference, held out of
differentiation), and the rest, ``f(x) - J0 (x - x0)``, taken explicitly by Diffrax's
additive Runge-Kutta method ``KenCarp5`` (or ``KenCarp4``); the two parts add up to the exact vector field.
The stiff motions of the car (the chassis modes at up to 525 rad/s, the tyres' relaxation
at speed / relaxation length, wheel hop and wheel spin) are close to linear about the
start, so the explicit remainder is no longer stiff and the step follows the manoeuvre.

As the car turns away from the state it was linearised at, the remainder grows stiff again
and the steps shrink (the benchmark step steer: 45 steps of 44 ms over its last 2 s).
:func:`relinearised_solve` therefore cuts the run into equal time segments and linearises
again at the start of each, one compiled segment solve in a ``lax.scan``: with KenCarp4
three segments took the step steer from 274 to about 210 steps, with KenCarp5 four take it
in about 140 (docs/manoeuvre.md, "Speed").

The implicit stage equations are then affine in the unknown, so one Newton step solves
them exactly: :class:`AffineRootFinder` factorises their Jacobian once per step (Diffrax
computes it at the second stage and reuses it for the others, both methods having one
diagonal coefficient) and takes one step per stage, where Optimistix's Newton would
re-linearise and iterate to a tolerance, and Diffrax's chord method (``VeryChord``) was
seen to reject tens of thousands of steps at rtol 1e-4 on this car.

Some states are left out of the implicit part (``explicit``: their columns of ``J0`` are
zero, so the field's dependence on them stays whole in the explicit part): the car's
position and heading on the ground. The car's equations do not depend on them, except
through a closed-loop driver's path or a road, and there they are neither stiff nor close
to linear over a run (a car on a skid-pad goes round the circle). Linearised, their
columns put a term ``J0 (x - x0)`` into the stiff rows that grows with the distance
travelled, is cancelled by the explicit part, and held the closed-loop skid-pad's steps
near 9 ms where 35 ms hold its accuracy (docs/manoeuvre.md, "Speed").
"""

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import optimistix as optx
from jax.flatten_util import ravel_pytree

from .._differences import forward_difference_jacobian
from .._linalg import lu_factor, lu_solve
from ..multibody._simulate import _status


class _AffineState(eqx.Module):
    lu: tuple
    steps: jax.Array


class AffineRootFinder(optx.AbstractRootFinder):
    """Root finder for an affine function ``fn(y) = A y + b``: the LU factors of ``A`` and
    one Newton step, which is exact up to round-off. Only for affine functions: nothing
    checks the residual afterwards (the implicit part of :func:`linearised_split` is affine
    by construction).

    ``A`` comes from forward mode over every state, or, given ``matrix`` (the ``J`` of an
    implicit term ``J (y - y0)``), as ``I - s J`` with the scalar ``s`` read from one
    directional derivative: the stage equations of a diagonally implicit Runge-Kutta method
    on that term have this form (``s`` = the diagonal coefficient times the step), and
    pushing every unit vector through ``J`` (a matrix product of the state's size cubed each
    step) is then not needed."""

    matrix: jax.Array | None = None
    rtol: float = 0.0  # unused: one step is exact (the fields Optimistix's root finders have)
    atol: float = 0.0
    norm: object = optx.max_norm

    def init(self, fn, y, args, options, f_struct, aux_struct, tags):
        if "init_state" in options:  # Diffrax's Jacobian of an earlier stage of the step
            return options["init_state"]
        flat, unravel = ravel_pytree(y)

        def flat_fn(x):
            return ravel_pytree(fn(unravel(x), args)[0])[0]

        if self.matrix is None:
            jacobian = jax.jacfwd(flat_fn)(flat)
        else:
            jacobian = _identity_minus_scaled(self.matrix, flat_fn, flat)
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


def _identity_minus_scaled(matrix, fn, x):
    """The Jacobian ``I - s J`` of an affine ``fn`` at ``x`` (``J`` = ``matrix``), ``s`` by
    least squares from one directional derivative along a fixed direction with no zero
    entry (``I`` where ``J`` maps it to zero, so that ``s`` is immaterial)."""
    probe = jnp.cos(jnp.arange(1.0, x.shape[0] + 1.0))
    moved = jax.jvp(fn, (x,), (probe,))[1]
    image = matrix @ probe
    norm = jnp.dot(image, image)
    scale = jnp.where(norm > 0.0, jnp.dot(image, probe - moved) / jnp.where(norm > 0.0, norm, 1.0), 0.0)
    return jnp.eye(x.shape[0], dtype=x.dtype) - scale * matrix


def split_jacobian(field, y0, t0=0.0, explicit: tuple[int, ...] = ()) -> jax.Array:
    """The matrix ``J0`` of :func:`linearised_split`: the Jacobian of ``field`` over every
    state (flattened) at ``(t0, y0)``, a forward difference held out of differentiation,
    with zero columns at the flat indices ``explicit`` (states kept explicit, see the
    module docs)."""
    x0, unravel = ravel_pytree(y0)
    jacobian = forward_difference_jacobian(lambda x: ravel_pytree(field(t0, unravel(x), None))[0], x0)
    if explicit:
        jacobian = jacobian.at[:, jnp.asarray(explicit)].set(0.0)
    return jax.lax.stop_gradient(jacobian)


def linearised_split(field, y0, t0=0.0, jacobian=None, explicit: tuple[int, ...] = ()) -> diffrax.MultiTerm:
    """``(explicit, implicit)`` Diffrax terms of ``field(t, y, args)`` for an IMEX solver:
    the implicit part is the field's linearisation at ``(t0, y0)`` over every state but the
    flat indices ``explicit`` (module docs), ``J0 (y - y0)``, the explicit part the rest, so
    the two add up to ``field``.

    The parts add up to ``field`` whatever the matrix, so ``J0`` only needs to be close:
    it is a forward difference (:func:`split_jacobian`; ``jacobian`` gives it instead;
    :func:`jaxveh._differences.forward_difference_jacobian`,
    one copy of the field in the program where ``jax.jacfwd`` compiled in about five times
    the field's time), and it is held out of differentiation. The solution depends on it
    only through the discretisation error, and the derivatives of the run are those of the
    same scheme with the matrix fixed, a consistent discretisation of the sensitivity
    equations; derivatives of ``J0`` would be second derivatives of the field, which
    tripled the compile time of a gradient."""
    x0, unravel = ravel_pytree(y0)
    jacobian = split_jacobian(field, y0, t0, explicit) if jacobian is None else jacobian

    def implicit_part(t, y, args):
        return unravel(jacobian @ (ravel_pytree(y)[0] - x0))

    def explicit_part(t, y, args):
        return jax.tree.map(jnp.subtract, field(t, y, args), implicit_part(t, y, args))

    return diffrax.MultiTerm(diffrax.ODETerm(explicit_part), diffrax.ODETerm(implicit_part))


#: The additive Runge-Kutta methods :func:`imex_solver` builds, by name.
IMEX_METHODS = {"kencarp5": diffrax.KenCarp5, "kencarp4": diffrax.KenCarp4}


def imex_solver(matrix=None, method: str = "kencarp5") -> diffrax.AbstractSolver:
    """``KenCarp5`` (5th order, 8 stages; or ``"kencarp4"``: 4th order, 6 stages; both with an
    L-stable implicit part) with :class:`AffineRootFinder`, for the terms of
    :func:`linearised_split` (``matrix``: their ``J0``, which spares the root finder a
    forward-mode Jacobian each step)."""
    if method not in IMEX_METHODS:
        raise ValueError(f"method = {method!r} is not an IMEX method: allowed {', '.join(map(repr, IMEX_METHODS))}")
    return IMEX_METHODS[method](root_finder=AffineRootFinder(matrix=matrix))


def _with_matrix(solver, matrix):
    """``solver`` with its :class:`AffineRootFinder` told the split's matrix (others as
    they are)."""
    finder = getattr(solver, "root_finder", None)
    if isinstance(finder, AffineRootFinder) and finder.matrix is None:
        return eqx.tree_at(lambda s: s.root_finder, solver, AffineRootFinder(matrix=matrix))
    return solver


class SegmentedSolution(eqx.Module):
    """What :func:`relinearised_solve` returns: ``ys`` the states at the save times (inf
    after a stop, as Diffrax fills them), ``status`` (0 completed, 1 stopped by an event, 2
    solver failure), ``event_mask`` (which event condition stopped the run) and ``stats``
    (steps, accepted and rejected steps summed over the segments)."""

    ys: object
    status: jax.Array
    event_mask: tuple
    stats: dict


_COUNTS = ("num_steps", "num_accepted_steps", "num_rejected_steps")


def relinearised_solve(field, y0, t1, ts, *, segments: int, controller, event, dt0, max_steps: int,
                       adjoint=None, solver=None, split: bool = True,
                       explicit: tuple[int, ...] = ()) -> SegmentedSolution:
    """Integrate ``field(t, y, args)`` from ``y0`` at t = 0 to ``t1`` (s), saving at ``ts``
    (s, in [0, t1]) by Diffrax's dense output, in ``segments`` equal time segments. With
    ``split`` each segment integrates :func:`linearised_split` at its own start state
    (``explicit``: the flat indices of the states it keeps explicit; ``solver`` default
    :func:`imex_solver`); without it ``field`` itself (``solver`` default
    Tsit5). A segment starts with the mean accepted step of the one before (``dt0`` the
    first); ``controller``, ``event``, ``max_steps`` (per segment) and ``adjoint`` go to
    every segment's ``diffeqsolve``. After a stop (an event or a failure) the later segments
    are skipped. One compiled segment solve, run in a ``lax.scan``: the program holds the
    vector field as often as one solve does."""
    if solver is None:
        solver = imex_solver() if split else diffrax.Tsit5()
    edges = jnp.linspace(0.0, t1, segments + 1)
    n_conditions = len(jax.tree.leaves(event.cond_fn, is_leaf=callable))
    options = {} if adjoint is None else {"adjoint": adjoint}
    # the solver steps one flat vector (fewer operations per step than a pytree state)
    x0, unravel = ravel_pytree(y0)

    def flat_field(t, x, args):
        return ravel_pytree(field(t, unravel(x), args))[0]

    flat_event = eqx.tree_at(lambda e: e.cond_fn, event, jax.tree.map(
        lambda c: lambda t, x, args, **kw: c(t, unravel(x), args, **kw), event.cond_fn, is_leaf=callable))

    def run(y, dt, a, b):
        if split:
            jacobian = split_jacobian(flat_field, y, a, explicit)
            terms, seg_solver = linearised_split(flat_field, y, a, jacobian), _with_matrix(solver, jacobian)
        else:
            terms, seg_solver = diffrax.ODETerm(flat_field), solver
        sol = diffrax.diffeqsolve(terms, seg_solver, a, b, dt, y, saveat=diffrax.SaveAt(ts=jnp.clip(ts, a, b), t1=True),
                                  event=flat_event, stepsize_controller=controller, max_steps=max_steps, throw=False,
                                  **options)
        counts = jnp.stack([jnp.asarray(sol.stats[k], jnp.int32) for k in _COUNTS])
        mask = jnp.stack([jnp.asarray(m, bool) for m in jax.tree.leaves(sol.event_mask)])
        status = _status(sol.result).astype(jnp.int32)
        return sol.ys[:-1], sol.ys[-1], status, mask, counts

    def skip(y, dt, a, b):
        del dt, a, b
        return (jnp.full(ts.shape + y.shape, jnp.inf, y.dtype), y, jnp.asarray(0, jnp.int32),
                jnp.zeros(n_conditions, bool), jnp.zeros(len(_COUNTS), jnp.int32))

    def segment(carry, ab):
        y, dt, status = carry
        a, b = ab
        ys, y_end, seg_status, mask, counts = jax.lax.cond(status != 0, skip, run, y, dt, a, b)
        mean_step = jnp.minimum((b - a) / jnp.maximum(counts[1], 1).astype(b.dtype), b - a)
        return (y_end, mean_step, jnp.maximum(status, seg_status)), (ys, mask, counts)

    dt0 = jnp.asarray(dt0, ts.dtype)
    if segments == 1:  # the plain solve: no loop, no branch
        ys, _, status, mask, count = run(x0, dt0, edges[0], edges[1])
        masks, counts = mask[None], count[None]
    else:
        start = (x0, dt0, jnp.asarray(0, jnp.int32))
        (_, _, status), (ys, masks, counts) = jax.lax.scan(segment, start, (edges[:-1], edges[1:]))
        # each save time from the segment it falls in (the last one holds t1)
        which = jnp.clip(jnp.searchsorted(edges, ts, side="right") - 1, 0, segments - 1)
        ys = ys[which, jnp.arange(ts.shape[0])]
    stats = {k: counts[:, i].sum() for i, k in enumerate(_COUNTS)} | {"max_steps": max_steps}
    return SegmentedSolution(ys=jax.vmap(unravel)(ys), status=status, event_mask=tuple(masks.any(axis=0)), stats=stats)
