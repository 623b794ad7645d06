"""Vehicle corner (quarter car) from the Appendix B hard points: kinematics (Figs. 6.11-6.12), projection-
matrix kinematic gradients (section 7.1.3) against finite differences of the assembled
kinematics, gradients through assembly and simulation, and the dynamic residual bound."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxveh
from jaxveh import multibody as mb, vehicle
from jaxveh.params import HARD_POINT_NAMES, load_vehicle_data

#: Assembly converges quadratically; residual after 25 Newton steps is round-off.
ASSEMBLY_RESIDUAL = 1e-12
#: Finite-difference step (m) for kinematic gradients; central differences of smooth curves
#: with O(1) curvature per 0.1 m give errors ~1e-10, round-off ~1e-16/1e-5 = 1e-11.
FD_STEP = 1e-5
GRADIENT_ATOL = 1e-8
#: The rack steers strongly (~17 rad/m), so the FD truncation error (h^2/6 times the third
#: derivative) of the track curve reaches ~1e-8; a relative tolerance covers it.
RACK_RTOL = 1e-5
#: Constraint residual bound promised by the simulate wrapper (m).
RESIDUAL_BOUND = 1e-9


@pytest.fixture(scope="module")
def car():
    return vehicle.quarter_car()


def _outputs(system, params, bump, rack):
    _, out = vehicle.quarter_car_kinematics(system, params, bump, rack)
    return jnp.stack([out["camber"], out["toe"], out["track"], out["wheel_centre"][0]])


def test_kinematics_assemble_and_match_design(car):
    system, params = car
    sweep = jax.jit(jax.vmap(lambda b: vehicle.quarter_car_kinematics(system, params, b, 0.0)[1]))
    out = sweep(jnp.linspace(-0.025, 0.025, 11))
    assert float(jnp.max(out["residual"])) < ASSEMBLY_RESIDUAL
    mid = 5
    np.testing.assert_allclose(out["camber"][mid], 0.0, atol=1e-14)  # Table B.1: zero static camber
    np.testing.assert_allclose(out["toe"][mid], 0.0, atol=1e-14)
    np.testing.assert_allclose(out["track"][mid], 1.26, atol=1e-12)  # Table B.1 front track
    np.testing.assert_allclose(out["wheel_centre"][:, 2], 0.255 + np.linspace(-0.025, 0.025, 11), atol=1e-14)
    # double wishbone with a shorter upper arm: camber becomes negative in bump (top inwards)
    assert np.all(np.diff(np.asarray(out["camber"])) < 0.0)


def _gradients_from_r(system, params, q, rack):
    """d(outputs)/d(wheel-centre z) and d(outputs)/d(rack) from R and S b (section 7.1.3)."""
    inputs = lambda t: jnp.reshape(rack + t, (1,))  # unit rack rate  # noqa: E731
    proj = mb.projection(system, params, q, 0.0, inputs)
    bt = mb.velocity_matrix(system, params, q)

    def outputs(qq):
        camber, toe = vehicle.wheel_angles(system, params, qq)
        return jnp.stack([camber, toe, 2.0 * qq[1], qq[0]])

    dq_ds = bt @ proj.R[:, 0]  # unit independent bump velocity (upright body uz)
    d_bump = jax.jvp(outputs, (q,), (dq_ds,))[1] / dq_ds[2]  # per unit global wheel-centre z
    d_rack = jax.jvp(outputs, (q,), (bt @ proj.Sb,))[1]  # at z = 0: bump and spin held
    return d_bump, d_rack


def test_projection_gradients_match_finite_differences(car):
    system, params = car
    kin = jax.jit(lambda b, r: _outputs(system, params, b, r))
    grads = jax.jit(lambda q, r: _gradients_from_r(system, params, q, r))
    for bump in (0.0, 0.015):
        q, _ = vehicle.quarter_car_kinematics(system, params, bump, 0.0)
        d_bump, d_rack = grads(q, 0.0)
        fd = (kin(bump + FD_STEP, 0.0) - kin(bump - FD_STEP, 0.0)) / (2 * FD_STEP)
        np.testing.assert_allclose(d_bump, fd, atol=GRADIENT_ATOL)
        if bump == 0.0:  # at design the upright axes are global, so z = 0 holds the wheel height
            fd_rack = (kin(0.0, FD_STEP) - kin(0.0, -FD_STEP)) / (2 * FD_STEP)
            np.testing.assert_allclose(d_rack, fd_rack, rtol=RACK_RTOL, atol=GRADIENT_ATOL)
            assert abs(float(d_rack[1])) > 1.0  # the rack steers: > 1 rad of toe per m of rack


def test_camber_gradient_with_respect_to_hard_points(car):
    """jax.grad through assembly (unrolled Newton) w.r.t. the upper ball joint H."""
    system, params = car
    hp = load_vehicle_data().hard_points_front.points
    w = jnp.asarray([0.0, 0.63, vehicle.WHEEL_CENTRE_HEIGHT])
    k = HARD_POINT_NAMES.index("H")

    def camber_at_bump(hz):
        p = vehicle.quarter_car_with_hard_points(system, params, hp.at[k, 2].set(hz), w)
        return vehicle.quarter_car_kinematics(system, p, 0.02, 0.0, wheel_centre=w)[1]["camber"]

    f = jax.jit(camber_at_bump)
    g = float(jax.jit(jax.grad(camber_at_bump))(hp[k, 2]))
    h = 1e-6
    fd = (float(f(hp[k, 2] + h)) - float(f(hp[k, 2] - h))) / (2 * h)
    np.testing.assert_allclose(g, fd, rtol=1e-6)
    assert abs(g) > 1e-3


def test_redundant_sixth_link_is_named():
    # rebuild the quarter car with the lower-rear link defined twice
    hp = load_vehicle_data().hard_points_front.points
    w = np.array([0.0, 0.63, vehicle.WHEEL_CENTRE_HEIGHT])
    b = mb.SystemBuilder()
    b.add_rigid_body("upright", 14.0, np.eye(3) * 0.3, rotation="zxy")
    pts = {n: np.asarray(hp[HARD_POINT_NAMES.index(n)]) for n in ("A", "B", "C", "E", "F", "H", "L", "M")}
    for n in ("A", "B", "E", "F", "L"):
        b.add_point(n, "ground", pts[n])
    for n in ("C", "H", "M"):
        b.add_point(n, "upright", pts[n] - w)
    for name, pa, pb in vehicle.QUARTER_CAR_LINKS + (("lower_rear_again", "A", "C"),):
        b.add_link(name, pa, pb, np.linalg.norm(pts[pa] - pts[pb]))
    b.add_independent("upright", "uz")  # 6 - 6 = 0 left: the build names the redundancy count
    with pytest.raises(ValueError, match="1 constraint equation\\(s\\) are redundant"):
        b.build()


@pytest.fixture(scope="module")
def drop_run(car):
    system, params = car
    q0 = vehicle.quarter_car_design_q(system)
    rate = vehicle.WheelRate(k=20000.0, c=0.0, z0=vehicle.WHEEL_CENTRE_HEIGHT, fz=14.0 * jaxveh.GRAVITY)
    inputs = lambda t: jnp.zeros((1,))  # noqa: E731

    def run(params, rate, bump0):
        q = q0.at[2].add(bump0)
        q = mb.assemble(system, params, q, fixed=(2, 6), inputs=inputs, throw=False)
        z0 = jnp.asarray([0.0, 30.0])  # bump rate 0, wheel spinning at 30 rad/s
        ext = lambda q, v, t, a: a.force(system, params, q, v)  # noqa: E731
        return mb.simulate(
            system, params, q, z0, 0.0, 0.3, ts=jnp.linspace(0.0, 0.3, 31), inputs=inputs, external=ext, args=rate
        )

    return jax.jit(run), params, rate


@pytest.mark.slow
def test_quarter_car_bounce_residual_and_energy(car, drop_run):
    system, _ = car
    run, params, rate = drop_run
    sim = run(params, rate, jnp.asarray(0.02))
    assert float(sim.max_residual) < RESIDUAL_BOUND
    total = sim.energy + jax.vmap(rate.energy)(sim.q)
    assert float(jnp.max(jnp.abs(total - total[0]))) < 1e-6
    # it bounces: the wheel centre passes below its release height by several mm
    assert float(jnp.min(sim.q[:, 2])) < vehicle.WHEEL_CENTRE_HEIGHT + 0.02 - 0.01
    del system


@pytest.mark.slow
def test_gradient_of_simulation_wrt_mass_and_hard_point(car, drop_run):
    """jax.grad of the final wheel-centre height w.r.t. the upright mass and a hard point."""
    system, _ = car
    run, params, rate = drop_run
    hp = load_vehicle_data().hard_points_front.points
    w = jnp.asarray([0.0, 0.63, vehicle.WHEEL_CENTRE_HEIGHT])
    kc = HARD_POINT_NAMES.index("C")

    def final_height(x):
        mass, cz = x[0], x[1]
        p = vehicle.quarter_car_with_hard_points(system, params, hp.at[kc, 2].set(cz), w)
        p = eqx.tree_at(lambda s: s.bodies[0].mass, p, mass)
        return run(p, rate, jnp.asarray(0.02)).q[-1, 2]

    x0 = jnp.asarray([14.0, float(hp[kc, 2])])
    g = np.asarray(jax.jit(jax.grad(final_height))(x0))
    f = jax.jit(final_height)
    fd = [
        (float(f(x0.at[i].add(h))) - float(f(x0.at[i].add(-h)))) / (2 * h) for i, h in ((0, 1e-4), (1, 1e-6))
    ]
    np.testing.assert_allclose(g, fd, rtol=1e-4)


def test_unreachable_travel_raises_naming_constraint_and_gap(car):
    system, params = car
    with pytest.raises(mb.AssemblyError, match=r"bump 400 mm.*constraint \w+\[length\] residual \(gap\) \d"):
        vehicle.quarter_car_kinematics(system, params, 0.4, 0.0)


def test_unreachable_travel_in_jitted_sweep_is_flagged_and_finite(car):
    system, params = car
    sweep = jax.jit(jax.vmap(lambda b: vehicle.quarter_car_kinematics(system, params, b, 0.0)[1]))
    out = sweep(jnp.asarray([0.0, 0.02, 0.4]))
    np.testing.assert_array_equal(np.asarray(out["ok"]), [True, True, False])
    for key in ("camber", "toe", "track", "wheel_centre", "residual"):
        assert np.all(np.isfinite(np.asarray(out[key])))
    assert float(out["residual"][2]) > 1e-3  # the failed point says it failed


@pytest.mark.parametrize("link", ["lower_front", "upper_front"])
def test_halved_link_branch_jump_is_refused(car, link):
    """Halving a wishbone link lets Newton converge to a distant branch (70-125 deg of
    upright rotation): refused with a message, not returned as a camber curve."""
    system, params = car
    k = system.joint_names.index(link)
    halved = eqx.tree_at(lambda p: p.joints[k].length, params, params.joints[k].length * 0.5)
    result = mb.solve_assembly(
        system, halved, vehicle.quarter_car_design_q(system), (system.q_index("upright", "z"), 6),
        inputs=lambda t: jnp.zeros((1,)),
    )
    assert float(result.residual) < mb.ASSEMBLY_TOL  # Newton did converge ...
    assert not bool(result.ok)  # ... but on another branch
    with pytest.raises(mb.AssemblyError, match="jumped to another branch: a body rotated by"):
        vehicle.quarter_car_kinematics(system, halved, 0.0, 0.0)


def test_cli_inspect_unreachable_travel_fails_cleanly():
    from typer.testing import CliRunner

    from jaxveh.cli import app

    result = CliRunner().invoke(app, ["multibody", "inspect", "quarter-car", "--q", "0.4", "0", "--json"])
    assert result.exit_code == 2
    assert "cannot assemble: constraint" in result.output
