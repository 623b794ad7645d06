"""Four-bar linkage (closed loop): constraint residual, energy conservation, and agreement
with an independent SciPy solution of the hand-derived minimal-coordinate Lagrangian."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from jaxveh import multibody as mb
from jaxveh.multibody import _examples as ex

#: Constraint residual bound promised by the simulate wrapper (m).
RESIDUAL_BOUND = 1e-9
#: Crank-angle agreement (rad): both integrations at rtol <= 1e-9; the reference uses
#: central differences (h = 1e-6) for M'(theta), V'(theta), error ~1e-9 relative.
ANGLE_ATOL = 2e-6
#: Energy drift bound (J) over 2 s at rtol 1e-9 with ~0.7 J of kinetic energy.
ENERGY_ATOL = 1e-7


def _e(a):
    return np.array([np.cos(a), np.sin(a)])


def _de(a):
    return np.array([-np.sin(a), np.cos(a)])


def _minimal_model(v):
    """Generalised mass M(theta) and potential V(theta) of the crank-angle Lagrangian."""
    l1, l2, l3 = v["crank"], v["coupler"], v["rocker"]
    m = (v["m_crank"], v["m_coupler"], v["m_rocker"])
    j = tuple(mi * li**2 / 12.0 for mi, li in zip(m, (l1, l2, l3)))

    def coefficients(th):
        beta, gamma = ex.four_bar_angles(th, v)
        lhs = np.stack([l2 * _de(beta), -l3 * _de(gamma)], axis=1)
        db, dg = np.linalg.solve(lhs, -l1 * _de(th))
        v1 = 0.5 * l1 * _de(th)
        v2 = l1 * _de(th) + 0.5 * l2 * _de(beta) * db
        v3 = 0.5 * l3 * _de(gamma) * dg
        return (beta, gamma), (v1, v2, v3), (1.0, db, dg)

    def mass(th):
        _, vs, ws = coefficients(th)
        return sum(mi * vi @ vi + ji * wi**2 for mi, vi, ji, wi in zip(m, vs, j, ws))

    def potential(th):
        (beta, gamma), _, _ = coefficients(th)
        z = (0.5 * l1 * _e(th)[1], l1 * _e(th)[1] + 0.5 * l2 * _e(beta)[1], 0.5 * l3 * _e(gamma)[1])
        return v["g"] * sum(mi * zi for mi, zi in zip(m, z))

    return mass, potential


def _reference(theta0, omega0, ts, v):
    mass, potential = _minimal_model(v)
    h = 1e-6

    def rhs(_, s):
        th, w = s
        dm = (mass(th + h) - mass(th - h)) / (2 * h)
        dv = (potential(th + h) - potential(th - h)) / (2 * h)
        return [w, (-dv - 0.5 * dm * w**2) / mass(th)]

    sol = solve_ivp(rhs, (ts[0], ts[-1]), [theta0, omega0], t_eval=ts, method="DOP853", rtol=1e-10, atol=1e-10)
    return sol.y[0]


@pytest.mark.slow
def test_four_bar_against_scipy_minimal_coordinates():
    v = ex.FOUR_BAR_DEFAULTS
    system, params = ex.four_bar()
    theta0, omega0 = 0.7, 3.0
    coupler, rocker = ex.four_bar_angles(theta0)
    q0 = jnp.asarray([theta0, coupler - theta0, rocker])
    np.testing.assert_allclose(mb.constraints(system, params, q0), 0.0, atol=1e-14)
    mb.check_rank(system, params, q0)
    ts = np.linspace(0.0, 2.0, 21)
    sim = mb.simulate(system, params, q0, jnp.asarray([omega0]), 0.0, 2.0, ts=jnp.asarray(ts), rtol=1e-9)
    assert float(sim.max_residual) < RESIDUAL_BOUND
    assert float(jnp.max(jnp.abs(sim.energy - sim.energy[0]))) < ENERGY_ATOL
    ref = _reference(theta0, omega0, ts, v)
    np.testing.assert_allclose(np.asarray(sim.q[:, 0]), ref, atol=ANGLE_ATOL)
    # the generalised mass of the projection equals the hand-derived one along the path
    mass, _ = _minimal_model(v)
    picks = jnp.asarray([0, 7, 15])
    reduced = jax.jit(jax.vmap(lambda q, z: mb.dynamics(system, params, q, z).mass_matrix[0, 0]))
    got = reduced(sim.q[picks], sim.z[picks])
    want = [mass(float(sim.q[k, 0])) for k in (0, 7, 15)]
    np.testing.assert_allclose(np.asarray(got), want, rtol=1e-10)


def test_assembly_reports_the_failing_constraint():
    system, params = ex.four_bar({"coupler": 0.15, "rocker": 0.1})  # tip-to-pivot 0.3 m > 0.15 + 0.1
    q_guess = jnp.asarray([0.0, 0.0, 1.5])
    try:
        mb.assemble(system, params, q_guess, fixed=(0,))
    except mb.AssemblyError as e:
        assert "pin[" in str(e) and "residual" in str(e)
    else:
        raise AssertionError("assembly of an impossible four-bar did not fail")
