"""Reverse mode by replaying the accepted steps (jaxveh.manoeuvre._replay): the same solution
and, to round-off, the same derivative as Diffrax's recursive checkpointing (Diffrax holds the
step sizes out of differentiation, so both differentiate the same sequence of steps), for
the linear-implicit IMEX step and an explicit one, with steps ending at a jump of the field
and an event stopping the run, under ``vmap``, and through the car's segmented solve; a
solve past the replay's step budget is refused by name in the reverse pass."""

import diffrax
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxveh  # noqa: F401  (float64)
from jaxveh.manoeuvre import _replay
from jaxveh.manoeuvre._imex import imex_solver, linearised_split, relinearised_solve, split_jacobian
from jaxveh.manoeuvre._replay import replayed_solve

Y0 = jnp.asarray([0.0, 0.0, 1.0, 0.0])
P0 = {"k": jnp.asarray(500.0), "c": jnp.asarray(0.02)}
#: save times: the start, one on the end, and times between (some steps hold several)
TS = jnp.concatenate([jnp.linspace(0.0, 1.5, 16), jnp.asarray([2.0])])


#: a jump of the forcing (s), where steps end (Diffrax's ``jump_ts``)
JUMP = 0.77


def _field(t, y, p):
    """A stiff oscillator (``k`` rad/s, damping ratio ``c``) coupled to a pendulum forced by a
    sine and a step at :data:`JUMP` (a field discontinuous in time, as the car's steering
    input's derivatives are at its kinks)."""
    x, v, q, w = y
    k, c = p["k"], p["c"]
    return jnp.stack([v, -k**2 * (x - 0.01 * jnp.sin(q)) - 2 * c * k * v, w,
                      -10.0 * jnp.sin(q) + x + 0.5 * jnp.sin(3.0 * t) + jnp.where(t >= JUMP, 2.0 * jnp.cos(q), 0.0)])


def _controller():
    return diffrax.PIDController(rtol=1e-6, atol=1e-8, jump_ts=jnp.asarray([JUMP]))


def _split_terms(params):
    p, x0, jacobian = params
    return linearised_split(lambda t, y, args: _field(t, y, p), x0, jacobian=jacobian)


def _plain_terms(params):
    return diffrax.ODETerm(lambda t, y, args: _field(t, y, params[0]))


def _solve(p, y0, method: str, replay: bool, stop_below: float):
    """``(ys at TS, final state)`` of the test system from ``y0`` to t = 2 s."""
    controller = _controller()
    event = diffrax.Event(lambda t, y, args, **kw: y[2] < stop_below)
    if method == "tsit5":
        terms_fn, solver, params = _plain_terms, diffrax.Tsit5(), (p,)
    else:
        jacobian = split_jacobian(lambda t, y, args: _field(t, y, p), y0)
        terms_fn, solver, params = _split_terms, imex_solver(matrix=jacobian, method=method), (p, y0, jacobian)
    if replay:
        sol = replayed_solve(terms_fn, params, y0, 0.0, 2.0, 1e-3, TS, solver=solver, controller=controller,
                             event=event, max_steps=100_000)
        return sol.ys, sol.y_end
    sol = diffrax.diffeqsolve(terms_fn(params), solver, 0.0, 2.0, 1e-3, y0, saveat=diffrax.SaveAt(ts=TS, t1=True),
                              stepsize_controller=controller, event=event, max_steps=100_000, throw=False)
    return sol.ys[:-1], sol.ys[-1]


def _loss(p, y0, method, replay, stop_below):
    ys, y_end = _solve(p, y0, method, replay, stop_below)
    valid = jnp.isfinite(ys[:, 0])
    ys = jnp.where(valid[:, None], ys, 0.0)  # save times after a stop hold inf
    return jnp.sum(ys[:, 2] * jnp.arange(1.0, TS.shape[0] + 1)) + 3.0 * y_end[0] + 1e-3 * y_end[1]


@pytest.mark.parametrize("method", ["kencarp5", "tsit5"])
@pytest.mark.parametrize("stop_below", [-5.0, 0.5], ids=["completed", "stopped-by-event"])
def test_replay_gives_diffrax_solution_and_derivative(method, stop_below):
    """The replayed solve returns Diffrax's saved states and final state, and its derivative
    with respect to the parameters and the initial state equals Diffrax's recursive
    checkpointing's to round-off, for a completed run and one an event stops."""
    runs = [_solve(P0, Y0, method, replay, stop_below) for replay in (False, True)]
    for a, b in zip(*runs):
        np.testing.assert_array_equal(b, a)
    if stop_below > 0:
        assert not np.all(np.isfinite(runs[0][0][:, 0])), "the event should stop the run before t = 2 s"
    grads = [jax.jit(jax.grad(_loss, argnums=(0, 1)), static_argnums=(2, 3, 4))(P0, Y0, method, replay, stop_below)
             for replay in (False, True)]
    for a, b in zip(jax.tree.leaves(grads[0]), jax.tree.leaves(grads[1])):
        assert np.all(np.isfinite(b))
        np.testing.assert_allclose(b, a, rtol=1e-9, atol=1e-12 * float(np.max(np.abs(a))))


@pytest.mark.parametrize("window", [1, 2])
def test_replay_takes_a_step_s_save_times_window_by_window(monkeypatch, window):
    """Steps holding more save times than the reverse pass's window (here 1 or 2 at a time;
    the dense save times put up to three in a step) give Diffrax's derivative to round-off."""
    monkeypatch.setattr(_replay, "SAVE_WINDOW", window)
    dense = jnp.linspace(0.0, 2.0, 2001)

    def loss(p, replay):
        jacobian = split_jacobian(lambda t, y, args: _field(t, y, p), Y0)
        solver, params = imex_solver(matrix=jacobian), (p, Y0, jacobian)
        if replay:
            ys = replayed_solve(_split_terms, params, Y0, 0.0, 2.0, 1e-3, dense, solver=solver,
                                controller=_controller(), event=None, max_steps=100_000).ys
        else:
            ys = diffrax.diffeqsolve(_split_terms(params), solver, 0.0, 2.0, 1e-3, Y0,
                                     saveat=diffrax.SaveAt(ts=dense), stepsize_controller=_controller(),
                                     max_steps=100_000).ys
        return jnp.sum(ys[:, 2] * jnp.sin(7.0 * dense)) + jnp.sum(ys[:, 0] ** 2)

    held = jnp.bincount(jnp.searchsorted(_accepted_ends(P0), dense, side="left"))
    assert int(held.max()) > window, "some step should hold more save times than the window"
    derivatives = [jax.jit(jax.grad(loss), static_argnums=1)(P0, replay) for replay in (False, True)]
    for a, b in zip(jax.tree.leaves(derivatives[0]), jax.tree.leaves(derivatives[1])):
        np.testing.assert_allclose(b, a, rtol=1e-9)


def _accepted_ends(p):
    """The accepted steps' end times (s) of the split test system's solve to 2 s."""
    jacobian = split_jacobian(lambda t, y, args: _field(t, y, p), Y0)
    sol = diffrax.diffeqsolve(_split_terms((p, Y0, jacobian)), imex_solver(matrix=jacobian), 0.0, 2.0, 1e-3, Y0,
                              saveat=diffrax.SaveAt(steps=True), stepsize_controller=_controller(),
                              max_steps=100_000)
    return sol.ts[jnp.isfinite(sol.ts)]


def test_replay_under_vmap():
    """A vmapped batch of derivatives (members taking different numbers of steps) equals the
    members' derivatives one by one."""
    ks = jnp.asarray([300.0, 500.0, 800.0])

    def grad_k(k):
        return jax.grad(_loss)({"k": k, "c": P0["c"]}, Y0, "kencarp5", True, -5.0)["k"]

    batched = jax.jit(jax.vmap(grad_k))(ks)
    np.testing.assert_allclose(batched, [jax.jit(grad_k)(k) for k in ks], rtol=1e-12)


def test_relinearised_solve_replays_as_diffrax_differentiates():
    """Through the segmented, relinearised solve (the fast car's), the default reverse mode
    gives the derivative Diffrax's recursive checkpointing gives, to round-off."""
    ts = jnp.linspace(0.0, 2.0, 41)

    def loss(scale, adjoint):
        sol = relinearised_solve(lambda t, y, args: _field(t, y, {"k": 500.0 * scale, "c": P0["c"]}), Y0, 2.0, ts,
                                 segments=3, controller=_controller(),
                                 event=diffrax.Event(lambda t, y, args, **kw: y[2] < -5.0), dt0=1e-3,
                                 max_steps=100_000, adjoint=adjoint)
        return jnp.sum(sol.ys[:, 2] ** 2) + sol.ys[-1, 0]

    derivatives = [jax.jit(jax.grad(loss), static_argnums=1)(1.0, adjoint)
                   for adjoint in (diffrax.RecursiveCheckpointAdjoint(), None)]
    np.testing.assert_allclose(derivatives[1], derivatives[0], rtol=1e-9)


def test_replay_refuses_a_solve_past_its_step_budget(monkeypatch):
    """A differentiated solve needing more accepted steps than the replay keeps stops there, and
    its reverse pass raises, naming the remedies; the undifferentiated solve is not limited."""
    monkeypatch.setattr(_replay, "REPLAY_STEPS", 5)
    ys, _ = jax.jit(_solve, static_argnums=(2, 3, 4))(P0, Y0, "kencarp5", True, -5.0)
    assert np.all(np.isfinite(ys))
    with pytest.raises(Exception, match=r"replays at most 5 accepted steps .* more linearisations"):
        jax.block_until_ready(jax.jit(jax.grad(_loss), static_argnums=(2, 3, 4))(P0, Y0, "kencarp5", True, -5.0))
