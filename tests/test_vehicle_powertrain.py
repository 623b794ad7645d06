"""Powertrain (``jaxveh.vehicle._powertrain``): a PI speed loop on a flywheel plant through
the library against the closed-form linear response, the open differential's equal split
and zero net torque, anti-windup, and named errors."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.linalg import expm

from jaxveh import multibody as mb, vehicle
from jaxveh._core import ParameterError

J, R = 2.0, 0.25  # flywheel inertia (kg m^2), radius of the speed point (m)
KP, KI, V_REF = 40.0, 120.0, 10.0


@pytest.fixture(scope="module")
def rig():
    """A flywheel turning about y on the ground; its rim point's speed is the 'vehicle
    speed' u = ω R; both 'driven wheels' are the flywheel, the reaction goes to the ground."""
    b = mb.SystemBuilder(gravity=(0.0, 0.0, 0.0))
    b.add_rigid_body("fly", 1.0, np.diag([1.0, J, 1.0]), parent="ground", revolute=((0, 0, 0), (0, 1, 0)))
    b.add_point("rim", "fly", (0.0, 0.0, R))
    b.add_point("hub", "fly", (0.0, 0.0, 0.0))
    b.add_point("base", "ground", (0.0, 0.0, 0.0))
    b.add_independent("fly", "theta_dot")
    system, params = b.build()
    pid = vehicle.SpeedPID(kp=KP, ki=KI)
    pt = vehicle.Powertrain.on(system, "fly", "rim", ("hub", "hub"), "base", pid, vehicle.ConstantSpeed(V_REF))
    return system, params, pt


def test_pi_speed_loop_matches_the_linear_closed_form(rig):
    system, params, pt = rig
    ts = jnp.linspace(0.0, 4.0, 41)
    sim = mb.simulate(system, params, jnp.zeros(1), jnp.zeros(1), 0.0, 4.0, ts, elements=(pt,),
                      rtol=1e-10, atol=1e-12)
    speed = np.asarray(sim.z[:, 0]) * R
    g = R / J  # speed x = ω R: x_dot = g T, T = kp (v - x) + ki s, s_dot = v - x
    a = np.array([[-g * KP, g * KI], [-1.0, 0.0]])
    b = np.array([g * KP * V_REF, V_REF])
    x_inf = np.linalg.solve(a, -b)
    expected = [(x_inf + expm(a * t) @ (np.zeros(2) - x_inf))[0] for t in np.asarray(ts)]
    np.testing.assert_allclose(speed, expected, atol=1e-8)
    assert abs(speed[-1] - V_REF) < 1e-3  # integral action reaches the target (poles -2.5 ± 2.96j)


def test_open_differential_and_zero_net_torque(rig):
    system, params, pt = rig
    dyn = mb.dynamics(system, params, jnp.asarray([0.3]), jnp.asarray([12.0]), 0.0, elements=(pt,),
                      aux=jnp.asarray([0.05, 2.0]))
    out = pt(dyn.kinematics, jnp.asarray([0.05, 2.0]), system)
    torque, _, _ = pt.control(dyn.kinematics, jnp.asarray([0.05, 2.0]))
    np.testing.assert_allclose(jnp.sum(out.torques, axis=0), 0.0, atol=1e-12)
    np.testing.assert_allclose(out.torques[system.point_index("hub")], [0.0, float(torque), 0.0], atol=1e-12)
    np.testing.assert_allclose(float(dyn.z_dot[0]), float(torque) / J, rtol=1e-12)


def test_anti_windup(rig):
    system, params, pt = rig
    limited = vehicle.Powertrain(pt.chassis, pt.speed_point, pt.wheels, pt.reaction,
                                 vehicle.SpeedPID(kp=KP, ki=KI, t_max=5.0), pt.target)
    dyn = mb.dynamics(system, params, jnp.zeros(1), jnp.asarray([4.0]), 0.0, elements=(limited,), aux=jnp.zeros(2))
    torque, integral_rate, _ = limited.control(dyn.kinematics, jnp.zeros(2))
    assert float(torque) == 5.0 and float(integral_rate) == 0.0  # saturated: no integration
    torque, integral_rate, _ = pt.control(dyn.kinematics, jnp.zeros(2))
    np.testing.assert_allclose(integral_rate, V_REF - 4.0 * R, rtol=1e-12)


def test_named_errors():
    with pytest.raises(ParameterError, match="tau"):
        vehicle.SpeedPID(kp=1.0, ki=1.0, tau=0.0)
    with pytest.raises(ParameterError, match="t_max"):
        vehicle.SpeedPID(kp=1.0, ki=1.0, t_max=-1.0)
    with pytest.raises(ParameterError, match="kp"):
        vehicle.SpeedPID(kp=-1.0, ki=1.0)
    assert jax.tree.leaves(vehicle.ConstantSpeed(3.0))  # a pytree: the speed is a leaf


def test_brakes_take_a_negative_torque_with_their_reactions_on_the_mounts(rig):
    """Too fast for the target: the torque is negative and goes to the brakes (front share on
    the 'front' entry, the rest on the 'rear' one, both on the flywheel here), reacted on the
    mounts; nothing through the differential. Net torque zero; the flywheel decelerates by
    T / J."""
    system, params, pt = rig
    pid = vehicle.SpeedPID(kp=KP, ki=KI, brake_front_share=0.7)
    braked = vehicle.Powertrain.on(system, "fly", "rim", ("hub", "hub"), "base", pid, vehicle.ConstantSpeed(V_REF),
                                   brakes=(("hub", "base", True), ("hub", "base", False)))
    aux = jnp.asarray([0.0, 12.0 * R])
    dyn = mb.dynamics(system, params, jnp.zeros(1), jnp.asarray([60.0]), 0.0, elements=(braked,), aux=aux)
    torque, _, _ = braked.control(dyn.kinematics, aux)
    assert float(torque) < 0.0
    drive, brake = braked.split(torque)
    np.testing.assert_allclose(drive, 0.0, atol=0.0)
    np.testing.assert_allclose(brake, [0.7 * float(torque), 0.3 * float(torque)], rtol=1e-12)
    out = braked(dyn.kinematics, aux, system)
    np.testing.assert_allclose(jnp.sum(out.torques, axis=0), 0.0, atol=1e-12)
    np.testing.assert_allclose(out.torques[system.point_index("hub")], [0.0, float(torque), 0.0], rtol=1e-12)
    np.testing.assert_allclose(float(dyn.z_dot[0]), float(torque) / J, rtol=1e-12)
    # below the target the same element drives through the differential, brakes off
    slow = mb.dynamics(system, params, jnp.zeros(1), jnp.asarray([4.0]), 0.0, elements=(braked,), aux=jnp.zeros(2))
    torque, _, _ = braked.control(slow.kinematics, jnp.zeros(2))
    drive, brake = braked.split(torque)
    assert float(torque) > 0.0 and np.all(np.asarray(brake) == 0.0)
    np.testing.assert_allclose(drive, [float(torque) / 2] * 2, rtol=1e-12)


def test_feedforward_follows_the_target_acceleration(rig):
    """With the feedforward gain J / R and no error, the torque is exactly what accelerates the
    flywheel's rim at the target's rate."""
    system, params, pt = rig
    target = vehicle.SpeedChange(speed=V_REF, final_speed=2.0 * V_REF, rate=3.0, start=0.0, rise=0.1)
    ff = vehicle.Powertrain.on(system, "fly", "rim", ("hub", "hub"), "base", vehicle.SpeedPID(kp=KP, ki=KI), target,
                               feedforward=J / R)
    t = 0.5  # in the hold: target acceleration 3 m/s^2
    u = float(target(t))
    dyn = mb.dynamics(system, params, jnp.zeros(1), jnp.asarray([u / R]), t, elements=(ff,),
                      aux=jnp.asarray([0.0, u]))
    torque, _, _ = ff.control(dyn.kinematics, jnp.asarray([0.0, u]))
    np.testing.assert_allclose(float(torque), J / R * 3.0, rtol=1e-9)
    np.testing.assert_allclose(float(dyn.z_dot[0]) * R, 3.0, rtol=1e-9)
