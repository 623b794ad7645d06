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

The implicit stage equations are then linear in the unknown: :class:`LinearImplicitARK`
(Diffrax's KenCarp tableaux and dense output) factorises ``I - h gamma J0`` once per step
(both methods have one diagonal coefficient) and solves each stage with it, with no root
finder. Optimistix's Newton would re-linearise and iterate to a tolerance, Diffrax's chord
method (``VeryChord``) was seen to reject tens of thousands of steps at rtol 1e-4 on this
car, and even a one-step root finder left Diffrax's implicit stages their root-finding
machinery (a Jacobian cond per stage and, in reverse mode, a Jacobian materialised and
factorised per stage by the implicit-function rule): the step cost about 20 % more.

Some states are left out of the implicit part (``explicit``: their columns of ``J0`` are
zero, so the field's dependence on them stays whole in the explicit part): the car's
position and heading on the ground. The car's equations do not depend on them, except
through a closed-loop driver's path or a road, and there they are neither stiff nor close
to linear over a run (a car on a skid-pad goes round the circle). Linearised, their
columns put a term ``J0 (x - x0)`` into the stiff rows that grows with the distance
travelled, is cancelled by the explicit part, and held the closed-loop skid-pad's steps
near 9 ms where 35 ms hold its accuracy (docs/manoeuvre.md, "Speed").
"""

from typing import ClassVar

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.flatten_util import ravel_pytree

from .._differences import forward_difference_jacobian
from .._linalg import lu_factor, lu_solve
from ..multibody._simulate import _status
from ._replay import COUNTS, replayed_solve

#: The additive Runge-Kutta methods of :class:`LinearImplicitARK`, by name: Diffrax's solver
#: whose tableaux and dense output it takes, and its order.
IMEX_METHODS = {"kencarp5": (diffrax.KenCarp5, 5), "kencarp4": (diffrax.KenCarp4, 4)}


def _tableau_matrices(method: str):
    """The additive Runge-Kutta method ``method``'s coefficients from Diffrax's tableaux
    (NumPy): stage-coupling matrices ``a`` (explicit, implicit: stages x stages, the
    implicit one without its diagonal), the implicit diagonal ``gamma`` (stages,), the
    stage times ``c``, the weights ``b`` and error weights ``b_error`` of each part."""
    explicit, implicit = IMEX_METHODS[method][0].tableau.tableaus
    stages = implicit.num_stages

    def lower(tableau):
        a = np.zeros((stages, stages))
        for i, row in enumerate(tableau.a_lower, start=1):
            a[i, :i] = row
        return a

    c = np.concatenate([[explicit.c1], explicit.c])
    return ((lower(explicit), lower(implicit)), np.asarray(implicit.a_diagonal), c,
            (explicit.b_sol, implicit.b_sol), (explicit.b_error, implicit.b_error))


class LinearImplicitARK(diffrax.AbstractAdaptiveSolver):
    """Kennedy and Carpenter's additive Runge-Kutta method ``method`` ("kencarp5": 5th order,
    8 stages; "kencarp4": 4th order, 6 stages; Diffrax's tableaux and dense output) for
    terms ``MultiTerm(explicit, implicit)`` whose implicit part is linear with the
    constant matrix ``matrix`` (n x n): ``implicit(t, y) = matrix (y - y0) + const``, as
    :func:`linearised_split` builds (without ``matrix`` the solver takes the term's Jacobian
    at the start, by forward mode). The state is a flat array (n,).

    Each implicit stage equation ``y_i = z_i + h gamma implicit(y_i)`` is then linear,
    ``(I - h gamma matrix) (y_i - z_i) = h gamma implicit(z_i)``, and the step solves it
    with one LU factorisation per step (every stage has the same diagonal coefficient),
    with no root finder and no implicit-function rule in reverse mode: the derivatives are
    those of the stage arithmetic. Diffrax's ``KenCarp5`` with a root finder takes the
    same steps to the same solution with the same derivatives
    (tests/test_manoeuvre_imex.py); on the car this step's forward pass costs about 20 %
    less (docs/manoeuvre.md, "Speed", nineteenth measurement)."""

    matrix: jax.Array | None = None
    method: str = eqx.field(static=True, default="kencarp5")

    term_structure: ClassVar = diffrax.MultiTerm[tuple[diffrax.AbstractTerm, diffrax.AbstractTerm]]

    def __check_init__(self):
        if self.method not in IMEX_METHODS:
            raise ValueError(f"method = {self.method!r} is not an IMEX method: allowed "
                             f"{', '.join(map(repr, IMEX_METHODS))}")

    @property
    def interpolation_cls(self):
        return IMEX_METHODS[self.method][0].interpolation_cls

    def order(self, terms):
        del terms
        return IMEX_METHODS[self.method][1]

    def init(self, terms, t0, t1, y0, args):
        """The solver state: ``None`` with ``matrix`` given, else the implicit term's
        Jacobian at the start by forward mode (constant: the term is linear)."""
        del t1
        if jnp.ndim(y0) != 1:
            raise ValueError(f"LinearImplicitARK steps a flat state (n,): got shape {jnp.shape(y0)}")
        if self.matrix is not None:
            if self.matrix.shape != (y0.shape[0],) * 2:
                raise ValueError(f"matrix has shape {self.matrix.shape}: the implicit term's Jacobian over the "
                                 f"state of shape {y0.shape} is ({y0.shape[0]}, {y0.shape[0]})")
            return None
        return jax.lax.stop_gradient(jax.jacfwd(lambda y: terms.terms[1].vf(t0, y, args))(y0))

    def step(self, terms, t0, t1, y0, args, solver_state, made_jump):
        del made_jump
        matrix = self.matrix if self.matrix is not None else solver_state
        explicit, implicit = terms.terms
        (a_explicit, a_implicit), gamma, c, (b_explicit, b_implicit), (e_explicit, e_implicit) = (
            _tableau_matrices(self.method))
        h = t1 - t0
        stages, n = gamma.shape[0], y0.shape[0]
        factors = lu_factor(jnp.eye(n, dtype=y0.dtype) - (h * gamma[-1]) * matrix)

        def stage(ks, coefficients):
            k_explicit, k_implicit = ks
            i, row_explicit, row_implicit, diagonal, ci = coefficients
            z = y0 + row_explicit @ k_explicit + row_implicit @ k_implicit
            t = t0 + ci * h
            # diagonal is 0 at the explicit first stage: the solve then returns 0
            y = z + lu_solve(factors, (h * diagonal) * implicit.vf(t, z, args))
            k_explicit = k_explicit.at[i].set(h * explicit.vf(t, y, args))
            k_implicit = k_implicit.at[i].set(h * implicit.vf(t, y, args))
            return (k_explicit, k_implicit), None

        zeros = jnp.zeros((stages, n), y0.dtype)
        coefficients = (jnp.arange(stages), jnp.asarray(a_explicit, y0.dtype), jnp.asarray(a_implicit, y0.dtype),
                        jnp.asarray(gamma, y0.dtype), jnp.asarray(c, y0.dtype))
        (k_explicit, k_implicit), _ = jax.lax.scan(stage, (zeros, zeros), coefficients)
        y1 = y0 + jnp.asarray(b_explicit, y0.dtype) @ k_explicit + jnp.asarray(b_implicit, y0.dtype) @ k_implicit
        error = jnp.asarray(e_explicit, y0.dtype) @ k_explicit + jnp.asarray(e_implicit, y0.dtype) @ k_implicit
        # a non-finite step is rejected by the step-size controller, not saved
        error = jnp.where(jnp.all(jnp.isfinite(y1)), error, jnp.inf)
        dense_info = dict(y0=y0, y1=y1, k=(k_explicit, k_implicit))
        return y1, error, dense_info, solver_state, diffrax.RESULTS.successful

    def func(self, terms, t0, y0, args):
        explicit, implicit = terms.terms
        return explicit.vf(t0, y0, args) + implicit.vf(t0, y0, args)


def split_jacobian(field, y0, t0=0.0, explicit: tuple[int, ...] = ()) -> jax.Array:
    """The matrix ``J0`` of :func:`linearised_split`: the Jacobian of ``field`` over every
    state (flattened) at ``(t0, y0)``, a forward difference held out of differentiation,
    with zero columns at the flat indices ``explicit`` (states kept explicit, see the
    module docs; not evaluated)."""
    x0, unravel = ravel_pytree(y0)
    jacobian = forward_difference_jacobian(lambda x: ravel_pytree(field(t0, unravel(x), None))[0], x0,
                                           skip=tuple(explicit))
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


def imex_solver(matrix=None, method: str = "kencarp5") -> LinearImplicitARK:
    """``KenCarp5`` (5th order, 8 stages; or ``"kencarp4"``: 4th order, 6 stages; both with an
    L-stable implicit part) for the terms of :func:`linearised_split` (``matrix``: their
    ``J0``; :func:`relinearised_solve` sets it for each segment)."""
    return LinearImplicitARK(matrix=matrix, method=method)


def _with_matrix(solver, matrix):
    """``solver`` told the split's matrix when it is a :class:`LinearImplicitARK` without one
    (others as they are)."""
    if isinstance(solver, LinearImplicitARK) and solver.matrix is None:
        return eqx.tree_at(lambda s: s.matrix, solver, matrix, is_leaf=lambda x: x is None)
    return solver


def _segment_terms(params):
    """The split of a segment for :func:`._replay.replayed_solve`: ``params`` the field, the
    segment's start state and time and the split's matrix."""
    field, y0, t0, jacobian = params
    return linearised_split(field, y0, t0, jacobian)


def _plain_terms(params):
    """The unsplit field of a segment for :func:`._replay.replayed_solve`."""
    return diffrax.ODETerm(params[0])


class SegmentedSolution(eqx.Module):
    """What :func:`relinearised_solve` returns: ``ys`` the states at the save times (inf
    after a stop, as Diffrax fills them), ``status`` (0 completed, 1 stopped by an event, 2
    solver failure), ``event_mask`` (which event condition stopped the run) and ``stats``
    (steps, accepted and rejected steps summed over the segments)."""

    ys: object
    status: jax.Array
    event_mask: tuple
    stats: dict




def relinearised_solve(field, y0, t1, ts, *, segments: int, controller, event, dt0, max_steps: int,
                       adjoint=None, solver=None, split: bool = True,
                       explicit: tuple[int, ...] = ()) -> SegmentedSolution:
    """Integrate ``field(t, y, args)`` from ``y0`` at t = 0 to ``t1`` (s), saving at ``ts``
    (s, in [0, t1]) by Diffrax's dense output, in ``segments`` equal time segments. With
    ``split`` each segment integrates :func:`linearised_split` at its own start state
    (``explicit``: the flat indices of the states it keeps explicit; ``solver`` default
    :func:`imex_solver`); without it ``field`` itself (``solver`` default
    Tsit5). A segment starts with the mean accepted step of the one before (``dt0`` the
    first); ``controller``, ``event`` and ``max_steps`` (per segment) go to every segment's
    ``diffeqsolve``, and ``adjoint`` too when given; by default reverse mode replays each
    segment's accepted steps (:func:`._replay.replayed_solve`). After a stop (an event or a
    failure) the later segments are skipped. One compiled segment solve, run in a ``lax.scan``: the program holds the
    vector field as often as one solve does."""
    if solver is None:
        solver = imex_solver() if split else diffrax.Tsit5()
    edges = jnp.linspace(0.0, t1, segments + 1)
    n_conditions = len(jax.tree.leaves(event.cond_fn, is_leaf=callable))
    # the solver steps one flat vector (fewer operations per step than a pytree state)
    x0, unravel = ravel_pytree(y0)

    def flat_field(t, x, args):
        return ravel_pytree(field(t, unravel(x), args))[0]

    flat_event = eqx.tree_at(lambda e: e.cond_fn, event, jax.tree.map(
        lambda c: lambda t, x, args, **kw: c(t, unravel(x), args, **kw), event.cond_fn, is_leaf=callable))

    def run(y, dt, a, b):
        save_ts = jnp.clip(ts, a, b)
        jacobian = split_jacobian(flat_field, y, a, explicit) if split else None
        seg_solver = _with_matrix(solver, jacobian) if split else solver
        if adjoint is None:
            # the field's closed-over parameters made explicit, so the replay differentiates them
            params = (eqx.filter_closure_convert(flat_field, a, y, None), y, a, jacobian)
            sol = replayed_solve(_segment_terms if split else _plain_terms, params, y, a, b, dt, save_ts,
                                 solver=seg_solver, controller=controller, event=flat_event, max_steps=max_steps)
            ys, y_end, result, event_mask, stats = sol.ys, sol.y_end, sol.result, sol.event_mask, sol.stats
        else:
            terms = linearised_split(flat_field, y, a, jacobian) if split else diffrax.ODETerm(flat_field)
            sol = diffrax.diffeqsolve(terms, seg_solver, a, b, dt, y, saveat=diffrax.SaveAt(ts=save_ts, t1=True),
                                      event=flat_event, stepsize_controller=controller, max_steps=max_steps,
                                      throw=False, adjoint=adjoint)
            ys, y_end, result, event_mask, stats = sol.ys[:-1], sol.ys[-1], sol.result, sol.event_mask, sol.stats
        counts = jnp.stack([jnp.asarray(stats[k], jnp.int32) for k in COUNTS])
        mask = jnp.stack([jnp.asarray(m, bool) for m in jax.tree.leaves(event_mask)])
        return ys, y_end, _status(result).astype(jnp.int32), mask, counts

    def skip(y, dt, a, b):
        del dt, a, b
        return (jnp.full(ts.shape + y.shape, jnp.inf, y.dtype), y, jnp.asarray(0, jnp.int32),
                jnp.zeros(n_conditions, bool), jnp.zeros(len(COUNTS), jnp.int32))

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
    stats = {k: counts[:, i].sum() for i, k in enumerate(COUNTS)} | {"max_steps": max_steps}
    return SegmentedSolution(ys=jax.vmap(unravel)(ys), status=status, event_mask=tuple(masks.any(axis=0)), stats=stats)
