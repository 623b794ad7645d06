"""Tube sizes of the chassis frame as design variables of the car (optimise._frame_design,
study (d)): the chassis rebuilt from a resized frame equals the FE model's own modal
reduction with the car's damping and multipliers and keeps each mode's sign; frame paths,
frame objectives and bounds relative to the rigid car are checked by name; the whole chain
frame -> FE -> modes -> car -> objective has its forward-mode Jacobian checked against
central differences; the optimum's frame file reads back.

Compile cost: as in test_optimise_car, the car tests use the 2-mode car (one compiled
study program, plus the rigid car's χ for the relative bound).
"""

import json
import textwrap

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from typer.testing import CliRunner

import jaxveh.fe as fe
import optimise
from jaxveh import ParameterError
from jaxveh.cli import app
from jaxveh.vehicle import load_car

#: Chassis modes of the car tests (module docs).
MODES = 2
#: Central differences in the unconstrained variable z: the steady states converge to
#: 1e-11 relative and the eigen-solve to round-off, so a quotient over 2e-4 keeps < 1e-6
#: relative; truncation is O(h^2) ~ 1e-8 relative.
FD_STEP, FD_RTOL = 1e-4, 1e-5

STUDY = """
[study]
name = "lightest"
model = "car"
modes = {modes}

[[variables]]
path = "frame.sections.rail+side_impact.thickness"
name = "t_main"
lower = 0.0005
upper = 0.003
initial = 0.0012

[[variables]]
path = "frame.sections.front_rail.diameter"
lower = 0.012
upper = 0.035
initial = 0.02

[objective]
name = "chassis_mass"
minimise = true

[[constraints]]
name = "chi"
reference = "rigid"
relative = true
"<=" = 0.5
">=" = -0.5
[[constraints]]
name = "torsional_stiffness"
">=" = 10.0
[[constraints]]
name = "understeer_gradient"
"<=" = 50.0

[optimiser]
steps = 3
outer_steps = 1
"""


def _write(folder, text, name="study.toml"):
    path = folder / name
    path.write_text(textwrap.dedent(text))
    return path


# ---- the chassis of a resized frame ------------------------------------------------------


@pytest.fixture(scope="module")
def frame():
    return fe.load_frame()


def _resized(frame, name, quantity, factor):
    var = optimise.FrameVariable((name,), quantity)
    k = frame.section_names.index(name)
    return optimise.set_frame_sizes(frame, ((var, factor * getattr(frame.sections[k], quantity)),))


def test_chassis_of_the_same_frame_is_the_cars(frame):
    like = fe.frame_modal_body(frame, 6, damping_ratio=0.03)
    like = eqx.tree_at(lambda b: b.stiffness_scale, like, jnp.arange(1.0, 7.0))
    same = fe.frame_modal_body_like(frame, like)
    for a, b in zip(jax.tree.leaves(like), jax.tree.leaves(same)):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * float(np.max(np.abs(like.Ke))))


def test_modes_keep_their_coordinates_when_they_change_order(frame):
    """A base chassis with its modes in reverse order: the frame's modes come back in that
    order (each with its multiplier), signs kept."""
    base = fe.frame_modal_body(frame, 6)
    rev = np.arange(5, -1, -1)
    like = eqx.tree_at(
        lambda b: (b.Ke, b.point_phi_translation, b.point_phi_rotation, b.stiffness_scale), base,
        (base.Ke[rev][:, rev], -base.point_phi_translation[..., rev], base.point_phi_rotation[..., rev],
         jnp.arange(1.0, 7.0)))
    body = fe.frame_modal_body_like(frame, like)
    np.testing.assert_allclose(np.diag(body.Ke), np.diag(base.Ke)[rev], rtol=1e-12)
    np.testing.assert_allclose(body.point_phi_translation, like.point_phi_translation, atol=1e-12)
    np.testing.assert_array_equal(body.stiffness_scale, like.stiffness_scale)


def test_resized_chassis_is_the_fe_reduction_with_signs_kept(frame):
    like = fe.frame_modal_body(frame, 6)
    bigger = _resized(frame, "front_bulkhead", "diameter", 0.7)
    body = fe.frame_modal_body_like(bigger, like)
    reference = fe.frame_modal_body(bigger, 6)
    # the same modes up to sign: frequencies, and shapes column by column
    np.testing.assert_allclose(np.diag(body.Ke), np.diag(reference.Ke), rtol=1e-12)
    got, want = np.asarray(body.point_phi_translation), np.asarray(reference.point_phi_translation)
    signs = np.sign(np.einsum("pkn,pkn->n", got, want))
    np.testing.assert_allclose(got, want * signs, atol=1e-12)
    np.testing.assert_allclose(np.asarray(body.point_phi_rotation), np.asarray(reference.point_phi_rotation) * signs,
                               atol=1e-12)
    # each kept sign agrees with the base chassis's mode
    agreement = np.einsum("pkn,pkn->n", body.point_phi_translation, like.point_phi_translation)
    assert np.all(agreement > 0.0)
    # a change of frame changes the modes
    assert not np.allclose(np.diag(body.Ke), np.diag(like.Ke), rtol=1e-3)


# ---- paths, objectives and bounds refused by name ----------------------------------------


@pytest.mark.parametrize("path, match", [
    ("frame.sections.rail.wall", "QUANTITY one of diameter, thickness"),
    ("frame.rail.thickness", "allowed frame.sections.NAME.QUANTITY"),
    ("frame.sections.thickness", "allowed frame.sections.NAME.QUANTITY"),
    ("frame.sections.rail+rail.thickness", "repeats a section"),
])
def test_bad_frame_paths_are_refused(path, match):
    with pytest.raises(ParameterError, match=match):
        optimise.parse_frame_path(path)


def test_bad_frame_variables_are_refused_through_the_python_api(frame):
    for var, match in ((optimise.FrameVariable(("roll_cage",), "thickness"), "names 'roll_cage'"),
                       (optimise.FrameVariable(("rail",), "wall"), "quantity = 'wall' is not allowed")):
        with pytest.raises(ParameterError, match=match):
            optimise.set_frame_sizes(frame, ((var, 0.001),))


def _variant(old, new):
    assert old in STUDY
    return STUDY.replace(old, new, 1)


@pytest.mark.parametrize("old, new, match", [
    ('path = "frame.sections.front_rail.diameter"', 'path = "frame.sections.front_rail.wall"',
     r"variables\[1\]\.path = 'frame.sections.front_rail.wall' is not a frame path"),
    ("lower = 0.0005", "lower = 0.0", r"variables\[0\]\.lower = 0.0 is not allowed: a tube size"),
    ('name = "t_main"', 'name = "t_main"\nunits = "mm"', r"variables\[0\]\.units = 'mm' is not allowed"),
    ('reference = "rigid"', 'reference = "flexible"', r"constraints\[0\]\.reference = 'flexible'"),
    ('name = "understeer_gradient"', 'name = "understeer_gradient"\nrelative = true',
     r"constraints\[2\]\.relative = True is not allowed"),
    ('name = "torsional_stiffness"', 'name = "torsional_stiffness"\nreference = "rigid"',
     "the rigid car has no frame"),
    ('name = "understeer_gradient"', 'name = "first_mode_frequency"\nreference = "rigid"',
     "bound 3 on 'first_mode_frequency' has reference = 'rigid': allowed on"),
    ('[[variables]]\npath = "frame.sections.front_rail.diameter"', '[[variables]]\npath = "coupling"',
     "has reference = 'rigid' with the variable 'coupling'"),
    ('name = "chassis_mass"', 'name = "chassis_mass"\nay_g = 0.1', r"objective\.ay_g is not a key"),
])
def test_bad_frame_study_files_are_refused_by_name(tmp_path, old, new, match):
    path = _write(tmp_path, _variant(old, new).format(modes=MODES))
    with pytest.raises(ParameterError, match=match):
        optimise.load_optimisation_study(path)


def test_frame_objectives_need_frame_variables(tmp_path):
    path = _write(tmp_path, """
        [study]
        modes = 2
        [[variables]]
        path = "coupling"
        lower = 0.1
        upper = 0.9
        [objective]
        name = "chassis_mass"
        minimise = true
        """)
    with pytest.raises(ParameterError, match=r"objective\.name = 'chassis_mass' is an objective of the chassis "
                                             "frame.*allowed in a study with frame variables"):
        optimise.load_optimisation_study(path)


def test_bound_relative_to_the_rigid_car():
    spec = optimise.objective_spec("chi")
    bound = optimise.Bound(spec, "<=", 0.02, 0.5, reference="rigid", relative=True)
    with pytest.raises(RuntimeError, match="build the study's design first"):
        bound.violation(0.4)
    bound = bound._replace(rigid_value=-0.4)
    assert bound.limit == pytest.approx(-0.4 + 0.02 * 0.4) and bound.limit_scale == pytest.approx(0.2)
    assert bound.violation(-0.392 + 0.2) == pytest.approx(1.0)
    absolute = optimise.Bound(spec, ">=", -0.01, 2.0, reference="rigid")._replace(rigid_value=0.5)
    assert absolute.limit == pytest.approx(0.49) and absolute.violation(0.47) == pytest.approx(0.01)


# ---- the chain on the car -----------------------------------------------------------------


#: The car tests' study: the file above without the skid-pad bound (its steady state would
#: only lengthen the compilation) and with two Adam steps (one evaluation each).
CAR_STUDY = STUDY.replace('[[constraints]]\nname = "understeer_gradient"\n"<=" = 50.0\n', "").replace(
    "steps = 3", 'method = "adam"\nsteps = 2')


@pytest.fixture(scope="module")
def study_path(tmp_path_factory):
    assert CAR_STUDY.count("[[constraints]]") == 2 and "adam" in CAR_STUDY
    return _write(tmp_path_factory.mktemp("frame_study"), CAR_STUDY.format(modes=MODES))


@pytest.fixture(scope="module")
def design(study_path):
    return optimise.build_design(optimise.load_optimisation_study(study_path))


def test_unknown_section_and_thick_wall_are_refused_on_the_car(tmp_path):
    for old, new, match in (
        ("rail+side_impact", "rail+roll_cage", r"variables\[0\] \(frame.sections.rail\+roll_cage.thickness\) "
                                               "names the section 'roll_cage'"),
        ('path = "frame.sections.front_rail.diameter"', 'path = "frame.sections.rail.thickness_scale"',
         r"variables\[1\] \(frame.sections.rail.thickness_scale\) sets the thickness of section 'rail', which "
         r"variables\[0\] \(.*\) sets"),
        ("initial = 0.02", 'initial = 0.02\nunits = "m"\n[[variables]]\npath = "frame.sections.hoop.thickness_scale"\n'
         "lower = 0.5\nupper = 30.0",
         r"variables\[2\] .* has upper = 30.0, a wall thicker than half of section 'hoop'"),
        ("upper = 0.003", "upper = 0.02", "a wall thicker than half of section 'rail'"),
    ):
        path = _write(tmp_path, _variant(old, new).format(modes=MODES))
        with pytest.raises(ParameterError, match=match):
            optimise.build_design(optimise.load_optimisation_study(path))
    path = _write(tmp_path, STUDY.format(modes=0))
    with pytest.raises(ParameterError, match=r"study\.modes = 0: frame variables need a flexible chassis"):
        optimise.build_design(optimise.load_optimisation_study(path))


@pytest.mark.slow
def test_chain_jacobian_equals_central_differences(design):
    """d (mass, chi, torsion) / d z through frame -> FE -> modes -> car, forward mode,
    against central differences of the same compiled values."""
    z = design.problem.to_z({"t_main": 0.0012, "front_rail_diameter": 0.02})
    values, jac = design.evaluate(np.asarray(z))
    assert np.all(np.isfinite(values)) and np.all(np.abs(jac) > 0.0)
    for i in range(len(z)):
        step = np.zeros(len(z))
        step[i] = FD_STEP
        up, down = design.evaluate(np.asarray(z) + step)[0], design.evaluate(np.asarray(z) - step)[0]
        np.testing.assert_allclose(jac[:, i], (up - down) / (2 * FD_STEP), rtol=FD_RTOL, atol=1e-12)


@pytest.mark.slow
def test_values_are_the_resized_cars(design):
    """The study's values at a design are the objectives of the car loaded with that frame."""
    sizes = {"t_main": 0.0012, "front_rail_diameter": 0.02}
    values = design.evaluate(np.asarray(design.problem.to_z(sizes)))[0]
    frame = optimise.load_car_frame(None)
    frame = optimise.set_frame_sizes(frame, (
        (optimise.parse_frame_path("frame.sections.rail+side_impact.thickness"), 0.0012),
        (optimise.parse_frame_path("frame.sections.front_rail.diameter"), 0.02)))
    assert float(values[0]) == pytest.approx(float(fe.frame_mass(frame)), rel=1e-12)
    assert float(values[2]) == pytest.approx(float(fe.torsion_test(frame).stiffness_nm_per_deg), rel=1e-12)
    car = load_car(modes=MODES)
    body = fe.frame_modal_body(frame, MODES, damping_ratio=float(car.params.chassis.damping_ratio[0]))
    resized = eqx.tree_at(lambda c: c.params.chassis, car, body)
    assert float(values[1]) == pytest.approx(float(optimise.chi(resized)), rel=1e-9)


@pytest.mark.slow
def test_run_writes_a_frame_the_car_file_names(design, study_path, tmp_path):
    study = optimise.load_optimisation_study(study_path, out=tmp_path)
    result = optimise.optimise_study(study, design=design)
    rigid = optimise.chi(load_car(modes=0))
    chi_bounds = [c for c in result.constraints if c["name"] == "chi"]
    assert [c["rigid_value"] for c in chi_bounds] == [pytest.approx(float(rigid), rel=1e-10)] * 2
    assert chi_bounds[0]["bound"] == pytest.approx(float(rigid) * 1.5)
    files = optimise.write_outputs(result)
    written = fe.load_frame(files["frame"])
    k = written.section_names.index("side_impact")
    assert float(written.sections[k].thickness) == pytest.approx(result.optimum["t_main"], abs=1e-12)
    car = load_car(files["vehicle"], modes=MODES)
    np.testing.assert_allclose(np.diag(car.params.chassis.Ke), np.diag(result.car.params.chassis.Ke), rtol=1e-9)
    report = json.loads(open(files["json"]).read())
    assert report["units"]["chassis_mass"] == "kg" and report["optimum"] == result.optimum


@pytest.mark.slow
def test_cli_json(design, study_path, tmp_path):
    done = CliRunner().invoke(app, ["optimise", str(study_path), "--out", str(tmp_path), "--json"])
    assert done.exit_code == 0, done.output
    report = json.loads(done.output)
    assert set(report["optimum"]) == {"t_main", "front_rail_diameter"} and isinstance(report["converged"], bool)
    assert report["files"]["frame"].endswith("lightest_frame.toml")


# ---- following a mode along a design path --------------------------------------------------


def _two_mode_state_matrix(p):
    """Two coupled oscillators (unit masses) whose stiffnesses cross at p = 0: k1 = 100 (1 + p),
    k2 = 100, coupling 5 (an avoided crossing), light damping."""
    k = np.array([[100.0 * (1.0 + p) + 5.0, -5.0], [-5.0, 100.0 + 5.0]])
    d = 0.01 * np.eye(2)
    return np.block([[np.zeros((2, 2)), np.eye(2)], [-k, -d]])


def test_a_followed_mode_keeps_its_branch_where_a_fixed_reference_jumps():
    """Through an avoided crossing, the mode followed in small steps stays on its frequency
    branch (the lower one) while its shape turns into the other oscillator's; the fixed
    reference picks, at the end, the eigenvector that resembles the start's shape: the other
    branch."""
    path = np.linspace(-0.5, 0.5, 41)
    lam, vec = np.linalg.eig(_two_mode_state_matrix(path[0]))
    lower = np.argmin(np.where(lam.imag > 0, lam.imag, np.inf))
    start = vec[:, lower]
    followed = start
    for p in path[1:]:
        followed = optimise.follow_mode(followed, _two_mode_state_matrix(p))
    lam_end, vec_end = np.linalg.eig(_two_mode_state_matrix(path[-1]))
    branches = np.sort(lam_end.imag[lam_end.imag > 0])

    def frequency(v):
        k = np.argmax(np.abs(np.conj(v) @ vec_end))
        return lam_end[k].imag

    assert frequency(followed) == pytest.approx(branches[0], rel=1e-9)
    assert frequency(optimise.follow_mode(start, _two_mode_state_matrix(path[-1]))) == pytest.approx(branches[1],
                                                                                                      rel=1e-9)
