"""Declarative schema for vehicle data files: units, ranges, sources, validation.

A data file is TOML; each section holds numbers in the unit the thesis tables use (mm,
deg, Nm/deg, ...). A :class:`Quantity` says what a key means, in which unit it is written,
where it comes from and which values are allowed. :func:`read_section` checks a section
against its quantities and returns SI values.
"""

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from .._core import ParameterError as ParameterError, read_toml as read_toml

#: Factor that converts a value written in the unit to SI.
UNIT_TO_SI: dict[str, float] = {
    "-": 1.0,
    "kg": 1.0,
    "kg m2": 1.0,
    "m": 1.0,
    "mm": 1e-3,
    "rad": 1.0,
    "deg": math.pi / 180.0,
    "N": 1.0,
    "N/m": 1.0,
    "Ns/m": 1.0,
    "Nm/deg": 180.0 / math.pi,
    "Nms/deg": 180.0 / math.pi,
    "Nm/rad": 1.0,
    "Nms/rad": 1.0,
    "1/rad": 1.0,
    "1/deg": 180.0 / math.pi,
    "m/s": 1.0,
    "km/h": 1.0 / 3.6,
    "Hz": 1.0,
    "s": 1.0,
    "Nm": 1.0,
    "Nm s/m": 1.0,
    "Nm s2/m": 1.0,
    "m2": 1.0,
    "kg/m3": 1.0,
    "mm/deg": 1e-3 * 180.0 / math.pi,
}


@dataclass(frozen=True)
class Quantity:
    """One number of a data file.

    Attributes:
        key: key in the TOML section.
        unit: unit the value is written in (a key of :data:`UNIT_TO_SI`).
        description: what the number is.
        source: where it comes from (thesis table or a documented choice).
        lower, upper: allowed range in the file's unit (``None``: unbounded).
        lower_open, upper_open: whether the bound itself is excluded.
    """

    key: str
    unit: str
    description: str
    source: str
    lower: float | None = 0.0
    upper: float | None = None
    lower_open: bool = True
    upper_open: bool = False

    def allowed(self) -> str:
        lo = "" if self.lower is None else ("> " if self.lower_open else ">= ") + f"{self.lower:g}"
        hi = "" if self.upper is None else ("< " if self.upper_open else "<= ") + f"{self.upper:g}"
        parts = [p for p in (lo, hi) if p]
        return " and ".join(parts) + f" {self.unit}" if parts else "any finite value"

    def check(self, value: float, where: str) -> None:
        name = f"{where}.{self.key}"
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ParameterError(f"{name} ({self.description}) must be a number in {self.unit}, got {value!r}")
        if not math.isfinite(value):
            raise ParameterError(f"{name} ({self.description}) must be finite, got {value!r}")
        bad_low = self.lower is not None and (value <= self.lower if self.lower_open else value < self.lower)
        bad_high = self.upper is not None and (value >= self.upper if self.upper_open else value > self.upper)
        if bad_low or bad_high:
            raise ParameterError(
                f"{name} ({self.description}) = {value:g} {self.unit} is out of range: allowed {self.allowed()}"
            )


def read_section(
    table: Mapping, section: str, quantities: Sequence[Quantity], where: str
) -> dict[str, float]:
    """Validate ``table[section]`` against ``quantities``; return SI values by key.

    Raises:
        ParameterError: missing section, missing or unknown key, non-number or value out
            of range. The message names ``where`` (the file), the section and the key.
    """
    if section not in table or not isinstance(table[section], Mapping):
        raise ParameterError(f"{where}: missing section [{section}]")
    data = table[section]
    known = {q.key: q for q in quantities}
    unknown = sorted(set(data) - set(known))
    if unknown:
        raise ParameterError(
            f"{where} [{section}]: unknown key(s) {unknown}; allowed keys are {sorted(known)}"
        )
    missing = [q.key for q in quantities if q.key not in data]
    if missing:
        raise ParameterError(f"{where} [{section}]: missing key(s) {missing}")
    out = {}
    for q in quantities:
        value = data[q.key]
        q.check(value, f"{where} [{section}]")
        out[q.key] = float(value) * UNIT_TO_SI[q.unit]
    return out


def check_sections(table: Mapping, allowed: Sequence[str], where: str) -> None:
    """Raise if the file has top-level sections other than ``allowed``."""
    unknown = sorted(set(table) - set(allowed))
    if unknown:
        raise ParameterError(f"{where}: unknown section(s) {unknown}; allowed are {list(allowed)}")


def schema_markdown(sections: Mapping[str, Sequence[Quantity]]) -> str:
    """Render a schema as a Markdown table (used to write the data documentation)."""
    lines = ["| section | key | unit | allowed | description | source |", "|---|---|---|---|---|---|"]
    for section, quantities in sections.items():
        for q in quantities:
            lines.append(f"| {section} | `{q.key}` | {q.unit} | {q.allowed()} | {q.description} | {q.source} |")
    return "\n".join(lines)
