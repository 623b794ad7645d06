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
    p0 = 1e-3
    q0 = jnp.concatenate([jnp.zeros(6), jnp.asarray([p0, 0.0])])
    z0 = jnp.zeros(system.n_dof)
    ts = jnp.linspace(0.0, 3.0 / f0, 61)
    sim = jax.jit(lambda p: mb.simulate(system, p, q0, z0, 0.0, 3.0 / f0, ts=ts, rtol=1e-10, atol=1e-13))(params)
    expected = p0 * np.cos(2 * np.pi * f0 * np.asarray(ts))
    # nonlinear (first-order-in-p) inertia coupling at p0 = 1e-3 is ~1e-6 relative
    np.testing.assert_allclose(np.asarray(sim.q[:, 6]), expected, atol=1e-8)
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
