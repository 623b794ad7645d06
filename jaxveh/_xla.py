"""XLA CPU options jaxveh sets when it is imported (docs/manoeuvre.md, "Speed").

XLA's newer CPU fusion emitters take about twice as long as the classic loop emitters to
compile the car's programs on these machines. Measured 2026-12-05 in fresh
processes on the fast car's 6-mode step steer: the step-steer program compiles in 23 s
instead of 46 s and its steady-state program in 15 s instead of 24 s; one run takes
0.12-0.14 s instead of 0.16 s; vmapped batches lose about a tenth (a batch of 64 on 2 cores
30-33 against 37 simulations/s, where the newer emitters vectorise across the batch
better); the results agree to round-off. Compilation being what users of the car wait for
most (docs/manoeuvre.md, "Compilation"), :func:`apply_cpu_flags` adds
``--xla_cpu_use_fusion_emitters=false`` to ``XLA_FLAGS`` before JAX starts its CPU backend;
``JAXVEH_XLA_FLAGS=0`` leaves ``XLA_FLAGS`` alone (large vmapped batches may prefer that).

It was opt-in until then: in its first benchmark a vmapped batch of 16 step steers hung
twice in jaxlib 0.10's LAPACK thread pool, two batched LAPACK calls each waiting for the
other's threads. That hang is jaxlib's, not the emitters' (sweeps met it without them), and
the batched LAPACK call it was met in, the IMEX stage solves' LU, has since run one system
after the other (:mod:`jaxveh._linalg`); batches of 1, 16 and 64 then ran to the end with
the flag, in one call and spread over the cores.

XLA aborts the process on a flag it does not know, so the flag is added only for the jaxlib
versions it was measured on (:data:`TESTED_JAXLIB`) and never when ``XLA_FLAGS`` already
names it. It has no effect when a JAX computation ran before jaxveh was imported (the
backend reads ``XLA_FLAGS`` once).
"""

import os

#: ``(major, minor)`` jaxlib versions the flags were measured on.
TESTED_JAXLIB = ((0, 10),)
#: The flags, ``--name=value``.
CPU_FLAGS = ("--xla_cpu_use_fusion_emitters=false",)


def _jaxlib_version() -> tuple[int, ...]:
    from jaxlib import version

    return tuple(int(part) for part in version.__version__.split(".")[:2])


def apply_cpu_flags(environ=os.environ, jaxlib_version: tuple[int, ...] | None = None) -> tuple[str, ...]:
    """Add :data:`CPU_FLAGS` to ``environ["XLA_FLAGS"]`` where allowed (module docs); return
    the flags added. ``JAXVEH_XLA_FLAGS``: "1" (the default, also when unset or empty) or "0"
    (add nothing); any other value raises ``ValueError``."""
    setting = environ.get("JAXVEH_XLA_FLAGS", "") or "1"
    if setting not in ("0", "1"):
        raise ValueError(f"JAXVEH_XLA_FLAGS = {setting!r} is not allowed: '1' (the default: jaxveh sets its XLA "
                         "CPU flags) or '0' (leave XLA_FLAGS alone)")
    if setting == "0":
        return ()
    version = _jaxlib_version() if jaxlib_version is None else tuple(jaxlib_version)
    if version[:2] not in TESTED_JAXLIB:
        return ()
    current = environ.get("XLA_FLAGS", "")
    added = tuple(flag for flag in CPU_FLAGS if flag.split("=")[0] not in current)
    if added:
        environ["XLA_FLAGS"] = " ".join([current, *added]).strip()
    return added
