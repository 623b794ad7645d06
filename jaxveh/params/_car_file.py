"""The car file (``car.toml``): Appendix B plus the sections the 14-DOF car needs beyond the
thesis's tables (springs, dampers, anti-roll bars, steering, aerodynamics, powertrain, tyre
and frame files, chassis damping). :func:`read_car_file` validates it and returns SI values;
:mod:`jaxveh.vehicle` turns them into the car.
"""

import math
from dataclasses import dataclass
from pathlib import Path

from ._appendix_b import SECTIONS as APPENDIX_B_SECTIONS, VehicleData, vehicle_data_from_dict
from ._schema import ParameterError, Quantity, check_sections, read_section, read_toml

_CHOICE = "choice (docs/vehicle.md)"
SUSPENSION = (
    Quantity("spring_rate", "N/m", "push-rod spring rate at the spring", _CHOICE),
    Quantity("damping", "Ns/m", "linear damper rate at the spring", _CHOICE, lower_open=False),
    Quantity("arb_rate", "Nm/rad", "anti-roll bar rate per radian of bar twist (rocker to rocker)", _CHOICE,
             lower_open=False),
    Quantity("bump_stop_clearance", "mm", "spring compression from its design length before the bump stop",
             _CHOICE),
    Quantity("bump_stop_rate", "N/m", "bump-stop rate at the spring (0: none)", _CHOICE, lower_open=False),
)
STEERING = (
    Quantity("rack_ratio", "mm/deg", "rack travel per degree of steering-wheel angle", _CHOICE),
)
AERO = (
    Quantity("cda", "m2", "drag area C_d A", _CHOICE, lower_open=False),
    Quantity("cla", "m2", "downforce area C_l A", _CHOICE, lower_open=False),
    Quantity("front_share", "-", "share of the downforce on the front axle", _CHOICE, lower_open=False, upper=1.0),
    Quantity("density", "kg/m3", "air density", _CHOICE),
    Quantity("max_speed", "m/s", "last speed of the aero tables (linear beyond)", _CHOICE),
)
POWERTRAIN = (
    Quantity("kp", "Nm s/m", "PID proportional gain (torque per speed error)", "section 6.1.5", lower_open=False),
    Quantity("ki", "N", "PID integral gain (torque per metre of integrated error)", "section 6.1.5",
             lower_open=False),
    Quantity("kd", "Nm s2/m", "PID derivative gain", "section 6.1.5", lower_open=False),
    Quantity("tau", "s", "speed filter time constant of the derivative", _CHOICE),
    Quantity("torque_min", "Nm", "most negative (braking) torque of the four wheels together", _CHOICE, lower=None,
             upper=0.0),
    Quantity("torque_max", "Nm", "largest rear-wheel drive torque", _CHOICE, lower_open=False),
    Quantity("brake_front_share", "-", "front axle's share of the brake torque", _CHOICE, lower_open=False,
             upper=1.0),
)
CHASSIS = (
    Quantity("damping_ratio", "-", "modal damping ratio of every chassis mode", "section 7.3", lower_open=False,
             upper=1.0, upper_open=True),
    Quantity("coupling", "-", "coupling factor of the mode shapes at the chassis points", "section 7.1",
             lower_open=False, upper=1.0),
)
FILES = ("tyre_front", "tyre_rear", "frame")
#: The optional list key of ``[chassis]``: each mode's stiffness multiplier µ (mode 1 first).
STIFFNESS_SCALE = "stiffness_scale"
#: The most modes a car has (``load_car``'s ``modes``).
MAX_MODES = 20
SECTIONS = {"suspension_front": SUSPENSION, "suspension_rear": SUSPENSION, "steering": STEERING, "aero": AERO,
            "powertrain": POWERTRAIN, "chassis": CHASSIS}


@dataclass(frozen=True)
class CarFile:
    """A validated car file: ``vehicle`` (Appendix B), ``sections`` (SI values by section
    and key), ``files`` (tyre and frame files: a shipped name or a path resolved against
    the car file's folder), ``stiffness_scale`` (``[chassis] stiffness_scale``: each
    mode's stiffness multiplier µ from mode 1, ``()`` when absent) and ``where`` (the
    file, for messages)."""

    vehicle: VehicleData
    sections: dict
    files: dict
    where: str
    stiffness_scale: tuple = ()


def _stiffness_scale(table, where: str) -> tuple:
    """``[chassis] stiffness_scale`` (removed from ``table``'s chassis section): a list of
    1-20 finite numbers > 0, or absent."""
    chassis = table.get("chassis")
    if not isinstance(chassis, dict) or STIFFNESS_SCALE not in chassis:
        return ()
    value = chassis.pop(STIFFNESS_SCALE)
    ok = isinstance(value, list) and 1 <= len(value) <= MAX_MODES and all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0 for v in value)
    if not ok:
        raise ParameterError(f"{where} [chassis].{STIFFNESS_SCALE} = {value!r} is not allowed: a list of 1 to "
                             f"{MAX_MODES} numbers > 0, each mode's stiffness multiplier µ from mode 1")
    return tuple(float(v) for v in value)


def _files(table, where: str, folder: Path | None) -> dict:
    if "files" not in table:
        raise ParameterError(f"{where}: missing section [files]")
    data = table["files"]
    unknown = sorted(set(data) - set(FILES))
    if unknown:
        raise ParameterError(f"{where} [files]: unknown key(s) {unknown}; allowed keys are {list(FILES)}")
    out = {}
    for key in FILES:
        if key not in data or not isinstance(data[key], str) or not data[key]:
            raise ParameterError(f"{where} [files].{key} must name a file (a shipped name or a path)")
        path = Path(data[key])
        if folder is not None and not path.is_absolute() and (folder / path).is_file():
            path = folder / path
        out[key] = str(path)
    return out


def read_car_file(path: str | Path | None = None) -> CarFile:
    """Read and validate a car file (default: the shipped ``car.toml``)."""
    table, where = read_toml(path, "jaxveh.params", "data/car.toml", "car")
    check_sections(table, (*APPENDIX_B_SECTIONS, *SECTIONS, "files"), where)
    stiffness_scale = _stiffness_scale(table, where)
    vehicle = vehicle_data_from_dict({k: table[k] for k in APPENDIX_B_SECTIONS if k in table}, where)
    sections = {name: read_section(table, name, quantities, where) for name, quantities in SECTIONS.items()}
    folder = None if path is None else Path(path).parent
    return CarFile(vehicle=vehicle, sections=sections, files=_files(table, where, folder), where=where,
                   stiffness_scale=stiffness_scale)
