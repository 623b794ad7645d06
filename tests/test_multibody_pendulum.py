"""Double pendulum of thesis section 5.7: reduced M, Qi, Qe against the printed closed forms,
multipliers, named errors, vmap / no-retrace, and the inspection CLI contract."""

import json

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from typer.testing import CliRunner

from jaxveh import multibody as mb
from jaxveh.cli._main import app
from jaxveh.multibody import _examples as ex

#: Closed forms vs projection: both exact, differences are float64 round-off of O(10) terms.
CLOSED_FORM_RTOL = 1e-11
CLOSED_FORM_ATOL = 1e-11
#: Constraint residual bound promised by the simulate wrapper (m or rad).
RESIDUAL_BOUND = 1e-9


def _random_values(rng):
    return {
        "m1": rng.uniform(0.5, 3.0),
        "m2": rng.uniform(0.5, 3.0),
        "J1": rng.uniform(0.01, 0.5),
        "J2": rng.uniform(0.01, 0.5),
        "l1": rng.uniform(0.5, 1.5),
        "a1": rng.uniform(0.1, 0.5),
        "a2": rng.uniform(0.1, 0.8),
        "g": rng.uniform(1.0, 10.0),
    }


@pytest.mark.parametrize("tree", [False, True])
def test_closed_forms_random_states_and_parameters(tree):
    rng = np.random.default_rng(5 + tree)
    system, _ = ex.double_pendulum(tree=tree)

    @jax.jit
    def reduced(params, theta, omega):
        q, z = ex.double_pendulum_state(system, params, theta, omega)
        dyn = mb.dynamics(system, params, q, z)
        return dyn.mass_matrix, dyn.internal_forces, dyn.external_forces

    for _ in range(4):
        values = _random_values(rng)
        theta, omega = rng.uniform(-2.5, 2.5, 2), rng.uniform(-3.0, 3.0, 2)
        built, params = ex.double_pendulum(values, tree=tree)
        assert built == system  # same static topology: parameters only change leaves
        got = reduced(params, jnp.asarray(theta), jnp.asarray(omega))
        for g, want in zip(got, ex.double_pendulum_closed_form(theta, omega, values)):
            np.testing.assert_allclose(g, want, rtol=CLOSED_FORM_RTOL, atol=CLOSED_FORM_ATOL)


def test_constraints_velocity_and_projection_identities():
    system, params = ex.double_pendulum()
    q, z = ex.double_pendulum_state(system, params, (0.4, 0.9), (1.3, -0.7))
    proj = mb.projection(system, params, q)
    phi_y = mb.constraint_jacobian(system, params, q) @ mb.velocity_matrix(system, params, q)
    np.testing.assert_allclose(proj.phi_y, phi_y, atol=1e-14)  # explicit rates == autodiff Phi_q B T
    np.testing.assert_allclose(proj.phi, 0.0, atol=1e-15)
    # eq. (5.56): Phi_q B T R = 0 and P R = I
    np.testing.assert_allclose(phi_y @ proj.R, 0.0, atol=1e-13)
    np.testing.assert_allclose(proj.R[jnp.asarray(system.independent)], np.eye(2), atol=1e-14)
    # the tip of B2 moves with the closed-form velocity
    y = proj.R @ z
    l1, a2 = ex.DOUBLE_PENDULUM_DEFAULTS["l1"], ex.DOUBLE_PENDULUM_DEFAULTS["a2"]
    vel = mb.point_velocity(system, params, q, y, "P3")  # B2's point at the joint: moves with B1's tip
    t1, w1 = 0.4, 1.3
    np.testing.assert_allclose(vel, [0.0, l1 * np.cos(t1) * w1, l1 * np.sin(t1) * w1], atol=1e-13)
    del a2


def test_multipliers_are_joint_reactions_at_rest():
    """Hanging at rest: the pivot carries the total weight, the elbow the weight of B2."""
    values = dict(ex.DOUBLE_PENDULUM_DEFAULTS)
    system, params = ex.double_pendulum(values)
    q, z = ex.double_pendulum_state(system, params, (0.0, 0.0), (0.0, 0.0))
    lam = mb.multipliers(system, mb.dynamics(system, params, q, z))
    g, m1, m2 = values["g"], values["m1"], values["m2"]
    # force on the second point's body is +lambda (on the first, -lambda): B1 under C1, B2 under C2
    np.testing.assert_allclose(lam[system.constraint_rows("C1")][:3], [0, 0, (m1 + m2) * g], atol=1e-11)
    np.testing.assert_allclose(lam[system.constraint_rows("C2")][:3], [0, 0, m2 * g], atol=1e-11)


@pytest.mark.slow
def test_energy_and_residual_in_simulation():
    system, params = ex.double_pendulum()
    q, z = ex.double_pendulum_state(system, params, (1.2, -0.5), (1.0, 2.0))
    sim = mb.simulate(system, params, q, z, 0.0, 3.0, ts=jnp.linspace(0.0, 3.0, 31))
    drift = float(jnp.max(jnp.abs(sim.energy - sim.energy[0])))
    assert float(sim.max_residual) < RESIDUAL_BOUND
    assert drift < 1e-7 * abs(float(sim.energy[0])) + 1e-7


def test_redundant_and_dependent_choices_are_named():
    b = mb.SystemBuilder()
    b.add_rigid_body("B1", 1.0, np.eye(3) * 0.1)
    b.add_point("P0", "ground", (0, 0, 0))
    b.add_point("P1", "B1", (0, 0, 0.5))
    b.add_revolute("C1", "P0", "P1", axis_i=(1, 0, 0))
    b.add_spherical("S1", "P0", "P1", components="x")  # repeats C1[x]
    b.add_independent("B1", "wx")
    with pytest.raises(ValueError, match="leave 0"):
        b.build()
    # a dependent choice of independent velocity: wy is locked by the revolute joint
    b = mb.SystemBuilder()
    b.add_rigid_body("B1", 1.0, np.eye(3) * 0.1)
    b.add_point("P0", "ground", (0, 0, 0))
    b.add_point("P1", "B1", (0, 0, 0.5))
    b.add_revolute("C1", "P0", "P1", axis_i=(1, 0, 0))
    b.add_independent("B1", "wy")
    system, params = b.build()
    q = jnp.asarray([0.0, 0.0, -0.5, 0.0, 0.0, 0.0])
    with pytest.raises(mb.RedundantConstraintError, match=r"independent velocities \['B1.wy'\] are dependent"):
        mb.check_rank(system, params, q)


def test_redundant_constraints_named():
    b = mb.SystemBuilder()
    b.add_rigid_body("B1", 1.0, np.eye(3) * 0.1)
    b.add_point("P0", "ground", (0, 0, 0))
    b.add_point("P1", "B1", (0, 0, 0.5))
    b.add_point("Q0", "ground", (0, 0, -1.0))
    b.add_point("Q1", "B1", (0, 0, -0.5))
    b.add_spherical("S1", "P0", "P1")
    b.add_spherical("S2", "Q0", "Q1", components="xz")  # S2[z] repeats S1[z] to first order
    b.add_independent("B1", "wz")
    system, params = b.build()
    q = jnp.asarray([0.0, 0.0, -0.5, 0.0, 0.0, 0.0])
    with pytest.raises(mb.RedundantConstraintError, match=r"redundant .*S1\[z\].*S2\[z\]"):
        mb.check_rank(system, params, q)


def test_vmap_over_parameters_and_no_retrace():
    system, params = ex.double_pendulum()
    q, z = ex.double_pendulum_state(system, params, (0.3, -0.5), (1.0, 2.0))
    masses = jnp.asarray([0.5, 1.0, 2.0])

    def with_m2(m2):
        return eqx.tree_at(lambda p: p.bodies[1].mass, params, m2)

    @jax.jit
    @eqx.debug.assert_max_traces(max_traces=1)
    def zdot(p, q, z):
        return mb.dynamics(system, p, q, z).z_dot

    batched = jax.jit(jax.vmap(lambda m2: mb.dynamics(system, with_m2(m2), q, z).z_dot))(masses)
    for k in range(masses.shape[0]):
        np.testing.assert_allclose(batched[k], zdot(with_m2(masses[k]), q, z), rtol=1e-12)
    zdot(with_m2(jnp.asarray(3.0, jnp.float64)), q + 0.0, z * 2.0)


def test_cli_inspect_contract():
    runner = CliRunner()
    result = runner.invoke(
        app, ["multibody", "inspect", "double-pendulum", "--q", "0.3", "-0.5", "--qdot", "1.0", "2.0", "--json"]
    )
    assert result.exit_code == 0, result.output
    out = json.loads(result.stdout)
    m, qi, qe = ex.double_pendulum_closed_form((0.3, -0.5), (1.0, 2.0))
    np.testing.assert_allclose(out["mass_matrix"], m, rtol=CLOSED_FORM_RTOL)
    np.testing.assert_allclose(out["internal_forces"], qi, rtol=CLOSED_FORM_RTOL)
    np.testing.assert_allclose(out["external_forces"], qe, rtol=CLOSED_FORM_RTOL)
    assert set(out["params"]) == {"m1", "m2", "J1", "J2", "l1", "a1", "a2", "g"}
    result = runner.invoke(
        app, ["multibody", "inspect", "double-pendulum", "--q", "0.3", "-0.5", "--param", "m2=1.2", "--json"]
    )
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["params"]["m2"] == 1.2
    bad = runner.invoke(app, ["multibody", "inspect", "double-pendulum", "--param", "m2=-1", "--json"])
    assert bad.exit_code != 0 and "m2" in bad.output
    bad = runner.invoke(app, ["multibody", "inspect", "double-pendulum", "--q", "0.3", "--json"])
    assert bad.exit_code != 0 and "--q" in bad.output


def test_singular_reduced_mass_matrix_is_reported():
    b = mb.SystemBuilder()
    b.add_rigid_body("B1", 1.0, np.diag([0.0, 0.1, 0.1]))  # no inertia about x, c.g. on the axis
    b.add_point("P0", "ground", (0, 0, 0))
    b.add_point("P1", "B1", (0, 0, 0))
    b.add_revolute("C1", "P0", "P1", axis_i=(1, 0, 0))
    b.add_independent("B1", "wx")
    system, params = b.build()
    with pytest.raises(mb.SingularMassMatrixError, match=r"\['B1.wx'\] carry no inertia"):
        mb.check_mass_matrix(system, params, jnp.zeros(6))


def test_table_5_3_routines_consistent():
    """T, B, B T, their time derivatives and dX/dq agree with each other and with finite
    differences along the motion."""
    system, params = ex.double_pendulum()
    q, z = ex.double_pendulum_state(system, params, (0.4, 0.9), (1.3, -0.7))

    @jax.jit
    def routines(q, z):
        y = mb.projection(system, params, q).R @ z
        t_mat = mb.recursion_matrix(system, params, q)
        b_mat = mb.velocity_matrix_b(system, params, q)
        bt = mb.velocity_matrix(system, params, q)
        q_dot = bt @ y
        return y, t_mat, b_mat, bt, q_dot, mb.recursion_matrix_dot(system, params, q, q_dot), mb.marker_jacobian(
            system, params, q
        )

    y, t_mat, b_mat, bt, q_dot, t_dot, dxdq = routines(q, z)
    np.testing.assert_allclose(b_mat @ t_mat, bt, atol=1e-14)
    h = 1e-6
    t_of = lambda qq: mb.recursion_matrix(system, params, qq)  # noqa: E731
    fd = (t_of(q + h * q_dot) - t_of(q - h * q_dot)) / (2 * h)
    np.testing.assert_allclose(t_dot, fd, atol=1e-8)
    # dX/dq q_dot is the marker velocity
    vel = jnp.einsum("pij,j->pi", dxdq, q_dot)
    np.testing.assert_allclose(vel[system.point_index("P3")], mb.point_velocity(system, params, q, y, "P3"), atol=1e-13)


def test_simulate_rejects_unassembled_initial_state():
    system, params = ex.double_pendulum()
    q, z = ex.double_pendulum_state(system, params, (0.4, 0.9), (1.3, -0.7))
    with pytest.raises(mb.AssemblyError, match=r"constraint C\d\[.\] residual 1.000e-02"):
        mb.simulate(system, params, q.at[7].add(0.01), z, 0.0, 1.0)
