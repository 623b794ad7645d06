"""The fast car's IMEX pieces (jaxveh.manoeuvre._imex) on small systems: the linear-implicit
solver against Diffrax's KenCarp with Newton, the linearised split adding up to the vector
field, and KenCarp4 with both on a stiff oscillator coupled to a slow pendulum against SciPy's
implicit Radau at tight tolerance, and derivatives through the solve (reverse and forward
mode) against a central difference; the same in time segments linearised again at each
segment's start (``relinearised_solve``), and a stop by an event in a segment. The car's
step steer with it, and its step count against the explicit solver's:
tests/test_manoeuvre.py."""

import diffrax
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
import pytest
import scipy.integrate

import jaxveh  # noqa: F401  (float64)
from jaxveh.manoeuvre._imex import (
    LinearImplicitARK,
    imex_solver,
    linearised_split,
    relinearised_solve,
    split_jacobian,
)


def _stiff_field(t, y, args, np=jnp):
    """A 500 rad/s oscillator (1 % damping) coupled to a slow nonlinear pendulum."""
    x, v, p, w = y
    return np.stack([v, -500.0**2 * (x - 0.01 * np.sin(p)) - 2 * 0.01 * 500.0 * v, w, -10.0 * np.sin(p) + x])

@pytest.mark.parametrize("method, cls", [("kencarp5", diffrax.KenCarp5), ("kencarp4", diffrax.KenCarp4)])
def test_linear_implicit_ark_steps_as_diffrax_kencarp(method, cls):
    """The linear-implicit solver, told the split's matrix or taking it by forward mode, takes
    the same steps to the same solution as Diffrax's KenCarp with Optimistix's Newton solving
    each stage to round-off, and its derivative (the stage arithmetic differentiated) equals
    Diffrax's (the implicit-function rule at each stage)."""
    y0 = jnp.asarray([0.0, 0.0, 1.0, 0.0])
    jac = split_jacobian(_stiff_field, y0)
    ts = jnp.linspace(0.0, 2.0, 21)

    def run(solver, scale=1.0):
        field = lambda t, y, args: scale * _stiff_field(t, y, args)  # noqa: E731
        return diffrax.diffeqsolve(linearised_split(field, y0, jacobian=jac), solver, 0.0, 2.0, 1e-3, y0,
                                   saveat=diffrax.SaveAt(ts=ts), max_steps=100_000,
                                   stepsize_controller=diffrax.PIDController(rtol=1e-6, atol=1e-8))

    reference = cls(root_finder=optx.Newton(rtol=1e-13, atol=1e-14))
    runs = [run(solver) for solver in (reference, imex_solver(matrix=jac, method=method), imex_solver(method=method))]
    for sol in runs[1:]:
        assert int(sol.stats["num_steps"]) == int(runs[0].stats["num_steps"])
        np.testing.assert_allclose(sol.ys, runs[0].ys, rtol=1e-9, atol=1e-11)
    linear = imex_solver(matrix=jac, method=method)
    derivatives = [jax.grad(lambda x, s=solver: run(s, x).ys[-1, 2])(1.0) for solver in (reference, linear)]
    np.testing.assert_allclose(derivatives[1], derivatives[0], rtol=1e-8)


def test_linear_implicit_ark_refuses_bad_input():
    """A state that is not flat, a matrix of the wrong shape and an unknown method are refused
    by name."""
    y0 = jnp.zeros(4)
    terms = linearised_split(_stiff_field, y0)
    with pytest.raises(ValueError, match=r"flat state \(n,\): got shape \(2, 2\)"):
        imex_solver().init(terms, 0.0, 1.0, jnp.zeros((2, 2)), None)
    with pytest.raises(ValueError, match=r"matrix has shape \(3, 3\): .* is \(4, 4\)"):
        imex_solver(matrix=jnp.eye(3)).init(terms, 0.0, 1.0, y0, None)
    with pytest.raises(ValueError, match="method = 'kvaerno5' is not an IMEX method: allowed 'kencarp5', 'kencarp4'"):
        LinearImplicitARK(method="kvaerno5")


def test_relinearised_solve_keeps_the_state_pytree():
    """A state pytree (a dict) is stepped as one flat vector: the saved states come back as
    the same pytree, events read it by name, and the result equals the same run on an array."""
    ts = jnp.linspace(0.0, 2.0, 11)
    options = dict(segments=2, controller=diffrax.PIDController(rtol=1e-8, atol=1e-10), dt0=1e-3, max_steps=100_000)
    y0 = jnp.asarray([0.01 * np.sin(1.0), 0.0, 1.0, 0.0])

    def field(t, y, args):
        out = _stiff_field(t, jnp.concatenate([y["osc"], y["pendulum"]]), args)
        return {"osc": out[:2], "pendulum": out[2:]}

    def swung(t, y, args, **kwargs):
        return y["pendulum"][0] < -0.5

    tree = relinearised_solve(field, {"osc": y0[:2], "pendulum": y0[2:]}, 2.0, ts, event=diffrax.Event(swung),
                              **options)
    flat = relinearised_solve(_stiff_field, y0, 2.0, ts, event=diffrax.Event(lambda t, y, args, **kw: y[2] < -0.5),
                              **options)
    assert set(tree.ys) == {"osc", "pendulum"} and tree.ys["osc"].shape == (11, 2)
    assert int(tree.status) == int(flat.status) == 1  # the pendulum swings past -0.5 rad
    np.testing.assert_array_equal(np.concatenate([tree.ys["osc"], tree.ys["pendulum"]], axis=1), flat.ys)


def test_linearised_split_adds_up_to_the_field():
    y0 = jnp.asarray([0.0, 0.0, 1.0, 0.0])
    terms = linearised_split(_stiff_field, y0)
    y = jnp.asarray([1e-3, 0.2, 0.7, -0.4])
    total = terms.terms[0].vf(0.3, y, None) + terms.terms[1].vf(0.3, y, None)
    np.testing.assert_allclose(total, _stiff_field(0.3, y, None), rtol=1e-13, atol=1e-9)
    # the implicit part: J at y0, a forward difference (round-off about 1e-10 of the largest
    # entry, 2.5e5: the 500 rad/s oscillator's stiffness)
    jac = jax.jacfwd(lambda x: terms.terms[1].vf(0.0, x, None))(y)
    exact = jax.jacfwd(lambda x: _stiff_field(0.0, x, None))(y0)
    np.testing.assert_allclose(jac, exact, rtol=1e-7, atol=1e-9 * np.max(np.abs(exact)))
    at_t = linearised_split(lambda t, y, args: _stiff_field(t, y, args) * (1.0 + t), y0, t0=2.0)
    jac = jax.jacfwd(lambda x: at_t.terms[1].vf(0.0, x, None))(y)  # linearised at t0 = 2 s
    np.testing.assert_allclose(jac, 3.0 * exact, rtol=1e-7, atol=3e-9 * np.max(np.abs(exact)))
    # held out of differentiation: a parameter of the field moves the split's sum, not J
    def implicit_at(scale):
        split = linearised_split(lambda t, y, args: scale * _stiff_field(t, y, args), y0)
        return split.terms[1].vf(0.0, y, None)

    assert np.all(np.asarray(jax.jacfwd(implicit_at)(2.0)) == 0.0)


def test_explicit_states_stay_out_of_the_implicit_part():
    """``explicit``: those columns of the split's matrix are zero, the others the Jacobian's,
    the parts still add up to the field, and a segmented solve with them still matches the
    tight reference (the fast car keeps its position and heading on the ground explicit)."""
    y0 = jnp.asarray([0.0, 0.0, 1.0, 0.0])
    full, kept = split_jacobian(_stiff_field, y0), split_jacobian(_stiff_field, y0, explicit=(2,))
    assert np.all(np.asarray(kept[:, 2]) == 0.0) and np.any(np.asarray(full[:, 2]) != 0.0)
    np.testing.assert_array_equal(np.delete(np.asarray(kept), 2, axis=1), np.delete(np.asarray(full), 2, axis=1))
    terms = linearised_split(_stiff_field, y0, explicit=(2,))
    y = jnp.asarray([1e-3, 0.2, 0.7, -0.4])
    np.testing.assert_allclose(terms.terms[0].vf(0.3, y, None) + terms.terms[1].vf(0.3, y, None),
                               _stiff_field(0.3, y, None), rtol=1e-13, atol=1e-9)
    np.testing.assert_array_equal(np.asarray(jax.jacfwd(lambda x: terms.terms[1].vf(0.0, x, None))(y)),
                                  np.asarray(kept))
    start, ts = jnp.asarray([0.01 * np.sin(1.0), 0.0, 1.0, 0.0]), jnp.linspace(0.0, 5.0, 51)  # quasi-static
    sol = relinearised_solve(_stiff_field, start, 5.0, ts, explicit=(2, 3), segments=2, dt0=1e-3, max_steps=100_000,
                             controller=diffrax.PIDController(rtol=1e-8, atol=1e-10),
                             event=diffrax.Event(lambda t, y, args, **kw: False))
    ref = scipy.integrate.solve_ivp(lambda t, y: _stiff_field(t, y, None, np=np), (0.0, 5.0), np.asarray(start),
                                    method="Radau", t_eval=np.asarray(ts), rtol=1e-11, atol=1e-13)
    assert int(sol.status) == 0 and ref.success
    errors = np.max(np.abs(np.asarray(sol.ys) - ref.y.T), axis=0)
    assert np.all(errors <= [1e-10, 1e-7, 1e-10, 1e-10]), errors


@pytest.mark.parametrize("method", ["kencarp5", "kencarp4"])
def test_imex_matches_radau(method):
    """From the oscillator's quasi-static position; rtol 1e-8 against Radau at 1e-11, with
    either IMEX method."""
    y0 = jnp.asarray([0.01 * np.sin(1.0), 0.0, 1.0, 0.0])
    ts = jnp.linspace(0.0, 5.0, 51)
    imex = diffrax.diffeqsolve(linearised_split(_stiff_field, y0), imex_solver(method=method), 0.0, 5.0, 1e-3, y0,
                               saveat=diffrax.SaveAt(ts=ts), max_steps=100_000,
                               stepsize_controller=diffrax.PIDController(rtol=1e-8, atol=1e-10))
    ref = scipy.integrate.solve_ivp(lambda t, y: _stiff_field(t, y, None, np=np), (0.0, 5.0), np.asarray(y0),
                                    method="Radau", t_eval=np.asarray(ts), rtol=1e-11, atol=1e-13)
    assert imex.result == diffrax.RESULTS.successful and ref.success
    errors = np.max(np.abs(np.asarray(imex.ys) - ref.y.T), axis=0)
    assert np.all(errors <= [1e-10, 1e-7, 1e-10, 1e-10]), errors


def test_imex_solver_names_its_methods():
    """KenCarp5 by default; an unknown method is refused by name."""
    assert imex_solver().method == "kencarp5" and imex_solver(method="kencarp4").method == "kencarp4"
    assert imex_solver().order(None) == 5 and imex_solver(method="kencarp4").order(None) == 4
    with pytest.raises(ValueError, match="method = 'kvaerno5' is not an IMEX method: allowed 'kencarp5', 'kencarp4'"):
        imex_solver(method="kvaerno5")


def _radau(y0, ts):
    return scipy.integrate.solve_ivp(lambda t, y: _stiff_field(t, y, None, np=np), (0.0, float(ts[-1])),
                                     np.asarray(y0), method="Radau", t_eval=np.asarray(ts), rtol=1e-11, atol=1e-13)


def _never(t, y, args, **kwargs):
    return False


def _segmented_pendulum(segments, method):
    y0 = jnp.asarray([0.01 * np.sin(1.0), 0.0, 1.0, 0.0])
    ts = jnp.linspace(0.0, 5.0, 51)
    return relinearised_solve(_stiff_field, y0, 5.0, ts, segments=segments, solver=imex_solver(method=method),
                              controller=diffrax.PIDController(rtol=1e-8, atol=1e-10), event=diffrax.Event(_never),
                              dt0=1e-3, max_steps=100_000), _radau(y0, ts)


@pytest.mark.parametrize("segments, method", [(3, "kencarp4"), (7, "kencarp4"), (3, "kencarp5")])
def test_relinearised_solve_matches_radau(segments, method):
    """Every segment linearised at its start (the pendulum swings far from the first
    linearisation), saves from the segment each time falls in: rtol 1e-8 against Radau at
    1e-11 (as one linearisation is, test_imex_matches_radau). KenCarp4 takes fewer steps than
    with one linearisation; KenCarp5 at this tolerance resolves the oscillator's motion
    whatever the linearisation (8102 steps in three segments, 8060 in one, when written)."""
    sol, ref = _segmented_pendulum(segments, method)
    assert int(sol.status) == 0 and not bool(np.any(sol.event_mask))
    errors = np.max(np.abs(np.asarray(sol.ys) - ref.y.T), axis=0)
    assert np.all(errors <= [1e-10, 1e-7, 1e-10, 1e-10]), errors
    assert int(sol.stats["num_steps"]) == int(sol.stats["num_accepted_steps"] + sol.stats["num_rejected_steps"])
    once, _ = _segmented_pendulum(1, method)
    if method == "kencarp4":
        assert int(sol.stats["num_steps"]) < int(once.stats["num_steps"])
    else:
        assert int(sol.stats["num_steps"]) < 1.02 * int(once.stats["num_steps"])


def test_relinearised_solve_takes_the_solver_given():
    """Without the split the field goes to the solver given (the fast car's Kvaerno5), in
    segments too: the implicit solver, not held by the 500 rad/s oscillator's stability
    limit, takes fewer steps than Tsit5 (the default: 860 against 555 when written), and
    both agree with Radau."""
    y0 = jnp.asarray([0.01 * np.sin(1.0), 0.0, 1.0, 0.0])
    ts = jnp.linspace(0.0, 2.0, 21)
    ref = _radau(y0, ts)
    steps = {}
    for name, solver in (("tsit5", None), ("kvaerno5", diffrax.Kvaerno5(root_finder=optx.Newton(1e-10, 1e-12)))):
        sol = relinearised_solve(_stiff_field, y0, 2.0, ts, segments=2, split=False, solver=solver,
                                 controller=diffrax.PIDController(rtol=1e-6, atol=1e-8), event=diffrax.Event(_never),
                                 dt0=1e-3, max_steps=100_000)
        assert int(sol.status) == 0
        np.testing.assert_allclose(np.asarray(sol.ys)[:, 2], ref.y[2], atol=1e-5)
        steps[name] = int(sol.stats["num_steps"])
    assert steps["kvaerno5"] < 0.8 * steps["tsit5"], steps


def test_relinearised_solve_stops_at_an_event():
    """A stop in the second of four segments: the states before the event, the later save
    times inf (as Diffrax fills them), the later segments skipped (no steps), status 1 and the
    event's mask; Tsit5 without the split alike. (KenCarp4: on this field the split's explicit
    part is constant, so the error estimate is zero and the steps grow until the 3rd-order
    dense output of either KenCarp, not the steps, sets the saved values' error; KenCarp5's
    longer steps put it above this test's 1e-6.)"""
    def field(t, y, args):
        return jnp.stack([jnp.ones_like(y[0]), -y[1]])

    def crossed(t, y, args, **kwargs):
        return y[0] > 1.5

    ts = jnp.linspace(0.0, 4.0, 41)
    for split in (True, False):
        sol = relinearised_solve(field, jnp.asarray([0.0, 1.0]), 4.0, ts, segments=4,
                                 controller=diffrax.PIDController(rtol=1e-8, atol=1e-10),
                                 event=diffrax.Event((_never, crossed)), dt0=1e-2, max_steps=10_000, split=split,
                                 solver=imex_solver(method="kencarp4") if split else None)
        reached = np.asarray(ts) <= 1.5
        assert int(sol.status) == 1 and [bool(m) for m in sol.event_mask] == [False, True]
        np.testing.assert_allclose(np.asarray(sol.ys)[reached, 1], np.exp(-np.asarray(ts)[reached]), rtol=1e-6)
        assert np.all(np.isinf(np.asarray(sol.ys)[np.asarray(ts) > 1.65]))  # (1.6 may hold the stop's state)
        single = relinearised_solve(field, jnp.asarray([0.0, 1.0]), 2.0, ts[:21], segments=2,
                                    controller=diffrax.PIDController(rtol=1e-8, atol=1e-10),
                                    event=diffrax.Event((_never, crossed)), dt0=1e-2, max_steps=10_000, split=split,
                                    solver=imex_solver(method="kencarp4") if split else None)
        assert int(sol.stats["num_steps"]) == int(single.stats["num_steps"])  # segments 3 and 4 took none


def _pendulum_end(gravity, adjoint):
    """The pendulum's angle at 2 s with gravity ``gravity`` (the oscillator stiff, IMEX)."""
    def field(t, y, args):
        x, v, p, w = y
        return jnp.stack([v, -500.0**2 * (x - 0.01 * jnp.sin(p)) - 10.0 * v, w, -gravity * jnp.sin(p) + x])

    y0 = jnp.asarray([0.01 * jnp.sin(1.0), 0.0, 1.0, 0.0])
    sol = diffrax.diffeqsolve(linearised_split(field, y0), imex_solver(), 0.0, 2.0, 1e-3, y0, adjoint=adjoint,
                              stepsize_controller=diffrax.PIDController(rtol=1e-9, atol=1e-11), max_steps=100_000)
    return sol.ys[-1, 2]


def _pendulum_end_segments(gravity, adjoint):
    """:func:`_pendulum_end` in three segments, each linearised at its start."""
    def field(t, y, args):
        x, v, p, w = y
        return jnp.stack([v, -500.0**2 * (x - 0.01 * jnp.sin(p)) - 10.0 * v, w, -gravity * jnp.sin(p) + x])

    y0 = jnp.asarray([0.01 * jnp.sin(1.0), 0.0, 1.0, 0.0])
    sol = relinearised_solve(field, y0, 2.0, jnp.asarray([2.0]), segments=3, adjoint=adjoint,
                             controller=diffrax.PIDController(rtol=1e-9, atol=1e-11), event=diffrax.Event(_never),
                             dt0=1e-3, max_steps=100_000)
    return sol.ys[-1, 2]


def test_derivatives_through_the_relinearised_solve():
    """Reverse and forward mode through the segments (the linearisations included) equal a
    central difference, and the angle equals one linearisation's."""
    g, h = 10.0, 1e-4
    plain = diffrax.RecursiveCheckpointAdjoint()
    np.testing.assert_allclose(_pendulum_end_segments(g, plain), _pendulum_end(g, plain), rtol=1e-7)
    fd = (_pendulum_end_segments(g + h, plain) - _pendulum_end_segments(g - h, plain)) / (2 * h)
    reverse = jax.grad(lambda x: _pendulum_end_segments(x, plain))(g)
    _, forward = jax.jvp(lambda x: _pendulum_end_segments(x, diffrax.ForwardMode()), (g,), (1.0,))
    np.testing.assert_allclose(reverse, fd, rtol=1e-6)
    np.testing.assert_allclose(forward, fd, rtol=1e-6)


def test_derivatives_through_the_imex_solve():
    """Reverse mode (Diffrax's checkpointing) and forward mode through the split and the
    linear-implicit solver equal a central difference."""
    g, h = 10.0, 1e-4
    plain = diffrax.RecursiveCheckpointAdjoint()
    fd = (_pendulum_end(g + h, plain) - _pendulum_end(g - h, plain)) / (2 * h)
    reverse = jax.grad(lambda x: _pendulum_end(x, plain))(g)
    _, forward = jax.jvp(lambda x: _pendulum_end(x, diffrax.ForwardMode()), (g,), (1.0,))
    np.testing.assert_allclose(reverse, fd, rtol=1e-6)
    np.testing.assert_allclose(forward, fd, rtol=1e-6)


def test_solver_names():
    """``pick_solver``: "auto" takes KenCarp5 on the fast car from AUTO_IMEX_RTOL up and Tsit5
    below it and on the library car; each name builds its solver (the fast car's IMEX with
    the linear-implicit solver, the library car's Diffrax KenCarp with Optimistix's Newton); an unknown name is
    refused with the allowed ones."""
    from jaxveh.manoeuvre import AUTO_IMEX_RTOL, IMEX_SOLVERS, SOLVERS, pick_solver
    from jaxveh.manoeuvre._simulate import _solver

    assert pick_solver("auto", "fast", 1e-4) == "kencarp5" and pick_solver("auto", "fast", AUTO_IMEX_RTOL) == "kencarp5"
    assert pick_solver("auto", "fast", 0.5 * AUTO_IMEX_RTOL) == "tsit5"
    assert pick_solver("auto", "library", 1e-4) == "tsit5"
    assert set(IMEX_SOLVERS) <= set(SOLVERS)
    for name in SOLVERS:
        assert pick_solver(name, "library", 1e-4) == name
    for name, cls in (("kencarp5", diffrax.KenCarp5), ("kencarp4", diffrax.KenCarp4)):
        fast, library = _solver(name, "fast"), _solver(name, "library")
        assert type(fast) is LinearImplicitARK and fast.method == name
        assert type(library) is cls and isinstance(library.root_finder, optx.Newton)
    with pytest.raises(jaxveh.ParameterError, match="solver = 'rk4' is not available: allowed 'auto', 'tsit5', "
                                                   "'kencarp5', 'kencarp4', 'kvaerno5'"):
        pick_solver("rk4", "fast", 1e-4)


def test_manoeuvre_channels_takes_auto():
    """``manoeuvre_channels(solver="auto")`` picks as :func:`pick_solver` does (it was refused
    with a message listing "auto" as allowed); with a traced rtol it cannot pick and says so.
    Traced only (``jax.eval_shape``): the channels of the rigid car's step steer."""
    from jaxveh.manoeuvre import manoeuvre_channels, save_times, step_steer
    from jaxveh.vehicle import load_car

    car, m = load_car(modes=0), step_steer(duration=1.0)
    ts = save_times(m, 11)
    channels, _, _ = jax.eval_shape(lambda: manoeuvre_channels(car, m, ts, form="fast", solver="auto", rtol=1e-4))
    assert channels["yaw_rate"].shape == (11,)
    with pytest.raises(jaxveh.ParameterError, match="solver = 'auto' picks by rtol, which is traced here"):
        jax.eval_shape(lambda r: manoeuvre_channels(car, m, ts, form="fast", solver="auto", rtol=r), 1e-4)


def test_vmapped_relinearised_solve_equals_single_runs():
    """Under ``vmap`` (the stage solves one member after the other, jaxveh._linalg) each
    member takes the steps its own run takes, to the same solution (round-off apart), and its
    derivative (the replayed reverse pass, vmapped) is the same."""
    amplitudes = jnp.asarray([0.5, 1.0, 1.5])
    ts = jnp.linspace(0.0, 2.0, 21)

    def run(amplitude):
        y0 = jnp.asarray([0.01 * jnp.sin(amplitude), 0.0, amplitude, 0.0])
        sol = relinearised_solve(_stiff_field, y0, 2.0, ts, segments=3, controller=diffrax.PIDController(
            rtol=1e-8, atol=1e-10), event=diffrax.Event(_never), dt0=1e-3, max_steps=100_000)
        return sol.ys, sol.stats["num_steps"]

    batched_ys, batched_steps = jax.jit(jax.vmap(run))(amplitudes)
    for k, amplitude in enumerate(amplitudes):
        ys, steps = jax.jit(run)(amplitude)
        assert abs(int(batched_steps[k]) - int(steps)) <= 1, (batched_steps, steps)
        np.testing.assert_allclose(batched_ys[k], ys, rtol=1e-9, atol=1e-11)
    swing = lambda a: run(a)[0][-1, 2]  # noqa: E731
    np.testing.assert_allclose(jax.jit(jax.vmap(jax.grad(swing)))(amplitudes),
                               [jax.jit(jax.grad(swing))(a) for a in amplitudes], rtol=1e-7)
