"""Tube sizes of the chassis frame as design variables of the car (study (d), "the lightest
frame", docs/objectives.md): the whole chain frame -> FE model -> modal reduction -> car ->
objective, differentiated end to end.

A variable's path ``frame.sections.NAMES.QUANTITY`` sets the outer ``diameter`` or the wall
``thickness`` (m) of one or more cross sections of the car's frame (the car file's
``[files] frame``), or multiplies them (``diameter_scale``, ``thickness_scale``: 1 is the
car file's frame); ``NAMES`` joins section names with ``+`` for one gauge or one factor
shared by several sections (``frame.sections.rail+hoop.thickness``). Each evaluation
assembles the frame, solves its free-free eigenproblem and rebuilds the car's chassis from
it with :func:`jaxveh.fe.frame_modal_body_like`: the same points, mode count, damping and
stiffness multipliers as the base car's chassis, each mode kept on its coordinate and sign. The car's sprung mass and
inertia stay the car file's (Table B.1 gives them for the whole car): the frame's own mass
is the objective ``chassis_mass``.
"""

import re
from importlib import resources
from pathlib import Path
from typing import NamedTuple

import equinox as eqx
import jax.numpy as jnp
import tomllib

import jaxveh.fe as fe
from jaxveh import ParameterError
from jaxveh.params import read_car_file

#: Prefix of the frame variables' paths.
FRAME_PREFIX = "frame.sections."
#: What a frame variable sets: a size (m) or a multiplier of the base frame's size (1).
FRAME_QUANTITIES = ("diameter", "thickness", "diameter_scale", "thickness_scale")
#: The shipped frame's name in a car file's ``[files] frame``.
SHIPPED_FRAME = "fsae_2009_frame.toml"


class FrameVariable(NamedTuple):
    """The sections (names) whose ``quantity`` (:data:`FRAME_QUANTITIES`) one variable sets."""

    sections: tuple[str, ...]
    quantity: str

    @property
    def size(self) -> str:
        """The section attribute set: ``diameter`` or ``thickness``."""
        return self.quantity.removesuffix("_scale")

    @property
    def is_scale(self) -> bool:
        return self.quantity.endswith("_scale")


def is_frame_path(path: str) -> bool:
    """Whether a variable's ``path`` names frame sizes (``frame.``...)."""
    return isinstance(path, str) and path.strip().startswith("frame.")


def parse_frame_path(path: str) -> FrameVariable:
    """The :class:`FrameVariable` of ``frame.sections.NAME[+NAME...].QUANTITY``;
    ``ParameterError`` saying the allowed form."""
    form = (f"allowed {FRAME_PREFIX}NAME.QUANTITY with NAME a section of the frame (several joined by '+') and "
            f"QUANTITY one of {', '.join(FRAME_QUANTITIES)}")
    path = path.strip()
    body = path[len(FRAME_PREFIX):] if path.startswith(FRAME_PREFIX) else ""
    names, _, quantity = body.rpartition(".")
    sections = tuple(names.split("+")) if names else ()
    if quantity not in FRAME_QUANTITIES or not sections or not all(re.fullmatch(r"[A-Za-z0-9_-]+", s)
                                                                   for s in sections):
        raise ParameterError(f"is not a frame path: {form}")
    if len(set(sections)) != len(sections):
        raise ParameterError(f"repeats a section: {form}, each section once")
    return FrameVariable(sections, quantity)


def frame_file(vehicle) -> str:
    """The frame file a car file (None: the shipped car) names in ``[files] frame``."""
    return read_car_file(vehicle).files["frame"]


def load_car_frame(vehicle) -> fe.Frame:
    """The chassis frame of a car file (None: the shipped car)."""
    name = frame_file(vehicle)
    return fe.load_frame() if name == SHIPPED_FRAME else fe.load_frame(name)


def frame_text(vehicle) -> str:
    """The TOML text of a car file's frame."""
    name = frame_file(vehicle)
    if name == SHIPPED_FRAME:
        return (resources.files("jaxveh.fe") / "data" / SHIPPED_FRAME).read_text()
    return Path(name).read_text()


def check_frame_variables(frame: fe.Frame, variables) -> None:
    """Each of ``variables`` (``((FrameVariable, lower, upper), ...)``) names sections the
    frame has, with the size it sets, each section's size set by one variable at most, and
    bounds the sections allow (> 0; a wall at most half the section's diameter, or of its
    smaller side); ``ParameterError`` starting with ``variables[i]``. Entries with ``var``
    None (a study's other variables) are skipped."""
    seen = {}
    for i, (var, lower, upper) in enumerate(variables):
        if var is None:
            continue
        where = f"variables[{i}] ({FRAME_PREFIX}{'+'.join(var.sections)}.{var.quantity})"
        for name in var.sections:
            if name not in frame.section_names:
                raise ParameterError(f"{where} names the section {name!r}, which the frame does not have: allowed "
                                     f"{', '.join(frame.section_names)}")
            section = frame.sections[frame.section_names.index(name)]
            if not hasattr(section, var.size):
                raise ParameterError(f"{where} sets the {var.size} of section {name!r}, a {type(section).__name__}, "
                                     "which has none: allowed thickness (and diameter for circular tubes)")
            if (name, var.size) in seen:
                raise ParameterError(f"{where} sets the {var.size} of section {name!r}, which {seen[name, var.size]} "
                                     "sets: each size by one variable")
            seen[name, var.size] = where
        if not lower > 0.0:
            raise ParameterError(f"{where} has lower = {lower!r}: a size or a factor needs lower > 0")
        if var.size == "thickness":
            for name in var.sections:
                section = frame.sections[frame.section_names.index(name)]
                half = 0.5 * float(section.diameter if hasattr(section, "diameter")
                                   else min(section.width, section.height))
                most = half / float(section.thickness) if var.is_scale else half
                if upper > most:
                    raise ParameterError(f"{where} has upper = {upper!r}, a wall thicker than half of section "
                                         f"{name!r} ({half!r} m): allowed upper <= {most!r}")


def section_sizes(frame: fe.Frame, assignments) -> dict:
    """``{(section, size): value (m)}`` of the assignments ``((FrameVariable, value),
    ...)`` on the base ``frame`` (factors multiply its sizes); traceable."""
    out = {}
    for var, value in assignments:
        if var.quantity not in FRAME_QUANTITIES:
            raise ParameterError(f"FrameVariable.quantity = {var.quantity!r} is not allowed: one of "
                                 f"{', '.join(FRAME_QUANTITIES)}")
        for name in var.sections:
            if name not in frame.section_names:
                raise ParameterError(f"FrameVariable.sections names {name!r}, which the frame does not have: "
                                     f"allowed {', '.join(frame.section_names)}")
            base = getattr(frame.sections[frame.section_names.index(name)], var.size)
            out[name, var.size] = value * base if var.is_scale else jnp.asarray(value, jnp.float64)
    return out


def set_frame_sizes(frame: fe.Frame, assignments) -> fe.Frame:
    """``frame`` with the assignments ``((FrameVariable, value), ...)`` made (traceable)."""
    sections = list(frame.sections)
    for (name, size), value in section_sizes(frame, assignments).items():
        k = frame.section_names.index(name)
        sections[k] = eqx.tree_at(lambda s, q=size: getattr(s, q), sections[k], value)
    return fe.with_sections(frame, sections)


def car_with_frame(car, frame: fe.Frame):
    """``car`` with its chassis rebuilt from ``frame`` (:func:`jaxveh.fe.frame_modal_body_like`
    of the car's own chassis). Pure and differentiable in the frame's sizes."""
    if car.params.chassis is None:
        raise ParameterError("frame variables need a flexible chassis: the car has modes = 0")
    return eqx.tree_at(lambda c: c.params.chassis, car, fe.frame_modal_body_like(frame, car.params.chassis))


def _set_size(text: str, section: str, key: str, value_mm: float) -> str:
    pattern = re.compile(rf"(^\s*\[sections\.{re.escape(section)}\][^\[]*?^\s*{key}\s*=\s*)([^#\n]+?)(\s*(#[^\n]*)?)$",
                         re.MULTILINE | re.DOTALL)
    new, count = pattern.subn(lambda m: f"{m.group(1)}{value_mm!r}{m.group(3)}", text, count=1)
    if count != 1:
        raise ParameterError(f"the frame file has no line '{key} = ...' under [sections.{section}]: write its "
                             "sections as tables to have the optimum written back")
    return new


def optimum_frame_text(text: str, frame: fe.Frame, assignments) -> str:
    """The frame file ``text`` (of the base ``frame``) with the sizes of ``assignments``
    (``((FrameVariable, value), ...)``) written in (mm, the file's unit), checked by
    reading it back."""
    sizes = {k: float(v) for k, v in section_sizes(frame, assignments).items()}
    for (name, size), value in sizes.items():
        text = _set_size(text, name, size, round(value * 1e3, 9))
    written = fe.frame_from_dict(tomllib.loads(text), "optimum frame")
    for (name, size), value in sizes.items():
        got = float(getattr(written.sections[written.section_names.index(name)], size))
        if abs(got - value) > 1e-11:
            raise ParameterError(f"writing the optimum frame: section {name!r} {size} reads back as {got!r} m, not "
                                 f"{value!r} m")
    return text
