"""Markdown documentation of the data-file schemas (written to ``docs/data.md``)."""

from . import _appendix_a, _appendix_b, _car_file
from ._schema import schema_markdown

HEADER = """# Vehicle data files

Generated from the schemas in `jaxveh/params` by `python -m jaxveh.params.docs`; a test
checks that this file is current. Values are written in the unit of the column *unit*
and converted to SI on load; a value outside *allowed* raises `ParameterError` naming
the file, section and key.

## Appendix A: the chapter-3 analytic vehicle (`appendix_a.toml`)

Consistency checks: `m = ms + muF + muR`, `l = a + b = as + bs` (c.g. inside the
wheelbase), `a = (ms as + muR l)/m` (unsprung masses at the axles), all to a relative
tolerance of 1e-3; `hG = (msF hsF + msR hsR + muF huF + muR huR)/m` with `msF = ms bs/l`,
`msR = ms as/l`, to 2.5 mm (Table A.1 rounds heights to 5 mm); `hsF > zF`, `hsR > zR`.
`m`, `a`, `b`, `l` and `hG` are checked, not stored: `AnalyticVehicle` computes them from
the masses, `as`, `bs` and the heights, so they follow any change of those.

The Python API checks the same ranges (SI units) when an `AnalyticVehicle` is built and
again in every analytic function (see "Input validation" in `docs/analytic.md`).

"""

MIDDLE = """

## Appendix B: the 14-DOF vehicle (`appendix_b.toml`)

Sections `[hard_points_front]` and `[hard_points_rear]` hold the 14 hard points
A, B, C, D, E, F, H, L, M, P, Q, R, S, T of the left corner as `[x, y, z]` in mm
(Tables B.2, B.3), in the corner frame: origin on the ground in the vehicle centre plane
below the axle centre, x forward, y left (y > 0 required), z up. The product of inertia
must keep the inertia tensor positive definite (|Jxz| < sqrt(Jxx Jzz)).

"""


CAR = """

## The car file (`car.toml`)

The 14-DOF car of `jaxveh.vehicle.load_car`: every Appendix B section above (same keys,
units and checks) plus the sections below, the car's data beyond the thesis's tables
(choices documented in `docs/vehicle.md`). `[files]` names the tyre file of each axle and
the chassis frame file: a shipped name (`fsae_20x7_13.tir`, `fsae_2009_frame.toml`) or a
path, relative paths resolved against the car file's folder; a missing file raises
`ParameterError` naming the key. Table B.4's `kz`, `cz` and relaxation lengths replace the
tyre file's. `[chassis]` may also hold `stiffness_scale = [µ1, µ2, ...]`: each chassis
mode's stiffness multiplier (1 to 20 numbers > 0, mode 1 first; modes beyond the list keep
1, entries beyond the car's mode count are not used), as `jaxveh optimise` writes an
optimum's µ. The right corners mirror the left; the springs' free lengths are not data: they
are set so that the car rests at the design position (`rest_spring_preloads`).

"""


def render() -> str:
    """The full Markdown text of ``docs/data.md``."""
    b_sections = {
        "general": _appendix_b.GENERAL,
        "sprung": _appendix_b.SPRUNG,
        "unsprung_front / unsprung_rear": _appendix_b.UNSPRUNG,
        "tyre": _appendix_b.TYRE,
    }
    car = {"suspension_front / suspension_rear": _car_file.SUSPENSION, "steering": _car_file.STEERING,
           "aero": _car_file.AERO, "powertrain": _car_file.POWERTRAIN, "chassis": _car_file.CHASSIS}
    return (HEADER + schema_markdown(_appendix_a.SCHEMA) + MIDDLE + schema_markdown(b_sections) + CAR
            + schema_markdown(car) + "\n")
