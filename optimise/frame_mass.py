"""Worked example: minimum chassis frame mass for a target torsional stiffness and first
free-free frequency, with tube diameters and wall thicknesses as design variables.

The FE pipeline of :mod:`jaxveh.fe` is differentiable, so the constrained problem

    min  mass(D, t)   s.t.  k_torsion(D, t) >= k_target,  f_1(D, t) >= f_target,
         D_min <= D <= D_max,  t_min <= t <= t_max

is solved with Adam on log-sizes and a quadratic exterior penalty whose weight grows
each phase (a classic penalty continuation). Gradients of the torsion test and of the
first eigenfrequency come from ``jax.grad`` through the assembly, the Cholesky static
solve and the eigen-solve.

    .venv/bin/python -m optimise.frame_mass --steps 40
"""

import argparse
import math
import time
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import optax

import jaxveh.fe as fe
from jaxveh import ParameterError

#: Practical tube limits (as in experiments/fe_tune_frame.py): 15-35 mm diameter,
#: 0.8-3 mm wall (0.8 mm = 0.032 in, the thinnest common chromoly frame tube).
D_BOUNDS = (15e-3, 35e-3)
T_BOUNDS = (0.8e-3, 3.0e-3)


def _sizes(x):
    """Log-sizes -> (diameters, thicknesses) clipped smoothly into the bounds (m)."""
    logd, logt = x
    d = D_BOUNDS[0] + (D_BOUNDS[1] - D_BOUNDS[0]) * jax.nn.sigmoid(logd)
    t = T_BOUNDS[0] + (T_BOUNDS[1] - T_BOUNDS[0]) * jax.nn.sigmoid(logt)
    return d, t


def _frame(frame, x):
    d, t = _sizes(x)
    return fe.with_sections(frame, tuple(fe.CircularTube(a, b) for a, b in zip(d, t)))


def _metrics(frame):
    return fe.frame_mass(frame), fe.torsion_test(frame).stiffness_nm_per_deg, fe.chassis_modes(frame, 1)[0][0]


def _inverse(v, lo, hi):
    p = jnp.clip((v - lo) / (hi - lo), 1e-3, 1 - 1e-3)
    return jnp.log(p / (1 - p))


def minimise_frame_mass(
    frame: fe.Frame,
    k_target: float = 385.0,
    f_target: float = 38.0,
    steps: int = 40,
    phases: int = 3,
    learning_rate: float = 0.05,
    verbose: bool = True,
):
    """Return the lightest frame found and the history ``[(mass, k, f1), ...]``.

    Args:
        frame: starting design; every section must be a :class:`jaxveh.fe.CircularTube`.
        k_target: minimum torsional stiffness (Nm/deg, thesis test set-up).
        f_target: minimum first free-free frequency (Hz).
        steps: Adam steps per penalty phase; phases: number of penalty weights (x10 each).
        Targets and the learning rate must be > 0, ``steps`` and ``phases`` ints >= 1
        (``ParameterError``).
    """
    if not all(isinstance(s, fe.CircularTube) for s in frame.sections):
        raise ValueError("minimise_frame_mass handles circular tubes only")
    for name, value in (("k_target", k_target), ("f_target", f_target), ("learning_rate", learning_rate)):
        if not (math.isfinite(float(value)) and float(value) > 0.0):
            raise ParameterError(f"{name} must lie in (0, inf); got {value!r}")
    for name, value in (("steps", steps), ("phases", phases)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ParameterError(f"{name} must be a Python int >= 1; got {value!r}")
    x = (
        _inverse(jnp.stack([s.diameter for s in frame.sections]), *D_BOUNDS),
        _inverse(jnp.stack([s.thickness for s in frame.sections]), *T_BOUNDS),
    )
    m0 = fe.frame_mass(frame)

    @eqx.filter_jit
    def step(x, state, weight):
        def loss(x):
            m, k, f1 = _metrics(_frame(frame, x))
            viol = jax.nn.relu(1.0 - k / k_target) ** 2 + jax.nn.relu(1.0 - f1 / f_target) ** 2
            return m / m0 + weight * viol, (m, k, f1)

        (val, aux), g = jax.value_and_grad(loss, has_aux=True)(x)
        upd, state = opt.update(g, state)
        return optax.apply_updates(x, upd), state, aux

    opt = optax.adam(learning_rate)
    state = opt.init(x)
    history = []
    for phase in range(phases):
        weight = jnp.asarray(10.0 * 10.0**phase)
        for i in range(steps):
            x, state, (m, k, f1) = step(x, state, weight)
            history.append((float(m), float(k), float(f1)))
            if verbose and (i % 10 == 0 or i == steps - 1):
                print(
                    f"phase {phase} step {i:3d}: mass {float(m):6.2f} kg  k {float(k):6.1f} Nm/deg  "
                    f"f1 {float(f1):6.2f} Hz"
                )
    return _frame(frame, x), history


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frame", type=Path, default=None, help="frame TOML (default: shipped FSAE frame)")
    ap.add_argument("--k-target", type=float, default=385.0, help="Nm/deg")
    ap.add_argument("--f-target", type=float, default=38.0, help="Hz")
    ap.add_argument("--steps", type=int, default=40, help="Adam steps per penalty phase")
    args = ap.parse_args()
    frame = fe.load_frame(args.frame)
    t0 = time.perf_counter()
    best, _ = minimise_frame_mass(frame, args.k_target, args.f_target, args.steps)
    m, k, f1 = (float(v) for v in _metrics(best))
    m0, k0, f0 = (float(v) for v in _metrics(frame))
    print(f"start : mass {m0:.2f} kg, k {k0:.1f} Nm/deg, f1 {f0:.2f} Hz")
    print(f"result: mass {m:.2f} kg, k {k:.1f} Nm/deg, f1 {f1:.2f} Hz ({time.perf_counter() - t0:.0f} s)")
    for name, s in zip(best.section_names, best.sections):
        print(f"  {name:16s} D {float(s.diameter) * 1e3:6.2f} mm  t {float(s.thickness) * 1e3:5.2f} mm")


if __name__ == "__main__":
    main()
