"""Tyres at the contact patch (``jaxveh.vehicle._contact``): contact geometry and
inclination sign, normal load, free rolling, steady slip against ``tyre_forces``, forces
opposing sliding, equivariance under yaw, and the element through the library on a wheel
rig (upright + spinning wheel)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxveh import multibody as mb, tyre, vehicle
from jaxveh._core import GRAVITY

TYRE = tyre.load_fsae_tyre()
R0, KZ = float(TYRE.unloaded_radius), float(TYRE.vertical_stiffness)
DEFLECTION = 0.006  # m


def _yaw(psi):
    c, s = np.cos(psi), np.sin(psi)
    return jnp.asarray([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _contact(centre, velocity, axis, spin, deflection=jnp.zeros(2), omega_upright=jnp.zeros(3)):
    omega_wheel = omega_upright + spin * axis
    return vehicle.wheel_contact(TYRE, centre, velocity, axis, omega_wheel, omega_upright, deflection)


def test_geometry_and_inclination_sign():
    centre = jnp.asarray([1.0, 2.0, R0 - DEFLECTION])
    e_x, e_y, gamma, h, contact, _ = vehicle.contact_geometry(centre, jnp.asarray([0.0, 1.0, 0.0]))
    np.testing.assert_allclose(e_x, [1.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(e_y, [0.0, 1.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(contact, [1.0, 2.0, 0.0], atol=1e-15)
    assert float(gamma) == 0.0 and abs(float(h) - (R0 - DEFLECTION)) < 1e-15
    # top leaning to -y by 3 deg: ISO-W inclination +3 deg; the plane meets the road further out
    g = np.radians(3.0)
    axis = jnp.asarray([0.0, np.cos(g), np.sin(g)])
    _, _, gamma, h, contact, _ = vehicle.contact_geometry(centre, axis)
    np.testing.assert_allclose(gamma, g, rtol=1e-13)
    np.testing.assert_allclose(h, (R0 - DEFLECTION) / np.cos(g), rtol=1e-13)
    np.testing.assert_allclose(contact[2], 0.0, atol=1e-15)
    assert float(contact[1]) > 2.0  # the contact point moves to +y (under the leaning top's opposite side)


def test_normal_load_and_free_rolling():
    v = 15.0
    centre = jnp.asarray([0.0, 0.0, R0 - DEFLECTION])
    fz0 = KZ * DEFLECTION
    re = float(tyre.effective_rolling_radius(TYRE, fz0))
    force, moment, rates, out = _contact(centre, jnp.asarray([v, 0.0, 0.0]), jnp.asarray([0.0, 1.0, 0.0]), v / re)
    np.testing.assert_allclose(out["fz"], fz0, rtol=1e-12)
    np.testing.assert_allclose(force[2], fz0, rtol=1e-12)
    np.testing.assert_allclose(rates, 0.0, atol=1e-12)  # free rolling, relaxed: nothing changes
    np.testing.assert_allclose(out["kappa"], 0.0, atol=1e-15)
    # lifted wheel: no load, no force
    force, _, _, out = _contact(centre.at[2].set(R0 + 0.01), jnp.asarray([v, 0.0, 0.0]), jnp.asarray([0.0, 1.0, 0.0]),
                                v / re)
    assert float(out["fz"]) == 0.0 and float(jnp.max(jnp.abs(force))) == 0.0


@pytest.mark.parametrize("slip_deg", [-4.0, 2.0, 6.0])
def test_steady_lateral_slip_matches_the_magic_formula(slip_deg):
    """Relaxed at a steady slip angle (deflection v = σ_α tan α): the lateral force is
    ``tyre_forces`` at that angle and opposes the sliding."""
    v, a = 15.0, np.radians(slip_deg)
    centre = jnp.asarray([0.0, 0.0, R0 - DEFLECTION])
    velocity = jnp.asarray([v, v * np.tan(a), 0.0])  # heading +x, sliding sideways
    fz0 = KZ * DEFLECTION
    re = float(tyre.effective_rolling_radius(TYRE, fz0))
    sigma_k, sigma_a = (float(s) for s in tyre.relaxation_lengths(TYRE, fz0, 0.0))
    deflection = jnp.asarray([0.0, sigma_a * np.tan(a)])
    force, _, rates, out = _contact(centre, velocity, jnp.asarray([0.0, 1.0, 0.0]), v / re, deflection)
    np.testing.assert_allclose(rates, 0.0, atol=1e-10)  # steady state of the relaxation
    np.testing.assert_allclose(out["alpha"], a, rtol=1e-12)
    expected = tyre.tyre_forces(TYRE, fz0, 0.0, a, 0.0, v)
    np.testing.assert_allclose(force[1], expected.fy, rtol=1e-12)
    assert float(force[1]) * float(velocity[1]) < 0.0  # opposes the sliding


def test_braking_force_opposes_slip_and_yaw_equivariance():
    v = 12.0
    centre = jnp.asarray([0.3, -0.2, R0 - DEFLECTION])
    axis = jnp.asarray([0.0, np.cos(0.02), np.sin(0.02)])
    velocity = jnp.asarray([v, 0.4, 0.0])
    deflection = jnp.asarray([-0.004, 0.002])  # braking (u < 0) and some lateral deflection
    f0, m0, r0, out0 = _contact(centre, velocity, axis, 0.9 * v / R0, deflection)
    assert float(out0["kappa"]) < 0.0 and float(f0[0]) < 0.0  # braking: force backwards
    rot = _yaw(0.7)
    f1, m1, r1, out1 = _contact(rot @ centre, rot @ velocity, rot @ axis, 0.9 * v / R0, deflection)
    np.testing.assert_allclose(f1, rot @ f0, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(m1, rot @ m0, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(r1, r0, rtol=1e-12, atol=1e-12)


@pytest.fixture(scope="module")
def rig():
    """An upright (free, 8 kg) carrying a wheel (spin inertia 0.3 kg m²) on a tyre."""
    b = mb.SystemBuilder(gravity=(0.0, 0.0, -GRAVITY))
    b.add_rigid_body("upright", 8.0, np.diag([0.4, 0.5, 0.4]))
    b.add_rigid_body("wheel", 0.0, np.diag([0.0, 0.3, 0.0]), parent="upright", revolute=((0, 0, 0), (0, 1, 0)))
    b.add_point("U", "upright", (0.0, 0.0, 0.0))
    b.add_point("W", "wheel", (0.0, 0.0, 0.0))
    for name in ("ux", "uy", "uz", "wx", "wy", "wz"):
        b.add_independent("upright", name)
    b.add_independent("wheel", "theta_dot")
    system, params = b.build()
    contact = vehicle.TyreContact.on(system, {"wheel": ("W", "U")}, tyre.stack_tyres([TYRE]))
    return system, params, contact


def test_element_through_the_library(rig):
    """The upright accelerates by the tyre force over its mass (gravity included) and the
    wheel's spin by the moment about its axis over the spin inertia."""
    system, params, contact = rig
    q = jnp.zeros(system.n_q).at[2].set(R0 - DEFLECTION)
    z = jnp.asarray([15.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.9 * 15.0 / R0])
    aux = jnp.asarray([-0.003, 0.001])
    dyn = mb.dynamics(system, params, q, z, elements=(contact,), aux=aux)
    force, moment, rates, out = jax.tree.map(lambda x: x[0], contact.evaluate(dyn.kinematics, aux))
    assert float(out["fz"]) > 0 and abs(float(force[0])) > 10.0
    np.testing.assert_allclose(dyn.z_dot[:3], force / 8.0 - jnp.asarray([0.0, 0.0, GRAVITY]), rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(dyn.z_dot[6], moment[1] / 0.3 - dyn.z_dot[4], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(dyn.aux_dot, rates, rtol=1e-12)
    assert contact.aux_names == ("wheel.u", "wheel.v")


def test_post_road_and_sloped_road():
    """A post raised by 4 mm and rising at 0.1 m/s loads the tyre by kz (4 mm) plus the
    damping of the closing rate; on a 5 % cross slope the normal tilts and the contact point
    lies on the slope."""
    centre = jnp.asarray([0.0, 0.0, R0 - DEFLECTION])
    axis = jnp.asarray([0.0, 1.0, 0.0])
    post = vehicle.PostRoad(lambda t: jnp.stack([0.004 + 0.1 * t, 0.0]))
    omega = jnp.zeros(3)
    _, _, _, out = vehicle.wheel_contact(TYRE, centre, jnp.zeros(3), axis, omega, omega, jnp.zeros(2), post, 0.0, 0)
    expected = KZ * (DEFLECTION + 0.004) + float(TYRE.vertical_damping) * 0.1
    np.testing.assert_allclose(out["fz"], expected, rtol=1e-12)
    np.testing.assert_allclose(out["road_height"], 0.004, rtol=1e-12)

    class Slope(vehicle.AbstractRoad):
        def height(self, x, y, t, wheel):
            return 0.05 * y

    c2 = jnp.asarray([0.0, 0.4, 0.02 + R0 - DEFLECTION])
    _, _, _, h, contact, normal = vehicle.contact_geometry(c2, axis, 0.02, (0.0, 0.05))
    np.testing.assert_allclose(contact[2], 0.05 * contact[1], atol=1e-15)  # on the road
    np.testing.assert_allclose(normal, np.array([0.0, -0.05, 1.0]) / np.sqrt(1.0025), rtol=1e-13)
    _, _, _, out = vehicle.wheel_contact(TYRE, c2, jnp.zeros(3), axis, omega, omega, jnp.zeros(2), Slope())
    np.testing.assert_allclose(out["gamma"], -np.arcsin(0.05 / np.sqrt(1.0025)), rtol=1e-12)


def test_gradients_against_finite_differences():
    """d F_y / d (centre height) and d F_y / d (lateral contact deflection) through the
    contact chain (deflection, load, relaxation, slip, MF) by jax.grad, against central
    differences."""
    v = 14.0
    axis = jnp.asarray([0.0, np.cos(0.01), np.sin(0.01)])
    re = float(tyre.effective_rolling_radius(TYRE, KZ * DEFLECTION))

    def fy(height, lateral_deflection):
        centre = jnp.asarray([0.0, 0.0, 0.0]).at[2].set(height)
        velocity = jnp.asarray([v, 0.6, 0.0])
        force, _, _, _ = _contact(centre, velocity, axis, v / re, jnp.stack([jnp.asarray(0.001), lateral_deflection]))
        return force[1]

    x0 = (jnp.asarray(R0 - DEFLECTION), jnp.asarray(0.01))
    grads = jax.grad(fy, argnums=(0, 1))(*x0)
    for k, h in ((0, 1e-6), (1, 1e-5)):
        up = [x0[0], x0[1]]
        down = [x0[0], x0[1]]
        up[k], down[k] = x0[k] + h, x0[k] - h
        fd = (float(fy(*up)) - float(fy(*down))) / (2 * h)
        assert abs(float(grads[k])) > 1e3  # N/m: both matter
        np.testing.assert_allclose(grads[k], fd, rtol=1e-6)
