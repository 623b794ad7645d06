"""XLA CPU options jaxveh can set when it is imported, opt-in (docs/manoeuvre.md, "Speed").

XLA's newer CPU fusion emitters compile the car's vector field into code that runs about a
third slower, and compiles about a third slower, than the classic loop emitters on these
machines (the fast car's step steer: one evaluation 94 -> 71 us, compilation 46 -> 34 s,
the same results to round-off). With ``JAXVEH_XLA_FLAGS=1`` :func:`apply_cpu_flags` adds
``--xla_cpu_use_fusion_emitters=false`` to ``XLA_FLAGS`` before JAX starts its CPU backend.
It is off by default: with it, a vmapped batch of 16 step steers hung twice in jaxlib's
LAPACK thread pool (docs/manoeuvre.md, "Speed"), which without it happened only in sweeps.

XLA aborts the process on a flag it does not know, so the flag is added only for the jaxlib
versions it was measured on (:data:`TESTED_JAXLIB`) and never when ``XLA_FLAGS`` already
names it. It has no effect when a JAX computation ran before jaxveh was imported (the backend reads ``XLA_FLAGS`` once).
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
    the flags added."""
    if environ.get("JAXVEH_XLA_FLAGS", "0") != "1":
        return ()
    version = _jaxlib_version() if jaxlib_version is None else tuple(jaxlib_version)
    if version[:2] not in TESTED_JAXLIB:
        return ()
    current = environ.get("XLA_FLAGS", "")
    added = tuple(flag for flag in CPU_FLAGS if flag.split("=")[0] not in current)
    if added:
        environ["XLA_FLAGS"] = " ".join([current, *added]).strip()
    return added
