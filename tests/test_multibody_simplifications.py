"""Thesis section 7.6.2 (Table 7.2) on a constrained system with a rheonomic input, the
quarter car (five links, rack): neglected ``S b`` and ``S c`` of the coordinate reduction,
and projection matrices held for k integration steps (``freeze_steps``). Each variant is
checked against what it must keep and against what it must change."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxveh
from jaxveh import multibody as mb, vehicle

#: Two evaluations of the same float64 formulas (LU solves of a 5 x 5 block of order 1).
SAME_ATOL = 1e-11
RESIDUAL_BOUND = 1e-9
#: Rack law ``u = A sin(w t)``: 10 mm at 2 Hz, so ``u(0) = 0`` (the assembled design) and
#: ``u_dot(0) = A w`` = 0.13 m/s.
RACK_AMPLITUDE, RACK_OMEGA = 0.01, 2.0 * np.pi * 2.0


def _rack(t):
    return jnp.atleast_1d(RACK_AMPLITUDE * jnp.sin(RACK_OMEGA * t))


def _still(t):
    return jnp.zeros((1,)) + 0.0 * t


@pytest.fixture(scope="module")
def corner():
    system, params = vehicle.quarter_car()
    q0 = vehicle.quarter_car_design_q(system)
    rate = vehicle.WheelRate(k=20000.0, c=0.0, z0=vehicle.WHEEL_CENTRE_HEIGHT, fz=14.0 * jaxveh.GRAVITY)
    external = lambda q, v, t, a: a.force(system, params, q, v)  # noqa: E731
    return system, params, q0, rate, external


def _dynamics(corner, z, inputs, options=mb.FlexOptions(), frozen=None, q=None):
    system, params, q0, rate, external = corner
    q = q0 if q is None else q
    return mb.dynamics(system.with_options(options), params, q, jnp.asarray(z), 0.0, inputs, external, rate,
                       frozen=frozen)


def test_projection_held_at_the_same_state_is_exact(corner):
    """Held matrices computed at the state itself give the exact accelerations; held from
    another state (20 mm of bump away) they do not."""
    system, params, q0, _, _ = corner
    z = jnp.asarray([0.4, 30.0])
    exact = _dynamics(corner, z, _rack)
    held = mb.projection(system, params, q0, 0.0, _rack)
    same = _dynamics(corner, z, _rack, frozen=held)
    np.testing.assert_allclose(same.z_dot, exact.z_dot, atol=SAME_ATOL * float(jnp.max(jnp.abs(exact.z_dot))))
    np.testing.assert_allclose(same.y, exact.y, atol=SAME_ATOL)
    bumped = mb.assemble(system, params, q0.at[2].add(0.02), fixed=(2, 6), inputs=_still)
    other = mb.projection(system, params, bumped, 0.0, _rack)
    stale = _dynamics(corner, z, _rack, frozen=other)
    assert float(jnp.max(jnp.abs(stale.y - exact.y))) > 1e-4  # m/s or rad/s: R changed with the bump


def test_neglect_sb_drops_exactly_the_input_motion(corner):
    """``y = R z``: with the rack still, ``S b`` is zero and nothing changes; with the rack
    moving, ``y`` lacks exactly ``S b`` (not zero: the rack drags the track rod)."""
    z = jnp.asarray([0.4, 30.0])
    options = mb.FlexOptions(neglect_sb=True)
    still, still_nsb = _dynamics(corner, z, _still), _dynamics(corner, z, _still, options)
    np.testing.assert_allclose(still_nsb.z_dot, still.z_dot, atol=SAME_ATOL * float(jnp.max(jnp.abs(still.z_dot))))
    moving, moving_nsb = _dynamics(corner, z, _rack), _dynamics(corner, z, _rack, options)
    sb = moving.projection.Sb
    assert float(jnp.max(jnp.abs(sb))) > 1e-2
    np.testing.assert_allclose(moving_nsb.y, moving.y - sb, atol=SAME_ATOL)


def test_neglect_sc_changes_nothing_at_rest_and_the_accelerations_in_motion(corner):
    """``S c`` collects the velocity-product terms of the constraint accelerations: zero at
    rest with the rack still, so the accelerations agree; in bump motion they differ, and
    the simplified dependent accelerations are ``R z_dot`` alone."""
    options = mb.FlexOptions(neglect_sc=True)
    rest, rest_nsc = _dynamics(corner, jnp.zeros(2), _still), _dynamics(corner, jnp.zeros(2), _still, options)
    np.testing.assert_allclose(rest_nsc.z_dot, rest.z_dot, atol=SAME_ATOL * float(jnp.max(jnp.abs(rest.z_dot))))
    z = jnp.asarray([0.8, 30.0])
    full, nsc = _dynamics(corner, z, _rack), _dynamics(corner, z, _rack, options)
    assert float(jnp.max(jnp.abs(full.Sc))) > 1e-2
    assert float(jnp.abs(nsc.z_dot[0] - full.z_dot[0])) > 1e-3 * float(jnp.abs(full.z_dot[0]))
    np.testing.assert_allclose(nsc.y_dot, nsc.projection.R @ nsc.z_dot, atol=SAME_ATOL)


@pytest.fixture(scope="module")
def bounce(corner):
    """A 0.3 s bounce from 20 mm of bump while the rack steers (2 Hz, 10 mm)."""
    system, params, q0, rate, external = corner
    q = mb.assemble(system, params, q0.at[2].add(0.02), fixed=(2, 6), inputs=_rack)
    z0 = jnp.asarray([0.0, 30.0])
    ts = jnp.linspace(0.0, 0.3, 31)

    def run(options=mb.FlexOptions(), freeze_steps=0):
        s = system.with_options(options)
        return mb.simulate(s, params, q, z0, 0.0, 0.3, ts=ts, inputs=_rack, external=external, args=rate,
                           rtol=1e-8, atol=1e-10, freeze_steps=freeze_steps)

    return run, run()


@pytest.mark.slow
@pytest.mark.parametrize("variant", ["freeze_1", "freeze_4", "neglect_sb", "neglect_sc"])
def test_simplified_runs_stay_on_the_manifold_near_the_complete_run(bounce, variant):
    """Each simplification keeps the constraints (the position correction) and stays close
    to the complete run, without reproducing it: the largest wheel-centre height deviation
    lies between 1e-9 m and 1 mm of a bounce of about 20 mm."""
    run, complete = bounce
    if variant.startswith("freeze"):
        sim = run(freeze_steps=int(variant.split("_")[1]))
    else:
        sim = run(mb.FlexOptions(**{variant: True}))
    assert float(sim.max_residual) < RESIDUAL_BOUND
    deviation = float(jnp.max(jnp.abs(sim.q[:, 2] - complete.q[:, 2])))
    swing = float(jnp.max(complete.q[:, 2]) - jnp.min(complete.q[:, 2]))
    assert swing > 0.01
    assert 1e-9 < deviation < 1e-3, deviation


def test_freeze_steps_is_checked(corner):
    system, params, q0, _, _ = corner
    z0 = jnp.zeros(2)
    with pytest.raises(ValueError, match="freeze_steps = -1 is out of range: allowed integers >= 0"):
        mb.simulate(system, params, q0, z0, 0.0, 0.1, inputs=_still, freeze_steps=-1)
    with pytest.raises(ValueError, match="freeze_steps needs project=True"):
        mb.simulate(system, params, q0, z0, 0.0, 0.1, inputs=_still, freeze_steps=2, project=False)


def test_table_7_2_options_are_static_and_named():
    """The options are static flags (one compiled program each) under their Table 7.2 names."""
    assert jax.tree.leaves(mb.FlexOptions(True, True, True, True, True)) == []  # every flag is static
    assert set(mb.FlexOptions.__dataclass_fields__) == {
        "constant_mass", "neglect_gyroscopic", "neglect_com_shift", "neglect_sc", "neglect_sb"}
