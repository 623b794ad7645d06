"""Modal invariants (eqs. 5.38-5.45) against direct nodal sums and Lagrange's equations."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxveh.fe as fe

#: Invariants are nodal sums of O(1) numbers: only round-off separates two evaluations.
RTOL_EXACT = 1e-10
#: Mean-axis conditions (Ct = Cr0 = 0, Me = I) hold to the accuracy of the eigen-solver.
ATOL_EIG = 1e-8


@pytest.fixture(scope="module")
def random_body():
    """A random lumped body with 5 nodes and 3 (non-orthogonal) mode shapes."""
    rng = np.random.default_rng(0)
    n, N = 5, 3
    xyz = rng.normal(size=(n, 3))
    m = rng.uniform(0.5, 2.0, n)
    a = rng.normal(size=(n, 3, 3))
    J = np.einsum("kij,klj->kil", a, a) + np.eye(3)
    pt = rng.normal(size=(n, 3, N))
    pr = rng.normal(size=(n, 3, N))
    ke = np.diag([4.0, 9.0, 16.0])
    body = fe.modal_body(
        jnp.asarray(xyz), jnp.asarray(m), jnp.asarray(J), jnp.asarray(pt), jnp.asarray(pr),
        jnp.asarray(ke), jnp.asarray([1.0, 2.0, 3.0]), ("a", "b"), (0, 3),
    )
    return body, (xyz, m, J, pt, pr)


def nodal_kinetic_energy(z, p, data):
    """T = ½ Σ m_k |v + ω × x_k + Ψt_k ṗ|² + ½ Σ (ω + Ψr_k ṗ)ᵀ J_k (ω + Ψr_k ṗ)."""
    xyz, m, J, pt, pr = (jnp.asarray(d) for d in data)
    v, w, pd = z[:3], z[3:6], z[6:]
    x = xyz + jnp.einsum("kil,l->ki", pt, p)
    vel = v[None, :] + jnp.cross(jnp.broadcast_to(w, x.shape), x) + jnp.einsum("kil,l->ki", pt, pd)
    rot = w[None, :] + jnp.einsum("kil,l->ki", pr, pd)
    return 0.5 * jnp.sum(m[:, None] * vel**2) + 0.5 * jnp.einsum("ki,kij,kj->", rot, J, rot)


def test_invariants_match_nodal_sums(random_body):
    body, (xyz, m, J, pt, pr) = random_body
    inv = body.invariants
    np.testing.assert_allclose(inv.mass, m.sum(), rtol=RTOL_EXACT)
    np.testing.assert_allclose(inv.c0, (m[:, None] * xyz).sum(0) / m.sum(), rtol=RTOL_EXACT)
    np.testing.assert_allclose(inv.Ct, np.einsum("k,kil->il", m, pt), rtol=RTOL_EXACT)
    # J0 = Σ J_k + m_k (|x|² I − x xᵀ)
    j0 = J.sum(0) + sum(m[k] * (xyz[k] @ xyz[k] * np.eye(3) - np.outer(xyz[k], xyz[k])) for k in range(len(m)))
    np.testing.assert_allclose(inv.J0, j0, rtol=RTOL_EXACT)
    cr0 = sum(m[k] * np.cross(xyz[k][:, None], pt[k], axis=0) + J[k] @ pr[k] for k in range(len(m)))
    np.testing.assert_allclose(inv.Cr0, cr0, rtol=RTOL_EXACT)
    me = np.einsum("k,kil,kim->lm", m, pt, pt) + np.einsum("kil,kij,kjm->lm", pr, J, pr)
    np.testing.assert_allclose(inv.Me, me, rtol=RTOL_EXACT)
    np.testing.assert_allclose(body.point_xyz, xyz[[0, 3]])


def test_mass_matrix_is_hessian_of_nodal_energy(random_body):
    """M(0) and ∂M/∂p at p = 0 equal those of the exact nodal kinetic energy."""
    body, data = random_body
    N = body.n_modes
    hess = lambda p: jax.hessian(nodal_kinetic_energy)(jnp.zeros(6 + N), p, data)
    p0 = jnp.zeros(N)
    np.testing.assert_allclose(body.mass_matrix(p0), jax.jit(hess)(p0), rtol=RTOL_EXACT, atol=1e-12)
    dm = jax.jit(jax.jacfwd(body.mass_matrix))(p0)
    np.testing.assert_allclose(dm, jax.jit(jax.jacfwd(hess))(p0), rtol=1e-9, atol=1e-10)


def test_quadratic_velocity_forces_are_lagrange_equations(random_body):
    """h_ω equals −(Ṁ z + [ω̃P; ω̃H + ṽP; −∂T/∂p]) for T = ½ zᵀ M(p) z (quasi-velocities)."""
    body, _ = random_body
    N = body.n_modes
    rng = np.random.default_rng(1)
    p, z = jnp.asarray(rng.normal(size=N) * 0.1), jnp.asarray(rng.normal(size=6 + N))
    v, w, pd = z[:3], z[3:6], z[6:]
    T = lambda z_, p_: 0.5 * z_ @ body.mass_matrix(p_) @ z_
    mom = body.mass_matrix(p) @ z
    mdot_z = jax.jvp(lambda q: body.mass_matrix(q) @ z, (p,), (pd,))[1]
    P, H = mom[:3], mom[3:6]
    ref = -jnp.concatenate(
        [mdot_z[:3] + jnp.cross(w, P), mdot_z[3:6] + jnp.cross(w, H) + jnp.cross(v, P), mdot_z[6:] - jax.grad(T, 1)(z, p)]
    )
    np.testing.assert_allclose(body.quadratic_velocity_forces(p, v, w, pd), ref, rtol=1e-10, atol=1e-12)


def test_gravity_forces_are_potential_gradient(random_body):
    body, (xyz, m, J, pt, pr) = random_body
    g = jnp.asarray([0.3, -0.2, -9.81])
    p = jnp.asarray([0.1, -0.2, 0.05])
    h = body.gravity_forces(p, g)
    # virtual work of gravity on a translation, a rotation and the modal coordinates
    np.testing.assert_allclose(h[:3], m.sum() * g, rtol=RTOL_EXACT)
    x = xyz + np.einsum("kil,l->ki", pt, p)
    np.testing.assert_allclose(h[3:6], np.sum(m[:, None] * np.cross(x, g), axis=0), rtol=1e-9)
    np.testing.assert_allclose(h[6:], np.einsum("k,kil,i->l", m, pt, g), rtol=1e-9)


def test_free_free_beam_body_mean_axis_conditions():
    """Free-free modes are M-orthogonal to rigid motion: Ct = Cr0 = 0, Me = I, c0 centred."""
    body = fe.straight_beam_body(length=1.2, n_modes=6, n_elements=12)
    inv = body.invariants
    np.testing.assert_allclose(inv.Me, np.eye(6), atol=ATOL_EIG)
    np.testing.assert_allclose(inv.Ct, 0.0, atol=ATOL_EIG)
    np.testing.assert_allclose(inv.Cr0 - np.cross(inv.c0[:, None], inv.Ct, axis=0), 0.0, atol=ATOL_EIG)
    np.testing.assert_allclose(inv.c0, [0.6, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(np.diag(body.Ke), (2 * np.pi * body.frequencies_hz) ** 2, rtol=1e-9)
    assert body.point_names == ("start", "mid", "end")
    np.testing.assert_allclose(body.point_xyz[2], [1.2, 0.0, 0.0], atol=1e-12)


def test_stiffness_scale_and_damping():
    body = fe.straight_beam_body(n_modes=4)
    mu = jnp.asarray([0.5, 1.0, 2.0, 0.0])
    b2 = eqx.tree_at(lambda b: b.stiffness_scale, body, mu)
    np.testing.assert_allclose(np.diag(b2.stiffness_matrix()), mu * np.diag(body.Ke), rtol=1e-12)
    np.testing.assert_allclose(b2.damping_matrix(), 0.01 * b2.stiffness_matrix() + 0.0 * body.invariants.Me)
    # finite gradient of the scaled stiffness at µ = 0
    g = jax.grad(lambda m: jnp.sum(eqx.tree_at(lambda b: b.stiffness_scale, body, m).stiffness_matrix()))(mu)
    assert np.all(np.isfinite(g))
