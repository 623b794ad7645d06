"""Reader and writer for MF-Tyre ``.tir`` property files (MF 5.2 / PAC2002 family).

Format: ``[SECTION]`` headers, ``KEY = value`` lines, comments after ``$`` or ``!`` (outside
quotes), quoted strings, Fortran exponents (``1.0D-3``) and free-form table sections such as
``[SHAPE]``. Every numeric MF 5.2 key becomes a float64 leaf of :class:`MagicFormulaTyre`,
matched by key name whatever section it appears in; everything else (header strings,
unknown keys, table sections) is kept verbatim in ``MagicFormulaTyre.extras`` and written
back, so read -> write -> read is lossless. Comments are not kept.
"""

import importlib.resources
import math
import re
from pathlib import Path

import numpy as np

from .._core import check_x64
from ..params import ParameterError
from ._model import SUPPORTED_FITTYP, MagicFormulaTyre, coefficient_fields

#: Units jaxveh accepts in the [UNITS] block (lower case); values must be SI.
SI_UNITS: dict[str, tuple[str, ...]] = {
    "LENGTH": ("meter", "meters", "metre", "m"),
    "FORCE": ("newton", "newtons", "n"),
    "ANGLE": ("radians", "radian", "rad"),
    "MASS": ("kg", "kilogram", "kilograms"),
    "TIME": ("second", "seconds", "sec", "s"),
}
_UNITS_OUT = {"LENGTH": "meter", "FORCE": "newton", "ANGLE": "radians", "MASS": "kg", "TIME": "second"}
_HEADER_OUT = (("FILE_TYPE", "'tir'"), ("FILE_VERSION", "3.0"), ("FILE_FORMAT", "'ASCII'"))
_TABLE = ""  # key used in extras for a raw line of a table section
_FSAE_FILE = "fsae_20x7_13.tir"
_NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eEdD][+-]?\d+)?$")


class TirError(ParameterError):
    """A ``.tir`` file is malformed, lacks a required key or has an unsupported FITTYP."""


def _strip_comment(line: str) -> str:
    """Remove a ``$`` or ``!`` comment that is not inside single quotes."""
    quoted = False
    for i, ch in enumerate(line):
        if ch == "'":
            quoted = not quoted
        elif ch in "$!" and not quoted:
            return line[:i]
    return line


def _to_float(raw: str, key: str, where: str) -> float:
    text = raw.strip().strip("'")
    if not _NUMBER.match(text):
        raise TirError(f"{where}: {key} = {raw.strip()!r} is not a number")
    value = float(text.replace("D", "e").replace("d", "e"))
    if not math.isfinite(value):
        raise TirError(f"{where}: {key} = {raw.strip()!r} is not finite")
    return value


def _parse(text: str, source: str) -> list[tuple[str, str, str, int]]:
    """Split a ``.tir`` text into (section, key, raw value, line number) entries."""
    entries = []
    section = ""
    for lineno, line in enumerate(text.splitlines(), start=1):
        body = _strip_comment(line).strip()
        if not body:
            continue
        if body.startswith("[") and body.endswith("]"):
            section = body[1:-1].strip().upper()
            continue
        if "=" in body and not body.startswith("{"):
            key, raw = body.split("=", 1)
            key = key.strip().upper()
            if not key or not raw.strip():
                raise TirError(f"{source}:{lineno}: malformed line {line.strip()!r} (expected KEY = value)")
            entries.append((section, key, raw.strip(), lineno))
        elif section:
            entries.append((section, _TABLE, body, lineno))
        else:
            raise TirError(f"{source}:{lineno}: text {line.strip()!r} before the first [SECTION]")
    return entries


def parse_tir(text: str, source: str = "<tir>") -> MagicFormulaTyre:
    """Parse the text of a ``.tir`` property file into a :class:`MagicFormulaTyre`.

    Raises:
        TirError: malformed line, non-numeric value, duplicate or missing required key,
            non-SI ``[UNITS]``, or a FITTYP outside the MF 5.x family.
    """
    check_x64()
    fields = {f.name.upper(): f for f in coefficient_fields()}
    values: dict[str, float] = {}
    extras: list[tuple[str, str, str]] = []
    seen: dict[str, int] = {}
    fittyp = None
    has_relaxation_section = False
    for section, key, raw, lineno in _parse(text, source):
        where = f"{source}:{lineno} [{section}]"
        if key != _TABLE:
            ident = key if key in fields else f"{section}.{key}"
            if ident in seen:
                raise TirError(f"{where}: duplicate key {key} (first on line {seen[ident]})")
            seen[ident] = lineno
        if section == "UNITS" and key != _TABLE:
            unit = raw.strip("'").strip().lower()
            if key in SI_UNITS and unit not in SI_UNITS[key]:
                raise TirError(
                    f"{where}: {key} = {raw} is not supported; jaxveh reads SI .tir files "
                    f"({key} = '{_UNITS_OUT[key]}')"
                )
            if key not in SI_UNITS:
                extras.append((section, key, raw))
        elif key == "FITTYP":
            fittyp = int(_to_float(raw, key, where))
            if fittyp not in SUPPORTED_FITTYP:
                raise TirError(
                    f"{where}: FITTYP = {fittyp} is not supported; this reader implements the "
                    f"MF 5.2 family (FITTYP {', '.join(map(str, SUPPORTED_FITTYP))}); MF 6.x files "
                    f"(FITTYP 61/62) need another model"
                )
        elif key in fields:
            values[fields[key].name] = _to_float(raw, key, where)
            has_relaxation_section |= section == "RELAXATION_LENGTH"
        else:
            extras.append((section, key, raw))
    if fittyp is None:
        raise TirError(f"{source}: missing required key FITTYP in [MODEL]")
    for key, f in fields.items():
        if f.metadata["required"] and f.name not in values:
            raise TirError(f"{source}: missing required key {key} in [{f.metadata['section']}] ({f.metadata['doc']})")
    _check_ranges(values, source)
    mf52 = values.get("ptx1", 0.0) != 0.0 and values.get("pty1", 0.0) != 0.0
    model = "mf52" if mf52 and not has_relaxation_section else "constant"
    try:
        return MagicFormulaTyre(**values, fittyp=fittyp, relaxation_model=model, extras=tuple(extras))
    except ParameterError as e:
        raise TirError(f"{source}: {e}") from None


def _check_ranges(values: dict[str, float], source: str) -> None:
    """Reject values for which the Magic Formula has no meaning."""
    for key in ("fnomin", "unloaded_radius", "pcx1", "pcy1", "pdx1", "pdy1", "qcz1", "pky2"):
        if values[key] <= 0.0:
            raise TirError(f"{source}: {key.upper()} = {values[key]:g} must be > 0")
    for key in ("vxlow", "longvl", "vertical_stiffness", "lfzo", "lmux", "lmuy"):
        if key in values and values[key] <= 0.0:
            raise TirError(f"{source}: {key.upper()} = {values[key]:g} must be > 0")


def read_tir(path: str | Path) -> MagicFormulaTyre:
    """Read a ``.tir`` property file (SI units, FITTYP 5, 6 or 21).

    Raises:
        TirError: see :func:`parse_tir`; ``FileNotFoundError`` if the file is missing.
    """
    path = Path(path)
    return parse_tir(path.read_text(encoding="utf-8", errors="replace"), str(path))


def _fmt(value) -> str:
    """Shortest text that reads back to the same float64."""
    return repr(float(np.asarray(value)))


def format_tir(tyre: MagicFormulaTyre) -> str:
    """The ``.tir`` text of a tyre: SI units, every coefficient, unknown entries kept."""
    by_section: dict[str, list[tuple[str, str, str]]] = {}
    for f in coefficient_fields():
        section = f.metadata["section"]
        if section == "RELAXATION_LENGTH" and tyre.relaxation_model != "constant":
            continue
        by_section.setdefault(section, []).append((f.name.upper(), _fmt(getattr(tyre, f.name)), f.metadata["doc"]))
    extra_sections: dict[str, list[tuple[str, str]]] = {}
    for section, key, raw in tyre.extras:
        extra_sections.setdefault(section, []).append((key, raw))

    lines: list[str] = []

    def header(name: str) -> None:
        lines.append(f"${'-' * 60}{name.lower()}")
        lines.append(f"[{name}]")

    def extra_lines(section: str) -> None:
        for key, raw in extra_sections.pop(section, []):
            lines.append(raw if key == _TABLE else f"{key:<25}= {raw}")

    header("MDI_HEADER")
    given = {k for k, _ in extra_sections.get("MDI_HEADER", [])}
    lines += [f"{k:<25}= {v}" for k, v in _HEADER_OUT if k not in given]
    extra_lines("MDI_HEADER")
    header("UNITS")
    lines += [f"{k:<25}= '{v}'" for k, v in _UNITS_OUT.items()]
    extra_lines("UNITS")
    header("MODEL")
    lines.append(f"{'FITTYP':<25}= {tyre.fittyp:<20} $Magic Formula version number")
    extra_lines("MODEL")
    for section, entries in by_section.items():
        if section != "MODEL":
            header(section)
        for key, value, doc in entries:
            lines.append(f"{key:<25}= {value:<20} ${doc}")
        extra_lines(section)
    for section in list(extra_sections):
        header(section)
        extra_lines(section)
    return "\n".join(lines) + "\n"


def write_tir(path: str | Path, tyre: MagicFormulaTyre) -> Path:
    """Write a tyre as a ``.tir`` property file; returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(format_tir(tyre), encoding="utf-8")
    return path


def fsae_tir_path() -> Path:
    """Path of the shipped Goodyear FSAE 20.0x7.0-13 ``.tir`` file (Appendix B, Fig. B.1)."""
    return Path(str(importlib.resources.files("jaxveh.tyre") / "data" / _FSAE_FILE))


def load_fsae_tyre() -> MagicFormulaTyre:
    """The thesis's FSAE tyre (Goodyear 20.0x7.0-13), coefficients derived to match Fig. B.1."""
    return read_tir(fsae_tir_path())
