"""Linear model (3.29-3.37): autodiff linearisation, modes, frequency response."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.signal
from jax.test_util import check_grads

from jaxveh.analytic import (
    RIGID,
    dynamic_subsystem,
    eigenvalues,
    frequency_response,
    linearise,
    mass_matrix,
    state_space,
    understeer_gradient,
    understeer_gradient_rigid,
    vector_field,
    vehicle_modes,
    with_distribution,
)
from jaxveh.analytic._linear import _rigid_embedding
from jaxveh.params import load_analytic_vehicle

#: jacfwd and the explicit matrices are the same algebra: agreement to round-off.
ROUND_OFF = 1e-10
SPEEDS = (5 / 3.6, 50 / 3.6, 120 / 3.6)


@pytest.fixture(scope="module")
def vehicle():
    return load_analytic_vehicle()


@pytest.mark.parametrize("rigid", [False, True])
@pytest.mark.parametrize("speed", SPEEDS)
def test_jacfwd_equals_explicit_matrices(vehicle, speed, rigid):
    for v in (vehicle, with_distribution(vehicle, lam=0.3, mu=0.4)):
        a, b = state_space(v, speed, rigid)
        a2, b2 = linearise(v, speed, rigid)
        scale = float(jnp.max(jnp.abs(a)))
        np.testing.assert_allclose(a2, a, atol=ROUND_OFF * scale)
        np.testing.assert_allclose(b2, b, atol=ROUND_OFF * float(jnp.max(jnp.abs(b))))


def test_rigid_model_is_invariant_subspace_of_jacobian(vehicle):
    # With the rigid variant, φF = φR is invariant: A8 E = E A6.
    speed = 50 / 3.6
    index = jnp.asarray((7, 8, 4, 5, 0, 1, 2, 3))
    f = lambda x: vector_field(vehicle, jnp.zeros(9).at[index].set(x), speed, 0.0, RIGID)[index]
    a8 = jax.jacfwd(f)(jnp.zeros(8))
    a6, _ = state_space(vehicle, speed, rigid=True)
    e = _rigid_embedding()
    np.testing.assert_allclose(a8 @ e, e @ a6, atol=1e-9 * float(jnp.max(jnp.abs(a6))))


def test_mass_matrix_symmetric_positive_definite(vehicle):
    m = np.asarray(mass_matrix(vehicle))
    np.testing.assert_allclose(m, m.T, atol=0)
    assert np.all(np.linalg.eigvalsh(m) > 0)


def test_mode_labels(vehicle):
    flex = vehicle_modes(vehicle, 50 / 3.6)
    assert sorted(m["label"] for m in flex) == ["roll", "torsion", "yaw/sideslip"]
    rigid = vehicle_modes(vehicle, 50 / 3.6, rigid=True)
    assert sorted(m["label"] for m in rigid) == ["roll", "yaw/sideslip"]
    for m in flex + rigid:
        assert 0 < m["damping_ratio"] <= 1.0


def test_torsion_frequency_grows_with_stiffness_and_other_modes_tend_to_rigid(vehicle):
    def torsion(mu):
        modes = vehicle_modes(with_distribution(vehicle, mu=mu), 50 / 3.6)
        return next(m for m in modes if m["label"] == "torsion")

    freqs = [torsion(mu)["freq_hz"] for mu in (0.5, 1.0, 2.0, 5.0)]
    assert np.all(np.diff(freqs) > 0)
    stiff = vehicle_modes(with_distribution(vehicle, mu=1e5), 50 / 3.6)
    rigid = vehicle_modes(vehicle, 50 / 3.6, rigid=True)
    for label in ("roll", "yaw/sideslip"):
        f_stiff = next(m["freq_hz"] for m in stiff if m["label"] == label)
        f_rigid = next(m["freq_hz"] for m in rigid if m["label"] == label)
        assert f_stiff == pytest.approx(f_rigid, rel=1e-3)


@pytest.mark.parametrize("rigid", [False, True])
def test_static_yaw_gain_is_bicycle_closed_form(vehicle, rigid):
    # Steady yaw-rate gain per road-wheel angle: r/δ = u / (l + ku u²).
    speed = 50 / 3.6
    ku = understeer_gradient_rigid(vehicle) if rigid else understeer_gradient(vehicle)
    expected = speed / (vehicle.a + vehicle.b + ku * speed**2)
    fr = frequency_response(vehicle, speed, np.array([1e-6]), rigid)
    assert abs(complex(fr["yaw_rate"][0])) == pytest.approx(float(expected), rel=1e-8)


@pytest.mark.filterwarnings("ignore::scipy.signal.BadCoefficients")
def test_frequency_response_against_scipy(vehicle):
    speed = 50 / 3.6
    a, b = dynamic_subsystem(*state_space(vehicle, speed))
    freqs = np.geomspace(0.1, 5.0, 7)
    c = np.zeros((1, a.shape[0]))
    c[0, 3] = 1.0  # yaw rate
    system = scipy.signal.StateSpace(np.asarray(a), np.asarray(b) * float(vehicle.k_stw), c, np.zeros((1, 1)))
    _, h = scipy.signal.freqresp(system, 2 * np.pi * freqs)
    ours = np.asarray(frequency_response(vehicle, speed, freqs)["yaw_rate"])
    np.testing.assert_allclose(ours, h, rtol=1e-10)


def test_eigenvalues_stable_over_speed(vehicle):
    for speed in SPEEDS:
        assert np.all(np.asarray(eigenvalues(vehicle, speed)).real < 0)


def test_check_grads_of_linear_model_in_speed_and_stiffness(vehicle):
    """A of (3.37) and the static yaw gain, in u and kC, forward and reverse mode."""

    def a_matrix(x):
        v = with_distribution(vehicle, mu=x[1])
        return state_space(v, x[0])[0]

    check_grads(a_matrix, (jnp.asarray([15.0, 1.2]),), order=2, modes=("fwd", "rev"), eps=1e-5)

    def yaw_gain(x):
        return frequency_response(with_distribution(vehicle, mu=x[1]), x[0], [0.0])["yaw_rate"][0].real

    check_grads(yaw_gain, (jnp.asarray([20.0, 0.8]),), order=1, modes=("fwd", "rev"), eps=1e-5)
