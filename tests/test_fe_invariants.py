"""Modal invariants (eqs. 5.38-5.45) against direct nodal sums and Lagrange's equations."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxveh.fe as fe
from jaxveh._core import ParameterError

#: Invariants are nodal sums of O(1) numbers: only round-off separates two evaluations.
RTOL_EXACT = 1e-10
#: Mean-axis conditions (Ct = Cr0 = 0, Me = I) hold to the accuracy of the eigen-solver.
ATOL_EIG = 1e-8


def physical_inertias(rng, n):
    """Random nodal inertia tensors of real mass distributions: ``J = tr(S) I − S`` with a
    positive-definite second moment ``S = Σ m s sᵀ`` (so J obeys the triangle inequality)."""
    b = rng.normal(size=(n, 3, 3)) * 0.3
    S = np.einsum("kij,klj->kil", b, b) + 0.05 * np.eye(3)
    return np.trace(S, axis1=1, axis2=2)[:, None, None] * np.eye(3) - S


@pytest.fixture(scope="module")
def random_body():
    """A random lumped body with 5 nodes and 3 (non-orthogonal) mode shapes."""
    rng = np.random.default_rng(0)
    n, N = 5, 3
    xyz = rng.normal(size=(n, 3))
    m = rng.uniform(0.5, 2.0, n)
    J = physical_inertias(rng, n)
    pt = rng.normal(size=(n, 3, N))
    pr = rng.normal(size=(n, 3, N))
    ke = np.diag([4.0, 9.0, 16.0])
    body = fe.modal_body(
        jnp.asarray(xyz), jnp.asarray(m), jnp.asarray(J), jnp.asarray(pt), jnp.asarray(pr),
        jnp.asarray(ke), ("a", "b"), (0, 3),
    )
    return body, (xyz, m, J, pt, pr)


def point_cloud(data):
    """Each node as 7 point masses with the node's mass, centroid and inertia tensor.

    A centre point plus pairs at ``±r e_i`` along the eigenvectors of ``S = ½ tr(J) I − J``
    carrying ``λ_i / (2 r²)`` each. The points move rigidly with their node: translation
    ``Ψt_k + Ψr_k × s`` per unit modal coordinate. Returns (xyz, mass, phi_translation).
    """
    xyz, m, J, pt, pr = data
    pts, masses, modes = [], [], []
    for k in range(len(m)):
        S = 0.5 * np.trace(J[k]) * np.eye(3) - J[k]
        lam, vec = np.linalg.eigh(S)
        assert lam.min() > 0.0
        r = np.sqrt(2.0 * lam.sum() / m[k])  # the six outer points carry half the mass
        offsets = [np.zeros(3)] + [sign * r * vec[:, i] for i in range(3) for sign in (1.0, -1.0)]
        weights = [m[k] - lam.sum() / r**2] + [lam[i] / (2 * r**2) for i in range(3) for _ in (1.0, -1.0)]
        for s, w in zip(offsets, weights):
            pts.append(xyz[k] + s)
            masses.append(w)
            modes.append(pt[k] + np.cross(pr[k], s[:, None], axis=0))
    return np.asarray(pts), np.asarray(masses), np.asarray(modes)


def cloud_kinetic_energy(z, p, cloud):
    """Exact T = ½ Σ m_i |v + ω × x_i + Ψ_i ṗ|² of the point cloud at modal coordinates p."""
    xyz, m, phi = (jnp.asarray(d) for d in cloud)
    v, w, pd = z[:3], z[3:6], z[6:]
    x = xyz + jnp.einsum("kil,l->ki", phi, p)
    vel = v[None, :] + jnp.cross(jnp.broadcast_to(w, x.shape), x) + jnp.einsum("kil,l->ki", phi, pd)
    return 0.5 * jnp.sum(m[:, None] * vel**2)


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


def test_rotary_inertia_enters_every_invariant_as_point_cloud(random_body):
    """Nodal inertias with rotational mode shapes give exactly the invariants of an
    explicit point cloud of the same masses and inertias moving rigidly with the nodes
    (translational sums only): J0, Ct, Cr0, C4, C5 and Me to round-off."""
    body, data = random_body
    xyz, m, phi = point_cloud(data)
    n, N = len(m), phi.shape[2]
    ref = fe.modal_invariants(
        jnp.asarray(xyz), jnp.asarray(m), jnp.zeros((n, 3, 3)), jnp.asarray(phi), jnp.zeros((n, 3, N))
    )
    inv = body.invariants
    for name in ("mass", "c0", "J0", "Ct", "Cr0", "C4", "C5", "Me"):
        np.testing.assert_allclose(getattr(inv, name), getattr(ref, name), rtol=RTOL_EXACT, atol=1e-12, err_msg=name)
    # the rotary part is not negligible here: without it C4 and C5 differ at O(1)
    xyz0, m0, _, pt, pr = data
    no_rot = fe.modal_invariants(*(jnp.asarray(a) for a in (xyz0, m0, np.zeros((len(m0), 3, 3)), pt, pr)))
    assert np.max(np.abs(np.asarray(no_rot.C4) - np.asarray(inv.C4))) > 0.1
    assert np.max(np.abs(np.asarray(no_rot.C5) - np.asarray(inv.C5))) > 0.1


def test_mass_matrix_is_hessian_of_exact_kinetic_energy(random_body):
    """M(0) and ∂M/∂p at p = 0 equal those of the exact kinetic energy of the point cloud
    (nodes with rotary inertia moving with their nodes' translations and rotations)."""
    body, data = random_body
    cloud = point_cloud(data)
    N = body.n_modes
    hess = lambda p: jax.hessian(cloud_kinetic_energy)(jnp.zeros(6 + N), p, cloud)
    p0 = jnp.zeros(N)
    np.testing.assert_allclose(body.mass_matrix(p0), jax.jit(hess)(p0), rtol=RTOL_EXACT, atol=1e-12)
    dm = jax.jit(jax.jacfwd(body.mass_matrix))(p0)
    np.testing.assert_allclose(dm, jax.jit(jax.jacfwd(hess))(p0), rtol=1e-9, atol=1e-10)


def test_kinetic_energy_equals_fe_mass_matrix_energy():
    """½ zᵀ M(0) z from the invariants equals ½ uᵀ M_FE u of the assembled (lumped, with
    rotary inertia) FE mass matrix for the nodal velocities u of a rigid motion (about an
    origin off the centre of mass) plus modal velocities, to round-off."""
    from test_fe_reduction import box_frame

    frame = box_frame()
    K, M = fe.assemble(frame)
    N = 5
    _, phi = fe.free_free_modes(K, M, N)
    origin = jnp.asarray([0.3, -0.2, 0.1])
    xyz = fe.mesh_xyz(frame) - origin[None, :]
    mass, inertia = fe.nodal_mass_data(M)
    pt, pr = fe.split_modes(phi)
    body = fe.modal_body(xyz, mass, inertia, pt, pr, phi.T @ K @ phi, (), ())
    rng = np.random.default_rng(5)
    for _ in range(3):
        z = jnp.asarray(rng.normal(size=6 + N))
        v, w, pd = z[:3], z[3:6], z[6:]
        rigid = jnp.concatenate([v[None, :] + jnp.cross(jnp.broadcast_to(w, xyz.shape), xyz),
                                 jnp.broadcast_to(w, xyz.shape)], axis=1).reshape(-1)
        u = rigid + phi @ pd
        t_fe = 0.5 * u @ M @ u
        t_inv = 0.5 * z @ body.mass_matrix(jnp.zeros(N)) @ z
        np.testing.assert_allclose(t_inv, t_fe, rtol=RTOL_EXACT)
        # without the modal rotations (Ψr = 0 in Cr0, Me) the energy would be wrong
        no_rot = fe.modal_body(xyz, mass, inertia, pt, 0.0 * pr, phi.T @ K @ phi, (), ())
        assert abs(float(0.5 * z @ no_rot.mass_matrix(jnp.zeros(N)) @ z) - float(t_fe)) > 1e-8 * float(t_fe)


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
        [
            mdot_z[:3] + jnp.cross(w, P),
            mdot_z[3:6] + jnp.cross(w, H) + jnp.cross(v, P),
            mdot_z[6:] - jax.grad(T, 1)(z, p),
        ]
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


def test_point_kinematics(random_body):
    """Named points: elastic translation Ψt p and small rotation Ψr p (body frame)."""
    body, (xyz, m, J, pt, pr) = random_body
    p = jnp.asarray([0.1, -0.2, 0.3])
    np.testing.assert_allclose(body.point_displacement(p), pt[[0, 3]] @ np.asarray(p), rtol=RTOL_EXACT)
    np.testing.assert_allclose(body.point_rotation(p), pr[[0, 3]] @ np.asarray(p), rtol=RTOL_EXACT)
    assert body.point_index("b") == 1
    with pytest.raises(ParameterError, match="modal body has no point 'c'; known points: \\['a', 'b'\\]"):
        body.point_index("c")


def test_neglect_c_keeps_the_undeformed_centre_of_mass(random_body):
    """Thesis Table 7.2 option: the centre of mass c0 instead of c(p) in M(p) and h_g."""
    body, _ = random_body
    p, g = jnp.asarray([0.1, -0.2, 0.3]), jnp.asarray([0.0, 0.0, -9.81])
    m = body.invariants.mass
    full, fixed = body.mass_matrix(p), body.mass_matrix(p, neglect_c=True)
    np.testing.assert_allclose(fixed[3:6, :3], m * fe.skew(body.invariants.c0), rtol=RTOL_EXACT)
    np.testing.assert_allclose(fixed[6:, :], full[6:, :], rtol=RTOL_EXACT)
    np.testing.assert_allclose(fixed[3:6, 3:], full[3:6, 3:], rtol=RTOL_EXACT)
    hg = body.gravity_forces(p, g, neglect_c=True)
    np.testing.assert_allclose(hg[3:6], m * jnp.cross(body.invariants.c0, g), rtol=RTOL_EXACT)
    p0 = jnp.zeros(3)
    np.testing.assert_allclose(body.gravity_forces(p0, g, neglect_c=True), body.gravity_forces(p0, g))
