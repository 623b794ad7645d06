"""The push-rod suspension as a force element (``jaxveh.vehicle._suspension``): mirror
symmetry of the right corner, virtual work of its point forces through the quarter car and
the library's generalised forces, and the static wheel load against the installation
ratio."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxveh import multibody as mb, vehicle
from jaxveh.params import HARD_POINT_NAMES, load_vehicle_data

MIRROR = jnp.asarray([[1.0, -1.0, 1.0]])  # y -> -y, one row per point


@pytest.fixture(scope="module")
def corner():
    data = load_vehicle_data()
    pts = data.hard_points_front.points
    hp = {n: pts[k] for k, n in enumerate(HARD_POINT_NAMES)}
    system, params = vehicle.quarter_car(data, "front")
    design = vehicle.installation_ratios("front", data)
    law = vehicle.linear_spring_damper(30_000.0, design.spring_length + 0.012, 1500.0)
    element = vehicle.pushrod_suspension(system, ("",), [hp], law)
    return data, hp, system, params, element


def _first(tree):
    return jax.tree.map(lambda a: a[0], tree)


def _corner_points(system, params, q):
    x = mb.marker_positions(system, params, q, jnp.zeros(1))
    return x[jnp.asarray([system.point_index(n) for n in vehicle.CORNER_POINTS])]


def test_right_corner_mirrors_the_left(corner):
    """Heave: the mirrored corner has the same spring length and the opposite rocker angle
    (so the anti-roll bar, twisted by their sum, stays untwisted)."""
    data, hp, system, params, element = corner
    mirrored = {n: v * MIRROR[0] for n, v in hp.items()}
    right = vehicle.pushrod_suspension(system, ("",), [mirrored], vehicle.linear_spring_damper(30_000.0, 0.28, 0.0))
    for bump in (-0.02, 0.0, 0.03):
        q, _ = vehicle.quarter_car_kinematics(system, params, bump, 0.0)
        x = _corner_points(system, params, q)
        (ls_l, th_l), _ = vehicle.corner_state(x, jnp.zeros_like(x), _first(element.wishbone),
                                               _first(element.mount))
        (ls_r, th_r), _ = vehicle.corner_state(x * MIRROR, jnp.zeros_like(x), _first(right.wishbone),
                                               _first(right.mount))
        np.testing.assert_allclose(ls_r, ls_l, rtol=1e-13)
        np.testing.assert_allclose(th_r, -th_l, atol=1e-13)
        if bump:
            assert abs(float(th_l)) > 1e-3



@pytest.mark.parametrize("bump", [0.0, 0.018])
def test_virtual_work_through_the_library(corner, bump):
    """The element's point forces do the spring-damper's work, F_s l_s_dot, and the
    library's generalised forces (R^T T^T Q) do the same work on the independent velocities."""
    data, hp, system, params, element = corner
    q, _ = vehicle.quarter_car_kinematics(system, params, bump, 0.0)
    z = jnp.asarray([0.37, 55.0])  # upright heave rate (m/s), wheel spin (rad/s)
    rack = lambda t: jnp.zeros(1)  # noqa: E731
    with_el = mb.dynamics(system, params, q, z, 0.0, rack, elements=(element,))
    without = mb.dynamics(system, params, q, z, 0.0, rack)
    kin = with_el.kinematics
    forces = element(kin, jnp.zeros(0), system).forces
    (lengths, _), (rates, _) = element.states(kin)
    spring_power = element.spring_forces(lengths, rates)[0] * rates[0]
    assert abs(float(rates[0])) > 0.1  # the spring moves
    np.testing.assert_allclose(jnp.sum(forces * kin.xd), spring_power, rtol=1e-10)
    f_el = with_el.external_forces - without.external_forces
    np.testing.assert_allclose(f_el @ z, spring_power, rtol=1e-10)


def test_static_wheel_load_is_spring_force_times_installation_ratio(corner):
    data, hp, system, params, element = corner
    q = vehicle.quarter_car_design_q(system)
    rack = lambda t: jnp.zeros(1)  # noqa: E731
    z = jnp.zeros(2)
    f_el = (mb.dynamics(system, params, q, z, 0.0, rack, elements=(element,)).external_forces
            - mb.dynamics(system, params, q, z, 0.0, rack).external_forces)
    ratio = vehicle.installation_ratios("front", data).spring
    spring_force = 30_000.0 * 0.012  # compressed by 12 mm at design (no bump stop)
    uz = system.independent.index(system.y_index("upright", "uz"))
    np.testing.assert_allclose(f_el[uz], spring_force * ratio, rtol=1e-10)
    assert float(f_el[uz]) < 0  # a compressed spring pushes the wheel down


def test_anti_roll_bar_on_an_axle(corner):
    """Left and mirrored right corner in one element with a bar: the point forces do the
    springs' work plus the bar's, -k_arb (θ_l + θ_r)(θ_l_dot + θ_r_dot); heave leaves the bar
    untwisted, roll twists it."""
    data, hp, system, params, element = corner
    mirrored = {n: v * MIRROR[0] for n, v in hp.items()}
    geometry_only = vehicle.linear_spring_damper(1.0, 1.0, 0.0)
    left = vehicle.pushrod_suspension(system, ("",), [hp], geometry_only)
    right = vehicle.pushrod_suspension(system, ("",), [mirrored], geometry_only)

    def concat(a, b):
        return jax.tree.map(lambda u, v: jnp.concatenate([u, v]), a, b)

    def concat1(a, b):  # two single laws -> stacked
        return jax.tree.map(lambda u, v: jnp.stack([u, v]), a, b)

    # right: a progressive table with a bump stop near the static length (same table sizes)
    progressive = vehicle.SpringDamperLaw(
        spring_length=jnp.asarray([0.25, 0.281]), spring_force=jnp.asarray([900.0, 0.0]),
        damper_rate=jnp.asarray([-1.0, 1.0]), damper_force=jnp.asarray([1300.0, -800.0]),
        bump_stop_length=jnp.asarray(0.27), bump_stop_rate=jnp.asarray(2e5))

    both = vehicle.PushrodSuspension(
        points=(tuple(range(6)), tuple(range(6, 12))),  # rows of the hand-made kinematics below
        wishbone=concat(left.wishbone, right.wishbone), mount=concat(left.mount, right.mount),
        law=concat1(vehicle.linear_spring_damper(30_000.0, 0.28, 900.0), progressive), arb_rate=jnp.asarray(40.0))

    def points(bumps):
        q_l, _ = vehicle.quarter_car_kinematics(system, params, bumps[0], 0.0, throw=False)
        q_r, _ = vehicle.quarter_car_kinematics(system, params, bumps[1], 0.0, throw=False)
        return jnp.concatenate([_corner_points(system, params, q_l), _corner_points(system, params, q_r) * MIRROR])

    def kinematics(bumps, rates):
        x, xd = jax.jvp(points, (bumps,), (rates,))
        zeros = jnp.zeros((12, 3))
        return mb.Kinematics(t=jnp.zeros(()), q=jnp.zeros(0), v=jnp.zeros(0), u=jnp.zeros(0), u_dot=jnp.zeros(0),
                             origins=jnp.zeros((0, 3)), rotations=jnp.zeros((0, 3, 3)), x=x, xd=xd,
                             point_rotations=jnp.zeros((12, 3, 3)), point_omega=zeros, modal=())

    for bumps, rates in (((0.01, 0.01), (0.2, 0.2)), ((0.012, -0.012), (0.3, -0.25))):
        kin = kinematics(jnp.asarray(bumps), jnp.asarray(rates))
        (lengths, thetas), (l_dot, th_dot) = both.states(kin)
        forces = both(kin, jnp.zeros(0), None).forces
        twist = jnp.sum(thetas)
        expected = jnp.sum(both.spring_forces(lengths, l_dot) * l_dot) - both.arb_rate * twist * jnp.sum(th_dot)
        np.testing.assert_allclose(jnp.sum(forces * kin.xd), expected, rtol=1e-10)
        if bumps[0] == bumps[1]:
            assert abs(float(twist)) < 1e-12  # heave
        else:
            assert abs(float(twist)) > 0.1  # roll: about 2 x 11 rad/m x 12 mm
