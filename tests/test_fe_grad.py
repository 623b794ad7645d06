"""Derivatives of frequencies, torsional stiffness and invariants w.r.t. tube sizes."""

import json
import os
import subprocess
import sys
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import assert_grad_matches_fd
from jax.test_util import check_grads
from test_fe_reduction import box_frame

import jaxveh.fe as fe

#: Central differences with h = 1e-8 m on millimetre sizes: truncation O(h²) is
#: negligible, round-off ~1e-16 f / h ~ 1e-7 relative: compare to 1e-5.
RTOL_FD = 1e-5
H_FD = 1e-8


@pytest.fixture(scope="module")
def frame():
    return box_frame()


def sized(frame, x):
    """The box frame with section "tube" = CircularTube(x[0], x[1]) (m)."""
    secs = list(frame.sections)
    secs[0] = fe.CircularTube(x[0], x[1])
    return fe.with_sections(frame, secs)


X0 = np.array([25.4e-3, 1.6e-3])


def first_frequencies(frame, x):
    K, M = fe.assemble(sized(frame, x))
    return fe.free_free_modes(K, M, 4)[0]


@pytest.mark.slow
def test_frequency_gradient_matches_fd(frame):
    f = jax.jit(lambda x: first_frequencies(frame, x)[0])
    assert_grad_matches_fd(f, X0, h=H_FD, rtol=RTOL_FD)
    f3 = jax.jit(lambda x: first_frequencies(frame, x)[3])
    assert_grad_matches_fd(f3, X0, h=H_FD, rtol=RTOL_FD)


@pytest.mark.slow
def test_frequency_forward_and_reverse_agree(frame):
    f = lambda x: first_frequencies(frame, x)
    J_fwd = jax.jacfwd(f)(jnp.asarray(X0))
    J_rev = jax.jacrev(f)(jnp.asarray(X0))
    np.testing.assert_allclose(J_fwd, J_rev, rtol=1e-10)


def test_torsional_stiffness_gradient_matches_fd(frame):
    k = jax.jit(lambda x: fe.torsion_test(sized(frame, x)).stiffness_nm_per_deg)
    assert_grad_matches_fd(k, X0, h=H_FD, rtol=RTOL_FD)


def test_mass_gradient_closed_form(frame):
    """d(mass)/dt = rho L pi (D - 2t) summed over the members of that section."""
    m = lambda x: fe.frame_mass(sized(frame, x))
    g = jax.grad(m)(jnp.asarray(X0))
    L = sum(
        np.linalg.norm(np.diff(np.asarray(frame.node_xyz)[list(ij)], axis=0))
        for ij, s in zip(frame.member_nodes, frame.member_section) if s == 0
    )
    np.testing.assert_allclose(g[1], 7850.0 * L * np.pi * (X0[0] - 2 * X0[1]), rtol=1e-12)
    np.testing.assert_allclose(g[0], 7850.0 * L * np.pi * X0[1], rtol=1e-12)


def test_invariant_gradients_match_fd(frame):
    def inv(x):
        body = fe.frame_modal_body(sized(frame, x), 3, points=("s0c0",))
        i = body.invariants
        # sign-invariant functions of mode-dependent invariants
        return i.J0[0, 0] + jnp.sum(i.C4**2) + jnp.sum(i.C5**2) + 1e-6 * jnp.sum(body.Ke)

    assert_grad_matches_fd(jax.jit(inv), X0, h=H_FD, rtol=RTOL_FD)


@pytest.mark.slow
def test_repeated_eigenvalues_give_finite_exact_cluster_gradient():
    """A circular tube has equal bending frequencies in y and z: per-mode derivatives
    are finite and the pair's sum is exact."""
    def pair(x):
        tube = fe.straight_tube_frame(1.0, 8, x[0], x[1])
        K, M = fe.assemble(tube)
        return fe.free_free_modes(K, M, 2)[0]

    x = jnp.asarray([30e-3, 2e-3])
    f = pair(x)
    np.testing.assert_allclose(f[0], f[1], rtol=1e-9)
    g = jax.jacrev(pair)(x)
    assert np.all(np.isfinite(g))
    assert_grad_matches_fd(jax.jit(lambda x: jnp.sum(pair(x))), x, h=H_FD, rtol=RTOL_FD)


def vmap_of_grad() -> dict:
    """A jitted, vmapped gradient of the box frame's first frequency at ``X0`` and ``1.1 X0``,
    and the plain gradient at ``X0`` (lists, for JSON)."""
    frame = box_frame()
    g = jax.jit(jax.vmap(jax.grad(lambda x: first_frequencies(frame, x)[0])))
    out = g(jnp.stack([jnp.asarray(X0), jnp.asarray(X0) * 1.1]))
    plain = jax.grad(lambda x: first_frequencies(frame, x)[0])(jnp.asarray(X0))
    return {"batched": np.asarray(out).tolist(), "plain": np.asarray(plain).tolist()}


#: Runs :func:`vmap_of_grad` in a process pinned to one CPU (before JAX starts).
_PINNED = """
import json, os, sys
os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
sys.path.insert(0, sys.argv[1])
from test_fe_grad import vmap_of_grad
print(json.dumps(vmap_of_grad()))
"""


def test_vmap_of_grad():
    """The vmapped gradient equals the plain one and moves with the design. On jaxlib 0.10.2
    the vmapped generalised eigenproblem's batched LAPACK calls (Cholesky, triangular
    solves) can deadlock in XLA's intra-op thread pool when it has more than one thread
    (docs/optimise.md; a cold CI run hung here twice on 2026-12-06), so the batch runs in a
    process pinned to one CPU, whose pool has one thread: the same program and results,
    without the pool's batched path."""
    if hasattr(os, "sched_setaffinity"):
        here = str(Path(__file__).resolve().parent)
        done = subprocess.run([sys.executable, "-c", _PINNED, here], capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr[-3000:]
        result = json.loads(done.stdout.strip().splitlines()[-1])
    else:
        result = vmap_of_grad()
    batched, plain = np.asarray(result["batched"]), np.asarray(result["plain"])
    np.testing.assert_allclose(batched[0], plain, rtol=1e-10)
    assert np.all(np.isfinite(batched)) and not np.allclose(batched[0], batched[1])


def test_no_retrace_on_new_sizes(frame):
    @eqx.filter_jit
    @eqx.debug.assert_max_traces(max_traces=1)
    def freq(fr):
        K, M = fe.assemble(fr)
        return fe.free_free_modes(K, M, 2)[0]

    a = freq(sized(frame, jnp.asarray(X0)))
    b = freq(sized(frame, jnp.asarray(X0) * 1.05))
    assert not np.allclose(a, b)


def test_gradient_wrt_node_coordinates_and_material(frame):
    """Torsional stiffness w.r.t. the height of one mid-station node and Young's modulus."""
    k0 = fe.torsion_test(frame).stiffness
    j = frame.node_index("s1c2")

    def k_of(x):
        xyz = frame.node_xyz.at[j, 2].set(x[0])
        mat = fe.Material(x[1], frame.materials[0].shear_modulus, frame.materials[0].density)
        fr = eqx.tree_at(lambda f: (f.node_xyz, f.materials), frame, (xyz, (mat,)))
        return fe.torsion_test(fr).stiffness / k0

    x0 = np.array([float(frame.node_xyz[j, 2]), float(frame.materials[0].youngs_modulus)])
    g = jax.grad(jax.jit(k_of))(jnp.asarray(x0))
    fd = [
        (float(k_of(jnp.asarray(x0 + dx))) - float(k_of(jnp.asarray(x0 - dx)))) / (2 * dx[i])
        for i, dx in enumerate((np.array([1e-6, 0.0]), np.array([0.0, 1e8])))
    ]
    np.testing.assert_allclose(g, fd, rtol=1e-5)


def test_check_grads_sections_mass_and_torsion(frame):
    """``jax.test_util.check_grads`` (forward and reverse mode) w.r.t. sizes in mm."""
    props = lambda x: jnp.stack(jax.tree.leaves(fe.CircularTube(1e-3 * x[0], 1e-3 * x[1]).properties()))
    rect = lambda x: jnp.stack(jax.tree.leaves(fe.RectangularTube(1e-3 * x[0], 1e-3 * x[1], 1e-3 * x[2]).properties()))
    check_grads(lambda x: 1e6 * props(x), (jnp.asarray([25.4, 1.6]),), order=2, modes=("fwd", "rev"), eps=1e-4)
    check_grads(lambda x: 1e6 * rect(x), (jnp.asarray([20.0, 30.0, 1.2]),), order=2, modes=("fwd", "rev"), eps=1e-4)
    mass = jax.jit(lambda x: fe.frame_mass(sized(frame, 1e-3 * x)))
    check_grads(mass, (jnp.asarray(X0 * 1e3),), order=1, modes=("fwd", "rev"), eps=1e-4)
    k = jax.jit(lambda x: fe.torsion_test(sized(frame, 1e-3 * x)).stiffness_nm_per_deg)
    check_grads(k, (jnp.asarray(X0 * 1e3),), order=1, modes=("fwd", "rev"), eps=1e-4, rtol=1e-6)


def test_check_grads_invariants_wrt_mode_shapes():
    """Invariants (with the rotary-inertia terms) are polynomial in the mode shapes."""
    rng = np.random.default_rng(2)
    n, N = 4, 2
    xyz, m = jnp.asarray(rng.normal(size=(n, 3))), jnp.asarray(rng.uniform(0.5, 2.0, n))
    J = jnp.asarray(np.broadcast_to(np.diag([0.2, 0.3, 0.4]), (n, 3, 3)).copy())

    def f(pt, pr):
        inv = fe.modal_invariants(xyz, m, J, pt, pr)
        return jnp.concatenate([inv.C4.ravel(), inv.C5.ravel(), inv.Cr0.ravel(), inv.Me.ravel()])

    args = (jnp.asarray(rng.normal(size=(n, 3, N))), jnp.asarray(rng.normal(size=(n, 3, N))))
    check_grads(jax.jit(f), args, order=2, modes=("fwd", "rev"))
