"""Study files and sweeps (optimise._study, optimise._sweep, ``jaxveh sweep``): file errors
by name, the grid against point-by-point evaluation, chunking and padding, resume from
checkpoints, the Ray backend against the local one, several local devices, the CLI's JSON
contract, and a small χ map on the car against jaxveh.analysis."""

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.optimize
import xarray as xr
from typer.testing import CliRunner

import jaxveh.analytic as analytic
import optimise
from jaxveh import GRAVITY, ParameterError, analysis, vehicle
from jaxveh.cli import app
from jaxveh.manoeuvre import skid_pad
from jaxveh.params import load_analytic_vehicle, set_at

#: vmapped chapter-3 formulas against the same formulas on one point: the batched program
#: may reorder or fuse floating-point operations, so agreement is to rounding, not bits.
BATCH_RTOL = 1e-13
#: chi_error = |χ - χ0| / χ0 is a difference of two numbers near 0.5: its rounding error is
#: absolute (a few ulp of 0.5, i.e. ~1e-16), however small the error itself.
BATCH_ATOL = 1e-15
#: The car's χ by the sweep against jaxveh.analysis on the same compiled program: the
#: designs are built by different routes (vmapped set_all, per-group anti-roll-bar rates
#: vs lambda_designs), which agree to rounding.
CAR_RTOL = 1e-9

LAMS = (0.3, 0.45, 0.6, 0.75)
MUS = (0.2, 1.0, 5.0)
EPS_F = (0.0, 0.1)

ANALYTIC = """
[study]
name = "grid"
model = "analytic"
quantities = ["chi", "chi_error", "understeer_gradient"]

[[variables]]
path = "lambda"
values = [0.3, 0.45, 0.6, 0.75]

[[variables]]
path = "mu"
start = 0.2
stop = 5.0
num = 3
log = true

[[variables]]
path = "epsF"
units = "1"
values = [0.0, 0.1]

[run]
chunk = 5
"""


def write(folder: Path, text: str, name: str = "s.toml") -> Path:
    path = folder / name
    path.write_text(textwrap.dedent(text))
    return path


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("sweep")


@pytest.fixture(scope="module")
def study_file(folder):
    return write(folder, ANALYTIC, "grid.toml")


@pytest.fixture(scope="module")
def local(study_file, folder):
    """The reference: the analytic grid on the local backend, chunks of 5 (24 points: the
    last chunk padded)."""
    return optimise.sweep(optimise.load_study(study_file, out=folder / "local"))


# ---- study files ------------------------------------------------------------------------


def _variant(old: str, new: str) -> str:
    assert old in ANALYTIC
    return ANALYTIC.replace(old, new)


CAR_OBJECTIVES = """
[study]
model = "car"
modes = 0
quantities = ["bump_steer", "camber_gain"]
[[variables]]
path = "vehicle.hard_points_front.points[7, 2]"
name = "front_L_z"
units = "m"
values = [0.305, 0.315, 0.325]
[settings.bump_steer]
corner = "front"
[run]
chunk = 2
"""

BAD = [
    ("unknown key", _variant('model = "analytic"', 'model = "analytic"\ncolour = "red"'),
     r"s\.toml: study\.colour is not a known key: allowed keys of \[study\] are name, description"),
    ("reversed range", _variant("start = 0.2\nstop = 5.0", "start = 5.0\nstop = 0.2"),
     r"s\.toml: variables\[1\] has start = 5\.0, stop = 0\.2: reversed or empty range, allowed stop > start"),
    ("empty values", _variant("values = [0.0, 0.1]", "values = []"),
     r"s\.toml: variables\[2\]\.values = \[\] is empty or not a list"),
    ("empty range", _variant("num = 3", "num = 0"),
     r"s\.toml: variables\[1\]\.num = 0 gives an empty or single-point range: allowed integers >= 2"),
    ("decreasing values", _variant("values = [0.0, 0.1]", "values = [0.1, 0.0]"),
     r"variables\[2\]\.values = \[0\.1, 0\.0\] is not allowed: strictly increasing values"),
    ("unknown quantity", _variant('"chi_error"', '"chii"'),
     r"s\.toml: study\.quantities has the unknown quantity 'chii': allowed for model = 'analytic': chi, "
     r"chi_rigid, chi_error, understeer_gradient, understeer_gradient_rigid"),
    ("chapter-3 quantity on the car", _variant("[run]", "[run]").replace('model = "analytic"', 'model = "car"')
     .replace('path = "mu"', 'path = "chassis.stiffness_scale[0]"').replace('"chi_error", "understeer_gradient"',
                                                                             '"chi_rigid"'),
     r"study\.quantities has the unknown quantity 'chi_rigid': allowed for model = 'car': chi, understeer_gradient"),
    ("settings of a quantity not swept", CAR_OBJECTIVES.replace("corner = \"front\"", "corner = \"front\"\n"
                                                                "[settings.roll_gradient]\nay_g = 0.2"),
     r"s\.toml: settings\.roll_gradient is not allowed: settings of the car's objective quantities of "
     r"study\.quantities only \(bump_steer, camber_gain\)"),
    ("unknown setting", CAR_OBJECTIVES.replace('corner = "front"', 'corner = "front"\nspeed_kmh = 3.0'),
     r"s\.toml: settings\.bump_steer\.speed_kmh is not a key of objective 'bump_steer': allowed corner"),
    ("bad corner", CAR_OBJECTIVES.replace('corner = "front"', 'corner = "middle"'),
     r"s\.toml: settings\.bump_steer\.corner = 'middle' is not allowed: one of front_left, front_right, "
     r"rear_left, rear_right, front, rear"),
    ("unknown backend", _variant("chunk = 5", 'chunk = 5\nbackend = "spark"'),
     r"s\.toml: run\.backend = 'spark' is not allowed: one of local, ray"),
    ("chunk", _variant("chunk = 5", "chunk = 0"), r"s\.toml: run\.chunk = 0 is not allowed: an integer from 1"),
    ("too many points", _variant("values = [0.0, 0.1]", "start = 0.0\nstop = 0.1\nnum = 100000"),
     r"s\.toml: variables give 1200000 grid points \(4 x 3 x 100000\): more than the maximum of 1000000 "
     r"for model = 'analytic'"),
    ("lambda range", _variant("values = [0.3,", "values = [0.0,"),
     r"variables\[0\] has lambda values 0\.0 to 0\.75: allowed 0 < lambda < 1"),
    ("log start", _variant("start = 0.2", "start = 0.0"),
     r"variables\[1\]\.start = 0\.0 is not allowed with log = true: start > 0"),
    ("car-only key", _variant('model = "analytic"', 'model = "analytic"\nmodes = 2'),
     r"s\.toml: study\.modes applies to model = 'car' only"),
    ("label of another model", _variant('model = "analytic"', 'model = "car"'),
     r"variables\[1\]\.path = 'mu' is a label of another model: labels of model = 'car' are lambda"),
    ("both values and range", _variant("values = [0.0, 0.1]", "values = [0.0, 0.1]\nnum = 3"),
     r"variables\[2\] needs either values = \[\.\.\.\] or start, stop and num \(not both\)"),
    ("malformed path", _variant('path = "epsF"', 'path = "eps F"'),
     r"variables\[2\]\.path = 'eps F': parameter path 'eps F' is malformed"),
    ("repeated variable", _variant('path = "epsF"', 'path = "mu"').replace("[0.0, 0.1]", "[0.5, 1.5]"),
     r"s\.toml: variables repeat the path 'mu': each variable once"),
]


@pytest.mark.parametrize("text, message", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_study_file_is_refused_by_name(tmp_path, text, message):
    with pytest.raises(ParameterError, match=message):
        optimise.load_study(write(tmp_path, text))


@pytest.mark.parametrize("path, values, message", [
    ("kX", "[1.0, 2.0]", r"s\.toml: variables\[2\]\.path = 'kX' is not allowed: parameter path 'kX': "
                         r"AnalyticVehicle has no field 'kX'"),
    ("tyre", "[1.0, 2.0]", r"variables\[2\]\.path = 'tyre' is not allowed"),
    ("epsF", "[0.0, 2.0]", r"s\.toml: variables\[2\] value 2\.0 of 'epsF' is out of range: .*epsF"),
])
def test_bad_path_is_refused_before_any_chunk(tmp_path, path, values, message):
    study = optimise.load_study(write(tmp_path, _variant('path = "epsF"', f'path = "{path}"').replace(
        "values = [0.0, 0.1]", f"values = {values}")), out=tmp_path / "out")
    with pytest.raises(ParameterError, match=message):
        optimise.sweep(study)
    assert not (tmp_path / "out" / "chunks").exists() or not list((tmp_path / "out" / "chunks").glob("chunk_*"))


def test_study_defaults_and_overrides(study_file, tmp_path):
    study = optimise.load_study(study_file, backend="ray", chunk=7, out=tmp_path, address="auto")
    assert (study.backend, study.chunk, study.out, study.address) == ("ray", 7, str(tmp_path), "auto")
    assert study.shape == (4, 3, 2) and study.n_points == 24
    assert [v.name for v in study.variables] == ["lambda", "mu", "epsF"]
    np.testing.assert_allclose(study.variables[1].values, np.geomspace(0.2, 5.0, 3), rtol=0, atol=0)
    default = optimise.load_study(write(tmp_path, ANALYTIC.replace("[run]\nchunk = 5\n", "")))
    assert (default.backend, default.out) == ("local", "results/grid")
    car = optimise.load_study(write(tmp_path, """
        [study]
        [[variables]]
        path = "chassis.stiffness_scale[0]"
        values = [1.0, 2.0]
        """, "car.toml"))
    assert (car.model, car.modes, car.quantities, car.ay_g, car.radius) == ("car", 6, ("chi",), (0.05, 0.1), 50.0)
    assert car.variables[0].name == "chassis_stiffness_scale_0" and car.variables[0].units == "SI"


# ---- the local backend ------------------------------------------------------------------


def test_grid_equals_point_by_point_evaluation(local):
    ds = local.dataset
    base = load_analytic_vehicle()
    assert ds.chi.dims == ("lambda", "mu", "epsF") and ds.chi.shape == (4, 3, 2)
    for i, lam in enumerate(LAMS):
        for j, mu in enumerate(np.geomspace(*MUS[::2], 3)):
            for k, eps in enumerate(EPS_F):
                v = analytic.with_distribution(set_at(base, "epsF", eps), lam=lam, mu=mu)
                chi, chi0 = float(analytic.chi(v)), float(analytic.chi_rigid(v))
                ku = float(analytic.understeer_gradient(v)) * float(analytic.RAD_PER_MS2_TO_DEG_PER_G)
                np.testing.assert_allclose(ds.chi.values[i, j, k], chi, rtol=BATCH_RTOL)
                np.testing.assert_allclose(ds.chi_error.values[i, j, k], abs(chi - chi0) / chi0, rtol=BATCH_RTOL,
                                           atol=BATCH_ATOL)
                np.testing.assert_allclose(ds.understeer_gradient.values[i, j, k], ku, rtol=BATCH_RTOL)
    # roll steer changes the understeer gradient, not the load transfer
    assert not np.allclose(ds.understeer_gradient.values[..., 0], ds.understeer_gradient.values[..., 1])
    np.testing.assert_array_equal(ds.chi.values[..., 0], ds.chi.values[..., 1])


def test_dataset_units_netcdf_and_plots(local):
    ds = local.dataset
    assert ds.attrs["grid_hash"] == optimise.grid_hash(optimise.load_study(local.path.parent.parent / "grid.toml"))
    assert {d: ds[d].attrs["units"] for d in ds.dims} == {"lambda": "1", "mu": "1", "epsF": "1"}
    assert ds.mu.attrs["scale"] == "log" and ds.epsF.attrs["path"] == "epsF"
    assert (ds.chi.attrs["units"], ds.understeer_gradient.attrs["units"]) == ("1", "deg/g")
    assert local.path.suffix == ".nc" and local.n_points == 24
    with xr.open_dataset(local.path, engine="scipy") as back:
        xr.testing.assert_identical(back.load(), ds)
    assert local.plots == ()  # three variables: no contour or line plot


@pytest.mark.parametrize("chunk", [1, 7, 24, 64])
def test_chunk_size_does_not_change_results_and_chunks_have_one_shape(study_file, local, tmp_path, chunk):
    study = optimise.load_study(study_file, out=tmp_path, chunk=chunk)
    model = optimise.build_model(study)
    shapes = []

    def evaluate(points):
        shapes.append(points.shape)
        return model.evaluate(points)

    result = optimise.sweep(study, evaluate=evaluate)
    n_chunks = -(-24 // chunk)
    assert shapes == [(min(chunk, 24), 3)] * n_chunks  # padded: one shape, one compiled program
    assert result.computed == tuple(range(n_chunks))
    xr.testing.assert_allclose(result.dataset.drop_attrs(), local.dataset.drop_attrs(), rtol=BATCH_RTOL,
                               atol=BATCH_ATOL)


def test_resume_recomputes_only_the_missing_chunk(study_file, local, tmp_path):
    study = optimise.load_study(study_file, out=tmp_path)
    first = optimise.sweep(study)
    assert first.computed == (0, 1, 2, 3, 4) and first.reused == ()
    (tmp_path / "chunks" / "chunk_0002.npz").unlink()
    model = optimise.build_model(study)
    calls = []

    def evaluate(points):
        calls.append(points.copy())
        return model.evaluate(points)

    second = optimise.sweep(study, evaluate=evaluate)
    assert second.computed == (2,) and second.reused == (0, 1, 3, 4)
    assert len(calls) == 1
    np.testing.assert_array_equal(calls[0], optimise.grid_points(study, 10, 15))
    xr.testing.assert_identical(second.dataset, first.dataset)
    xr.testing.assert_identical(second.dataset, local.dataset)
    third = optimise.sweep(study, evaluate=evaluate)  # nothing missing: nothing computed
    assert third.computed == () and len(calls) == 1


def test_resume_refuses_another_grid_or_chunk_size(study_file, tmp_path):
    optimise.sweep(optimise.load_study(study_file, out=tmp_path))
    other = optimise.load_study(write(tmp_path, _variant("values = [0.0, 0.1]", "values = [0.0, 0.2]")),
                                out=tmp_path)
    with pytest.raises(ParameterError, match="holds the chunks of another grid"):
        optimise.sweep(other)
    with pytest.raises(ParameterError, match=r"holds chunks of 5 points, this run asks for 6: rerun with --chunk 5"):
        optimise.sweep(optimise.load_study(study_file, out=tmp_path, chunk=6))


def test_a_foreign_chunk_file_is_recomputed(study_file, tmp_path):
    study = optimise.load_study(study_file, out=tmp_path)
    first = optimise.sweep(study)
    chunks = tmp_path / "chunks"
    (chunks / "chunk_0001.npz").write_bytes((chunks / "chunk_0003.npz").read_bytes())  # wrong range
    (chunks / "chunk_0004.npz").write_bytes(b"truncated")
    second = optimise.sweep(study)
    assert second.computed == (1, 4)
    xr.testing.assert_identical(second.dataset, first.dataset)


def test_line_and_contour_plots(tmp_path):
    one = optimise.sweep(optimise.load_study(write(tmp_path, """
        [study]
        name = "line"
        model = "analytic"
        quantities = ["understeer_gradient"]
        [[variables]]
        path = "lambda"
        start = 0.2
        stop = 0.8
        num = 7
        """), out=tmp_path / "line"))
    assert [p.name for p in one.plots] == ["line_understeer_gradient.png"] and one.plots[0].stat().st_size > 0
    two = optimise.sweep(optimise.load_study(write(tmp_path, ANALYTIC.replace(
        '[[variables]]\npath = "epsF"\nunits = "1"\nvalues = [0.0, 0.1]\n', "")), out=tmp_path / "map"))
    assert two.dataset.chi.dims == ("lambda", "mu")
    assert [p.name for p in two.plots] == ["grid_chi.png", "grid_chi_error.png", "grid_understeer_gradient.png"]


def test_several_local_devices_give_the_same_dataset(study_file, local, tmp_path):
    """Two forced host devices: each chunk sharded across them (5 points padded to 6)."""
    script = textwrap.dedent(f"""
        import jax, optimise
        assert jax.local_device_count() == 2, jax.local_devices()
        r = optimise.sweep(optimise.load_study({str(study_file)!r}, out={str(tmp_path)!r}))
        print(r.path)
        """)
    env = {**os.environ, "XLA_FLAGS": "--xla_force_host_platform_device_count=2", "JAX_PLATFORMS": "cpu"}
    done = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    with xr.open_dataset(done.stdout.strip().splitlines()[-1], engine="scipy") as ds:
        xr.testing.assert_allclose(ds.load().drop_attrs(), local.dataset.drop_attrs(), rtol=BATCH_RTOL, atol=BATCH_ATOL)


# ---- Ray --------------------------------------------------------------------------------


def test_ray_backend_with_two_local_workers_gives_the_identical_dataset(study_file, local, tmp_path):
    import ray

    assert not ray.is_initialized()
    study = optimise.load_study(study_file, out=tmp_path, backend="ray", num_cpus=2)
    result = optimise.sweep(study)
    assert not ray.is_initialized()  # shut down what it started
    assert result.backend == "ray" and result.computed == (0, 1, 2, 3, 4)
    xr.testing.assert_identical(result.dataset, local.dataset)
    with xr.open_dataset(result.path, engine="scipy") as back:
        xr.testing.assert_identical(back.load(), local.dataset)


# ---- the CLI ----------------------------------------------------------------------------


def test_cli_json_contract(study_file, local, tmp_path):
    runner = CliRunner()
    done = runner.invoke(app, ["sweep", str(study_file), "--json", "--out", str(tmp_path), "--chunk", "5"])
    assert done.exit_code == 0, done.output
    report = json.loads(done.stdout)
    assert isinstance(report["n_points"], int) and report["n_points"] == 24
    assert Path(report["dataset"]) == tmp_path / "grid.nc"
    with xr.open_dataset(report["dataset"], engine="scipy") as ds:
        xr.testing.assert_identical(ds.load(), local.dataset)
    assert report["computed_chunks"] == 5 and (tmp_path / "grid.json").is_file()
    again = json.loads(runner.invoke(app, ["sweep", str(study_file), "--json", "--out", str(tmp_path)]).stdout)
    assert (again["computed_chunks"], again["reused_chunks"]) == (0, 5)


def test_cli_refuses_a_bad_study_by_name(tmp_path):
    bad = write(tmp_path, _variant("chunk = 5", 'chunk = 5\nbackend = "spark"'))
    done = CliRunner().invoke(app, ["sweep", str(bad), "--json"])
    assert done.exit_code == 2
    assert "run.backend = 'spark' is not allowed: one of local, ray" in done.output


def test_shipped_study_files_load():
    root = Path(__file__).resolve().parents[1] / "experiments" / "studies"
    car = optimise.load_study(root / "lambda_mu_map.toml")
    assert car.model == "car" and car.modes == 6 and car.quantities[0] == "chi" and car.n_points <= 64
    assert [v.path for v in car.variables] == ["lambda", "chassis.stiffness_scale[0]"]
    assert min(car.variables[0].values) >= 0.3 and max(car.variables[0].values) <= 0.7
    assert car.variables[1].log and car.variables[1].values[0] == pytest.approx(0.1)
    cheap = optimise.load_study(root / "analytic_lambda_mu.toml")
    assert cheap.model == "analytic"


@pytest.mark.parametrize("name, variables, method", [
    ("roll_balance", ["lambda"], "lbfgs"),
    ("hard_points", ["rear_L_z"], "lbfgs"),
    ("hard_points_pareto", ["rear_L_z"], "slsqp"),
    ("lightest_frame", None, None),
    ("step_steer", ["front_arb", "rear_arb", "rear_L_z"], "slsqp"),
])
def test_shipped_optimisation_studies_load(name, variables, method):
    """Every shipped optimisation study file passes the loader's checks (no car built)."""
    root = Path(__file__).resolve().parents[1] / "experiments" / "studies"
    study = optimise.load_optimisation_study(root / f"{name}.toml")
    assert study.model == "car" and study.modes == 6
    if variables is not None:
        assert [v.name for v in study.variables] == variables
    if method is not None:
        assert study.optimiser["method"] == method


# ---- the car ----------------------------------------------------------------------------


@pytest.mark.slow
def test_car_chi_map_equals_analysis(tmp_path):
    """A 2 x 2 χ map (λ x first-mode stiffness multiplier) on the 2-mode car, chunks of 2:
    one compiled program, shared with chi_vs_lambda and the direct batch (2 designs each)."""
    study = optimise.load_study(write(tmp_path, """
        [study]
        name = "car_map"
        model = "car"
        modes = 2
        [[variables]]
        path = "lambda"
        values = [0.45, 0.55]
        [[variables]]
        path = "chassis.stiffness_scale[0]"
        name = "mu_1"
        units = "1"
        values = [1.0, 3.0]
        [run]
        chunk = 2
        """), out=tmp_path / "out")
    result = optimise.sweep(study)
    ds = result.dataset
    car = optimise.build_model(study).base
    assert car.n_modes == 2 and ds.chi.dims == ("lambda", "mu_1")
    np.testing.assert_array_equal(ds.converged.values, 1)
    lams = [0.45, 0.55]
    np.testing.assert_allclose(ds.chi.values[:, 0], analysis.chi_vs_lambda(car, lams), rtol=CAR_RTOL)
    designs = analysis.lambda_designs(car, lams)
    designs = eqx.tree_at(lambda p: p.chassis.stiffness_scale, designs,
                          designs.chassis.stiffness_scale.at[:, 0].set(jnp.asarray(3.0)))
    direct = analysis.load_transfer_batch(car, designs, analysis.LOW_AY_PAIR_G).chi_low_ay
    np.testing.assert_allclose(ds.chi.values[:, 1], direct, rtol=CAR_RTOL)
    assert abs(float(ds.chi.values[0, 1] - ds.chi.values[0, 0])) > 1e-5  # the multiplier is applied
    assert [p.name for p in result.plots] == ["car_map_chi.png"]


def test_car_objective_quantities_equal_the_objectives(tmp_path):
    """Objectives of the car as sweep quantities (bump steer of the front axle, camber gain
    of the front-left wheel with its default corner) over the front track-rod inner joint's
    height, chunks of 2 (one padded): each point equals the objective evaluated on its own
    car (1e-12), converged everywhere, units from the objective library."""
    study = optimise.load_study(write(tmp_path, CAR_OBJECTIVES), out=tmp_path / "out")
    ds = optimise.sweep(study).dataset
    car = optimise.build_model(study).base
    np.testing.assert_array_equal(ds.converged.values, 1)
    assert ds.bump_steer.attrs["units"] == "deg/m" and ds.bump_steer.dims == ("front_L_z",)
    for k, z in enumerate((0.305, 0.315, 0.325)):
        c = vehicle.with_params(car, {"vehicle.hard_points_front.points[7, 2]": z})
        assert float(ds.bump_steer.values[k]) == pytest.approx(float(optimise.bump_steer(c, "front")), rel=1e-12)
        assert float(ds.camber_gain.values[k]) == pytest.approx(float(optimise.camber_gain(c)), rel=1e-12)
    assert ds.bump_steer.values[2] > ds.bump_steer.values[0]  # raising the inner joint: less toe-out in bump


@pytest.mark.slow
def test_car_understeer_gradient_map_equals_the_skid_pad(tmp_path):
    """The understeer gradient at 0.1 g (``[settings.understeer_gradient]``) beside χ over λ
    on the rigid car equals jaxveh.manoeuvre.skid_pad's at the same λ (1e-9)."""
    study = optimise.load_study(write(tmp_path, """
        [study]
        model = "car"
        modes = 0
        quantities = ["chi", "understeer_gradient"]
        [[variables]]
        path = "lambda"
        values = [0.45, 0.55]
        [settings.understeer_gradient]
        ay_g = 0.1
        [run]
        chunk = 2
        """), out=tmp_path / "out")
    ds = optimise.sweep(study).dataset
    car = optimise.build_model(study).base
    np.testing.assert_array_equal(ds.converged.values, 1)
    for k, lam in enumerate((0.45, 0.55)):
        rates = np.asarray(analysis.arb_rates_for_distribution(car, lam))
        c = vehicle.with_params(car, {"arb_rates[0]": float(rates[0]), "arb_rates[1]": float(rates[1])})
        ku = float(skid_pad(c, 50.0, [0.1 * GRAVITY]).understeer_gradient[0])
        assert float(ds.understeer_gradient.values[k]) == pytest.approx(ku, rel=1e-9)
    np.testing.assert_allclose(ds.chi.values, analysis.chi_vs_lambda(car, [0.45, 0.55]), rtol=CAR_RTOL)


@pytest.mark.slow
def test_car_speed_sweep_equals_the_transfer_function(tmp_path):
    """``speed_kmh`` as a sweep variable (a traced speed: one program for both speeds) of
    the yaw-rate bandwidth on the rigid car equals the -3 dB frequency of
    jaxveh.analysis.transfer_function at each speed found by SciPy's brentq (1e-8)."""
    study = optimise.load_study(write(tmp_path, """
        [study]
        model = "car"
        modes = 0
        quantities = ["yaw_rate_bandwidth"]
        [[variables]]
        path = "speed_kmh"
        values = [50.0, 90.0]
        [run]
        chunk = 2
        """), out=tmp_path / "out")
    ds = optimise.sweep(study).dataset
    car = optimise.build_model(study).base
    np.testing.assert_array_equal(ds.converged.values, 1)
    assert ds.speed_kmh.attrs["units"] == "km/h"
    for k, speed in enumerate((50.0, 90.0)):
        lin = analysis.linearise(car, speed / 3.6, outputs=("yaw_rate",))
        row = analysis.output_index(lin, "yaw_rate")
        gain = lambda f, lin=lin, row=row: float(np.abs(analysis.transfer_function(lin, [f], "steering")[0, row]))
        ratio = lambda f, g0=gain(0.05), gain=gain: gain(f) / g0 - 2.0 ** -0.5
        grid = np.geomspace(0.05, 20.0, 400)
        first = next(i for i, f in enumerate(grid) if ratio(f) < 0.0)
        reference = scipy.optimize.brentq(ratio, grid[first - 1], grid[first], xtol=1e-14)
        assert float(ds.yaw_rate_bandwidth.values[k]) == pytest.approx(reference, rel=1e-8)
    assert ds.yaw_rate_bandwidth.values[1] != ds.yaw_rate_bandwidth.values[0]
