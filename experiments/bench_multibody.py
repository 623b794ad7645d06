"""Benchmark of the multibody vector field (eq. 5.61) and of the Table 7.2 simplifications.

For the double pendulum, the quarter car and the flexible pendulum (2 modes): compile time
and evaluation time of the jitted vector field, single and vmapped over a batch of 64 states;
then, for the flexible pendulum, simulation wall time and deviation of every Table 7.2
option from the full model. Prints a table and writes JSON.

    .venv/bin/python experiments/bench_multibody.py --out results/bench_multibody
"""

import argparse
import json
import sys
import time
from pathlib import Path

import jax
import jax.numpy as jnp

import jaxveh  # noqa: F401  (float64)
from jaxveh import multibody as mb, vehicle
from jaxveh.multibody import _examples as ex

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _vehicle_topology import assembly_fixed, vehicle_scale_system  # noqa: E402

BATCH = 64


def _time(f, *args, repeats=200):
    t0 = time.perf_counter()
    jax.block_until_ready(f(*args))
    compile_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    for _ in range(repeats):
        out = f(*args)
    jax.block_until_ready(out)
    return compile_s, (time.perf_counter() - t0) / repeats


def cases():
    s, p = ex.double_pendulum()
    q, z = ex.double_pendulum_state(s, p, (0.3, -0.5), (1.0, 2.0))
    yield "double pendulum", s, p, q, z, None
    s, p = vehicle.quarter_car()
    q, _ = vehicle.quarter_car_kinematics(s, p, 0.01, 0.002)
    yield "quarter car", s, p, q, jnp.asarray([0.1, 30.0]), (lambda t: jnp.reshape(0.002 + 0.0 * t, (1,)))
    s, p = ex.flexible_pendulum()
    q, z = ex.flexible_pendulum_state(s, 0.3, (1e-4, -1e-4))
    q = mb.assemble(s, p, q, fixed=(5, 6, 7))
    yield "flexible pendulum (2 modes)", s, p, q, z.at[0].set(1.0), None
    s, p, q = vehicle_scale_system()
    rack = lambda t: jnp.reshape(0.0 * t, (1,))  # noqa: E731
    mb.check_rank(s, p, q, inputs=rack)
    z = jnp.zeros(s.n_dof).at[jnp.asarray([s.independent.index(s.y_index("chassis", "ux"))])].set(10.0)
    yield "vehicle topology (9 bodies, 6 modes)", s, p, q, z, rack


def bench_vector_fields():
    rows = []
    for name, system, params, q, z, inputs in cases():
        vf = mb.vector_field(system)
        args = (params, inputs, None, None)
        single = jax.jit(lambda t, q, z, vf=vf, args=args: vf(t, mb.State(q, z, jnp.zeros(0)), args))
        c1, e1 = _time(single, 0.0, q, z)
        qb = jnp.broadcast_to(q, (BATCH,) + q.shape)
        zb = jnp.broadcast_to(z, (BATCH,) + z.shape) * jnp.linspace(0.5, 1.5, BATCH)[:, None]
        batched = jax.jit(jax.vmap(lambda q, z, vf=vf, args=args: vf(0.0, mb.State(q, z, jnp.zeros(0)), args)))
        cb, eb = _time(batched, qb, zb, repeats=50)
        rows.append(
            {
                "system": name,
                "n_q": system.n_q,
                "n_constraints": system.n_constraints,
                "n_dof": system.n_dof,
                "compile_s": c1,
                "eval_us": e1 * 1e6,
                "compile_batch64_s": cb,
                "eval_batch64_us": eb * 1e6,
                "eval_per_state_batch64_us": eb * 1e6 / BATCH,
            }
        )
    return rows


def bench_vehicle_simulation():
    """1 s of free motion of the vehicle-scale topology (10 m/s forward, wheels spinning,
    falling under gravity, chassis modes at 2.5 % modal damping), Tsit5, rtol 1e-6."""
    system, params, q0 = vehicle_scale_system()
    rack = lambda t: jnp.reshape(0.0 * t, (1,))  # noqa: E731
    z0 = jnp.zeros(system.n_dof)
    z0 = z0.at[system.independent.index(system.y_index("chassis", "ux"))].set(10.0)
    for corner in ("front_left", "front_right", "rear_left", "rear_right"):
        z0 = z0.at[system.independent.index(system.y_index(f"{corner}.wheel", "theta_dot"))].set(10.0 / 0.255)
    q0 = q0.at[6:12].set(1e-4)  # chassis modes slightly deflected
    q0 = mb.assemble(system, params, q0, fixed=assembly_fixed(system), inputs=rack)
    run = jax.jit(lambda p: mb.simulate(system, p, q0, z0, 0.0, 1.0, ts=jnp.linspace(0.0, 1.0, 101), inputs=rack,
                                        rtol=1e-6, atol=1e-9))
    t0 = time.perf_counter()
    sim = jax.block_until_ready(run(params))
    compile_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    sim = jax.block_until_ready(run(params))
    wall = time.perf_counter() - t0
    return {"compile_s": compile_s, "wall_s": wall, "steps": int(sim.stats["num_steps"]),
            "max_residual": float(sim.max_residual)}


def bench_options():
    system, params = ex.flexible_pendulum()
    # released horizontal with a 3 rad/s swing and both bending modes deflected (~6 mm tip)
    q0, z0 = ex.flexible_pendulum_state(system, 0.0, (2e-3, 2e-3))
    q0 = mb.assemble(system, params, q0, fixed=(5, 6, 7))  # place the frame so the pin closes
    z0 = z0.at[0].set(3.0)
    ts = jnp.linspace(0.0, 0.4, 41)
    out, base = [], None
    for label, options in (
        ("full", mb.FlexOptions()),
        ("constant mass matrix", mb.FlexOptions(constant_mass=True)),
        ("neglect Gr/Ge", mb.FlexOptions(neglect_gyroscopic=True)),
        ("neglect c shift", mb.FlexOptions(neglect_com_shift=True)),
        ("all three", mb.FlexOptions(True, True, True)),
    ):
        s = system.with_options(options)
        run = jax.jit(lambda p, s=s: mb.simulate(s, p, q0, z0, 0.0, 0.4, ts=ts, rtol=1e-8, atol=1e-11))
        t0 = time.perf_counter()
        sim = jax.block_until_ready(run(params))
        compile_s = time.perf_counter() - t0
        t0 = time.perf_counter()
        sim = jax.block_until_ready(run(params))
        wall = time.perf_counter() - t0
        if base is None:
            base = sim
        out.append(
            {
                "option": label,
                "compile_s": compile_s,
                "wall_s": wall,
                "steps": int(sim.stats["num_steps"]),
                "max_residual": float(sim.max_residual),
                "energy_drift_J": float(jnp.max(jnp.abs(sim.energy - sim.energy[0]))),
                "max_modal_deviation": float(jnp.max(jnp.abs(sim.q[:, 6:] - base.q[:, 6:]))),
                "max_swing_deviation_rad": float(jnp.max(jnp.abs(sim.q[:, 5] - base.q[:, 5]))),
                "max_modal_amplitude": float(jnp.max(jnp.abs(sim.q[:, 6:]))),
            }
        )
    return out


def bench_chassis_options():
    """Free-floating FE chassis (6 free-free modes, no gravity) tumbling with modal motion:
    the Table 7.2 simplifications on a three-dimensional body."""
    from jaxveh import fe

    modal = fe.frame_modal_body(fe.load_frame(), 6, beta=0.0)
    b = mb.SystemBuilder(gravity=(0.0, 0.0, 0.0))
    b.add_flexible_body("chassis", modal)
    for name in ("ux", "uy", "uz", "wx", "wy", "wz") + tuple(f"p{k}_dot" for k in range(6)):
        b.add_independent("chassis", name)
    system, params = b.build()
    q0 = jnp.zeros(12).at[6:].set(1e-3)
    z0 = jnp.concatenate([jnp.asarray([1.0, 0.0, 0.0, 2.0, 1.0, 3.0]), jnp.full((6,), 0.05)])
    ts = jnp.linspace(0.0, 0.2, 21)
    out, base = [], None
    for label, options in (
        ("full", mb.FlexOptions()),
        ("constant mass matrix", mb.FlexOptions(constant_mass=True)),
        ("neglect Gr/Ge", mb.FlexOptions(neglect_gyroscopic=True)),
        ("neglect c shift", mb.FlexOptions(neglect_com_shift=True)),
    ):
        s = system.with_options(options)
        run = jax.jit(lambda p, s=s: mb.simulate(s, p, q0, z0, 0.0, 0.2, ts=ts, rtol=1e-9, atol=1e-12))
        sim = jax.block_until_ready(run(params))
        base = sim if base is None else base
        out.append(
            {
                "option": label,
                "energy_drift_J": float(jnp.max(jnp.abs(sim.energy - sim.energy[0]))),
                "max_modal_deviation": float(jnp.max(jnp.abs(sim.q[:, 6:] - base.q[:, 6:]))),
                "max_modal_amplitude": float(jnp.max(jnp.abs(base.q[:, 6:]))),
                "max_angle_deviation_rad": float(jnp.max(jnp.abs(sim.q[:, 3:6] - base.q[:, 3:6]))),
            }
        )
    return [float(f) for f in modal.frequencies_hz], out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("results/bench_multibody"))
    args = parser.parse_args()
    print(f"jax {jax.__version__}, devices {jax.devices()}")
    rows = bench_vector_fields()
    print(f"{'system':<30}{'nq':>4}{'m':>4}{'dof':>4}{'compile s':>11}{'eval us':>10}{'b64 compile s':>15}"
          f"{'b64 us':>10}{'us/state':>10}")
    for r in rows:
        print(f"{r['system']:<30}{r['n_q']:>4}{r['n_constraints']:>4}{r['n_dof']:>4}{r['compile_s']:>11.2f}"
              f"{r['eval_us']:>10.1f}{r['compile_batch64_s']:>15.2f}{r['eval_batch64_us']:>10.1f}"
              f"{r['eval_per_state_batch64_us']:>10.2f}")
    veh = bench_vehicle_simulation()
    print(f"\nvehicle topology, 1 s free motion, Tsit5 rtol 1e-6: compile {veh['compile_s']:.1f} s, wall "
          f"{veh['wall_s']:.3f} s, {veh['steps']} steps ({veh['wall_s'] / veh['steps'] * 1e6:.0f} us/step), "
          f"max residual {veh['max_residual']:.1e} m")
    opts = bench_options()
    print("\nflexible pendulum, 0.4 s swing, Tsit5 rtol 1e-8 (Table 7.2 options)")
    print(f"{'option':<24}{'wall s':>8}{'steps':>7}{'residual':>11}{'energy J':>11}{'dev p':>11}{'max p':>11}"
          f"{'dev swing':>11}")
    for o in opts:
        print(f"{o['option']:<24}{o['wall_s']:>8.3f}{o['steps']:>7}{o['max_residual']:>11.1e}"
              f"{o['energy_drift_J']:>11.1e}{o['max_modal_deviation']:>11.2e}{o['max_modal_amplitude']:>11.2e}"
              f"{o['max_swing_deviation_rad']:>11.2e}")
    freqs, chassis = bench_chassis_options()
    print(f"\nfree FE chassis, 6 modes ({', '.join(f'{f:.1f}' for f in freqs)} Hz), tumbling 0.2 s")
    print(f"{'option':<24}{'energy J':>11}{'dev p':>11}{'max p':>11}{'dev angles':>12}")
    for o in chassis:
        print(f"{o['option']:<24}{o['energy_drift_J']:>11.1e}{o['max_modal_deviation']:>11.2e}"
              f"{o['max_modal_amplitude']:>11.2e}{o['max_angle_deviation_rad']:>12.2e}")
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "bench.json").write_text(
        json.dumps({"vector_field": rows, "vehicle_simulation": veh, "options_pendulum": opts,
                    "options_chassis": chassis}, indent=2)
    )


if __name__ == "__main__":
    main()
