"""The engine a car needs: force elements on one kinematics pass, auxiliary states,
closed-loop inputs, named outputs at save times, events, and exact linearisation."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg
import scipy.optimize

from jaxveh import multibody as mb
from jaxveh.multibody import _examples as ex

#: Two integrations of the same equations at rtol 1e-10 agree to about this (m, rad).
SAME_MOTION_ATOL = 1e-8


def _pendulum_with_tip():
    """Double pendulum (section 5.7 values) with an extra point at the tip of the lower bar."""
    v = ex.DOUBLE_PENDULUM_DEFAULTS
    b = mb.SystemBuilder(gravity=(0.0, 0.0, -v["g"]))
    b.add_rigid_body("B1", v["m1"], np.eye(3) * v["J1"])
    b.add_rigid_body("B2", v["m2"], np.eye(3) * v["J2"], parent="B1")
    b.add_point("P0", "ground", (0.0, 0.0, 0.0))
    b.add_point("A", "ground", (0.3, 0.2, -0.4))
    b.add_point("P1", "B1", (0.0, 0.0, v["a1"]))
    b.add_point("P2", "B1", (0.0, 0.0, v["a1"] - v["l1"]))
    b.add_point("P3", "B2", (0.0, 0.0, v["a2"]))
    b.add_point("tip", "B2", (0.0, 0.0, -v["a2"]))
    b.add_revolute("C1", "P0", "P1", axis_i=(1, 0, 0))
    b.add_revolute("C2", "P2", "P3", axis_i=(1, 0, 0))
    b.add_independent("B1", "wx")
    b.add_independent("B2", "wx")
    system, params = b.build()
    q, z = ex.double_pendulum_state(system, params, (0.3, -0.5), (1.0, 2.0))
    return system, params, q, z


@pytest.fixture(scope="module")
def tip_pendulum():
    return _pendulum_with_tip()


@pytest.mark.slow
def test_spring_damper_element_equals_the_same_force_through_external(tip_pendulum):
    system, params, q, z = tip_pendulum
    k, c, l0 = 80.0, 3.0, 0.4
    element = mb.SpringDamper.between(system, "A", "tip", k=k, c=c, l0=l0)
    ia, it = system.point_index("A"), system.point_index("tip")

    def external(qq, v, t, args):
        x = mb.marker_positions(system, params, qq)
        d = x[it] - x[ia]
        length = jnp.linalg.norm(d)
        y = mb.joint_velocities(system, params, qq, z_of(qq, v))
        xd = mb.point_velocity(system, params, qq, y, "tip")
        tension = k * (length - l0) + c * (d / length) @ xd
        return mb.point_force(system, params, qq, "tip", -tension * d / length)

    def z_of(qq, v):  # independent velocities from body velocities (both bars' wx)
        return jnp.stack([v[3], v[9] - v[3]])

    run = dict(rtol=1e-10, atol=1e-12, ts=jnp.linspace(0.0, 1.0, 11))
    with_element = mb.simulate(system, params, q, z, 0.0, 1.0, elements=(element,), **run)
    with_external = mb.simulate(system, params, q, z, 0.0, 1.0, external=external, **run)
    free = mb.simulate(system, params, q, z, 0.0, 1.0, **run)
    np.testing.assert_allclose(with_element.q, with_external.q, atol=SAME_MOTION_ATOL)
    assert float(jnp.max(jnp.abs(with_element.q - free.q))) > 0.1  # the spring matters


@pytest.mark.slow
def test_first_order_lag_state_matches_closed_form():
    """``tau x_dot = t - x`` from x(0) = 0: ``x = t - tau (1 - exp(-t / tau))``."""
    system, params, q, z = _pendulum_with_tip()
    tau = 0.25
    lag = mb.FirstOrderLag(signal=lambda kin: kin.t, tau=tau)
    ts = jnp.linspace(0.0, 1.0, 21)
    sim = mb.simulate(system, params, q, z, 0.0, 1.0, ts=ts, elements=(lag,), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(sim.aux[:, 0], ts - tau * (1.0 - jnp.exp(-ts / tau)), atol=1e-9)
    assert mb.aux_names((lag,), ("driver",)) == ("driver.x",)


def _yaw_table(k_t=40.0, k_s=2000.0, a=0.3, b=0.35):
    """A yawing table on a revolute about z with a torsion spring to ground and a zero-length
    spring from its point (a, 0, 0) to a ground anchor (b, u, 0) moved by the rack ``u``."""
    builder = mb.SystemBuilder(gravity=(0.0, 0.0, 0.0))
    builder.add_input("rack")
    builder.add_rigid_body("table", 5.0, np.diag([0.1, 0.1, 0.2]), parent="ground", revolute=((0, 0, 0), (0, 0, 1)))
    builder.add_point("O", "ground", (0.0, 0.0, 0.0))
    builder.add_point("anchor", "ground", (b, 0.0, 0.0), input="rack", input_direction=(0.0, 1.0, 0.0))
    builder.add_point("hub", "table", (0.0, 0.0, 0.0))
    builder.add_point("arm", "table", (a, 0.0, 0.0))
    builder.add_independent("table", "theta_dot")
    system, params = builder.build()
    elements = (
        mb.TorsionSpring.between(system, "O", "hub", axis=(0, 0, 1), kt=k_t, ct=10.0),
        mb.SpringDamper.between(system, "anchor", "arm", k=k_s, c=0.0, l0=0.0),
    )
    return system, params, elements


@pytest.mark.slow
def test_closed_loop_rack_settles_where_the_closed_form_says():
    """Rack actuator ``tau u_dot = r - K psi - u`` (an aux state) steering the table: the
    settled yaw solves ``k_t psi = k_s a (u cos psi - b sin psi)`` with ``u = r - K psi``."""
    k_t, k_s, a, b, gain, ref, tau = 40.0, 2000.0, 0.3, 0.35, 0.5, 0.05, 0.01
    system, params, springs = _yaw_table(k_t, k_s, a, b)
    psi = lambda q: q[system.q_index("table", "theta")]  # noqa: E731
    actuator = mb.FirstOrderLag(signal=lambda kin: ref - gain * psi(kin.q), tau=tau)
    law = mb.StateInputs(
        value_fn=lambda t, q, aux: aux[:1],
        rate_fn=lambda t, q, aux: (ref - gain * psi(q) - aux[:1]) / tau,
    )
    sim = mb.simulate(
        system, params, jnp.zeros(1), jnp.zeros(1), 0.0, 8.0, elements=springs + (actuator,), inputs=law,
        rtol=1e-9, atol=1e-11,
    )
    settled = float(sim.q[-1, 0])
    root = scipy.optimize.brentq(
        lambda s: k_t * s - k_s * a * ((ref - gain * s) * np.cos(s) - b * np.sin(s)), -1.0, 1.0
    )
    assert settled == pytest.approx(root, abs=1e-7)
    assert float(sim.aux[-1, 0]) == pytest.approx(ref - gain * root, abs=1e-7)


@pytest.mark.slow
def test_outputs_at_save_times_do_not_force_steps(tip_pendulum):
    system, params, q, z = tip_pendulum
    ts = jnp.linspace(0.0, 2.0, 401)

    def outputs(t, state, dyn):
        return {"theta1": state.q[system.q_index("B1", "rot2_x")], "tip": dyn.kinematics.x[system.point_index("tip")]}

    spring = (mb.SpringDamper.between(system, "A", "tip", k=80.0, c=3.0, l0=0.4),)
    sim = mb.simulate(system, params, q, z, 0.0, 2.0, ts=ts, elements=spring, outputs=outputs, rtol=1e-8, atol=1e-10)
    assert int(sim.stats["num_steps"]) < ts.shape[0]
    reference = mb.simulate(system, params, q, z, 0.0, 2.0, ts=ts, elements=spring, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(sim.outputs["theta1"], reference.q[:, system.q_index("B1", "rot2_x")], atol=1e-6)
    tips = jax.vmap(lambda qq: mb.marker_positions(system, params, qq)[system.point_index("tip")])(reference.q)
    np.testing.assert_allclose(sim.outputs["tip"], tips, atol=1e-6)
    assert float(sim.max_residual) < 1e-9


@pytest.mark.slow
def test_event_stops_the_run_and_names_itself(tip_pendulum):
    system, params, q, z = tip_pendulum
    iy = system.q_index("B1", "rot2_x")
    sim = mb.simulate(
        system, params, q, z, 0.0, 3.0, events={"swing past 0.5 rad": lambda t, s: s.q[iy] > 0.5}, rtol=1e-8, atol=1e-10
    )
    assert sim.stop_reason == "event: swing past 0.5 rad"
    assert int(sim.status) == 1
    assert 0.0 < float(sim.stop_time) < 3.0
    assert float(sim.final.q[iy]) == pytest.approx(0.5, abs=1e-2)
    assert np.all(np.isfinite(np.asarray(sim.q)))  # held after the stop, no inf/NaN
    assert not bool(sim.valid[-1])


@pytest.mark.slow
def test_linearised_double_pendulum_matches_closed_form():
    """Hanging double pendulum: ``det(K - w^2 M) = 0`` with the section 5.7 closed-form M
    and the Hessian of the potential energy; A and B (a torque on the lower bar) equal
    central differences of the vector field in minimal coordinates."""
    system, params = ex.double_pendulum()
    q, z = ex.double_pendulum_state(system, params, (0.0, 0.0), (0.0, 0.0))
    torque = lambda qq, v, t, w: mb.body_torque(system, params, qq, "B2", jnp.stack([w[0], 0.0, 0.0]))  # noqa: E731
    lin = mb.linearise(system, params, q, z, external=torque, args=jnp.zeros(1))
    m_closed, _, _ = ex.double_pendulum_closed_form((0.0, 0.0), (0.0, 0.0))

    def potential(theta):
        qq, zz = ex.double_pendulum_state(system, params, theta, jnp.zeros(2))
        return mb.energy(system, params, qq, jnp.zeros(system.n_y))["gravity"]

    stiffness = np.asarray(jax.hessian(potential)(jnp.zeros(2)))
    w2 = np.sort(np.real(scipy.linalg.eigvals(stiffness, np.asarray(m_closed))))
    eig = np.sort(np.abs(np.linalg.eigvals(np.asarray(lin.A)).imag))[::2]
    np.testing.assert_allclose(eig**2, w2, rtol=1e-9)
    q_of = mb.chart(system, params, q)
    @jax.jit
    def f(x, w):
        return mb.minimal_rates(system, params, q_of, x[:2], x[2:], jnp.zeros(0), w, external=torque, with_args=True)

    x0, h, w0 = jnp.zeros(4), 1e-6, jnp.zeros(1)
    fd_a = np.stack([(f(x0.at[i].set(h), w0) - f(x0.at[i].set(-h), w0)) / (2 * h) for i in range(4)], 1)
    fd_b = (f(x0, jnp.full((1,), h)) - f(x0, jnp.full((1,), -h))) / (2 * h)
    np.testing.assert_allclose(lin.A, fd_a, atol=1e-6)
    np.testing.assert_allclose(lin.B[:, 0], fd_b, atol=1e-6)


@pytest.mark.slow
def test_linearised_spring_mass_chain_matches_closed_form():
    """Three 2 kg bodies in a line joined to ground and to each other by 1000 N/m spring
    elements (fixed-free chain): eigenfrequencies ``2 sqrt(k/m) sin((2j - 1) pi / 14)``."""
    k, m = 1000.0, 2.0
    b = mb.SystemBuilder(gravity=(0.0, 0.0, 0.0))
    b.add_point("G", "ground", (0.0, 0.0, 0.0))
    names = ["m1", "m2", "m3"]
    for n in names:
        b.add_rigid_body(n, m, np.eye(3) * 0.01)
        b.add_point(f"{n}.c", n, (0.0, 0.0, 0.0))
        for vel in ("ux", "uy", "uz", "wx", "wy", "wz"):
            b.add_independent(n, vel)
    system, params = b.build()
    pts = ["G"] + [f"{n}.c" for n in names]
    springs = tuple(mb.SpringDamper.between(system, pts[i], pts[i + 1], k=k, c=0.0, l0=1.0) for i in range(3))
    q = jnp.zeros(system.n_q)
    for i, n in enumerate(names):
        q = q.at[system.q_index(n, "x")].set(float(i + 1))
    lin = mb.linearise(system, params, q, jnp.zeros(system.n_dof), elements=springs)
    freq = np.sort(np.abs(np.linalg.eigvals(np.asarray(lin.A)).imag))[::2]
    expected = 2 * np.sqrt(k / m) * np.sin((2 * np.arange(1, 4) - 1) * np.pi / 14)
    np.testing.assert_allclose(freq[freq > 1e-3], expected, rtol=1e-10)


@pytest.mark.slow
def test_static_trim_of_the_yaw_table_and_its_implicit_gradient():
    """Held rack ``u``: the equilibrium yaw solves ``k_t psi = k_s a (u cos psi - b sin psi)``;
    d psi / d k_t by the implicit-function adjoint equals the closed form's derivative."""
    k_t, k_s, a, b, u = 40.0, 2000.0, 0.3, 0.35, 0.02
    system, params, springs = _yaw_table(k_t, k_s, a, b)
    rack = lambda t: jnp.full((1,), u)  # noqa: E731
    trim = mb.trim(system, params, jnp.zeros(1), inputs=rack, elements=springs)
    f = lambda s, kt: kt * s - k_s * a * (u * np.cos(s) - b * np.sin(s))  # noqa: E731
    root = scipy.optimize.brentq(lambda s: f(s, k_t), -1.0, 1.0)
    assert float(trim.q[0]) == pytest.approx(root, abs=1e-10)
    assert float(trim.residual) < mb.TRIM_ATOL

    def yaw(kt):
        els = (eqx.tree_at(lambda e: e.kt, springs[0], kt),) + springs[1:]
        return mb.trim(system, params, jnp.zeros(1), inputs=rack, elements=els).q[0]

    dpsi = float(jax.grad(yaw)(jnp.asarray(k_t)))
    dfds = k_t + k_s * a * (u * np.sin(root) + b * np.cos(root))
    assert dpsi == pytest.approx(-root / dfds, rel=1e-7)


def test_trim_counts_unknowns_and_reports_failure():
    system, params, springs = _yaw_table()
    with pytest.raises(ValueError, match="as many free unknowns as equations"):
        mb.trim(system, params, jnp.zeros(1), hold_z=(), inputs=lambda t: jnp.zeros(1), elements=springs)
    with pytest.raises(mb.TrimError, match="equilibrium not found"):
        mb.trim(system, params, jnp.zeros(1), inputs=lambda t: jnp.zeros(1), max_steps=1,
                elements=(mb.TorsionSpring.between(system, "O", "hub", axis=(0, 0, 1), kt=40.0, ct=0.0, phi0=0.5),))
