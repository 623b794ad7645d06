"""Optimal preview controller (eqs. 3.38-3.46) on a linear bicycle test model.

The test model is defined here (independent of :mod:`jaxveh.analytic`): a linear
two-axle bicycle with states ``[Y, psi, v, r]`` and steering-wheel input (rad), with the
Appendix-A mass, yaw inertia, axle positions and steering ratio and plausible axle
cornering stiffnesses.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg

from jaxveh.control import preview_controller, preview_distance, preview_plant, zoh

DT = 0.01
Q_WEIGHT = 1000.0
#: Riccati solution of the 209-state plant vs SciPy's Schur solver (P entries span ~1e6).
SOLUTION_RTOL = 1e-9
#: Relative Frobenius residual of eq. (3.45) at the returned P.
RESIDUAL_TOL = 1e-12
#: Exactly independent blocks (see the tests) computed by different-sized solves.
STRUCTURE_RTOL = 1e-8
#: Far-ahead gains and filter gains are zero only in the limit of complete preview.
VANISHING_RATIO = 1e-4
#: Central differences with a relative step of 1e-6 on O(1e4) stiffnesses.
FD_RTOL = 1e-5


def bicycle(speed, cf=30_000.0, cr=35_000.0):
    """Continuous (A, B, c_y) of a linear bicycle at ``speed`` m/s; B per steering-wheel rad."""
    m, jz, a, b, k_stw = 290.0, 165.0, 0.843, 0.712, 12.0
    u = speed
    a_c = jnp.stack(
        [
            jnp.stack([0.0, u, 1.0, 0.0]),
            jnp.array([0.0, 0.0, 0.0, 1.0]),
            jnp.stack([0.0, 0.0, -(cf + cr) / (m * u), -u - (cf * a - cr * b) / (m * u)]),
            jnp.stack([0.0, 0.0, -(cf * a - cr * b) / (jz * u), -(cf * a**2 + cr * b**2) / (jz * u)]),
        ]
    )
    b_c = jnp.stack([0.0, 0.0, cf / m, cf * a / jz])[:, None] / k_stw
    return a_c, b_c, jnp.array([1.0, 0.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def gains_40():
    return preview_controller(*bicycle(jnp.asarray(40 / 3.6)))


def test_plant_structure():
    a_c, b_c, c_y = bicycle(jnp.asarray(20.0))
    plant = preview_plant(a_c, b_c, c_y, n_preview=5)
    nf, nv, nr = 4, 4, 6
    assert plant.a.shape == (nf + nv + nr,) * 2
    road = slice(nf + nv, nf + nv + nr)
    # Shift register: each sample moves one place nearer the car (eq. 3.40).
    np.testing.assert_array_equal(plant.a[road, road], np.eye(nr, k=1))
    # The filter feeds only the farthest sample; the vehicle block is the ZOH model.
    assert np.all(np.asarray(plant.a[road, :nf])[:-1] == 0.0)
    a_d, b_d = zoh(a_c, b_c, DT)
    np.testing.assert_array_equal(plant.a[nf : nf + nv, nf : nf + nv], a_d)
    np.testing.assert_array_equal(plant.b[nf : nf + nv], b_d)
    # Path error y = Y - yr[0] (C = [0 Cd Cr], Cr = [-1 0 ... 0]).
    expected_c = np.zeros(nf + nv + nr)
    expected_c[nf] = 1.0
    expected_c[nf + nv] = -1.0
    np.testing.assert_array_equal(plant.c[0], expected_c)


def test_riccati_matches_scipy_on_full_plant(gains_40):
    plant = preview_plant(*bicycle(jnp.asarray(40 / 3.6)))
    q = Q_WEIGHT * np.asarray(plant.c.T @ plant.c)
    reference = scipy.linalg.solve_discrete_are(np.asarray(plant.a), np.asarray(plant.b), q, np.eye(1))
    scale = np.abs(reference).max()
    np.testing.assert_allclose(gains_40.p, reference, atol=SOLUTION_RTOL * scale)
    assert float(gains_40.residual) < RESIDUAL_TOL
    assert float(gains_40.spectral_radius) < 1.0


def test_vehicle_gains_equal_plain_lqr(gains_40):
    """Road and filter are uncontrolled exogenous blocks, so Kd is the LQR gain of the
    vehicle alone with cost Q Y^2 + R u^2 (independent of the preview)."""
    a_d, b_d = (np.asarray(x) for x in zoh(*bicycle(jnp.asarray(40 / 3.6))[:2], DT))
    q = Q_WEIGHT * np.diag([1.0, 0.0, 0.0, 0.0])
    p = scipy.linalg.solve_discrete_are(a_d, b_d, q, np.eye(1))
    k = np.linalg.solve(np.eye(1) + b_d.T @ p @ b_d, b_d.T @ p @ a_d)[0]
    np.testing.assert_allclose(gains_40.vehicle, k, rtol=STRUCTURE_RTOL)


def test_preview_gains_independent_of_filter_and_horizon(gains_40):
    """The register feeds the car from the far end: the gain on a sample i steps ahead does
    not depend on the filter upstream nor on how many samples lie beyond it."""
    model = bicycle(jnp.asarray(40 / 3.6))
    other_filter = preview_controller(*model, cutoff_hz=5.0)
    shorter = preview_controller(*model, n_preview=120)
    scale = np.abs(gains_40.preview).max()
    np.testing.assert_allclose(other_filter.preview, gains_40.preview, atol=STRUCTURE_RTOL * scale)
    np.testing.assert_allclose(shorter.preview, gains_40.preview[:121], atol=STRUCTURE_RTOL * scale)


def test_complete_preview_physics(gains_40):
    """Gains vanish far ahead, filter gains vanish (complete preview, thesis p. 52), the
    peak gain is negative (u = -K z steers towards a road displaced to the left) and a
    uniform lateral shift of car and road asks for no steering."""
    kp = np.asarray(gains_40.preview)
    peak = np.abs(kp).max()
    assert np.abs(kp[-20:]).max() < VANISHING_RATIO * peak
    assert np.abs(np.asarray(gains_40.filter)).max() < VANISHING_RATIO * peak
    assert kp[np.argmax(np.abs(kp))] < 0.0
    shift = float(gains_40.vehicle[0]) + kp.sum()
    assert abs(shift) < VANISHING_RATIO * peak


def test_preview_distance_grows_with_speed():
    speeds = jnp.array([10.0, 20.0, 30.0])

    def lp(u):
        return preview_distance(preview_controller(*bicycle(u), n_preview=120).preview, u, DT)

    distances = np.asarray(jax.vmap(lp)(speeds))
    assert np.all(np.diff(distances) > 0.0)


def test_preview_distance_closed_forms():
    # Uniform gains: sum_{j<=n} 1 = n + 1 > 0.98 * 100 first at n = 98.
    u = 25.0
    np.testing.assert_allclose(preview_distance(-jnp.ones(100), u, DT), 98 * u * DT)
    # Geometric gains r^i: first n with (1 - r^(n+1)) > 0.98 (1 - r^N).
    r, n_points = 0.95, 201
    kp = r ** jnp.arange(n_points, dtype=jnp.float64)
    n = int(np.ceil(np.log(1 - 0.98 * (1 - r**n_points)) / np.log(r) - 1))
    np.testing.assert_allclose(preview_distance(kp, u, DT), n * u * DT)
    interpolated = preview_distance(kp, u, DT, interpolate=True)
    assert (n - 1) * u * DT < float(interpolated) <= n * u * DT
    with pytest.raises(eqx.EquinoxRuntimeError, match="preview gains are all zero"):
        preview_distance(jnp.zeros(10), u, DT)


@pytest.mark.slow
def test_gradients_match_finite_differences():
    """d/d(front cornering stiffness) of the interpolated Lp and of sum Kp^2.

    A 100-point horizon (30 m at 108 km/h, complete preview) keeps the test quick."""
    speed = jnp.asarray(30.0)

    @jax.jit
    def outputs(cf):
        gains = preview_controller(*bicycle(speed, cf=cf), n_preview=100)
        return jnp.stack(
            [preview_distance(gains.preview, speed, DT, interpolate=True), jnp.sum(gains.preview**2)]
        )

    cf = jnp.asarray(30_000.0)
    h = 1e-6 * cf
    fd = (outputs(cf + h) - outputs(cf - h)) / (2 * h)
    np.testing.assert_allclose(jax.jacrev(outputs)(cf), fd, rtol=FD_RTOL)
    np.testing.assert_allclose(jax.jacfwd(outputs)(cf), fd, rtol=FD_RTOL)


def test_no_retrace_for_new_values():
    @eqx.filter_jit
    @eqx.debug.assert_max_traces(max_traces=1)
    def gains(speed):
        return preview_controller(*bicycle(speed), n_preview=50).preview

    gains(jnp.asarray(15.0))
    gains(jnp.asarray(25.0))


def test_bad_shapes_raise():
    a_c, b_c, _ = bicycle(jnp.asarray(20.0))
    with pytest.raises(ValueError, match=r"c_y \(4,\)"):
        preview_plant(a_c, b_c, jnp.ones(3))
    with pytest.raises(ValueError, match="n_preview must be a Python int >= 1"):
        preview_plant(a_c, b_c, jnp.ones(4), n_preview=0)
