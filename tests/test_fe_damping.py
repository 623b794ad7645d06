"""Modal damping of a ModalBody: ζ per mode (thesis 7.3), Rayleigh as an option,
frequencies that follow the stiffness multiplier, no retracing for new damping values."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.test_util import check_grads

import jaxveh.fe as fe
import jaxveh.fe._body as fe_body

#: ζ from the eigenvalues of a 12×12 (or smaller) real matrix: eigen-solver round-off.
RTOL_EIG = 1e-9


@pytest.fixture(scope="module")
def chassis():
    """The shipped frame's six lowest modes with the default damping (ζ = 0.025)."""
    return fe.frame_modal_body(fe.load_frame(), 6)


def modal_eigenvalues(body):
    """Eigenvalues of ``[[0, I], [−Me⁻¹K, −Me⁻¹D]]`` (uncoupled modal block)."""
    n = body.n_modes
    me = np.asarray(body.invariants.Me)
    K, D = np.asarray(body.stiffness_matrix()), np.asarray(body.damping_matrix())
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(me, K), -np.linalg.solve(me, D)]])
    return np.linalg.eigvals(A)


@pytest.mark.parametrize("scale", [None, (0.3, 0.5, 1.0, 2.0, 3.0, 4.0)])
def test_default_modal_damping_is_zeta_0025_on_every_chassis_mode(chassis, scale):
    """Thesis 7.3: uncoupled chassis eigenvalues lie on ζ = 0.025, for any µ."""
    body = chassis if scale is None else eqx.tree_at(lambda b: b.stiffness_scale, chassis, jnp.asarray(scale))
    lam = modal_eigenvalues(body)
    lam = lam[lam.imag > 0]
    assert len(lam) == 6
    np.testing.assert_allclose(-lam.real / np.abs(lam), fe.DEFAULT_DAMPING_RATIO, rtol=RTOL_EIG)
    omega = 2 * np.pi * np.asarray(body.frequencies_hz)
    np.testing.assert_allclose(np.sort(np.abs(lam)), np.sort(omega), rtol=RTOL_EIG)
    np.testing.assert_allclose(body.damping_ratios(), 0.025, rtol=1e-12)


def test_frequencies_follow_stiffness_scale(chassis):
    f0 = np.asarray(chassis.frequencies_hz)
    np.testing.assert_allclose(f0[0], 39.327, rtol=1e-4)  # docs/fe.md, Table 6.4 comparison
    mu = jnp.asarray([0.25, 0.5, 1.0, 2.0, 4.0, 9.0])
    scaled = eqx.tree_at(lambda b: b.stiffness_scale, chassis, mu)
    np.testing.assert_allclose(scaled.frequencies_hz, f0 * np.sqrt(mu), rtol=1e-12)
    np.testing.assert_allclose(np.diag(scaled.stiffness_matrix()), mu * np.diag(chassis.Ke), rtol=1e-12)


def test_thesis_beta_read_literally_is_over_critical(chassis):
    """β = 0.01 s (Rayleigh, α = 0): ζ_i = β ω_i / 2 = 1.24 ... 2.91 for 39-93 Hz modes;
    every mode is over-damped (real eigenvalues)."""
    rayleigh = fe.frame_modal_body(fe.load_frame(), 6, beta=0.01)
    w = 2 * np.pi * np.asarray(chassis.frequencies_hz)
    zeta = np.asarray(rayleigh.damping_ratios())
    np.testing.assert_allclose(zeta, 0.01 * w / 2, rtol=1e-12)
    np.testing.assert_allclose(zeta[[0, -1]], [1.2355, 2.9103], atol=1e-4)
    np.testing.assert_allclose(fe.modal_damping_ratios(chassis.frequencies_hz, beta=0.01), zeta, rtol=1e-12)
    assert np.all(np.abs(modal_eigenvalues(rayleigh).imag) < 1e-6)
    np.testing.assert_allclose(rayleigh.damping_ratio, 0.0)  # beta alone selects Rayleigh only


def test_rayleigh_and_modal_damping_add(chassis):
    body = fe.frame_modal_body(fe.load_frame(), 6, alpha=2.0, beta=1e-4, damping_ratio=0.01)
    K, me = body.stiffness_matrix(), body.invariants.Me
    w = 2 * np.pi * np.asarray(body.frequencies_hz)
    expected = 2.0 * me + 1e-4 * K + jnp.diag(2 * 0.01 * w * np.sqrt(np.diag(me)))
    np.testing.assert_allclose(body.damping_matrix(), expected, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(body.damping_ratios(), 0.01 + 2.0 / (2 * w) + 1e-4 * w / 2, rtol=1e-10)
    # one ratio per mode
    zeta = jnp.asarray([0.01, 0.02, 0.03, 0.04, 0.05, 0.06])
    per_mode = eqx.tree_at(lambda b: b.damping_ratio, chassis, zeta)
    lam = modal_eigenvalues(per_mode)
    lam = lam[lam.imag > 0]
    order = np.argsort(np.abs(lam))
    np.testing.assert_allclose((-lam.real / np.abs(lam))[order], zeta, rtol=RTOL_EIG)


def test_straight_beam_defaults_and_rayleigh_selection():
    default = fe.straight_beam_body(n_modes=2, n_elements=6)
    np.testing.assert_allclose(default.damping_ratio, 0.025)
    np.testing.assert_allclose([default.alpha, default.beta], 0.0)
    undamped = fe.straight_beam_body(n_modes=2, n_elements=6, beta=0.0)  # multibody's energy tests
    np.testing.assert_allclose(undamped.damping_matrix(), 0.0)


def test_new_damping_values_do_not_recompile(monkeypatch):
    """frame_modal_body passes α, β, ζ (and the origin) as arrays to its jitted core."""
    traces = []
    original = fe_body.free_free_modes

    def counting(*args):
        traces.append(1)
        return original(*args)

    monkeypatch.setattr(fe_body, "free_free_modes", counting)
    frame = fe.straight_tube_frame(0.7, 5)  # a structure no other test compiles
    bodies = [
        fe.frame_modal_body(frame, 3, beta=b, damping_ratio=z, origin=o)
        for b, z, o in ((0.01, 0.02, None), (0.02, 0.03, (0.1, 0.0, 0.0)), (0.005, 0.0, [0.2, 0.1, 0.0]))
    ]
    fe.frame_modal_body(frame, 3, alpha=1.0)
    fe.frame_modal_body(frame, 3)
    assert len(traces) == 1
    np.testing.assert_allclose([float(b.beta) for b in bodies], [0.01, 0.02, 0.005])
    np.testing.assert_allclose(bodies[1].point_xyz[0], [-0.1, 0.0, 0.0])


def test_damping_gradients(chassis):
    """De and ζ_i are smooth in µ, ζ, α, β (forward and reverse, second order)."""

    def trace_d(mu, zeta, ab):
        b = eqx.tree_at(lambda b: (b.stiffness_scale, b.damping_ratio, b.alpha, b.beta), chassis,
                        (mu, zeta, ab[0], ab[1]))
        return jnp.sum(b.damping_matrix() ** 2) * 1e-6 + jnp.sum(b.frequencies_hz)

    args = (jnp.asarray([1.0, 0.8, 1.2, 1.5, 0.9, 1.1]), jnp.full(6, 0.025), jnp.asarray([0.5, 1e-4]))
    check_grads(jax.jit(trace_d), args, order=2, modes=("fwd", "rev"), eps=1e-6)
