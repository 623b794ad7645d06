"""The assembled 14-DOF car: loading, validation, static set-up at rest, rates, its gradients
and ``jaxveh vehicle info``. One rigid and one 6-mode car per module (compiled once)."""

import json
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from typer.testing import CliRunner

from jaxveh import multibody as mb, vehicle
from jaxveh.cli._main import app
from jaxveh.params import ParameterError

G = 9.80665


@pytest.fixture(scope="module")
def rigid():
    return vehicle.load_car(modes=0)


@pytest.fixture(scope="module")
def flexible():
    return vehicle.load_car(modes=6)


@pytest.fixture(scope="module")
def rigid_state(rigid):
    return vehicle.static_equilibrium(rigid)


@pytest.fixture(scope="module")
def flexible_state(flexible):
    return vehicle.static_equilibrium(flexible)


def _split(car):
    """Corner loads of the a/b split (Table B.1): the whole car's weight on the axles."""
    v = car.params.vehicle
    m = float(v.sprung.mass + 2 * v.unsprung_front.body.mass + 2 * v.unsprung_rear.body.mass)
    a, b = float(v.a), float(v.b)
    front, rear = m * G * b / (2 * (a + b)), m * G * a / (2 * (a + b))
    return np.array([front, front, rear, rear]), m


def test_topology_matches_table_6_1(rigid, flexible):
    for car, modes in ((rigid, 0), (flexible, 6)):
        s = car.system
        assert s.n_bodies == 9 and s.n_constraints == 20
        assert s.n_dof == 6 + 4 + 4 + modes  # chassis, suspension travels, spins, modes
        assert car.params.chassis is None if modes == 0 else car.params.chassis.n_modes == modes
    names = rigid.system.body_names
    assert names[0] == "chassis" and rigid.system.sequence[0] == "zyx"
    assert all(rigid.system.sequence[names.index(f"{c}.upright")] == "zxy" for c in vehicle.CORNERS)


def test_whole_car_cg_is_table_b1(rigid):
    """Sprung c.g. placed so that the car's c.g. is at (0, 0, h_cg) with Appendix B's a, b."""
    v = rigid.params.vehicle
    mu = np.array([14.0, 14.0, 18.5, 18.5])
    total = float(v.sprung.mass) * np.asarray(vehicle.sprung_cg(v)) + mu @ np.asarray(vehicle.wheel_centres(v))
    np.testing.assert_allclose(total / float(vehicle.total_mass(v)), [0.0, 0.0, float(v.h_cg)], atol=1e-12)


def test_design_position_closes_every_link(flexible):
    sp = vehicle.system_params(flexible)
    phi = mb.constraints(flexible.system, sp, flexible.q_design, jnp.zeros(1))
    assert float(jnp.max(jnp.abs(phi))) < 1e-12


# ---- static set-up ---------------------------------------------------------------------------


def test_corner_weights_follow_the_ab_split(rigid, rigid_state, flexible_state):
    split, m = _split(rigid)
    for state in (rigid_state, flexible_state):
        loads = np.asarray(state.corner_loads)
        np.testing.assert_allclose(loads, split, rtol=1e-3)  # the 0.1 %
        assert abs(loads.sum() - m * G) < 1e-7  # the tyres carry the whole weight
        assert float(state.residual) < 1e-8 and bool(state.ok)


def test_rest_configuration_is_the_design(rigid_state):
    """Preloads put the suspensions at the Table B.2/B.3 positions at rest (rigid chassis)."""
    assert np.max(np.abs(np.asarray(rigid_state.travel))) < 1e-5  # m: 10 µm from the 0.06 % pitch
    np.testing.assert_allclose(rigid_state.spring_forces, vehicle.rest_spring_preloads(vehicle.load_car(modes=0)),
                               rtol=1e-3)


def test_symmetric_car_rests_symmetrically(rigid_state):
    loads, travel = np.asarray(rigid_state.corner_loads), np.asarray(rigid_state.travel)
    np.testing.assert_allclose(loads[[0, 2]], loads[[1, 3]], rtol=1e-10)
    np.testing.assert_allclose(travel[[0, 2]], travel[[1, 3]], atol=1e-12)
    assert abs(float(rigid_state.roll)) < 1e-12
    links = np.asarray(rigid_state.link_forces)
    np.testing.assert_allclose(links[[0, 2]], links[[1, 3]], rtol=1e-8, atol=1e-8)


def test_flexible_differs_from_rigid_by_the_sag(rigid_state, flexible_state):
    """Same loads to 0.1 %; the suspensions and ride differ by the chassis sag (< 1 mm)."""
    np.testing.assert_allclose(flexible_state.corner_loads, rigid_state.corner_loads, rtol=1e-3)
    sag = np.asarray(flexible_state.travel) - np.asarray(rigid_state.travel)
    assert 1e-5 < np.max(np.abs(sag)) < 1e-3
    assert np.any(np.abs(np.asarray(flexible_state.modes)) > 1e-6)
    assert abs(float(flexible_state.twist)) > 0.0


def test_stiff_modes_tend_to_the_rigid_car(flexible, rigid_state):
    """Modal stiffness multiplier µ -> large: the flexible car's static state -> the rigid one."""
    scale = flexible.params.chassis.stiffness_scale * 1e6
    stiff = eqx.tree_at(lambda c: c.params.chassis.stiffness_scale, flexible, scale)
    state = vehicle.static_equilibrium(stiff)
    np.testing.assert_allclose(state.corner_loads, rigid_state.corner_loads, rtol=1e-8)
    np.testing.assert_allclose(state.travel, rigid_state.travel, atol=1e-8)
    assert np.max(np.abs(np.asarray(state.modes))) < 1e-8


@pytest.fixture(scope="module")
def running(rigid):
    return vehicle.straight_running(rigid, 20.0)


def test_straight_running_balances_weight_downforce_and_drag(rigid, running):
    """At 20 m/s: tyres carry weight + downforce (less the drag's share along the pitched
    chassis axis), the rear tyres' drive forces balance drag, no yaw; the downforce compresses
    the suspensions."""
    s = running.static
    assert bool(s.ok) and float(s.constraint_residual) < 1e-9
    pitch = float(s.pitch)
    vertical = 290.0 * G + float(running.downforce) * math.cos(pitch) - float(running.drag) * math.sin(pitch)
    np.testing.assert_allclose(float(jnp.sum(s.corner_loads)), vertical, rtol=1e-9)
    assert float(running.z[13]) == 0.0 and abs(float(running.rack)) < 1e-3  # straight: small correction only
    np.testing.assert_allclose(running.z[np.array([1, 3, 5, 7])], 20.0 / 0.245, rtol=0.05)  # rolling wheels
    assert np.all(np.asarray(s.travel) > 0.005)  # downforce: the car sits lower
    # drive torque = (drag + rolling resistance) x rolling radius, rolling resistance a few percent
    ratio = float(running.drive_torque) / (float(running.drag) * 0.245)
    assert 1.0 < ratio < 1.5


@pytest.mark.slow
def test_standstill_settles(rigid, rigid_state):
    """From the static set-up with the tyres' horizontal forces switched on: no NaN, the car
    stays put (the tyre deflection states take up the small force offsets), links closed."""
    sim = mb.simulate(rigid.system, vehicle.system_params(rigid), rigid_state.q, jnp.zeros(rigid.system.n_dof),
                      0.0, 1.0, jnp.linspace(0.0, 1.0, 11), inputs=lambda t: jnp.zeros(1),
                      elements=vehicle.car_elements(rigid), rtol=1e-6, atol=1e-8)
    assert sim.stop_reason == "completed"
    assert np.all(np.isfinite(np.asarray(sim.q))) and float(sim.max_residual) < 1e-9
    assert np.max(np.abs(np.asarray(sim.z[-1]))) < 1e-2  # m/s, rad/s: settled
    drift = np.asarray(sim.q[-1, :3]) - np.asarray(rigid_state.q[:3])
    assert np.max(np.abs(drift)) < 1e-3


# ---- rates -----------------------------------------------------------------------------------


def test_rates_reach_appendix_a(rigid):
    r = vehicle.car_rates(rigid)
    np.testing.assert_allclose(float(r["front"].roll_stiffness_nm_per_deg), 205.0, rtol=1e-3)
    np.testing.assert_allclose(float(r["rear"].roll_stiffness_nm_per_deg), 175.0, rtol=1e-3)
    assert 1.8 < float(r["rear"].ride_frequency) < float(r["front"].ride_frequency) < 3.0  # FSAE-typical
    lam = float(vehicle.roll_stiffness_distribution(r["front"], r["rear"]))
    np.testing.assert_allclose(lam, 205.0 / 380.0, rtol=2e-3)


def test_spring_table_gives_rate_and_preload(rigid):
    rates, forces = vehicle.spring_at_design(rigid)
    np.testing.assert_allclose(rates, [8770.0, 8770.0, 8920.0, 8920.0], rtol=1e-12)
    np.testing.assert_allclose(forces, vehicle.rest_spring_preloads(rigid), rtol=1e-10)


# ---- gradients (forward mode through the set-up's implicit function) ------------------------


def _with_fl_rate(car, k):
    laws = car.params.springs
    free = laws.spring_length[0, -1]
    return eqx.tree_at(lambda c: c.params.springs.spring_force, car, laws.spring_force.at[0, 0].set(k * free))


@pytest.mark.slow
def test_corner_weight_gradient_wrt_spring_rate(rigid):
    """A stiffer front-left spring at the same free length jacks weight onto the FL-RR diagonal."""
    def fl_load(k):
        return vehicle.static_equilibrium(_with_fl_rate(rigid, k)).corner_loads[0]

    k0 = 8770.0
    value, slope = jax.jvp(fl_load, (jnp.asarray(k0),), (jnp.asarray(1.0),))
    h = 20.0
    fd = (float(fl_load(jnp.asarray(k0 + h))) - float(fl_load(jnp.asarray(k0 - h)))) / (2 * h)
    assert float(slope) > 1e-3  # N per N/m: a measurable jacking effect
    np.testing.assert_allclose(float(slope), fd, rtol=1e-5)


@pytest.mark.slow
def test_twist_gradient_wrt_modal_stiffness(flexible, flexible_state):
    """d(static twist)/dµ against central differences (the twist is small: it comes from the
    FE frame's asymmetry, and it does not scale as 1/µ because the chassis's stiffness also
    redistributes the corner loads)."""
    def twist(scale):
        car = eqx.tree_at(lambda c: c.params.chassis.stiffness_scale, flexible, scale * jnp.ones(6))
        return vehicle.static_equilibrium(car).twist

    value, slope = jax.jvp(twist, (jnp.asarray(1.0),), (jnp.asarray(1.0),))
    h = 1e-3
    fd = (float(twist(jnp.asarray(1.0 + h))) - float(twist(jnp.asarray(1.0 - h)))) / (2 * h)
    np.testing.assert_allclose(float(value), float(flexible_state.twist), rtol=1e-9)
    assert abs(float(slope)) > 1e-7
    np.testing.assert_allclose(float(slope), fd, rtol=1e-4)


# ---- bad input -------------------------------------------------------------------------------


def test_mode_count_is_checked():
    for bad in (-1, 21, 2.5):
        with pytest.raises(ParameterError, match="modes"):
            vehicle.load_car(modes=bad)


def test_car_file_errors_name_the_field(tmp_path):
    from importlib import resources

    text = resources.files("jaxveh.params").joinpath("data/car.toml").read_text()
    bad = tmp_path / "negative.toml"
    bad.write_text(text.replace("spring_rate = 8770.0", "spring_rate = -8770.0"))
    with pytest.raises(ParameterError, match=r"\[suspension_front\]\.spring_rate"):
        vehicle.load_car(bad, modes=0)
    missing = tmp_path / "missing.toml"
    missing.write_text(text.replace('tyre_rear = "fsae_20x7_13.tir"', 'tyre_rear = "nowhere.tir"'))
    with pytest.raises(ParameterError, match=r"\[files\]\.tyre_rear"):
        vehicle.load_car(missing, modes=0)
    unknown = tmp_path / "unknown.toml"
    unknown.write_text(text + "\n[wings]\nsize = 1.0\n")
    with pytest.raises(ParameterError, match="wings"):
        vehicle.load_car(unknown, modes=0)


def test_car_file_stiffness_multipliers(tmp_path):
    """``[chassis] stiffness_scale``: the listed modes take the file's µ, the rest keep 1, a
    rigid car ignores it; a bad list is refused naming the key and what is allowed."""
    from importlib import resources

    text = resources.files("jaxveh.params").joinpath("data/car.toml").read_text()
    path = tmp_path / "scaled.toml"
    path.write_text(text.replace("[chassis]\n", "[chassis]\nstiffness_scale = [2.5, 0.5]\n"))
    np.testing.assert_array_equal(vehicle.load_car(path, modes=3).params.chassis.stiffness_scale, [2.5, 0.5, 1.0])
    np.testing.assert_array_equal(vehicle.load_car(path, modes=1).params.chassis.stiffness_scale, [2.5])
    assert vehicle.load_car(path, modes=0).params.chassis is None
    for value in ("[]", "[1.0, -2.0]", "[1.0, true]", '"stiff"', "[" + ", ".join(["1.0"] * 21) + "]"):
        path.write_text(text.replace("[chassis]\n", f"[chassis]\nstiffness_scale = {value}\n"))
        with pytest.raises(ParameterError, match=r"\[chassis\]\.stiffness_scale = .* is not allowed: a list of 1 to "
                                                 r"20 numbers > 0"):
            vehicle.load_car(path, modes=0)


def test_table_b4_tyre_values_reach_the_tyres():
    """``vehicle.tyre.kz`` (and cz, the relaxation lengths) set through with_params reach all
    four tyres the car runs on, as the car file's do; a corner's own path is applied after
    it; the chapter-3 parameters read from the car follow (tyre rate into the ride rate)."""
    car = vehicle.load_car(modes=0)
    changed = vehicle.with_params(car, {"vehicle.tyre.kz": 2.0e5, "vehicle.tyre.sigma_kappa": 0.05,
                                        "tyres.vertical_stiffness[3]": 1.8e5})
    np.testing.assert_array_equal(changed.params.tyres.vertical_stiffness, [2.0e5, 2.0e5, 2.0e5, 1.8e5])
    np.testing.assert_array_equal(changed.params.tyres.sigma_kappa, [0.05] * 4)
    assert float(changed.params.vehicle.tyre.kz) == 2.0e5
    np.testing.assert_array_equal(changed.params.tyres.vertical_damping, car.params.tyres.vertical_damping)
    jitted = jax.jit(lambda kz: vehicle.set_car_params(car.params, {"vehicle.tyre.kz": kz}).tyres.vertical_stiffness)
    np.testing.assert_array_equal(jitted(1.6e5), [1.6e5] * 4)


def test_form_is_checked():
    with pytest.raises(ParameterError, match="form = 'quick'.*'fast', 'library'"):
        vehicle.load_car(form="quick", modes=0)
    assert vehicle.load_car(modes=0).form == "fast"
    assert vehicle.load_car(modes=0, form="library").form == "library"


# ---- CLI -------------------------------------------------------------------------------------


def test_vehicle_info_json_contract(rigid_state):
    result = CliRunner().invoke(app, ["vehicle", "info", "--modes", "0", "--json"])
    assert result.exit_code == 0, result.output
    out = json.loads(result.stdout)
    assert out["total_mass_kg"] == pytest.approx(290.0)
    assert set(out["corner_loads_n"]) == {"fl", "fr", "rl", "rr"}
    np.testing.assert_allclose([out["corner_loads_n"][k] for k in ("fl", "fr", "rl", "rr")],
                               rigid_state.corner_loads, rtol=1e-9)
    assert set(out["roll_stiffness_nm_per_deg"]) == {"front", "rear"} == set(out["ride_frequency_hz"])
    assert out["roll_stiffness_nm_per_deg"]["front"] == pytest.approx(205.0, rel=1e-3)
    assert out["chassis_modes_hz"] == []
    assert out["model"]["independent_velocities"] == 14


def test_vehicle_info_lists_chassis_modes(flexible):
    result = CliRunner().invoke(app, ["vehicle", "info", "--json"])
    assert result.exit_code == 0, result.output
    out = json.loads(result.stdout)
    np.testing.assert_allclose(out["chassis_modes_hz"], flexible.params.chassis.frequencies_hz, rtol=1e-12)
    assert len(out["chassis_modes_hz"]) == 6 and all(z == pytest.approx(0.025) for z in out["chassis_damping_ratio"])
    assert math.isclose(sum(out["corner_loads_n"].values()), 290.0 * G, rel_tol=1e-9)


def test_vehicle_info_refuses_bad_modes():
    result = CliRunner().invoke(app, ["vehicle", "info", "--modes", "40", "--json"])
    assert result.exit_code == 2 and "modes" in result.output


def test_force_element_builders_name_unknown_points(rigid):
    with pytest.raises(ValueError, match="unknown point 'front_left.nowhere'"):
        vehicle.TyreContact.on(rigid.system, {"fl": ("front_left.nowhere", "front_left.W")}, rigid.params.tyres)
    with pytest.raises(ValueError, match="unknown point 'chassis.wing'"):
        vehicle.AeroLoads.on(rigid.system, "chassis", "chassis.cg", "chassis.wing", "chassis.aero_rear",
                             rigid.params.aero)


def test_new_parameter_values_never_retrace(rigid):
    """Every number is a leaf: the car's equations trace once for any values (a changed hard
    point, spring table, PID gain, mass or tyre coefficient; each edit changes the
    accelerations, so each reached the equations)."""

    s = rigid.system
    rows = np.asarray([s.q_index(b, "z") for b in ("chassis",) + tuple(f"{c}.upright" for c in vehicle.CORNERS)])
    lowered = rigid.q_design.at[rows].add(-0.005)  # the tyres touch the road; loops stay closed

    @eqx.filter_jit
    @eqx.debug.assert_max_traces(max_traces=1)
    def accelerations(car):
        sp = vehicle.system_params(car)
        dyn = mb.dynamics(car.system, sp, lowered, jnp.zeros(car.system.n_dof), 0.0, lambda t: jnp.zeros(1),
                          elements=vehicle.car_elements(car), aux=jnp.full((10,), 1e-3))
        return dyn.z_dot

    p = rigid.params
    edits = [
        lambda c: eqx.tree_at(lambda c: c.params.vehicle.hard_points_front.points, c,
                              p.vehicle.hard_points_front.points.at[6, 2].add(0.01)),
        lambda c: eqx.tree_at(lambda c: c.params.springs.spring_force, c, p.springs.spring_force * 1.1),
        lambda c: eqx.tree_at(lambda c: c.params.pid.ki, c, p.pid.ki * 2.0),
        lambda c: eqx.tree_at(lambda c: c.params.vehicle.sprung.mass, c, p.vehicle.sprung.mass + 10.0),
        lambda c: eqx.tree_at(lambda c: c.params.tyres.pdy1, c, p.tyres.pdy1 * 0.9),
    ]
    base = accelerations(rigid)
    for k, edit in enumerate(edits):
        assert not np.allclose(accelerations(edit(rigid)), base, rtol=1e-12, atol=0.0), f"edit {k} had no effect"
