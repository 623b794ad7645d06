"""Relaxation-length lag, slip kinematics, vertical tyre and the mapping to vehicle axes."""

from pathlib import Path

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import assert_grad_matches_fd
from jax.test_util import check_grads

import jaxveh.tyre as jt

FSAE = jt.load_fsae_tyre()
FIXTURE = jt.read_tir(Path(__file__).parent / "data" / "tyre_mf52_fixture.tir")
#: ODE solution against the closed-form exponential (Tsit5, rtol 1e-10)
ODE_RTOL = 1e-7


def test_table_b4_values():
    assert float(FSAE.vertical_stiffness) == 150000.0 and float(FSAE.vertical_damping) == 50.0
    sk, sa = jt.relaxation_lengths(FSAE, 700.0, 0.0)
    assert float(sk) == 0.3 and float(sa) == 0.3


def test_mf52_relaxation_lengths_closed_form():
    t, fz, g = FIXTURE, 2800.0, 0.02
    fz0, r0 = 3500.0, 0.31
    dfz = (fz - fz0) / fz0
    sk, sa = jt.relaxation_lengths(t, fz, g)
    np.testing.assert_allclose(sk, fz * (2.0 + 0.4 * dfz) * np.exp(-0.1 * dfz) * r0 / fz0, rtol=1e-13)
    np.testing.assert_allclose(sa, 2.1 * np.sin(2 * np.arctan(fz / (2.5 * fz0))) * (1 - 0.6 * g) * r0, rtol=1e-13)
    sk0, sa0 = jt.relaxation_lengths(t, -100.0, 0.0)  # lift-off: floored load, still positive
    assert float(sk0) > 0.0 and float(sa0) > 0.0


@pytest.mark.parametrize("tyre", [FSAE, FIXTURE], ids=["constant", "mf52"])
def test_lag_is_first_order_with_time_constant_sigma_over_v(tyre):
    fz, gamma, vx, vsx, vsy = 700.0, 0.0, 12.0, -0.6, 0.9
    sk, sa = (float(s) for s in jt.relaxation_lengths(tyre, fz, gamma))
    term = diffrax.ODETerm(lambda t, y, args: jt.transient_slip_rhs(tyre, y, fz, gamma, vx, vsx, vsy))
    ts = jnp.linspace(0.0, 0.2, 21)
    sol = diffrax.diffeqsolve(
        term, diffrax.Tsit5(), 0.0, 0.2, 1e-3, jnp.zeros(2), saveat=diffrax.SaveAt(ts=ts),
        stepsize_controller=diffrax.PIDController(rtol=1e-10, atol=1e-12),
    )
    u_ss, v_ss = -sk * vsx / vx, sa * vsy / vx
    t = np.asarray(ts)
    np.testing.assert_allclose(sol.ys[:, 0], u_ss * (1 - np.exp(-vx * t / sk)), rtol=ODE_RTOL, atol=1e-12)
    np.testing.assert_allclose(sol.ys[:, 1], v_ss * (1 - np.exp(-vx * t / sa)), rtol=ODE_RTOL, atol=1e-12)
    # the lagged slips tend to the steady-state slips
    k_ss, a_ss = jt.steady_slips(tyre, vx, vsx, vsy)
    k_l, a_l = jt.transient_slips(tyre, jnp.asarray([u_ss, v_ss]), fz, gamma)
    np.testing.assert_allclose([k_l, a_l], [k_ss, a_ss], rtol=1e-13)


def test_transient_rhs_at_standstill_is_finite_and_integrates_slip_velocity():
    d = jt.transient_slip_rhs(FSAE, jnp.asarray([0.01, -0.02]), 500.0, 0.0, 0.0, 0.3, -0.2)
    np.testing.assert_allclose(d, [-0.3, -0.2], rtol=1e-15)
    g = jax.grad(lambda v: jt.transient_slip_rhs(FSAE, jnp.asarray([0.01, -0.02]), 500.0, 0.0, v, 0.3, -0.2).sum())(0.0)
    assert np.isfinite(float(g))


def test_transient_rhs_gradient_wrt_relaxation_length():
    def f(x):
        t = eqx.tree_at(lambda t: (t.sigma_kappa, t.sigma_alpha), FSAE, (x[0], x[1]))
        return jnp.sum(jt.transient_slip_rhs(t, jnp.asarray([0.02, -0.01]), 600.0, 0.0, 10.0, 0.3, 0.4) ** 2)

    assert_grad_matches_fd(f, np.array([0.3, 0.25]), h=1e-7, rtol=1e-6)


def test_check_grads_of_transient_slip_model():
    """Deflection rates in deflections, speed and relaxation lengths; MF 5.2 lengths in load."""

    def rhs(x):
        t = eqx.tree_at(lambda t: (t.sigma_kappa, t.sigma_alpha), FSAE, (x[3], x[4]))
        return jt.transient_slip_rhs(t, x[:2], 600.0, 0.0, x[2], 0.3, 0.4)

    check_grads(rhs, (jnp.asarray([0.02, -0.01, 10.0, 0.3, 0.25]),), order=2, modes=("fwd", "rev"), eps=1e-6)
    check_grads(lambda fz: jnp.stack(jt.relaxation_lengths(FIXTURE, 1e3 * fz, 0.02)), (jnp.asarray(3.0),), order=2,
                modes=("fwd", "rev"), eps=1e-5)


def test_steady_slips_low_speed_treatment():
    vxlow = float(FSAE.vxlow)
    k, a = jt.steady_slips(FSAE, 10.0, -0.5, 0.3)
    np.testing.assert_allclose([k, a], [0.05, np.arctan(0.03)], rtol=1e-15)  # exact above VXLOW
    for vx in (0.0, 1e-300, -0.3):
        out = jt.steady_slips(FSAE, vx, -0.5, 0.3)
        assert all(np.isfinite(float(o)) for o in out)
    den = jax.vmap(lambda v: jt.low_speed_denominator(v, vxlow))
    dden = jax.vmap(jax.grad(lambda v: jt.low_speed_denominator(v, vxlow)))
    eps = 1e-9
    v = jnp.asarray([vxlow - eps, vxlow + eps])
    assert abs(float(den(v)[1] - den(v)[0])) < 1e-8 and abs(float(dden(v)[1] - dden(v)[0])) < 1e-8  # C1
    assert float(den(jnp.asarray([0.0]))[0]) == 0.5 * vxlow


def test_vertical_force_spring_damper_and_lift_off():
    np.testing.assert_allclose(jt.vertical_force(FSAE, 0.004, 0.1), 150000.0 * 0.004 + 50.0 * 0.1, rtol=1e-15)
    assert float(jt.vertical_force(FSAE, -0.001, 0.0)) == 0.0  # airborne
    assert float(jt.vertical_force(FSAE, 0.001, -10.0)) == 0.0  # damper would pull: lifted off
    rho = jnp.linspace(-1e-3, 1e-3, 2001)
    fz = jax.vmap(lambda r: jt.vertical_force(FSAE, r, 0.05))(rho)
    assert np.abs(np.diff(np.asarray(fz))).max() < 1.0  # continuous: 150 N/mm at most 0.15 N per step
    assert np.isfinite(float(jax.grad(lambda r: jt.vertical_force(FSAE, r, 0.0))(0.0)))


def test_rolling_radii():
    fz = 700.0
    np.testing.assert_allclose(jt.loaded_radius(FSAE, fz), 0.254 - fz / 150000.0, rtol=1e-15)
    rho_fz0 = 750.0 / 150000.0
    ref = 0.254 - rho_fz0 * (0.27 * np.arctan(8.4 * fz / 750.0) + 0.07 * fz / 750.0)
    np.testing.assert_allclose(jt.effective_rolling_radius(FSAE, fz), ref, rtol=1e-15)
    # the effective radius lies between loaded and free radius, as for real tyres
    assert float(jt.loaded_radius(FSAE, fz)) < float(jt.effective_rolling_radius(FSAE, fz)) < 0.254
    assert float(jt.effective_rolling_radius(FSAE, -5.0)) == 0.254


def test_axes_mapping_round_trip_and_signs():
    delta = 0.2
    f = jt.TyreForces(*(jnp.asarray(x) for x in (300.0, -800.0, 5.0, -2.0, 20.0)))
    force, moment = jt.forces_to_vehicle(f, 700.0, delta)
    # rotating back into the wheel frame recovers the ISO-W components
    c, s = np.cos(delta), np.sin(delta)
    in_wheel_axes = [c * force[0] + s * force[1], -s * force[0] + c * force[1], force[2]]
    np.testing.assert_allclose(in_wheel_axes, [300.0, -800.0, 700.0], rtol=1e-14)
    np.testing.assert_allclose(moment[2], 20.0)
    np.testing.assert_allclose(np.linalg.norm(force[:2]), np.hypot(300.0, -800.0), rtol=1e-14)
    # a wheel steered left (delta > 0) on a car going straight slides right: negative alpha,
    # positive (leftward) Fy in ISO-W: the car is pushed left
    vx_w, vsx, vsy = jt.slip_velocities(jnp.asarray([10.0, 0.0, 0.0]), 0.05, 10.0 * np.cos(0.05) / 0.25, 0.25)
    k, a = jt.steady_slips(FSAE, vx_w, vsx, vsy)
    assert float(a) < 0.0 and abs(float(k)) < 1e-14
    fy = jt.tyre_forces(FSAE, 700.0, k, a, 0.0, vx_w).fy
    assert float(jt.forces_to_vehicle(jt.TyreForces(0.0, fy, 0.0, 0.0, 0.0), 700.0, 0.05)[0][1]) > 0.0
    # camber: top of a left wheel leaning outboard (+y) is negative ISO-W inclination, and the
    # camber thrust pushes outboard (+y); mirrored on the right
    g_left, g_right = jt.inclination_angle(0.03, 1.0), jt.inclination_angle(0.03, -1.0)
    assert float(g_left) == -0.03 and float(g_right) == 0.03
    assert float(jt.tyre_forces(FSAE, 700.0, 0.0, 0.0, g_left, 11.0).fy) > 0.0
    assert float(jt.tyre_forces(FSAE, 700.0, 0.0, 0.0, g_right, 11.0).fy) < 0.0
    # lift-off: no vertical pull
    assert float(jt.forces_to_vehicle(f, -10.0, 0.0)[0][2]) == 0.0


def test_abstract_tyre_interface():
    assert isinstance(FSAE, jt.AbstractTyre)
    f = jax.jit(lambda t: t.forces(700.0, 0.05, 0.02, 0.0, 11.0))(FSAE)
    ref = jt.tyre_forces(FSAE, 700.0, 0.05, 0.02, 0.0, 11.0)
    np.testing.assert_allclose(list(f), list(ref), rtol=1e-14)
    assert FSAE.relaxation_lengths(700.0, 0.0) == jt.relaxation_lengths(FSAE, 700.0, 0.0)
    assert float(FSAE.vertical_force(0.002, 0.0)) == 300.0
    assert float(FSAE.effective_rolling_radius(700.0)) == float(jt.effective_rolling_radius(FSAE, 700.0))
