"""An optimum written back as a car file (``--vehicle``): every value of :class:`CarParams`
a car file holds — the Appendix B sections (c.g., tracks, static toe and camber, masses
and inertias, tyre vertical data, the hard points of the left corners), the anti-roll bars,
the coupling factor, the rack ratio, the speed controller and the chassis modes' stiffness
multipliers µ
(``[chassis] stiffness_scale``) — compared between the study's base car and the optimum,
and the changed ones written into a copy of the base file in its units, so that the file
read back gives the optimum's car.
"""

import functools
import json
import re
from importlib import resources
from pathlib import Path
from typing import NamedTuple

import numpy as np

from jaxveh import vehicle
from jaxveh.params import UNIT_TO_SI, get_at, read_car_file
from jaxveh.params._appendix_b import GENERAL, HARD_POINT_NAMES, SPRUNG, TYRE, UNSPRUNG
from jaxveh.params._car_file import STIFFNESS_SCALE

from ._frame_design import is_frame_path

#: CarParams paths of the car file's own sections: path -> (section, key, unit of the file).
CAR_FILE_KEYS = {
    "arb_rates[0]": ("suspension_front", "arb_rate", "Nm/rad"),
    "arb_rates[1]": ("suspension_rear", "arb_rate", "Nm/rad"),
    "coupling": ("chassis", "coupling", "-"),
    "rack_ratio": ("steering", "rack_ratio", "mm/deg"),
    "pid.kp": ("powertrain", "kp", "Nm s/m"),
    "pid.ki": ("powertrain", "ki", "N"),
    "pid.kd": ("powertrain", "kd", "Nm s2/m"),
    "pid.tau": ("powertrain", "tau", "s"),
    "pid.t_min": ("powertrain", "torque_min", "Nm"),
    "pid.t_max": ("powertrain", "torque_max", "Nm"),
    "pid.brake_front_share": ("powertrain", "brake_front_share", "-"),
}
#: Significant digits written (the file is read back to this precision).
DIGITS = 15
#: Where the keys of a body section live in ``RigidBodyData`` (path suffix, sign).
_BODY = {"m": ("mass", 1.0), "Jxx": ("inertia[0, 0]", 1.0), "Jyy": ("inertia[1, 1]", 1.0),
         "Jzz": ("inertia[2, 2]", 1.0), "Jxz": ("inertia[0, 2]", -1.0)}


def _number(x) -> str:
    return repr(float(f"{float(x):.{DIGITS}g}"))


def _scalar_entries(params) -> dict:
    """``{path: (section, key, unit, sign)}`` of the scalar values a car file holds."""
    out = dict((path, (*entry, 1.0)) for path, entry in CAR_FILE_KEYS.items())
    out |= {f"vehicle.{q.key}": ("general", q.key, q.unit, 1.0) for q in GENERAL}
    units = {q.key: q.unit for q in SPRUNG}
    out |= {f"vehicle.sprung.{suffix}": ("sprung", key, units[key], sign) for key, (suffix, sign) in _BODY.items()}
    units = {q.key: q.unit for q in UNSPRUNG}
    for axle in ("front", "rear"):
        section, root = f"unsprung_{axle}", f"vehicle.unsprung_{axle}"
        out |= {f"{root}.body.{suffix}": (section, key, units[key], sign)
                for key, (suffix, sign) in _BODY.items() if key != "Jxz"}
        out[f"{root}.wheel_spin_inertia"] = (section, "J_wheel", units["J_wheel"], 1.0)
    out |= {f"vehicle.tyre.{q.key}": ("tyre", q.key, q.unit, 1.0) for q in TYRE}
    return out


class FileEntry(NamedTuple):
    """One value of a car file: ``section``, ``key``, ``text`` as written (the file's
    units) and ``value`` (SI: a float, or a list for a hard point or the multipliers)."""

    section: str
    key: str
    text: str
    value: object


def _list(values) -> str:
    return "[" + ", ".join(_number(x) for x in values) + "]"


def file_entries(params) -> dict:
    """``{path: FileEntry}``: every value of ``params`` (CarParams) a car file holds (a
    hard point as its row, ``vehicle.hard_points_rear.points[7]``, written ``[x, y, z]`` in
    mm; the stiffness multipliers as ``chassis.stiffness_scale``, a list)."""
    out = {}
    for path, (section, key, unit, sign) in _scalar_entries(params).items():
        value = float(get_at(params, path))
        out[path] = FileEntry(section, key, _number(sign * value / UNIT_TO_SI[unit]), value)
    for axle in ("front", "rear"):
        points = np.asarray(get_at(params, f"vehicle.hard_points_{axle}.points"), dtype=float)
        for i, name in enumerate(HARD_POINT_NAMES):
            out[f"vehicle.hard_points_{axle}.points[{i}]"] = FileEntry(
                f"hard_points_{axle}", name, _list(points[i] * 1e3), points[i].tolist())
    if params.chassis is not None:
        scale = np.asarray(params.chassis.stiffness_scale, dtype=float)
        out["chassis.stiffness_scale"] = FileEntry("chassis", STIFFNESS_SCALE, _list(scale), scale.tolist())
    return out


@functools.lru_cache(maxsize=8)
def _base_entries(vehicle_file, modes: int, mtime_ns) -> dict:
    """:func:`file_entries` of the base car (its file and mode count; ``mtime_ns``, the
    file's modification time, keys the cache)."""
    return file_entries(vehicle.load_car(vehicle_file, modes=modes).params)


def changed_entries(result) -> dict:
    """``{path: FileEntry}`` of the car-file values whose text differs between the study's
    base car and the optimum (:func:`file_entries`)."""
    study = result.study
    base = _base_entries(study.vehicle, study.modes, Path(study.vehicle).stat().st_mtime_ns if study.vehicle else 0)
    return {path: e for path, e in file_entries(result.car.params).items()
            if path not in base or base[path].text != e.text}


def changed_car_values(result) -> dict:
    """``{path: value}`` (SI; a hard point's row and the stiffness multipliers as lists) of
    the car-file values that differ between the study's base car and the optimum."""
    return {path: e.value for path, e in changed_entries(result).items()}


def _written(path: str, entries) -> bool:
    """Whether the variable ``path`` is held by one of the car file's ``entries`` paths."""
    p = path.replace(" ", "")
    for e in (e.replace(" ", "") for e in entries):
        if p == e or p.startswith(e + "[") or (e.endswith("]") and p.startswith(e[:-1] + ",")):
            return True
    return False


def _car_text(study) -> str:
    if study.vehicle is None:
        return (resources.files("jaxveh.params") / "data" / "car.toml").read_text()
    return Path(study.vehicle).read_text()


def _set_value(text: str, section: str, key: str, value: str) -> str:
    """``text`` (TOML) with ``key = value`` in ``[section]``: the value of an existing line
    replaced (its comment kept), or a line added after the section's header."""
    lines = text.splitlines(keepends=True)
    header = re.compile(rf"^\s*\[{re.escape(section)}\]\s*(#.*)?$")
    start = next((i for i, line in enumerate(lines) if header.match(line.rstrip("\n"))), None)
    if start is None:
        return text.rstrip("\n") + f"\n\n[{section}]\n{key} = {value}\n"
    end = next((i for i in range(start + 1, len(lines)) if re.match(r"^\s*\[", lines[i])), len(lines))
    pattern = re.compile(rf"^(\s*{re.escape(key)}\s*=\s*)([^#\n]*?)(\s*(#.*)?)$")
    for i in range(start + 1, end):
        m = pattern.match(lines[i].rstrip("\n"))
        if m:
            lines[i] = f"{m.group(1)}{value}{m.group(3)}\n"
            return "".join(lines)
    lines.insert(start + 1, f"{key} = {value}\n")
    return "".join(lines)


def optimum_car_file(result, frame_file=None) -> str:
    """The base car file's text with the optimum's changed values written in (only those,
    in the file's units; :func:`file_entries`), its ``[files]`` made absolute where they
    were paths relative to the base file (``frame_file``: the optimum's frame file, for a
    study with frame variables), and a header naming the study and any variable a car
    file cannot hold. A car file for ``--vehicle``."""
    study = result.study
    text = _car_text(study)
    for e in changed_entries(result).values():
        text = _set_value(text, e.section, e.key, e.text)
    if study.vehicle is not None:  # tyre and frame files relative to the base file: absolute in the copy
        files = read_car_file(study.vehicle).files
        for key, name in files.items():
            if Path(name).is_file() and not Path(name).is_absolute():
                text = _set_value(text, "files", key, json.dumps(str(Path(name).resolve())))
    if frame_file is not None:
        text = _set_value(text, "files", "frame", json.dumps(str(Path(frame_file).resolve())))
    entries = file_entries(result.car.params)
    unwritten = [v.path for v in study.variables
                 if v.path != "lambda" and not is_frame_path(v.path) and not _written(v.path, entries)]
    head = [f"# The optimum of the study {study.name!r} ({study.file or 'built in Python'}), written by jaxveh "
            "optimise:", "# " + ", ".join(f"{k} = {v:.10g}" for k, v in result.optimum.items()) +
            f" (converged: {str(result.converged).lower()})"]
    if unwritten:
        head.append("# Not in a car file (set them with --param): " + ", ".join(
            f"{p} = {float(get_at(result.car.params, p)):.10g}" for p in unwritten))
    return "\n".join(head) + "\n" + text
