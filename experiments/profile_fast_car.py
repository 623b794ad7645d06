"""Cost of the fast car's vector field, piece by piece: top-level XLA operations of each
compiled piece (the ENTRY computation, counted by kind; on XLA CPU the cost follows their
number, not the flops) and its time per evaluation inside a compiled loop (best of
``--repeats``; the loop removes the dispatch overhead of one call).

Pieces: the kinematic map's guess, the corner poses, the corner motion, the car motion,
the ``Kinematics`` for the force elements, each of the library car's force elements, the
fast car's four-corner push-rod suspension (:mod:`jaxveh.vehicle._fast_suspension`) and the
full evaluation (``q_dot``, ``u_dot``, ``aux_dot``).

``--by-source N`` also attributes the full evaluation's operations to the innermost
``jaxveh`` function on their trace stack (from the stack-frame tables XLA prints with the
compiled program) and prints the ``N`` functions with the most: where to cut operations.

``--reverse`` profiles each piece's vector-Jacobian product instead, its forward time beside
(``jax.vjp`` with respect to the piece's array arguments, applied to a cotangent of ones:
the linearisation and the transpose, what a reverse pass runs per evaluation); the full
evaluation's product is also taken with respect to the fast model (the car's parameters,
as the replayed solve's reverse pass differentiates them), and ``--by-source`` then
attributes that program's operations. The car is traced with its run-time checks off, as
``simulate`` traces it.

    .venv/bin/python experiments/profile_fast_car.py [--json results/profile_fast_car.json] [--by-source 30] [--reverse]

``--json`` writes ``{"pieces": [...], "full_by_source": {...} or null}``.
"""

import argparse
import collections
import json
import re
import time
from pathlib import Path

import jax
import jax.numpy as jnp

import jaxveh  # noqa: F401  (float64)
import jaxveh.multibody as mb
from jaxveh._core import run_time_checks_off
from jaxveh.vehicle import (
    ConstantSpeed,
    _corner_kinematics as ck,
    _fast as fast,
    _fast_suspension as fs,
    car_elements,
    load_car,
    steering,
)

LOOP = 200


def compiled_text(f, *args) -> str:
    """The text of ``f`` compiled for ``args`` (XLA's optimised program)."""
    return jax.jit(f).lower(*args).compile().as_text()


def entry_ops(text: str) -> collections.Counter:
    """Top-level operations of a compiled program (its ENTRY computation) by kind."""
    entry = text.split("\nENTRY")[1]
    return collections.Counter(re.findall(r"= \S+ ([\w-]+)\(", entry))


#: Operations of the ENTRY computation that are bookkeeping, not kernels.
BOOKKEEPING = ("parameter", "constant", "get-tuple-element", "tuple", "bitcast")


def _stack_tables(text: str) -> dict[int, tuple[str, str, int, int]]:
    """``{frame id: (file, function, line, parent frame id)}`` from the tables at the end of
    a compiled program's text (empty when this XLA prints none)."""
    sections: dict[str, list[str]] = {}
    current = None
    for line in text.splitlines():
        if line in ("FileNames", "FunctionNames", "FileLocations", "StackFrames"):
            current = sections.setdefault(line, [])
        elif current is not None and re.match(r"\d+ ", line):
            current.append(line)
        else:
            current = None
    files = {int(m[1]): m[2] for m in (re.match(r'(\d+) "(.*)"', x) for x in sections.get("FileNames", []))}
    functions = {int(m[1]): m[2] for m in (re.match(r'(\d+) "(.*)"', x) for x in sections.get("FunctionNames", []))}
    locations = {int(m[1]): (files[int(m[2])], functions[int(m[3])], int(m[4])) for m in (
        re.match(r"(\d+) \{file_name_id=(\d+) function_name_id=(\d+) line=(\d+)", x)
        for x in sections.get("FileLocations", []))}
    frames = {}
    for x in sections.get("StackFrames", []):
        m = re.match(r"(\d+) \{file_location_id=(\d+)(?: parent_frame_id=(\d+))?", x)
        frames[int(m[1])] = (*locations[int(m[2])], int(m[3] or 0))
    return frames


def ops_by_source(text: str) -> collections.Counter:
    """Top-level operations of a compiled program by the innermost ``jaxveh`` function on
    their trace stack (``"module.py:function"``; ``"other"`` where none is recorded)."""
    frames = _stack_tables(text)
    entry = text.split("\nENTRY")[1].split("\n}\n")[0]
    counts: collections.Counter = collections.Counter()
    for line in entry.splitlines():
        kind = re.search(r"= \S+ ([\w-]+)\(", line)
        if not kind or kind[1] in BOOKKEEPING:
            continue
        frame = re.search(r"stack_frame_id=(\d+)", line)
        source, seen = "other", set()
        fid = int(frame[1]) if frame else 0
        while fid in frames and fid not in seen:
            seen.add(fid)
            file, function, _, parent = frames[fid]
            if "/jaxveh/" in file and "site-packages" not in file:
                source = f"{file.split('/jaxveh/')[-1]}:{function}"
                break
            fid = parent
        counts[source] += 1
    return counts


def loop_time(f, *args, repeats: int) -> float:
    """Seconds per evaluation of ``f`` inside a compiled loop of ``LOOP`` (best of
    ``repeats``); each iteration's arguments move by 1e-30 of the previous output's sum, so
    nothing is hoisted out of the loop."""

    def nudge(x, acc):
        return jax.tree.map(lambda leaf: leaf + 1e-30 * acc if jnp.issubdtype(leaf.dtype, jnp.floating) else leaf, x)

    def loop(*a):
        def body(_, acc):
            out = f(*nudge(a, acc))
            return sum(jnp.sum(leaf) for leaf in jax.tree.leaves(out))

        return jax.lax.fori_loop(0, LOOP, body, jnp.zeros(()))

    run = jax.jit(loop)
    jax.block_until_ready(run(*args))
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(run(*args))
        best = min(best, (time.perf_counter() - t0) / LOOP)
    return best


def pieces(with_model: bool = False):
    """``(name, function, arguments)`` of every piece at one state of the library car;
    ``with_model``: also the full evaluation as a function of the fast model."""
    car = load_car(modes=6)
    elements = car_elements(car, ConstantSpeed(25.0))
    inputs = steering(car, lambda t: 0.05 * jnp.sin(3.0 * t) + 0.02)
    model = jax.jit(fast.fast_model)(car)
    n = 14 + car.n_modes
    q = jnp.zeros(n).at[2].set(0.01).at[6:12].set(1e-4).at[12:16].set(0.004)
    u = jnp.zeros(n).at[0].set(25.0).at[3:6].set(0.1).at[6:12].set(0.02).at[12:16].set(0.05).at[16:].set(80.0)
    aux = jnp.full(10, 1e-3)
    rack, rack_rate = jnp.asarray(0.01), jnp.asarray(0.1)
    g, km = model.geometry, model.kmap
    travel, modes = q[12:16], q[6:12]

    def kinematics(q, u, aux):
        return fast.fast_dynamics(car, model, q, u, aux, 0.3, inputs, elements).kinematics

    kin = jax.jit(kinematics)(q, u, aux)
    suspensions = [e for e in elements if type(e).__name__ == "PushrodSuspension"]
    four = fs.four_corner_suspension(suspensions)
    yield "map guess", lambda tr: ck.map_guess(km, tr, jnp.broadcast_to(rack, (4,))), (travel,)
    yield "corner poses", lambda tr, md: ck.corner_poses(g, km, tr, rack, md), (travel, modes)
    yield "corner motion", lambda tr, md, ur: ck.corner_motion(g, km, tr, rack, md, ur[12:16], rack_rate,
                                                               ur[6:12], 0.0), (travel, modes, u)
    yield "car motion", lambda q, u: fast.car_motion(car, model, q, u, rack, rack_rate, 0.0), (q, u)
    yield "kinematics", kinematics, (q, u, aux)
    for k, e in enumerate(elements):
        yield f"{type(e).__name__} [{k}]", lambda kin, aux, e=e: mb.element_forces(
            car.system, model.params, (e,), kin, aux[: len(e.aux_names)]), (kin, aux)
    yield "four-corner suspension", lambda kin: fs.suspension_forces(four, kin), (kin,)
    yield "full", lambda q, u, aux: _outputs(fast.fast_dynamics(car, model, q, u, aux, 0.3, inputs, elements)), (
        q, u, aux)
    if with_model:
        yield "full with the model", lambda q, u, aux, model: _outputs(
            fast.fast_dynamics(car, model, q, u, aux, 0.3, inputs, elements)), (q, u, aux, model)


def _outputs(d):
    return d.q_dot, d.u_dot, d.aux_dot


def reverse(f):
    """``f``'s vector-Jacobian product with respect to its arguments' floating leaves, applied
    to a cotangent of ones (a function of the same arguments)."""

    def product(*a):
        out, pull = jax.vjp(f, *a)
        return pull(jax.tree.map(jnp.ones_like, out))

    return product


def profile(args):
    """Rows ``{piece, ops, us, forward_us, by_kind}`` (printed as they come) and the full
    evaluation's (or product's, ``--reverse``) operations by source (or None)."""
    rows, sources = [], None
    by_source_of = "full with the model" if args.reverse else "full"
    print(f"{'piece':28s} {'ops':>5s} {'us':>8s} {'fwd us':>7s}  by kind")
    for name, f, a in pieces(with_model=args.reverse):
        forward_us = loop_time(f, *a, repeats=args.repeats) * 1e6 if args.reverse else None
        g = reverse(f) if args.reverse else f
        text = compiled_text(g, *a)
        ops = entry_ops(text)
        us = loop_time(g, *a, repeats=args.repeats) * 1e6
        kinds = {k: v for k, v in ops.most_common() if k != "parameter"}
        rows.append({"piece": name, "ops": sum(kinds.values()), "us": us, "forward_us": forward_us, "by_kind": kinds})
        shown = f"{forward_us:7.1f}" if forward_us is not None else f"{'':7s}"
        print(f"{name:28s} {sum(kinds.values()):5d} {us:8.1f} {shown}  {dict(list(kinds.items())[:6])}", flush=True)
        if name == by_source_of and args.by_source:
            sources = ops_by_source(text)
    return rows, sources


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, help="also write the table as JSON here")
    parser.add_argument("--repeats", type=int, default=5, help="timed loops per piece (best taken)")
    parser.add_argument("--by-source", type=int, default=0, metavar="N",
                        help="also list the N jaxveh functions with the most operations in the full evaluation")
    parser.add_argument("--reverse", action="store_true",
                        help="profile each piece's vector-Jacobian product (beside its forward time)")
    args = parser.parse_args()
    with run_time_checks_off():  # as simulate traces the car (and the loop's nudges may not pass them)
        rows, sources = profile(args)
    if sources is not None:
        what = "vector-Jacobian product (state and model)" if args.reverse else "evaluation"
        print(f"\nfull {what}, operations by source ({sum(sources.values())} in all)")
        for source, n in sources.most_common(args.by_source):
            print(f"{n:5d}  {source}")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        out = {"pieces": rows, "full_by_source": None if sources is None else dict(sources.most_common())}
        args.json.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
