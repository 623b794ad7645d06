"""The .tir reader and writer: fixture, public MF 5.2 example, round trips, errors."""

from pathlib import Path

import jax
import numpy as np
import pytest

import jaxveh.tyre as jt

DATA = Path(__file__).parent / "data"
FIXTURE = DATA / "tyre_mf52_fixture.tir"
#: The public MF 5.2 example file of the workspace; absent in a user's clone.
REFERENCE = Path(__file__).resolve().parents[2] / "shared" / "reference" / "tyre" / "MagicFormula52_Parameters.tir"


def _equal(a: jt.MagicFormulaTyre, b: jt.MagicFormulaTyre) -> bool:
    leaves = jax.tree.map(lambda x, y: bool(np.asarray(x) == np.asarray(y)), a, b)
    return all(jax.tree.leaves(leaves)) and jax.tree.structure(a) == jax.tree.structure(b)


def test_fixture_values_comments_and_extras():
    t = jt.read_tir(FIXTURE)
    assert t.fittyp == 21
    assert float(t.vertical_stiffness) == 2.1e5  # Fortran D exponent
    assert float(t.pky1) == -18.0 and float(t.phx1) == 1.5e-4
    assert float(t.lmuy) == 0.95 and float(t.lmux) == 1.0  # missing scaling factor -> 1
    assert float(t.pdy1) == 0.95 and float(t.qtz1) == 0.0  # missing coefficient -> 0
    assert t.relaxation_model == "mf52"  # PTX1 and PTY1 given
    extras = {(s, k): v for s, k, v in t.extras}
    assert extras[("MODEL", "TYRESIDE")] == "'LEFT'"
    assert extras[("MODEL", "NOTE")] == "'rig run $12 ! ok'"  # quotes protect comment chars
    assert extras[("EXTRA_VENDOR_SECTION", "VENDOR_CODE")] == "1234"
    assert [v for s, k, v in t.extras if s == "SHAPE"] == ["{radial width}", "1.0    0.0", "0.95   1.0"]


@pytest.mark.parametrize("path", [FIXTURE, jt.fsae_tir_path()], ids=["fixture", "fsae"])
def test_round_trip_is_lossless(path, tmp_path):
    t1 = jt.read_tir(path)
    out = jt.write_tir(tmp_path / "copy.tir", t1)
    t2 = jt.read_tir(out)
    assert _equal(t1, t2)
    assert t2.extras == t1.extras and t2.fittyp == t1.fittyp and t2.relaxation_model == t1.relaxation_model
    assert jt.format_tir(t2) == out.read_text()  # writing is deterministic


def test_round_trip_keeps_non_round_numbers(tmp_path):
    t = jt.load_fsae_tyre()
    t = jax.tree.map(lambda x: x * (1.0 + 1e-13) + 1e-17, t)  # perturb every leaf in its last digits
    back = jt.read_tir(jt.write_tir(tmp_path / "x.tir", t))
    assert _equal(t, back)


@pytest.mark.skipif(not REFERENCE.exists(), reason="public MF 5.2 example not present (only in the jaxveh workspace)")
def test_public_mf52_example_loads_and_evaluates(tmp_path):
    t = jt.read_tir(REFERENCE)
    assert t.fittyp == 6 and float(t.fnomin) == 9416.6 and float(t.pky1) == -29.1
    assert t.relaxation_model == "mf52"
    f = jax.jit(jt.tyre_forces)(t, 5000.0, 0.05, 0.05, 0.02, 20.0)
    assert all(np.isfinite(np.asarray(v)) for v in f)
    # ISO-W: positive alpha, negative Fy; driving slip, positive Fx; aligning Mz > 0
    assert float(f.fy) < 0.0 < float(f.fx) and float(f.mz) > 0.0
    assert _equal(t, jt.read_tir(jt.write_tir(tmp_path / "ref.tir", t)))


def _write(tmp_path, text: str) -> Path:
    p = tmp_path / "bad.tir"
    p.write_text(text)
    return p


def _fixture_with(old: str, new: str) -> str:
    text = FIXTURE.read_text()
    assert old in text
    return text.replace(old, new, 1)


@pytest.mark.parametrize(
    "old, new, message",
    [
        ("PKY1                     = -18.0\n", "", r"missing required key PKY1 in \[LATERAL_COEFFICIENTS\]"),
        ("FITTYP                   = 21", "FITTYP = 61", r"FITTYP = 61 is not supported"),
        ("FITTYP                   = 21        ! MF-Tyre 5.2\n", "", r"missing required key FITTYP"),
        ("PDY1                     = 0.95", "PDY1 = abc", r"PDY1 = 'abc' is not a number"),
        ("LENGTH                   ='meter'", "LENGTH = 'mm'", r"LENGTH = 'mm' is not supported"),
        ("PCX1                     = 1.6", "PCX1 = 1.6\nPCX1 = 1.7", r"duplicate key PCX1"),
        ("FNOMIN                   = 3500", "FNOMIN = -1", r"FNOMIN = -1 must be > 0"),
        ("[MDI_HEADER]", "stray text\n[MDI_HEADER]", r"before the first \[SECTION\]"),
        ("WIDTH                    = 0.205", "WIDTH =", r"malformed line"),
    ],
    ids=["missing-key", "fittyp", "no-fittyp", "not-number", "units", "duplicate", "range", "stray", "malformed"],
)
def test_malformed_files_give_named_errors(tmp_path, old, new, message):
    with pytest.raises(jt.TirError, match=message):
        jt.read_tir(_write(tmp_path, _fixture_with(old, new)))


def test_tir_error_is_a_parameter_error():
    from jaxveh.params import ParameterError

    assert issubclass(jt.TirError, ParameterError) and issubclass(jt.TirError, ValueError)


def test_missing_file():
    with pytest.raises(FileNotFoundError):
        jt.read_tir("no/such/file.tir")


def test_constant_relaxation_section_written_only_for_constant_model(tmp_path):
    assert "[RELAXATION_LENGTH]" in jt.format_tir(jt.load_fsae_tyre())
    assert "[RELAXATION_LENGTH]" not in jt.format_tir(jt.read_tir(FIXTURE))
