"""Beam element and assembly against Euler-Bernoulli / Timoshenko closed forms."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxveh.fe as fe

E, G, RHO = 210e9, 80.8e9, 7850.0
D, T, LENGTH = 0.03, 0.002, 1.2
#: Exact element (cubic Hermite) statics: only round-off.
RTOL_STATIC = 1e-9
#: 60 consistent-mass elements converge the first free-free frequencies to < 1e-4.
RTOL_FREQ_CONSISTENT = 1e-4
#: 60 lumped-mass elements: the lumped rotary inertia gives an O((βL/n)²) error, 0.3-1 %
#: on the first three bending modes.
RTOL_FREQ_LUMPED = 1.5e-2


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


@pytest.mark.parametrize("lumped,rtol", [(False, RTOL_FREQ_CONSISTENT), (True, RTOL_FREQ_LUMPED)])
def test_free_free_bending_frequencies(lumped, rtol):
    frame = tube(60, lumped_mass=lumped)
    K, M = fe.assemble(frame)
    f, _ = jax.jit(fe.free_free_modes, static_argnums=2)(K, M, 6)
    area, i = tube_props()
    beta_l = np.array([4.730040745, 7.853204624, 10.99560784])
    exact = beta_l**2 / (2 * np.pi * LENGTH**2) * np.sqrt(E * i / (RHO * area))
    # circular section: each bending frequency appears twice (y and z planes)
    np.testing.assert_allclose(f[0::2], exact, rtol=rtol)
    np.testing.assert_allclose(f[1::2], exact, rtol=rtol)


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
