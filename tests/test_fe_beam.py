"""Beam element and assembly against Euler-Bernoulli / Timoshenko closed forms."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.optimize import brentq

import jaxveh.fe as fe

E, G, RHO = 210e9, 80.8e9, 7850.0
D, T, LENGTH = 0.03, 0.002, 1.2
#: Exact element (cubic Hermite) statics: only round-off.
RTOL_STATIC = 1e-9
#: 60 consistent-mass elements converge the first free-free frequencies to < 1e-4
#: (measured: < 1e-6 on the first three bending modes).
RTOL_FREQ_CONSISTENT = 1e-4
#: The lumped mass (nodal rotary inertia rho I per length) converges to a Rayleigh beam:
#: with 60 elements the first three bending frequencies are 0.14, 0.27, 0.41 % below the
#: Rayleigh closed form (measured; O(h^2), a quarter of the 30-element errors).
RTOL_FREQ_LUMPED_RAYLEIGH = 5e-3
#: Measured errors (%) of 60 lumped elements against Euler-Bernoulli (docs/fe.md).
LUMPED_VS_EB_PERCENT = (-0.311, -0.638, -1.043)
#: Rayleigh closed form below Euler-Bernoulli for this tube (%), first three modes.
RAYLEIGH_BELOW_EB_PERCENT = (0.169, 0.371, 0.633)
#: Printed digits of the percentages above.
ATOL_PERCENT = 1e-3


def tube_props():
    ro, ri = D / 2, D / 2 - T
    area = np.pi * (ro**2 - ri**2)
    i = np.pi / 4 * (ro**4 - ri**4)
    return area, i


def tube(n, **kw):
    return dataclasses.replace(fe.straight_tube_frame(LENGTH, n, D, T, E, G, RHO), **kw)


@pytest.mark.parametrize("timoshenko", [False, True])
def test_cantilever_tip_deflection(timoshenko):
    frame = tube(4, timoshenko=timoshenko)
    K, _ = fe.assemble(frame)
    P = 100.0
    f = jnp.zeros(K.shape[0]).at[6 * 4 + 2].set(P)  # tip, +z
    u = fe.solve_static(K, f, tuple(range(6)))
    area, i = tube_props()
    expected = P * LENGTH**3 / (3 * E * i) + (P * LENGTH / (G * area / 2) if timoshenko else 0.0)
    np.testing.assert_allclose(u[6 * 4 + 2], expected, rtol=RTOL_STATIC)
    np.testing.assert_allclose(u[6 * 4 + 4], -P * LENGTH**2 / (2 * E * i), rtol=RTOL_STATIC)


def test_axial_and_torsional_stiffness():
    frame = tube(3)
    K, _ = fe.assemble(frame)
    area, i = tube_props()
    f = jnp.zeros(K.shape[0]).at[6 * 3 + 0].set(1.0).at[6 * 3 + 3].set(1.0)
    u = fe.solve_static(K, f, tuple(range(6)))
    np.testing.assert_allclose(1.0 / u[6 * 3], E * area / LENGTH, rtol=RTOL_STATIC)
    np.testing.assert_allclose(1.0 / u[6 * 3 + 3], G * 2 * i / LENGTH, rtol=RTOL_STATIC)


BETA_L = np.array([4.730040745, 7.853204624, 10.99560784])  # free-free: cos x cosh x = 1


def euler_bernoulli_hz():
    area, i = tube_props()
    return BETA_L**2 / (2 * np.pi * LENGTH**2) * np.sqrt(E * i / (RHO * area))


def rayleigh_hz(n_modes=3):
    """Free-free Rayleigh beam (Euler-Bernoulli stiffness + rotary inertia rho I).

    ``X'''' + a X'' - b X = 0`` with ``a = rho w^2/E``, ``b = rho A w^2/(E I)``; free ends
    ``X'' = 0`` and ``X''' + a X' = 0``. Symmetric (cosh, cos) and antisymmetric (sinh,
    sin) modes about the centre; roots of the 2x2 determinants by Brent's method.
    """
    area, i = tube_props()
    h = 0.5 * LENGTH

    def det(w, symmetric):
        a, b = RHO * w**2 / E, RHO * area * w**2 / (E * i)
        root = np.sqrt(a * a + 4 * b)
        al, be = np.sqrt(0.5 * (root - a)), np.sqrt(0.5 * (root + a))
        if symmetric:  # X = C1 cosh(al x) + C3 cos(be x)
            m = [[al**2 * np.cosh(al * h), -(be**2) * np.cos(be * h)],
                 [(al**3 + a * al) * np.sinh(al * h), (be**3 - a * be) * np.sin(be * h)]]
        else:  # X = C2 sinh(al x) + C4 sin(be x)
            m = [[al**2 * np.sinh(al * h), -(be**2) * np.sin(be * h)],
                 [(al**3 + a * al) * np.cosh(al * h), (a * be - be**3) * np.cos(be * h)]]
        return np.linalg.det(np.asarray(m)) / np.cosh(al * h)

    w_eb = 2 * np.pi * euler_bernoulli_hz()
    grid = np.linspace(0.5 * w_eb[0], 1.05 * w_eb[-1], 4000)
    roots = []
    for symmetric in (True, False):
        v = np.asarray([det(w, symmetric) for w in grid])
        for k in np.nonzero(np.sign(v[:-1]) != np.sign(v[1:]))[0]:
            roots.append(brentq(det, grid[k], grid[k + 1], args=(symmetric,), xtol=1e-12))
    return np.sort(roots)[:n_modes] / (2 * np.pi)


def bending_hz(n, lumped):
    """Free-free bending frequencies (Hz) of the tube: y and z pairs (circular section)."""
    K, M = fe.assemble(tube(n, lumped_mass=lumped))
    f, _ = jax.jit(fe.free_free_modes, static_argnums=2)(K, M, 6)
    return np.asarray(f)


def test_rayleigh_closed_form_is_below_euler_bernoulli():
    """Rotary inertia lowers the bending frequencies, more for higher modes."""
    drop = 1 - rayleigh_hz() / euler_bernoulli_hz()
    assert 0.0 < drop[0] < drop[1] < drop[2]
    np.testing.assert_allclose(100 * drop, RAYLEIGH_BELOW_EB_PERCENT, atol=ATOL_PERCENT)


def test_consistent_mass_converges_to_euler_bernoulli():
    f = bending_hz(60, lumped=False)
    exact = euler_bernoulli_hz()
    # circular section: each bending frequency appears twice (y and z planes)
    np.testing.assert_allclose(f[0::2], exact, rtol=RTOL_FREQ_CONSISTENT)
    np.testing.assert_allclose(f[1::2], exact, rtol=RTOL_FREQ_CONSISTENT)


def test_lumped_mass_converges_to_rayleigh_beam():
    """The lumped mass (with nodal rotary inertia) converges to the Rayleigh beam at
    O(h^2); against Euler-Bernoulli it keeps the rotary-inertia offset (docs/fe.md)."""
    ray = rayleigh_hz()
    f60 = bending_hz(60, lumped=True)
    np.testing.assert_allclose(f60[0::2], ray, rtol=RTOL_FREQ_LUMPED_RAYLEIGH)
    np.testing.assert_allclose(f60[1::2], ray, rtol=RTOL_FREQ_LUMPED_RAYLEIGH)
    np.testing.assert_allclose(100 * (f60[0::2] / euler_bernoulli_hz() - 1), LUMPED_VS_EB_PERCENT, atol=ATOL_PERCENT)
    err30 = bending_hz(30, lumped=True)[0::2] / ray - 1
    err60 = f60[0::2] / ray - 1
    np.testing.assert_allclose(err30 / err60, 4.0, rtol=0.05)  # second order in h


def test_rectangular_section_properties():
    s = fe.RectangularTube(0.04, 0.02, 0.002).properties()
    np.testing.assert_allclose(s.area, 0.04 * 0.02 - 0.036 * 0.016)
    np.testing.assert_allclose(s.iz, (0.02 * 0.04**3 - 0.016 * 0.036**3) / 12)
    np.testing.assert_allclose(s.iy, (0.04 * 0.02**3 - 0.036 * 0.016**3) / 12)
    np.testing.assert_allclose(s.torsion, 4 * (0.038 * 0.018) ** 2 * 0.002 / (2 * (0.038 + 0.018)))


@pytest.fixture(scope="module")
def shipped():
    frame = fe.load_frame()
    K, M = jax.jit(fe.assemble)(frame)
    return frame, np.asarray(K), np.asarray(M)


def test_matrices_symmetric_and_definite(shipped):
    _, K, M = shipped
    np.testing.assert_allclose(K, K.T, atol=1e-9 * np.abs(K).max())
    np.testing.assert_allclose(M, M.T, atol=1e-15)
    assert np.linalg.eigvalsh(M).min() > 0.0
    wk = np.linalg.eigvalsh(K)
    assert wk.min() > -1e-9 * wk.max()


def test_six_zero_energy_rigid_modes(shipped):
    frame, K, M = shipped
    R = np.asarray(fe.rigid_body_modes(fe.mesh_xyz(frame)))
    np.testing.assert_allclose(K @ R, 0.0, atol=1e-8 * np.abs(K).max())
    w = np.asarray(fe.generalised_eigh(jnp.asarray(K), jnp.asarray(M))[0])
    assert np.all(np.abs(w[:6]) < 1e-6 * w[6])
    assert w[6] > 1e3  # first elastic mode well above zero (>5 Hz)


def test_rigid_translation_carries_total_mass(shipped):
    frame, _, M = shipped
    R = np.asarray(fe.rigid_body_modes(fe.mesh_xyz(frame)))
    np.testing.assert_allclose(np.diag(R[:, :3].T @ M @ R[:, :3]), float(fe.frame_mass(frame)), rtol=1e-12)
