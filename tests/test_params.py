"""Vehicle data files: SI conversion, validation errors, pytree behaviour."""

import math
import tomllib
from importlib import resources

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxveh.params import (
    ParameterError,
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
    assert float(v.a) == pytest.approx(0.843)
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
        ("geometry", "a", 2000.0, r"\[geometry\]\.l = 1.555 m is inconsistent with a \+ b \(c.g. must lie inside the wheelbase\) = 2.712 m"),
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
