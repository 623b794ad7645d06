"""Push-rod force path (eqs. 6.4-6.12, ``jaxveh.vehicle._pushrod``): wishbone frame and
point D, the closed-form rocker angle, virtual work through the whole chain, equilibrium
of rocker and wishbone, the thesis's (6.11)-(6.12) terms, and an independent FE solution
of the wishbone beam problem."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxveh import fe, vehicle as pr
from jaxveh.params import HARD_POINT_NAMES, hard_points_vehicle_frame, load_vehicle_data


@pytest.fixture(scope="module")
def corner():
    """Front-left hard points of Appendix B (vehicle frame, m) by name."""
    pts = np.asarray(hard_points_vehicle_frame(load_vehicle_data())["front_left"])
    return {n: jnp.asarray(pts[k]) for k, n in enumerate(HARD_POINT_NAMES)}


def _bumped_c(c, angle):
    """C after the lower wishbone turned by ``angle`` (rad) about A-B."""
    return pr.rotate_about_axis(c["C"], c["A"], c["B"], angle)


def _chain(c, angle, spring_force=0.0, arb_moment=0.0):
    geo = pr.wishbone_geometry(c["A"], c["B"], c["C"], c["D"])
    rocker = pr.rocker_geometry(c["P"], c["Q"], c["R"], c["S"], c["D"])
    xd = pr.point_d(c["A"], c["B"], _bumped_c(c, angle), geo)
    theta = pr.rocker_angle(rocker, xd)
    return geo, rocker, xd, theta


def test_point_d_rides_rigidly_on_the_wishbone(corner):
    c = corner
    geo = pr.wishbone_geometry(c["A"], c["B"], c["C"], c["D"])
    np.testing.assert_allclose(pr.point_d(c["A"], c["B"], c["C"], geo), c["D"], atol=1e-15)
    for angle in (-0.15, 0.07, 0.2):
        xc = _bumped_c(c, angle)
        xd = pr.point_d(c["A"], c["B"], xc, geo)
        for p, q in ((xd, c["A"]), (xd, c["B"]), (xd, xc)):
            d0 = {id(xd): c["D"], id(xc): c["C"]}.get(id(p), p)
            q0 = {id(xc): c["C"]}.get(id(q), q)
            np.testing.assert_allclose(jnp.linalg.norm(p - q), jnp.linalg.norm(d0 - q0), rtol=1e-13)
    assert float(geo.m) > 0 and float(geo.n) > 0 and 0 < float(geo.a) < float(geo.length)


def test_rocker_angle_closes_the_push_rod(corner):
    c = corner
    _, rocker, _, theta0 = _chain(c, 0.0)
    assert abs(float(theta0)) < 1e-12  # design position
    thetas = []
    for angle in np.linspace(-0.12, 0.12, 9):
        _, rocker, xd, theta = _chain(c, angle)
        xr = pr.rotate_about_axis(rocker.xr, rocker.xp, rocker.xq, theta)
        np.testing.assert_allclose(jnp.linalg.norm(xr - xd), rocker.l_p, rtol=1e-13)
        assert float(pr.rocker_reach(rocker, xd)) < 1.0
        thetas.append(float(theta))
    assert np.all(np.diff(thetas) > 0) or np.all(np.diff(thetas) < 0)  # one branch, monotonic
    assert abs(thetas[-1] - thetas[0]) > 0.05


@pytest.mark.parametrize("arb_moment", [0.0, 35.0])
def test_virtual_work_through_the_chain(corner, arb_moment):
    """Power at D equals spring power plus the anti-roll bar's: F_D . D_dot =
    F_s l_s_dot + M theta_dot (massless rocker and rod), for any wishbone rate."""
    c = corner
    spring_force = 2500.0

    def state(angle):
        geo, rocker, xd, theta = _chain(c, angle)
        return xd, theta, pr.spring_length(rocker, c["T"], theta)

    for angle in (-0.08, 0.0, 0.05):
        (xd, theta, ls), (xd_dot, theta_dot, ls_dot) = jax.jvp(state, (jnp.asarray(angle),), (jnp.asarray(1.0),))
        _, rocker, _, _ = _chain(c, angle)
        loads = pr.rocker_loads(rocker, xd, c["T"], theta, spring_force, arb_moment)
        power_d = jnp.dot(loads.on_d, xd_dot)
        np.testing.assert_allclose(power_d, spring_force * ls_dot + arb_moment * theta_dot, rtol=1e-11)
        assert abs(float(ls_dot)) > 1e-3  # the spring really moves (m/rad)


def test_rocker_equilibrium(corner):
    c = corner
    _, rocker, xd, theta = _chain(c, 0.06)
    m_arb = -20.0
    loads = pr.rocker_loads(rocker, xd, c["T"], theta, 1800.0, m_arb)
    xs = pr.rotate_about_axis(rocker.xs, rocker.xp, rocker.xq, theta)
    xr = pr.rotate_about_axis(rocker.xr, rocker.xp, rocker.xq, theta)
    u = (rocker.xq - rocker.xp) / jnp.linalg.norm(rocker.xq - rocker.xp)
    # forces on the rocker: spring -on_t at S, rod -on_d at R, chassis -on_p, -on_q
    total = -loads.on_t - loads.on_d - loads.on_p - loads.on_q
    moment = (jnp.cross(xs - rocker.xp, -loads.on_t) + jnp.cross(xr - rocker.xp, -loads.on_d)
              + jnp.cross(rocker.xq - rocker.xp, -loads.on_q) + m_arb * u)
    np.testing.assert_allclose(total, 0.0, atol=1e-9)
    np.testing.assert_allclose(moment, 0.0, atol=1e-9)
    # the rod pushes along itself
    rod = (xr - xd) / jnp.linalg.norm(xr - xd)
    np.testing.assert_allclose(loads.on_d, -loads.pushrod * rod, atol=1e-9)


def _random_wishbone(rng):
    xa, xb = rng.normal(size=3) * 0.05, np.array([0.35, 0.0, 0.0]) + rng.normal(size=3) * 0.05
    xc = np.array([0.1, 0.35, -0.01]) + rng.normal(size=3) * 0.03
    xd = 0.15 * xa + 0.05 * xb + 0.8 * xc + rng.normal(size=3) * 0.02
    return tuple(jnp.asarray(x) for x in (xa, xb, xc, xd))


def test_wishbone_loads_carry_the_force_and_its_moment():
    rng = np.random.default_rng(6)
    for _ in range(5):
        xa, xb, xc, xd = _random_wishbone(rng)
        geo = pr.wishbone_geometry(xa, xb, xc, xd)
        force = jnp.asarray(rng.normal(size=3) * 1000.0)
        loads = pr.wishbone_loads(xa, xb, xc, geo, force)
        np.testing.assert_allclose(loads.on_a + loads.on_b + loads.on_c, force, atol=1e-9)
        moment = jnp.cross(xa, loads.on_a) + jnp.cross(xb, loads.on_b) + jnp.cross(xc, loads.on_c)
        np.testing.assert_allclose(moment, jnp.cross(xd, force), atol=1e-9)


def test_thesis_equations_6_11_and_6_12_with_d_on_the_beam_line():
    """With D above the G-C line (d = 0) the derivation reproduces the thesis's terms."""
    geo = pr.WishboneGeometry(m=jnp.asarray(0.2), n=jnp.asarray(0.15), length=jnp.asarray(0.33), d=jnp.asarray(0.0),
                              a=jnp.asarray(0.29), e=jnp.asarray(0.025))
    fx, fy, fz = 300.0, -800.0, 2500.0
    at_g, at_c, my, mz = pr.beam_loads(geo, jnp.asarray([fx, fy, fz]))
    span, a, b, e = 0.33, 0.29, 0.33 - 0.29, 0.025  # the thesis's l, a, b, e
    np.testing.assert_allclose(
        at_c, [a**2 / (2 * span**3) * (3 * span - a) * fx, a / span * fy, a / span * fz - e / span * fy], rtol=1e-13)
    np.testing.assert_allclose(
        at_g, [b / (2 * span**3) * (3 * span**2 - b**2) * fx, b / span * fy, b / span * fz + e / span * fy],
        rtol=1e-13)
    np.testing.assert_allclose(abs(float(mz)), b / (2 * span**2) * (span**2 - b**2) * fx, rtol=1e-13)
    np.testing.assert_allclose(float(my), e * fx, rtol=1e-13)  # -> R_zA = n/p R_zG + e/p F_xD (6.12)


def test_beam_loads_against_a_finite_element_solution():
    """G-C as three Euler-Bernoulli elements (fe module), clamped at G except about the
    hinge axis x, pinned at C, loaded at D' (the foot of D) with the force and its offset
    moment: the support reactions equal the closed form."""
    geo = pr.WishboneGeometry(m=jnp.asarray(0.2), n=jnp.asarray(0.15), length=jnp.asarray(0.33), d=jnp.asarray(0.012),
                              a=jnp.asarray(0.27), e=jnp.asarray(0.02))
    force = jnp.asarray([420.0, -900.0, 2600.0])
    at_g, at_c, my, mz = pr.beam_loads(geo, force)
    span, a = float(geo.length), float(geo.a)
    frame = fe.frame_from_dict({
        "materials": {"steel": {"E": 210.0, "G": 80.0, "density": 7850.0}},
        "sections": {"tube": {"shape": "circular", "diameter": 20.0, "thickness": 1.5}},
        "nodes": {"G": [0.0, 0.0, 0.0], "D": [0.0, 1e3 * a / 2, 0.0], "Dp": [0.0, 1e3 * a, 0.0],
                  "C": [0.0, 1e3 * span, 0.0]},
        "members": [{"nodes": ["G", "D"], "section": "tube", "divisions": 1},
                    {"nodes": ["D", "Dp"], "section": "tube", "divisions": 1},
                    {"nodes": ["Dp", "C"], "section": "tube", "divisions": 1}],
    })
    k, _ = fe.assemble(frame)
    assert k.shape == (24, 24)
    g, dp, c = 0, 2, 3
    f = jnp.zeros(24)
    fx, fy, fz = force
    moment = jnp.asarray([-float(geo.e) * fy, float(geo.e) * fx - float(geo.d) * fz, float(geo.d) * fy])
    f = f.at[6 * dp : 6 * dp + 3].set(force).at[6 * dp + 3 : 6 * dp + 6].set(moment)
    fixed = (6 * g + 0, 6 * g + 1, 6 * g + 2, 6 * g + 4, 6 * g + 5, 6 * c + 0, 6 * c + 1, 6 * c + 2)
    u = fe.solve_static(k, f, fixed)
    transmitted = f - k @ u  # loads the beam passes to its supports
    np.testing.assert_allclose(transmitted[6 * c : 6 * c + 3], at_c, rtol=1e-9)
    np.testing.assert_allclose(transmitted[6 * g : 6 * g + 3], at_g, rtol=1e-9)
    np.testing.assert_allclose(transmitted[6 * g + 4], my, rtol=1e-9)
    np.testing.assert_allclose(transmitted[6 * g + 5], mz, rtol=1e-9)
