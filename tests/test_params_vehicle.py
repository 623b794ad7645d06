"""Vehicle parameters: data files (SI conversion, validation errors), checks on construction,
derived quantities that follow their base fields, pytree behaviour."""

import dataclasses
import math
from importlib import resources

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
import tomllib

from jaxveh.params import (
    CornerHardPoints,
    ParameterError,
    RigidBodyData,
    TyreData,
    UnsprungData,
    analytic_vehicle_from_dict,
    hard_points_vehicle_frame,
    load_analytic_vehicle,
    load_vehicle_data,
    vehicle_data_from_dict,
)

DEG = math.pi / 180.0


def _table(name):
    return tomllib.loads(resources.files("jaxveh.params").joinpath(f"data/{name}").read_text())


def test_appendix_a_in_si_units():
    v = load_analytic_vehicle()
    assert float(v.kF) == pytest.approx(205.0 / DEG)
    assert float(v.kC) == pytest.approx(380.0 / DEG)
    # a and hG are derived from the masses (unsprung masses at the axles); Table A.1 rounds them.
    assert float(v.a) == pytest.approx(0.843, rel=1e-3)
    assert float(v.hG) == pytest.approx(0.295, abs=2.5e-3)
    assert float(v.l) == pytest.approx(1.555)
    assert float(v.m) == 290.0
    assert v.kF.dtype == jnp.float64


def test_appendix_b_in_si_units():
    d = load_vehicle_data()
    assert float(d.wheelbase) == pytest.approx(1.7)
    np.testing.assert_allclose(d.hard_points_front["C"], [0.005, 0.5856, 0.14])
    np.testing.assert_allclose(d.sprung.inertia[0, 2], -20.0)
    corners = hard_points_vehicle_frame(d)
    np.testing.assert_allclose(corners["front_right"][2], [1.005, -0.5856, 0.14])
    np.testing.assert_allclose(corners["rear_left"][0], [-0.7 - 0.28, 0.2497, 0.145])


@pytest.mark.parametrize(
    "section,key,value,match",
    [
        ("mass", "ms", -1.0, r"\[mass\]\.ms \(sprung mass\) = -1 kg is out of range: allowed > 0 kg"),
        ("suspension", "kF", 0.0, r"\[suspension\]\.kF .* allowed > 0 Nm/deg"),
        ("chassis", "kC", -5.0, r"\[chassis\]\.kC"),
        (
            "geometry",
            "a",
            2000.0,
            r"\[geometry\]\.l = 1.555 m is inconsistent with a \+ b \(c.g. must lie inside the wheelbase\) = 2.712 m",
        ),
        ("geometry", "b", -10.0, r"\[geometry\]\.b"),
        ("mass", "m", 300.0, r"\[mass\]\.m = 300 kg is inconsistent with ms \+ muF \+ muR = 290 kg"),
        ("suspension", "cF", "soft", r"must be a number"),
    ],
)
def test_appendix_a_bad_values_name_the_field(section, key, value, match):
    table = _table("appendix_a.toml")
    table[section][key] = value
    with pytest.raises(ParameterError, match=match):
        analytic_vehicle_from_dict(table, "bad.toml")


def test_unknown_and_missing_keys():
    table = _table("appendix_a.toml")
    table["mass"]["mass_total"] = 1.0
    with pytest.raises(ParameterError, match=r"unknown key\(s\) \['mass_total'\]; allowed keys are"):
        analytic_vehicle_from_dict(table)
    table = _table("appendix_a.toml")
    del table["inertia"]["Jz"]
    with pytest.raises(ParameterError, match=r"\[inertia\]: missing key\(s\) \['Jz'\]"):
        analytic_vehicle_from_dict(table)
    table = _table("appendix_a.toml")
    table["aero"] = {"cl": 1.0}
    with pytest.raises(ParameterError, match=r"unknown section\(s\) \['aero'\]"):
        analytic_vehicle_from_dict(table)


def test_bad_files(tmp_path):
    with pytest.raises(ParameterError, match="does not exist"):
        load_analytic_vehicle(tmp_path / "nope.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[mass\nm = 1")
    with pytest.raises(ParameterError, match="not valid TOML"):
        load_analytic_vehicle(bad)


def test_user_copy_round_trip(tmp_path):
    text = resources.files("jaxveh.params").joinpath("data/appendix_a.toml").read_text()
    path = tmp_path / "my_car.toml"
    path.write_text(text.replace("kC = 380.0", "kC = 760.0"))
    assert float(load_analytic_vehicle(path).kC) == pytest.approx(760.0 / DEG)


def test_appendix_b_bad_hard_points():
    table = _table("appendix_b.toml")
    del table["hard_points_front"]["H"]
    with pytest.raises(ParameterError, match=r"\[hard_points_front\]: missing hard point H"):
        vehicle_data_from_dict(table)
    table = _table("appendix_b.toml")
    table["hard_points_rear"]["C"] = [1.0, 2.0]
    with pytest.raises(ParameterError, match=r"\[hard_points_rear\]\.C must be a list of 3 numbers"):
        vehicle_data_from_dict(table)
    table = _table("appendix_b.toml")
    table["sprung"]["Jxz"] = 100.0
    with pytest.raises(ParameterError, match="positive-definite"):
        vehicle_data_from_dict(table)
    table = _table("appendix_b.toml")
    table["unsprung_front"]["m"] = 0.0
    with pytest.raises(ParameterError, match=r"\[unsprung_front\]\.m"):
        vehicle_data_from_dict(table)


def test_every_leaf_differentiable_and_vmappable():
    v = load_analytic_vehicle()
    leaves = jax.tree_util.tree_leaves(v)
    assert all(isinstance(x, jax.Array) and x.dtype == jnp.float64 for x in leaves)

    def loss(veh):
        return sum(jnp.sum(x) for x in jax.tree_util.tree_leaves(veh))

    grads = eqx.filter_grad(loss)(v)
    assert all(float(g) == 1.0 for g in jax.tree_util.tree_leaves(grads))
    batch = jax.tree.map(lambda x: jnp.stack([x, 2.0 * x]), v)
    out = jax.vmap(lambda veh: veh.kF + veh.kR)(batch)
    np.testing.assert_allclose(out, [float(v.kF + v.kR), 2.0 * float(v.kF + v.kR)])


def test_data_documentation_is_current():
    from pathlib import Path

    from jaxveh.params._docs import render

    doc = Path(__file__).resolve().parents[1] / "docs" / "data.md"
    assert doc.read_text() == render(), "docs/data.md is stale: run python -m jaxveh.params.docs"


def test_derived_quantities_follow_their_base_fields():
    """m, l, a, b, hG are properties: a change of a base field (eqx.tree_at bypasses
    __init__) moves them, so nothing stored goes stale."""
    v = load_analytic_vehicle()
    heavier = eqx.tree_at(lambda x: x.ms, v, v.ms + 50.0)
    assert float(heavier.m) == pytest.approx(float(v.m) + 50.0, rel=1e-15)
    # The sprung mass sits behind the vehicle c.g. (as = 0.830 m < a = 0.842 m): more of it
    # moves the c.g. rearwards; its c.g. is higher than the unsprung ones: hG rises.
    assert float(heavier.a) < float(v.a) and float(heavier.hG) > float(v.hG)
    longer = eqx.tree_at(lambda x: x.bs, v, v.bs + 0.1)
    assert float(longer.l) == pytest.approx(float(v.l) + 0.1, rel=1e-15)
    assert float(longer.a + longer.b) == pytest.approx(float(longer.l), rel=1e-15)
    # Closed forms, and the gradients of the derived values with respect to their bases.
    ms, muf, mur = float(v.ms), float(v.muF), float(v.muR)
    assert float(v.a) == pytest.approx((ms * float(v.as_) + mur * float(v.l)) / (ms + muf + mur), rel=1e-14)
    grads = eqx.filter_grad(lambda x: x.m + x.l)(v)
    assert float(grads.ms) == float(grads.muF) == float(grads.muR) == 1.0
    assert float(grads.as_) == float(grads.bs) == 1.0
    for name in ("m", "a", "b", "l", "hG"):
        assert not hasattr(grads, name) or isinstance(getattr(type(v), name), property)


def test_rigid_load_transfers_add_up_to_the_total():
    """With hG derived from the masses, the axle transfers of (3.4) add up to m hG ay / t
    for any masses and heights (Table A.1's rounded hG would miss by 0.2 %)."""
    from jaxveh.analytic import load_transfer_rigid

    v = load_analytic_vehicle()
    rng = np.random.default_rng(3)
    for _ in range(5):
        scale = rng.uniform(0.7, 1.3, 5)
        w = eqx.tree_at(lambda x: (x.ms, x.muF, x.muR, x.hsF, x.huR),
                        v, tuple(jnp.asarray(s) * f for s, f in zip((v.ms, v.muF, v.muR, v.hsF, v.huR), scale)))
        front, rear = load_transfer_rigid(w, 1.0)
        assert float(front + rear) == pytest.approx(float(w.m * w.hG / w.t), rel=1e-13)


def test_file_checks_derived_values():
    table = _table("appendix_a.toml")
    table["geometry"]["hG"] = 300.0
    with pytest.raises(ParameterError, match=r"\[geometry\]\.hG = 0\.3 m is inconsistent with .* = 0\.294317 m"):
        analytic_vehicle_from_dict(table, "bad.toml")
    table = _table("appendix_a.toml")
    table["geometry"]["a"], table["geometry"]["b"] = 853.0, 702.0
    with pytest.raises(ParameterError, match=r"\[geometry\]\.a = 0\.853 m is inconsistent with \(ms as \+ muR l\)/m"):
        analytic_vehicle_from_dict(table, "bad.toml")


@pytest.mark.parametrize(
    "build, match",
    [
        (lambda d: RigidBodyData(-1.0, d.sprung.inertia), r"RigidBodyData\.mass must lie in \(0, inf\) \(mass, kg\)"),
        (lambda d: RigidBodyData(1.0, -np.eye(3)), r"RigidBodyData\.inertia eigenvalues must lie in \(0, inf\)"),
        (lambda d: RigidBodyData(1.0, np.eye(2)), r"RigidBodyData\.inertia must have shape \(3, 3\)"),
        (lambda d: TyreData(1.5e5, 50.0, 0.3, -0.3), r"TyreData\.sigma_alpha must lie in \(0, inf\)"),
        (lambda d: TyreData(1.5e5, -50.0, 0.3, 0.3), r"TyreData\.cz must lie in \[0, inf\)"),
        (lambda d: UnsprungData(d.unsprung_front.body, 0.0), r"UnsprungData\.wheel_spin_inertia must lie in"),
        (lambda d: CornerHardPoints(np.asarray(d.hard_points_front.points) * np.array([1.0, -1.0, 1.0])),
         r"CornerHardPoints\.points y must lie in \(0, inf\) \(left corner, m\)"),
        (lambda d: dataclasses.replace(d, track_rear=0.0), r"VehicleData\.track_rear must lie in \(0, inf\)"),
        (lambda d: dataclasses.replace(d, toe_front=0.5), r"VehicleData\.toe_front must lie in \[-0\.174533, 0\.1745"),
    ],
)
def test_appendix_b_modules_check_on_construction(build, match):
    with pytest.raises(ParameterError, match=match):
        build(load_vehicle_data())


class _Spring(eqx.Module):
    rate: jax.Array


def _checked_spring(rate):
    from jaxveh.params._checks import Range, check_module

    return check_module(_Spring(rate), "Spring", {"rate": Range(low=0.0, what="N/m")}).rate


def test_traced_checks_run_and_are_not_built_when_run_time_checks_are_off():
    """A traced value out of range fails at run time; inside ``run_time_checks_off`` the
    check is not traced at all (nothing to compile), and a concrete value is still refused."""
    from jaxveh import run_time_checks_off
    from jaxveh._core import check_range

    with pytest.raises(Exception, match=r"Spring\.rate must lie in \[0, inf\)"):
        jax.block_until_ready(jax.jit(_checked_spring)(jnp.asarray(-1.0)))
    with pytest.raises(Exception, match=r"k must lie in \[0, inf\)"):
        jax.block_until_ready(jax.jit(lambda x: check_range("k", x, low=0.0))(jnp.asarray(-1.0)))
    with run_time_checks_off():
        # new functions: JAX's trace cache would return the traces made with checks on
        for fn in (lambda x: _checked_spring(x), lambda x: check_range("k", x, low=0.0)):
            jaxpr = jax.make_jaxpr(fn)(jnp.asarray(-1.0, jnp.float64))
            assert not jaxpr.eqns, jaxpr  # the value passes straight through
            assert float(jax.jit(fn)(jnp.asarray(-1.0))) == -1.0
        with pytest.raises(ParameterError, match=r"Spring\.rate must lie in \[0, inf\)"):
            _checked_spring(np.asarray(-1.0))
