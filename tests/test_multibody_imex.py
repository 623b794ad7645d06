"""IMEX integration of stiff elastic modes (``simulate(..., implicit_modes=True)``): the
implicit part is exactly the modal motion of a free body, IMEX runs agree with explicit
ones, take fewer steps on stiff modes, and refuse systems without modes."""

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxveh import multibody as mb
from jaxveh.multibody import _examples as ex

T_END = 0.3


@pytest.fixture(scope="module")
def stiff_pendulum():
    """A pinned 0.5 m tube with 4 modes (273 and 723 Hz free-free; stiffness-proportional
    damping, zeta 0.17 and 0.45) swinging under gravity."""
    beam = ex.flexible_beam(length=0.5, n_modes=4, beta=2e-4)
    system, params = ex.flexible_pendulum(beam)
    q0, z0 = ex.flexible_pendulum_state(system)
    ts = jnp.linspace(0.0, T_END, 31)

    def run(params, implicit, rtol, atol):
        return mb.simulate(system, params, q0, z0, 0.0, T_END, ts, rtol=rtol, atol=atol, implicit_modes=implicit)

    return system, params, run


def test_implicit_part_is_the_free_modal_motion():
    """Free beam, no gravity, at rest with deflected modes: the whole vector field is the
    elastic motion, so it equals the implicit part exactly (remainder zero)."""
    beam = ex.flexible_beam(n_modes=3, beta=1e-4)
    system, params = ex.flexible_pendulum(beam, pinned=False, gravity=0.0)
    p = jnp.asarray([1e-4, -5e-5, 2e-5])
    q = jnp.concatenate([jnp.zeros(6), p])
    z = jnp.zeros(system.n_dof).at[6:].set(jnp.asarray([0.01, 0.02, -0.03]))
    state = mb.State(q, z, jnp.zeros(0))
    part = mb.modal_implicit_part(system, params, q, z, 0.0)
    full = mb.vector_field(system)(0.0, state, (params, None, None, None))
    lin = part(0.0, state, None)
    assert float(jnp.max(jnp.abs(full.z[6:]))) > 1.0  # a real elastic acceleration
    np.testing.assert_allclose(lin.z, full.z, rtol=1e-12, atol=1e-12 * float(jnp.max(jnp.abs(full.z))))
    np.testing.assert_allclose(lin.q, full.q, atol=1e-15)


def test_imex_matches_explicit_with_fewer_steps(stiff_pendulum):
    system, params, run = stiff_pendulum
    reference = jax.jit(lambda p: run(p, False, 1e-10, 1e-12))(params)
    imex = jax.jit(lambda p: run(p, True, 1e-7, 1e-10))(params)
    assert int(imex.status) == 0
    assert float(imex.max_residual) < 1e-9
    np.testing.assert_allclose(imex.q[:, 5], reference.q[:, 5], atol=1e-8)  # swing angle, rad
    np.testing.assert_allclose(imex.q[:, 6:], reference.q[:, 6:], atol=1e-10)  # modal coordinates (max 6e-7)
    # at a loose tolerance the explicit step is held by the stiff modes, the IMEX one is not
    # (measured: 477 against 115 steps)
    loose_explicit = jax.jit(lambda p: run(p, False, 1e-4, 1e-7))(params)
    loose_imex = jax.jit(lambda p: run(p, True, 1e-4, 1e-7))(params)
    assert int(loose_imex.stats["num_steps"]) < int(loose_explicit.stats["num_steps"]) / 3
    np.testing.assert_allclose(loose_imex.q[:, 5], reference.q[:, 5], atol=1e-6)


def test_implicit_modes_needs_modes_and_an_imex_solver(stiff_pendulum):
    system, params = ex.double_pendulum()
    q0, z0 = ex.double_pendulum_state(system, params, (0.3, -0.2), (0.0, 0.0))
    with pytest.raises(ValueError, match="flexible body with modes"):
        mb.simulate(system, params, q0, z0, 0.0, 0.1, implicit_modes=True)
    system, params, _ = stiff_pendulum
    q0, z0 = ex.flexible_pendulum_state(system)
    with pytest.raises(ValueError, match="IMEX solver.*Tsit5"):
        mb.simulate(system, params, q0, z0, 0.0, 0.1, implicit_modes=True, solver=diffrax.Tsit5())


@pytest.mark.slow
def test_imex_gradient_wrt_modal_stiffness(stiff_pendulum):
    """d(final deflection of the stiffest-loaded mode)/d(its stiffness multiplier) through
    KenCarp4 and its Newton stages, against a central difference."""
    system, params, run = stiff_pendulum

    final = jax.jit(lambda p: run(p, False, 1e-9, 1e-12))(params).q[-1, 6:]
    mode = int(jnp.argmax(jnp.abs(final)))

    def deflection(scale):
        p = eqx.tree_at(lambda pp: pp.bodies[0].modal.stiffness_scale, params,
                        params.bodies[0].modal.stiffness_scale.at[mode].set(scale))
        return run(p, True, 1e-9, 1e-12).q[-1, 6 + mode]

    grad = float(jax.jit(jax.grad(deflection))(1.0))
    f = jax.jit(deflection)
    h = 1e-3
    fd = (float(f(1.0 + h)) - float(f(1.0 - h))) / (2 * h)
    assert abs(grad) > 0.5 * float(jnp.abs(final[mode]))  # quasi-static: p ~ 1 / stiffness
    np.testing.assert_allclose(grad, fd, rtol=1e-4)
