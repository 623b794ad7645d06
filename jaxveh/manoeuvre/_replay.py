"""Reverse mode through an adaptive solve by replaying its accepted steps (docs/manoeuvre.md,
"Gradients").

Diffrax's step-size controller holds its step sizes out of differentiation, so the derivative
of an adaptive solve is the derivative of the fixed sequence of accepted steps it took: the
discrete adjoint of that sequence. :func:`replayed_solve` runs the solve forward with
Diffrax, recording every accepted step's end time and state; its reverse pass walks the
recorded steps backwards, each one recomputed from its start state and differentiated
(``jax.vjp`` of the solver's step and of its dense output at the save times it holds). The
reverse loop carries only the state's and the parameters' cotangents: none of the
checkpoint buffers, save-time loops and solver and controller states that Diffrax's
recursive checkpointing carries through every step. Same derivative as Diffrax's default
adjoint to round-off (tests/test_manoeuvre_replay.py).

The forward pass keeps at most :data:`REPLAY_STEPS` accepted steps (or ``max_steps``, if
fewer); a differentiated solve that needs more stops there and its reverse pass raises,
naming the remedies. Forward mode (``jax.jvp``) is not available through it: use
``adjoint=diffrax.ForwardMode()``.
"""

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp

#: Accepted steps a differentiated solve keeps for its reverse pass (per solve: per segment of
#: :func:`._imex.relinearised_solve`); each costs one state of memory (the fast car: 6.7 MB in all).
REPLAY_STEPS = 16_384
#: Diffrax's step counts a :class:`ReplayedSolution` reports.
COUNTS = ("num_steps", "num_accepted_steps", "num_rejected_steps")
#: Save times the reverse pass takes at a time from a step's dense output (a step holding more
#: takes several windows).
SAVE_WINDOW = 8


class ReplayedSolution(eqx.Module):
    """What :func:`replayed_solve` returns: ``ys`` the states at ``ts`` (inf where the solve
    stopped before), ``y_end`` the last state, Diffrax's ``result``, ``event_mask`` and
    ``stats`` (its :data:`COUNTS`)."""

    ys: jax.Array
    y_end: jax.Array
    result: object
    event_mask: object
    stats: dict


def _diffeqsolve(terms, solver, t0, t1, dt0, y0, ts, controller, event, max_steps, record_steps: bool):
    subs = [diffrax.SubSaveAt(ts=ts, t1=True)] + ([diffrax.SubSaveAt(steps=True)] if record_steps else [])
    sol = diffrax.diffeqsolve(terms, solver, t0, t1, dt0, y0, saveat=diffrax.SaveAt(subs=subs), event=event,
                              stepsize_controller=controller, max_steps=max_steps, throw=False)
    ys = sol.ys[0]
    out = ReplayedSolution(ys=ys[:-1], y_end=ys[-1], result=sol.result, event_mask=sol.event_mask,
                           stats={k: sol.stats[k] for k in COUNTS})
    return out, (sol.ts[1], sol.ys[1]) if record_steps else None


@eqx.filter_custom_vjp
def _replayed(params_and_y0, terms_fn, solver, t0, t1, dt0, ts, controller, event, max_steps):
    params, y0 = params_and_y0
    return _diffeqsolve(terms_fn(params), solver, t0, t1, dt0, y0, ts, controller, event, max_steps, False)[0]


@_replayed.def_fwd
def _replayed_fwd(perturbed, params_and_y0, terms_fn, solver, t0, t1, dt0, ts, controller, event, max_steps):
    del perturbed
    params, y0 = params_and_y0
    kept = min(max_steps, REPLAY_STEPS)
    out, (step_ts, step_ys) = _diffeqsolve(terms_fn(params), solver, t0, t1, dt0, y0, ts, controller, event, kept,
                                           True)
    capped = (kept < max_steps) & (out.result == diffrax.RESULTS.max_steps_reached)
    return out, (step_ts, step_ys, out.stats["num_accepted_steps"], capped)


def _zeros_or(cotangent, like):
    return jnp.zeros_like(like) if cotangent is None else cotangent


def _step_times(t0, recorded, jump_ts):
    """Each accepted step's start and end (s) from the times Diffrax records: a step cut short
    before a jump time ends just before it (``prevbefore``) and the next starts just after,
    where Diffrax records that start as the step's end."""
    starts = jnp.concatenate([jnp.reshape(t0, (1,)).astype(recorded.dtype), recorded[:-1]])
    if jump_ts is None:
        return starts, recorded
    jump_ts = jnp.asarray(jump_ts, recorded.dtype)
    next_jump = jnp.min(jnp.where(jump_ts[None, :] > starts[:, None], jump_ts[None, :], jnp.inf), axis=1)
    before_jump = jnp.nextafter(next_jump, -jnp.inf)
    return starts, jnp.where(jnp.isfinite(next_jump), jnp.minimum(recorded, before_jump), recorded)


@_replayed.def_bwd
def _replayed_bwd(residuals, grad_out, perturbed, params_and_y0, terms_fn, solver, t0, t1, dt0, ts, controller,
                  event, max_steps):
    del t1, dt0, event
    recorded_ts, step_ys, accepted, capped = residuals
    params, y0 = params_and_y0
    step_ys = eqx.error_if(step_ys, capped, f"the reverse pass replays at most {min(max_steps, REPLAY_STEPS)} accepted "
                                            "steps per solve (jaxveh.manoeuvre._replay.REPLAY_STEPS) and this solve "
                                            "took more: differentiate with more linearisations (segments), or pass "
                                            "adjoint=diffrax.RecursiveCheckpointAdjoint()")
    starts, ends = _step_times(t0, recorded_ts, getattr(controller, "jump_ts", None))
    ct_ys = _zeros_or(grad_out.ys, jnp.zeros(ts.shape + y0.shape, y0.dtype))
    ct_end = _zeros_or(grad_out.y_end, y0)
    # the step whose dense output saved each save time (Diffrax: the first step ending at or after it)
    saved_in = jnp.searchsorted(ends, ts, side="left")
    accepted = accepted.astype(saved_in.dtype)  # Diffrax's count is int64 under vmap
    # Diffrax writes the final state into the slot after the last save time reached: the t1 slot
    # of a completed solve, the first unreached save time's of a stopped one
    reached = jnp.sum(saved_in < accepted)
    ct_final = jnp.concatenate([ct_ys, ct_end[None]])[reached]
    diff_params, static_params = eqx.partition(params, perturbed[0])

    def step(diff, y, t_start, t_end):
        terms = terms_fn(eqx.combine(diff, static_params))
        state = solver.init(terms, t_start, t_end, y, None)
        y1, _, dense, _, _ = solver.step(terms, t_start, t_end, y, None, state, False)
        return y1, dense

    def saves_cotangent(dense, t_start, t_end, n):
        """The cotangent of step ``n``'s dense output from the save times it holds (a
        contiguous run of them: both are sorted), :data:`SAVE_WINDOW` at a time: the
        interpolation is differentiated at these times only, not at every save time."""
        first = jnp.searchsorted(saved_in, n, side="left")
        count = jnp.searchsorted(saved_in, n, side="right") - first
        window = jnp.arange(SAVE_WINDOW, dtype=first.dtype)

        def evaluate(d, t):
            return solver.interpolation_cls(t0=t_start, t1=t_end, **d).evaluate(t)

        def chunk(carry):
            j, ct_dense = carry
            index = first + j * SAVE_WINDOW + window
            held = j * SAVE_WINDOW + window < count
            index = jnp.minimum(index, ts.shape[0] - 1)
            times = jnp.clip(ts[index], t_start, t_end)
            _, vjp = jax.vjp(lambda d: jax.vmap(evaluate, in_axes=(None, 0))(d, times), dense)
            (g,) = vjp(jnp.where(held[:, None], ct_ys[index], 0.0))
            return j + 1, jax.tree.map(jnp.add, ct_dense, g)

        zero = jax.tree.map(jnp.zeros_like, dense)
        return jax.lax.while_loop(lambda c: c[0] * SAVE_WINDOW < count, chunk, (jnp.zeros_like(count), zero))[1]

    def back(i, carry):
        ct_y, ct_diff = carry
        n = accepted - 1 - i
        y = jnp.where(n == 0, y0, step_ys[jnp.maximum(n - 1, 0)])
        (_, dense), vjp = jax.vjp(lambda d, x: step(d, x, starts[n], ends[n]), diff_params, y)
        g_diff, g_y = vjp((ct_y, saves_cotangent(dense, starts[n], ends[n], n)))
        return g_y, jax.tree.map(jnp.add, ct_diff, g_diff)

    ct_y0, ct_diff = jax.lax.fori_loop(0, accepted, back, (ct_final, jax.tree.map(jnp.zeros_like, diff_params)))
    return ct_diff, (ct_y0 if perturbed[1] else None)


def replayed_solve(terms_fn, params, y0, t0, t1, dt0, ts, *, solver, controller, event, max_steps: int
                   ) -> ReplayedSolution:
    """Diffrax's adaptive solve of ``terms_fn(params)`` from ``y0`` (a flat array) at ``t0`` to
    ``t1`` (s) with ``solver``, ``controller``, ``event`` and ``max_steps``, saving at ``ts``
    (s, sorted, in [t0, t1]) and at t1, whose reverse-mode derivative with respect to
    ``params`` (a pytree: its inexact arrays) and ``y0`` replays the accepted steps (module
    docs). ``solver`` must step from ``init`` alone (its state is rebuilt at every replayed
    step), as Diffrax's Runge-Kutta methods and :class:`._imex.LinearImplicitARK` do."""
    return _replayed((params, y0), terms_fn, solver, t0, t1, dt0, ts, controller, event, max_steps)
