"""The fast car (minimal coordinates, corners vectorised) against the library car: the same
accelerations at random states, exact corner kinematics, gradients, no retrace."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxveh.multibody as mb
from jaxveh.vehicle import (
    CORNERS,
    ConstantSpeed,
    car_elements,
    corner_poses,
    design_coordinates,
    fast_dynamics,
    fast_model,
    fast_state_from_library,
    load_car,
    map_guess,
    pose_residual,
    system_params,
    travel_from_library,
)
from jaxveh.vehicle._corner_kinematics import MAP_RACK, MAP_TRAVEL, _newton, link_curvature, link_residual

N_STATES = 100


def _rack_law(t):
    """A rack travel (m) with nonzero rate and acceleration at every time."""
    return jnp.reshape(0.004 * jnp.sin(3.0 * t) + 0.002, (1,))


def _held_coordinates(car):
    """Library coordinates held while assembling: the chassis's, each upright's height and
    each wheel's spin angle."""
    sys = car.system
    c = sys.body_names.index("chassis")
    held = list(range(sys.q_offsets[c], sys.q_offsets[c + 1]))
    for corner in CORNERS:
        held.append(sys.q_offsets[sys.body_names.index(f"{corner}.upright")] + 2)
        held.append(sys.q_offsets[sys.body_names.index(f"{corner}.wheel")])
    return np.asarray(held)


def _random_library_states(car, n, seed):
    """Assembled library states near the set-up: chassis pose, small modal deflections,
    travels within +-20 mm, rolling wheels at 10-30 m/s, random other velocities."""
    rng = np.random.default_rng(seed)
    sys, params = car.system, system_params(car)
    held = _held_coordinates(car)
    scale = np.concatenate([[0.05, 0.05, 0.01, 0.05, 0.01, 0.01], np.full(car.n_modes, 2e-4), np.tile([0.02, 1.0], 4)])
    q0 = np.tile(np.asarray(design_coordinates(car)), (n, 1))
    q0[:, held] += rng.uniform(-1.0, 1.0, (n, held.size)) * scale
    ts = rng.uniform(0.0, 2.0, n)
    assemble = jax.vmap(lambda q, t: mb.solve_assembly(sys, params, q, tuple(held.tolist()), t, _rack_law))
    result = assemble(jnp.asarray(q0), jnp.asarray(ts))
    assert bool(jnp.all(result.ok)), "random states must assemble"
    z = rng.normal(size=(n, sys.n_dof)) * 0.3
    speed = rng.uniform(10.0, 30.0, n)
    z[:, 8] += speed  # independents: (upright uz, wheel spin) per corner, then the chassis's
    z[:, [1, 3, 5, 7]] += (speed / 0.26)[:, None]
    aux = rng.normal(size=(n, 10)) * 1e-3
    return result.q, jnp.asarray(z), jnp.asarray(aux), jnp.asarray(ts)


def _compare(car, q, z, aux, t):
    """(fast accelerations, library accelerations in the fast car's layout, aux rates of
    both) at one library state."""
    sys, params = car.system, system_params(car)
    elements = car_elements(car, ConstantSpeed(20.0))
    lib = mb.dynamics(sys, params, q, z, t, _rack_law, None, None, 0.0, elements, aux)
    y, y_dot = lib.y, lib.y_dot
    state = fast_state_from_library(car, q, y, aux)
    fast = fast_dynamics(car, fast_model(car), state.q, state.u, state.aux, t, _rack_law, elements)

    def travel_rate(qq, yy):
        q_dot = mb.velocity_maps(sys, params, qq, yy)[1]
        return jax.jvp(lambda x: travel_from_library(car, x), (qq,), (q_dot,))[1]

    travel_acc = jax.jvp(travel_rate, (q, y), (lib.q_dot, y_dot))[1]
    c = sys.body_names.index("chassis")
    wheels = [sys.q_offsets[sys.body_names.index(f"{k}.wheel")] for k in CORNERS]
    expected = jnp.concatenate([y_dot[sys.q_offsets[c] : sys.q_offsets[c + 1]], travel_acc, y_dot[np.asarray(wheels)]])
    kinematics = [(k.x, k.xd, k.point_rotations, k.point_omega) for k in (fast.kinematics, lib.kinematics)]
    return fast.u_dot, expected, fast.aux_dot, lib.aux_dot, fast.link_residual, kinematics


@pytest.fixture(scope="module")
def car():
    return load_car(modes=6)


@pytest.fixture(scope="module")
def compared(car):
    q, z, aux, t = _random_library_states(car, N_STATES, seed=3)
    return jax.jit(jax.vmap(lambda *a: _compare(car, *a)))(q, z, aux, t)


def test_accelerations_equal_the_library_car_at_random_states(compared):
    fast, lib, aux_fast, aux_lib, residual, _ = compared
    scale = jnp.max(jnp.abs(lib), axis=1, keepdims=True)
    assert float(jnp.min(scale)) > 1.0  # the states do accelerate
    assert float(jnp.max(jnp.abs(fast - lib) / scale)) < 1e-6
    assert float(jnp.max(jnp.abs(aux_fast - aux_lib))) < 1e-6 * float(jnp.max(jnp.abs(aux_lib)))
    assert float(jnp.max(residual)) < 1e-10


def test_point_kinematics_equal_the_library_car_at_random_states(compared):
    """What the force elements read: every point's position, velocity (the rack's rate
    included at the rack's points), material orientation and angular velocity equal the
    library car's."""
    fast, lib = compared[-1]
    for name, a, b in zip(("x", "xd", "point_rotations", "point_omega"), fast, lib, strict=True):
        scale = float(jnp.max(jnp.abs(b)))
        assert float(jnp.max(jnp.abs(a - b))) < 1e-9 * scale, name


def test_rigid_chassis_equals_the_library_car():
    car = load_car(modes=0)
    q, z, aux, t = _random_library_states(car, 8, seed=4)
    fast, lib, aux_fast, aux_lib, residual, _ = jax.jit(jax.vmap(lambda *a: _compare(car, *a)))(q, z, aux, t)
    assert fast.shape == (8, 14)
    scale = jnp.max(jnp.abs(lib), axis=1, keepdims=True)
    assert float(jnp.max(jnp.abs(fast - lib) / scale)) < 1e-6
    assert float(jnp.max(jnp.abs(aux_fast - aux_lib))) < 1e-6 * float(jnp.max(jnp.abs(aux_lib)))


def test_kinematic_map_guess_and_exact_solve(car):
    model = jax.jit(fast_model)(car)
    rng = np.random.default_rng(5)
    travel = jnp.asarray(rng.uniform(*MAP_TRAVEL, (6, 4)))
    rack = jnp.asarray(rng.uniform(*MAP_RACK, 6))
    modes = jnp.asarray(rng.normal(size=(6, car.n_modes)) * 5e-4)
    g = model.geometry

    def one(tr, rk, p):
        pivots = g.inner + jnp.einsum("kpim,m->kpi", g.inner_shapes, p)
        guess = map_guess(model.kmap, tr, jnp.broadcast_to(rk, (4,)))
        exact = jax.vmap(lambda w, gg, t, piv: _newton(w, gg, t, rk, piv, 20))(guess, g, tr, pivots)
        undeformed = jax.vmap(lambda w, gg, t: _newton(w, gg, t, rk, gg.inner, 20))(guess, g, tr)
        solved = corner_poses(g, model.kmap, tr, rk, p)
        return (jnp.max(jnp.abs(guess - undeformed)), jnp.max(jnp.abs(solved - exact)),
                pose_residual(g, tr, rk, p, solved), jnp.max(jnp.abs(pivots - g.inner)))

    map_error, solve_error, residual, deflection = jax.vmap(one)(travel, rack, modes)
    assert float(jnp.max(deflection)) > 1e-4  # the chassis deformation is felt at the pivots
    assert float(jnp.max(map_error)) < 1e-4  # the map is a good guess on the undeformed chassis
    assert float(jnp.max(solve_error)) < 1e-11  # two Newton iterations reach the exact pose
    assert float(jnp.max(residual)) < 1e-11


def test_link_curvature_equals_the_second_derivative_by_autodiff(car):
    """The closed-form velocity-product term of the link equations equals the second
    derivative of the residual along the motion by nested forward mode, at random poses,
    rates, pivots and pivot rates of every corner (a fourth of them at design pose)."""
    g = jax.jit(fast_model)(car).geometry
    rng = np.random.default_rng(11)
    n = 8
    w = jnp.asarray(rng.normal(size=(n, 4, 5)) * [0.01, 0.01, 0.05, 0.05, 0.05])
    w_dot = jnp.asarray(rng.normal(size=(n, 4, 5)) * [0.2, 0.2, 1.0, 1.0, 3.0])
    w = w.at[: n // 4].set(0.0)
    travel, travel_rate = jnp.asarray(rng.uniform(*MAP_TRAVEL, (n, 4))), jnp.asarray(rng.normal(size=(n, 4)))
    rack, rack_rate = jnp.asarray(rng.uniform(*MAP_RACK, n)), jnp.asarray(rng.normal(size=n) * 0.1)
    pivots = g.inner[None] + jnp.asarray(rng.normal(size=(n, *g.inner.shape)) * 1e-3)
    pivot_rates = jnp.asarray(rng.normal(size=(n, *g.inner.shape)) * 1e-2)

    def by_autodiff(w, wd, gg, t, td, r, rd, piv, pivd):
        def along(e):
            return link_residual(w + e * wd, gg, t + e * td, r + e * rd, piv + e * pivd)

        zero = jnp.zeros(())
        return jax.jvp(lambda e: jax.jvp(along, (e,), (jnp.ones(()),))[1], (zero,), (jnp.ones(()),))[1]

    corners = jax.vmap(jax.vmap(by_autodiff, (0, 0, 0, 0, 0, None, None, 0, 0)), (0, 0, None, 0, 0, 0, 0, 0, 0))
    closed = jax.vmap(jax.vmap(link_curvature, (0, 0, 0, 0, 0, None, None, 0, 0)), (0, 0, None, 0, 0, 0, 0, 0, 0))
    args = (w, w_dot, g, travel, travel_rate, rack, rack_rate, pivots, pivot_rates)
    expected, got = jax.jit(corners)(*args), jax.jit(closed)(*args)
    assert float(jnp.max(jnp.abs(expected))) > 1e-2  # the rotation's and the pivots' terms both act
    np.testing.assert_allclose(got, expected, rtol=1e-11, atol=1e-13 * float(jnp.max(jnp.abs(expected))))


def test_gradients_of_an_acceleration_match_central_differences(car):
    """Spring rate (front left), a hard point (front lower wishbone pivot A, z) and a modal
    stiffness multiplier, through the parameter pytree, the map and the corner solve."""
    q_lib = design_coordinates(car)
    sys = car.system
    z = jnp.zeros((sys.n_dof,)).at[8].set(20.0).at[jnp.asarray([1, 3, 5, 7])].set(20.0 / 0.26)
    aux = jnp.zeros((10,))
    y = mb.joint_velocities(sys, system_params(car), q_lib, z, 0.3, _rack_law, 0.0, aux)
    state = fast_state_from_library(car, q_lib, y, aux)
    state = eqx.tree_at(lambda s: s.q, state, state.q.at[12].add(0.004).at[6].add(3e-4))

    def metric(params):
        c = eqx.tree_at(lambda x: x.params, car, params)
        d = fast_dynamics(c, fast_model(c), state.q, state.u, state.aux, 0.3, _rack_law,
                          car_elements(c, ConstantSpeed(20.0)))
        return d.u_dot[2] + 0.3 * d.u_dot[4] + 0.01 * d.u_dot[6] + 0.01 * d.u_dot[12]

    knobs = {
        "spring": (lambda p: p.springs.spring_force, lambda x: x.at[0].multiply(1.0 + 1e-4)),
        "hard point": (lambda p: p.vehicle.hard_points_front.points, lambda x: x.at[0, 2].add(1e-5)),
        "modal stiffness": (lambda p: p.chassis.stiffness_scale, lambda x: x.at[0].add(1e-4)),
    }
    grad = jax.jit(jax.grad(metric))(car.params)
    value = jax.jit(metric)
    for name, (where, step) in knobs.items():
        leaf = where(car.params)
        delta = step(leaf) - leaf
        plus = value(eqx.tree_at(where, car.params, leaf + delta))
        minus = value(eqx.tree_at(where, car.params, leaf - delta))
        fd = (plus - minus) / 2.0
        ad = jnp.sum(where(grad) * delta)
        assert abs(float(fd)) > 1e-9, name
        assert float(jnp.abs(ad - fd)) < 1e-5 * float(jnp.abs(fd)) + 1e-12, name


def test_new_parameter_values_never_retrace(car):
    q = jnp.zeros((20,))
    u = jnp.zeros((20,)).at[0].set(10.0)

    @eqx.filter_jit
    @eqx.debug.assert_max_traces(max_traces=1)
    def accelerations(c):
        return fast_dynamics(c, fast_model(c), q, u, jnp.zeros((10,)), 0.0, _rack_law,
                             car_elements(c, ConstantSpeed(10.0))).u_dot

    first = accelerations(car)
    stiffer = eqx.tree_at(lambda c: c.params.arb_rates, car, car.params.arb_rates * 2.0)
    moved = eqx.tree_at(lambda c: c.params.vehicle.hard_points_rear.points, stiffer,
                        stiffer.params.vehicle.hard_points_rear.points + 1e-3)
    second = accelerations(moved)
    assert bool(jnp.all(jnp.isfinite(second))) and float(jnp.max(jnp.abs(second - first))) > 0.0


def test_state_of_the_wrong_size_is_refused(car):
    elements = car_elements(car, ConstantSpeed(10.0))
    model = fast_model(car)
    with pytest.raises(ValueError, match=r"q must hold 20 values \(chassis 6 \+ 6 modes"):
        fast_dynamics(car, model, jnp.zeros((19,)), jnp.zeros((20,)), jnp.zeros((10,)), 0.0, _rack_law, elements)
    with pytest.raises(ValueError, match=r"aux must hold 10 values"):
        fast_dynamics(car, model, jnp.zeros((20,)), jnp.zeros((20,)), jnp.zeros((8,)), 0.0, _rack_law, elements)
