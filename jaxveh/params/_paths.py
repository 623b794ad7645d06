"""Leaves of a parameter pytree by path: ``"coupling"``, ``"arb_rates[0]"``,
``"chassis.stiffness_scale[2]"``, ``"vehicle.hard_points_front.points[4, 2]"``.

A path is dotted attribute names, the last one optionally followed by integer indices into
its array. Used by ``jaxveh simulate --param PATH=VALUE`` and the optimiser's design
variables; errors name the path and what exists there.
"""

import re

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._core import ParameterError

_PATH = re.compile(r"^\s*([A-Za-z_]\w*(?:\.[A-Za-z_]\w*)*)\s*(?:\[\s*(-?\d+(?:\s*,\s*-?\d+)*)\s*\])?\s*$")


def parse_path(path: str) -> tuple[tuple[str, ...], tuple[int, ...]]:
    """``(attribute names, indices)`` of ``path``; ``ParameterError`` if malformed."""
    match = _PATH.match(path) if isinstance(path, str) else None
    if match is None:
        raise ParameterError(f"parameter path {path!r} is malformed: allowed dotted field names with optional "
                             "integer indices at the end, e.g. 'arb_rates[0]' or 'chassis.stiffness_scale[2]'")
    names = tuple(match.group(1).split("."))
    indices = tuple(int(i) for i in match.group(2).split(",")) if match.group(2) else ()
    return names, indices


def _field(node, path: str, part: str):
    if isinstance(getattr(type(node), part, None), property):
        raise ParameterError(f"parameter path {path!r}: {type(node).__name__}.{part} is derived from other fields "
                             "(a property), not a leaf; vary the fields it is computed from")
    if node is None or not hasattr(node, part):
        fields = sorted(k for k in getattr(node, "__dataclass_fields__", {}) if not k.startswith("_"))
        known = f"; known fields: {', '.join(fields)}" if fields else ""
        raise ParameterError(f"parameter path {path!r}: {type(node).__name__} has no field {part!r}{known}")
    return getattr(node, part)


def get_at(tree, path: str):
    """The value at ``path`` in ``tree`` (a leaf, or one element of it with indices)."""
    names, indices = parse_path(path)
    node = tree
    for part in names:
        node = _field(node, path, part)
    if not indices:
        return node
    shape = np.shape(node)
    if len(indices) != len(shape) or not all(-n <= i < n for i, n in zip(indices, shape)):
        raise ParameterError(f"parameter path {path!r}: indices {list(indices)} do not fit the shape {list(shape)} "
                             f"of {'.'.join(names)}")
    return node[indices]


def set_at(tree, path: str, value):
    """Copy of ``tree`` with the value at ``path`` replaced by ``value`` (float64; a whole
    leaf keeps its shape: a scalar value fills it, an array must match it)."""
    names, indices = parse_path(path)
    old = get_at(tree, path)
    leaf_path = ".".join(names)
    leaf = get_at(tree, leaf_path)
    value = jnp.asarray(value, dtype=jnp.float64)
    if indices:
        if value.ndim:
            raise ParameterError(f"parameter path {path!r}: one element takes a scalar, got shape {list(value.shape)}")
        new = jnp.asarray(leaf, dtype=jnp.float64).at[indices].set(value)
    else:
        if value.shape not in ((), np.shape(old)):
            raise ParameterError(f"parameter path {path!r}: shape {list(value.shape)} does not fit "
                                 f"{list(np.shape(old))}")
        new = jnp.broadcast_to(value, np.shape(old))

    def where(t):
        node = t
        for part in names:
            node = getattr(node, part)
        return node

    return eqx.tree_at(where, tree, new)


def set_all(tree, values: dict):
    """Copy of ``tree`` with every ``path: value`` of ``values`` set (:func:`set_at`)."""
    for path, value in values.items():
        tree = set_at(tree, path, value)
    return tree
