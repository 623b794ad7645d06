"""Flexible (modal) body: eq. (5.37)/(5.45) against the FE module's explicit invariant
formulas, free-free vibration at the FE frequency, a flexible pendulum's energy and
constraint residual, Table 7.2 simplifications, and gradients w.r.t. modal stiffness."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxveh import multibody as mb
from jaxveh.multibody import _examples as ex

#: Two independent implementations of the same float64 formulas.
FORMULA_ATOL = 1e-12
RESIDUAL_BOUND = 1e-9


@pytest.fixture(scope="module")
def beam():
    return ex.flexible_beam(n_modes=2, beta=0.0)


def test_mass_matrix_and_gyroscopic_forces_match_fe_formulas(beam):
    """Hamel/autodiff quadratic forces equal the explicit Gr, Ge, Oe terms of eq. (5.45)."""
    body = mb.FlexibleBody(beam)
    rng = np.random.default_rng(3)
    for _ in range(3):
        p = jnp.asarray(rng.normal(size=2) * 1e-2)
        v = jnp.asarray(rng.normal(size=8))
        full = mb.FlexOptions()
        np.testing.assert_allclose(body.mass_matrix(p, full), beam.mass_matrix(p), atol=FORMULA_ATOL)
        mine = mb.body_quadratic_forces(body, full, p, v)
        theirs = beam.quadratic_velocity_forces(p, v[:3], v[3:6], v[6:])
        np.testing.assert_allclose(mine, theirs, atol=FORMULA_ATOL)
        # neglecting Gr / Ge removes exactly sum_l pdot_l Gr_l omega and sum_l pdot_l Ge_l omega
        system, params = ex.flexible_pendulum(beam, pinned=False)
        system = system.with_options(mb.FlexOptions(neglect_gyroscopic=True))
        q = jnp.concatenate([jnp.zeros(6), p])
        qv, _ = mb.internal_forces(system, params, q, v)
        w, pd = v[3:6], v[6:]
        gr = jnp.einsum("l,lij,j->i", pd, beam.Gr(p), w)
        ge = jnp.einsum("l,ljk,k->j", pd, beam.Ge(), w)
        elastic = jnp.concatenate([jnp.zeros(6), beam.elastic_forces(p, pd)])
        np.testing.assert_allclose(qv, theirs + jnp.concatenate([jnp.zeros(3), gr, ge]) + elastic, atol=FORMULA_ATOL)


def test_free_free_vibration_at_fe_frequency(beam):
    """Floating beam, no gravity: mode 0 released from p0 oscillates at the FE frequency."""
    system, params = ex.flexible_pendulum(beam, pinned=False, gravity=0.0)
    f0 = float(beam.frequencies_hz[0])
    # small amplitude: with the tube's tiny polar inertia (8e-6 kg m^2, nodal rotary inertia)
    # the first-order mass matrix of eq. 5.37 stops being usable near p ~ 3e-4 (see docs)
    p0 = 1e-4
    q0 = jnp.concatenate([jnp.zeros(6), jnp.asarray([p0, 0.0])])
    z0 = jnp.zeros(system.n_dof)
    ts = jnp.linspace(0.0, 3.0 / f0, 61)
    sim = jax.jit(lambda p: mb.simulate(system, p, q0, z0, 0.0, 3.0 / f0, ts=ts, rtol=1e-10, atol=1e-13))(params)
    expected = p0 * np.cos(2 * np.pi * f0 * np.asarray(ts))
    # nonlinear (first-order-in-p) inertia coupling at p0 = 1e-4 is ~1e-7 relative
    np.testing.assert_allclose(np.asarray(sim.q[:, 6]), expected, atol=1e-10)
    np.testing.assert_allclose(np.asarray(sim.q[:, :6]), 0.0, atol=1e-9)  # mean-axis modes: frame at rest


@pytest.fixture(scope="module")
def pendulum(beam):
    system, params = ex.flexible_pendulum(beam)
    q0, z0 = ex.flexible_pendulum_state(system)
    ts = jnp.linspace(0.0, 0.4, 41)

    def run(system, params):
        return mb.simulate(system, params, q0, z0, 0.0, 0.4, ts=ts, rtol=1e-9, atol=1e-12)

    return system, params, run


def test_flexible_pendulum_energy_residual_and_deflection(pendulum):
    system, params, run = pendulum
    sim = jax.jit(lambda p: run(system, p))(params)
    assert float(sim.max_residual) < RESIDUAL_BOUND
    drift = float(jnp.max(jnp.abs(sim.energy - sim.energy[0])))
    assert drift < 1e-7  # J; the beam falls ~0.3 m, about 4 J of potential energy
    swing = np.asarray(sim.q[:, 5])
    assert swing[-1] > 0.5  # it swung down
    p_max = float(jnp.max(jnp.abs(sim.q[:, 6:])))
    assert 0.0 < p_max < 1e-2  # small elastic deflection


@pytest.mark.slow
def test_table_7_2_simplifications_on_fe_chassis():
    """Free-floating FE chassis (6 modes) tumbling with modal motion: the constant mass
    matrix and neglected c keep a Lagrangian (energy conserved) but change the response;
    neglecting Gr/Ge breaks energy conservation."""
    from jaxveh import fe

    modal = fe.frame_modal_body(fe.load_frame(), 6, beta=0.0)
    b = mb.SystemBuilder(gravity=(0.0, 0.0, 0.0))
    b.add_flexible_body("chassis", modal)
    for name in ("ux", "uy", "uz", "wx", "wy", "wz") + tuple(f"p{k}_dot" for k in range(6)):
        b.add_independent("chassis", name)
    system, params = b.build()
    q0 = jnp.zeros(12).at[6:].set(1e-3)
    z0 = jnp.concatenate([jnp.asarray([1.0, 0.0, 0.0, 2.0, 1.0, 3.0]), jnp.full((6,), 0.05)])
    ts = jnp.linspace(0.0, 0.1, 11)

    def run(options):
        s = system.with_options(options)
        return jax.jit(lambda p: mb.simulate(s, p, q0, z0, 0.0, 0.1, ts=ts, rtol=1e-9, atol=1e-12))(params)

    def drift(sim):
        return float(jnp.max(jnp.abs(sim.energy - sim.energy[0])))

    base = run(mb.FlexOptions())
    amplitude = float(jnp.max(jnp.abs(base.q[:, 6:])))
    assert drift(base) < 1e-7
    const = run(mb.FlexOptions(constant_mass=True))
    assert drift(const) < 1e-7
    assert 1e-3 * amplitude < float(jnp.max(jnp.abs(const.q[:, 6:] - base.q[:, 6:]))) < 0.5 * amplitude
    no_gyro = run(mb.FlexOptions(neglect_gyroscopic=True))
    assert drift(no_gyro) > 1e-4
    assert float(jnp.max(jnp.abs(no_gyro.q[:, 6:] - base.q[:, 6:]))) < 0.5 * amplitude


@pytest.mark.slow
def test_gradient_wrt_modal_stiffness(pendulum):
    system, params, run = pendulum

    def peak_mode(scale):
        p = eqx.tree_at(lambda s: s.bodies[0].modal.stiffness_scale, params, scale)
        return run(system, p).q[-1, 6]

    s0 = jnp.asarray([1.0, 1.0])
    g = np.asarray(jax.jit(jax.grad(peak_mode))(s0))
    f = jax.jit(peak_mode)
    h = 1e-5
    fd = [(float(f(s0.at[i].add(h))) - float(f(s0.at[i].add(-h)))) / (2 * h) for i in range(2)]
    np.testing.assert_allclose(g, fd, rtol=1e-4, atol=1e-12)


#: Linearised floating-frame model in the complete modal basis against the FE model itself:
#: the same linear equations in another basis, so agreement is to round-off.
FULL_BASIS_RTOL = 1e-7


@pytest.fixture(scope="module")
def pinned_tube():
    """A 1 m, 12 x 1 mm steel tube (4 elements, 30 DOF) pinned at its start by a revolute
    joint about y; the FE model clamped in the same five DOFs (the revolute leaves ry free)."""
    import scipy.linalg

    from jaxveh import fe

    frame = fe.straight_tube_frame(1.0, 4, 0.012, 0.001)
    k, m = (np.asarray(a) for a in fe.assemble(frame))
    start = frame.node_index("start")
    free = [i for i in range(k.shape[0]) if i not in {6 * start + c for c in (0, 1, 2, 3, 5)}]
    w2 = scipy.linalg.eigh(k[np.ix_(free, free)], m[np.ix_(free, free)], eigvals_only=True)
    reference_hz = np.sqrt(np.clip(w2, 0.0, None)) / (2 * np.pi)
    return frame, reference_hz


def _pinned_frequencies(frame, n_modes):
    from jaxveh import fe
    from jaxveh.multibody._linear import linearise

    modal = fe.frame_modal_body(frame, n_modes, points=("start", "end"), damping_ratio=0.0)
    system, params = ex.flexible_pendulum(modal, gravity=0.0)
    q, z = ex.flexible_pendulum_state(system, 0.0)
    eig = np.linalg.eigvals(np.asarray(linearise(system, params, q, z).A))
    return np.sort(np.abs(eig.imag))[::2] / (2 * np.pi)


@pytest.mark.slow
def test_revolute_on_flexible_body_clamps_rotational_mode_shapes(pinned_tube):
    """A revolute joint on a flexible body holds the material rotation at the joint (frame
    rotation plus rotational mode shapes): with every elastic mode kept the pinned tube has
    exactly the FE model's clamped-free (out-of-plane) and pinned-free (in-plane)
    frequencies; a truncated basis is a Ritz approximation, so it bounds them from above."""
    frame, reference_hz = pinned_tube
    full = _pinned_frequencies(frame, 24)
    np.testing.assert_allclose(full[1:10], reference_hz[1:10], rtol=FULL_BASIS_RTOL)
    assert reference_hz[1] == pytest.approx(10.86, abs=0.01)  # cantilever 1.875^2 sqrt(EI/rho A L^4)/2pi
    truncated = _pinned_frequencies(frame, 4)
    assert reference_hz[1] < truncated[1] < 1.5 * reference_hz[1]


def test_revolute_constraint_rates_on_flexible_body():
    """``Phi_q B T y`` of a revolute joint on a flexible body equals the time derivative of
    ``Phi`` along ``q_dot = B T y`` (rotational mode shapes included)."""
    from jaxveh.multibody._kinematics import body_poses, body_velocities, constraint_rates

    system, params = ex.flexible_pendulum(ex.flexible_beam(n_modes=4, beta=0.0))
    q, _ = ex.flexible_pendulum_state(system, 0.3, (2e-3, -1e-3, 5e-4, 1e-3))
    y = jnp.asarray(np.random.default_rng(0).normal(size=system.n_y))
    _, q_dot = mb.velocity_maps(system, params, q, y)
    poses = body_poses(system, params, q)
    rates = constraint_rates(system, params, poses, body_velocities(system, params, q, y, poses), jnp.zeros((0,)))
    phi_dot = jax.jvp(lambda qq: mb.constraints(system, params, qq), (q,), (q_dot,))[1]
    np.testing.assert_allclose(rates, phi_dot, atol=1e-12)
