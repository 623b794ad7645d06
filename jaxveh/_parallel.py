"""A batch over the machine's cores: compiled, vmapped calls on contiguous parts of the
batch, from one thread per core.

Why: XLA's CPU programs of the car are long chains of small operations that run on the
calling thread; a vmapped batch widens the operations but keeps one thread, so a batch of
16 step steers kept 1.4 of this machine's two cores busy (docs/manoeuvre.md, "Speed").
JAX releases the Python lock while a compiled program runs, so the same program called
from two threads on two halves of the batch runs on both cores at once.

The parts are padded to one size with copies of the batch's last element, so the function
compiles once; the padding's results are dropped. The first call for a function and part
size runs its first part alone (the compilation, once), the other parts after it together.
"""

import os
from concurrent.futures import ThreadPoolExecutor

import jax
import numpy as np

from ._core import ParameterError

_compiled: set = set()  # (id(fn), part size) already called once


def core_count() -> int:
    """Cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


def _part(batched, start: int, stop: int, size: int):
    """Rows ``start:stop`` of every leaf, padded to ``size`` rows with the last row."""
    def rows(x):
        part = x[start:stop]
        extra = size - part.shape[0]
        return part if extra == 0 else np.concatenate([np.asarray(part), np.repeat(np.asarray(x[-1:]), extra, 0)])

    return jax.tree.map(rows, batched)


def map_on_cores(fn, batched, cores: int | None = None, part_size: int | None = None):
    """``fn(batched)`` for a function ``fn`` vectorised over the leading axis of every leaf
    of ``batched`` (e.g. ``jax.jit(jax.vmap(...))``), evaluated as calls on contiguous parts
    of the batch from ``cores`` threads at once (default: every core of the machine,
    :func:`core_count`), each thread taking the next part when done; the outputs are joined
    along their leading axis as NumPy arrays. ``part_size``: the most elements one call
    takes (default: the batch split evenly over the cores). Smaller parts can be faster:
    a vmapped adaptive solve steps until its slowest member is done and its arrays grow
    with the part (docs/manoeuvre.md, "Speed": step steers of the car in parts of 32 against
    128). A batch smaller than ``cores`` takes one call per element. Each part's results
    are those of one call on that part; against one call on the whole batch an adaptive
    solver's can differ at its tolerance (the batch size changes the round-off of XLA's
    batched kernels, and with it accepted steps: 16 step steers at rtol 1e-4, 6e-6 of the
    yaw rate's peak; a single run differs from its batch's member as much). The first call
    for ``fn`` (the same function object) and a part size runs one part alone, so that it
    compiles once."""
    sizes = {np.shape(x)[0] if np.ndim(x) else None for x in jax.tree.leaves(batched)}
    if len(sizes) != 1 or None in sizes:
        raise ParameterError(f"map_on_cores: every leaf of the batch needs the same leading axis; got sizes {sizes}")
    n = sizes.pop()
    cores = core_count() if cores is None else cores
    if isinstance(cores, bool) or not isinstance(cores, int) or cores < 1:
        raise ParameterError(f"map_on_cores: cores must be an int >= 1; got {cores!r}")
    if part_size is not None and (isinstance(part_size, bool) or not isinstance(part_size, int) or part_size < 1):
        raise ParameterError(f"map_on_cores: part_size must be None or an int >= 1; got {part_size!r}")
    if n == 0:
        raise ParameterError("map_on_cores: the batch is empty")
    parts = min(cores, n) if part_size is None else max(min(cores, n), -(-n // part_size))
    size = -(-n // parts)
    chunks = [_part(batched, k * size, min((k + 1) * size, n), size) for k in range(parts) if k * size < n]

    def call(chunk):
        return jax.tree.map(np.asarray, jax.block_until_ready(fn(chunk)))

    key = (id(fn), size)
    first = [] if key in _compiled else [call(chunks[0])]
    _compiled.add(key)
    rest = chunks[len(first):]
    if len(rest) <= 1 or cores == 1:
        outs = first + [call(chunk) for chunk in rest]
    else:
        with ThreadPoolExecutor(min(cores, len(rest))) as pool:
            outs = first + list(pool.map(call, rest))
    return jax.tree.map(lambda *x: np.concatenate(x)[:n], *outs)
