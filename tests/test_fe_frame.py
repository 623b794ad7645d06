"""Frame file validation and the shipped FSAE 2009 frame against the thesis targets."""

import copy
from importlib import resources

import numpy as np
import pytest
import tomllib

import jaxveh.fe as fe
from jaxveh.params import (
    CORNERS,
    HARD_POINT_NAMES,
    SPRUNG_HARD_POINTS,
    ParameterError,
    hard_points_vehicle_frame,
    load_vehicle_data,
)

#: Thesis section 6.2.2 / Table 6.4 targets and the accepted deviation of the tuned frame.
TARGET_MASS, TOL_MASS = 23.5, 0.02
TARGET_K, TOL_K = 385.0, 0.05  # the thesis's own measurement uncertainty (5 %)
TARGET_F1, TOL_F1 = 38.35, 0.05


@pytest.fixture(scope="module")
def table():
    return tomllib.loads(resources.files("jaxveh.fe").joinpath("data/fsae_2009_frame.toml").read_text())


def test_hard_points_sit_at_appendix_b_positions():
    frame = fe.load_frame()
    hp = hard_points_vehicle_frame(load_vehicle_data())
    assert len(frame.interface) == 32
    for corner in CORNERS:
        for p in SPRUNG_HARD_POINTS:
            xyz = np.asarray(frame.node_xyz[frame.node_index(f"{corner}.{p}")])
            np.testing.assert_allclose(xyz, np.asarray(hp[corner][HARD_POINT_NAMES.index(p)]), atol=1e-4)


@pytest.mark.slow
def test_shipped_frame_meets_thesis_targets():
    frame = fe.load_frame()
    t = fe.torsion_test(frame)
    assert abs(float(t.mass) / TARGET_MASS - 1) < TOL_MASS
    assert abs(float(t.stiffness_nm_per_deg) / TARGET_K - 1) < TOL_K
    f, phi = fe.chassis_modes(frame, 6)
    assert abs(float(f[0]) / TARGET_F1 - 1) < TOL_F1
    assert "torsion" in fe.mode_labels(frame, phi)[0]


def test_torsion_test_statics():
    """Reactions make a pure torque: the rear support line stays level and the measured
    stiffness is independent of the load magnitude (linear model)."""
    frame = fe.load_frame()
    t = fe.torsion_test(frame)
    u = np.asarray(t.displacement)
    for n in frame.torsion_test.rear_supports + (frame.torsion_test.front_support,):
        assert abs(u[frame.node_index(n), 2]) < 1e-15
    w = 2 * 0.2598
    np.testing.assert_allclose(t.torque, 1000.0 * w, rtol=1e-9)
    np.testing.assert_allclose(t.stiffness, 1000.0 * w**2 / t.deflection, rtol=1e-12)


def _bad(table, edit):
    t = copy.deepcopy(table)
    edit(t)
    return t


def _member(a, b):
    return lambda t: t["members"].append({"nodes": [a, b], "section": "rail"})


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda t: t["nodes"].__setitem__("dup", list(t["nodes"]["bulkhead_lower_left"])), "duplicate node position"),
        (_member("bulkhead_lower_left", "nowhere"), "'nowhere' is not defined"),
        (_member("bulkhead_lower_left", "bulkhead_lower_left"), "zero length"),
        (lambda t: t["sections"]["rail"].__setitem__("thickness", 0.0), r"thickness = 0 mm is out of range"),
        (lambda t: t["sections"]["rail"].__setitem__("diameter", -5.0), r"diameter = -5 mm is out of range"),
        (lambda t: t["sections"]["rail"].__setitem__("thickness", 20.0), "allowed <= diameter/2"),
        (lambda t: t["materials"]["steel"].__setitem__("density", 0.0), "density = 0"),
        (_member("bulkhead_lower_left", "front_left.B"), "duplicate member"),
        (lambda t: t["members"][0].__setitem__("section", "unobtainium"), "section 'unobtainium' is not defined"),
        (lambda t: t["torsion_test"].__setitem__("loaded", "rear_left.F"), "four different nodes"),
        (lambda t: t["frame"].__setitem__("colour", "red"), r"unknown key\(s\) \['colour'\]"),
        (lambda t: t["nodes"].__setitem__("lonely", [0.0, 0.0, 5000.0]), r"node\(s\) \['lonely'\] belong to no member"),
    ],
)
def test_bad_frames_give_named_errors(table, edit, message):
    with pytest.raises(ParameterError, match=message):
        fe.frame_from_dict(_bad(table, edit), "frame.toml")


def test_disconnected_frame_is_an_error():
    table = {
        "materials": {"steel": {"E": 205.0, "G": 80.0, "density": 7850.0}},
        "sections": {"t": {"shape": "circular", "diameter": 20.0, "thickness": 1.0}},
        "nodes": {"a": [0.0, 0.0, 0.0], "b": [100.0, 0.0, 0.0], "c": [0.0, 500.0, 0.0], "d": [100.0, 500.0, 0.0]},
        "members": [{"nodes": ["a", "b"], "section": "t"}, {"nodes": ["c", "d"], "section": "t"}],
    }
    with pytest.raises(ParameterError, match=r"disconnected; node\(s\) \['c', 'd'\]"):
        fe.frame_from_dict(table, "f.toml")


def test_missing_file_and_bad_toml(tmp_path):
    with pytest.raises(ParameterError, match="does not exist"):
        fe.load_frame(tmp_path / "none.toml")
    p = tmp_path / "bad.toml"
    p.write_text("[nodes\n")
    with pytest.raises(ParameterError, match="not valid TOML"):
        fe.load_frame(p)
