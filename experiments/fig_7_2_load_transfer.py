"""Fig. 7.2: lateral load transfer of the 14-DOF car on the 50 m skid-pad (steady states by
root finding, left and right turns), rigid vs 6-mode flexible chassis, beside the chapter-3
model (eqs. 3.4-3.6) fed with the car's own parameters (jaxveh.analysis.chapter3_parameters):
(a) front lateral load transfer vs ay; (b) χ vs the roll stiffness distribution λ (set
through the anti-roll bars); (c) χ vs the number of chassis modes; (d) χ vs each single
mode's stiffness multiplier µ. Writes fig_7_2.json and fig_7_2.png (default results/fig_7_2).

Programs: for the rigid and the 6-mode car a curve and one vmapped call over all their
designs; one for each of 1-5 modes; expect 10-20 minutes on two cores, mostly compilation."""

import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from _util import output_dir, write_json

from jaxveh import analysis as an, analytic
from jaxveh._core import GRAVITY
from jaxveh.plots import figure, save
from jaxveh.vehicle import load_car

N_MODES = 6
LAMBDAS = np.round(np.arange(0.2, 0.801, 0.1), 2)
MUS = np.logspace(-1.0, 1.0, 5)
THESIS = {"chi_6_modes": 0.441, "chi_eq_3_6": 0.445, "lam": 0.54}


def _concat(*stacks):
    return jax.tree.map(lambda *x: jnp.concatenate(x), *stacks)


def _one(params):
    return jax.tree.map(lambda x: x[None], params)


def _designs(car, stack, i):
    return eqx.tree_at(lambda c: c.params, car, jax.tree.map(lambda x: x[i], stack))


def main():
    out = output_dir("fig_7_2", __doc__)
    start = time.perf_counter()
    kc = an.frame_torsional_stiffness()
    rigid, flex = load_car(modes=0), load_car(modes=N_MODES)
    n_lam = len(LAMBDAS)

    # per car: the load-transfer curve (one design), then one call over the car itself, the
    # λ designs (and the µ designs) at the two low lateral accelerations
    curve_r, curve_f = an.load_transfer(rigid), an.load_transfer(flex)
    print(f"curves: {time.perf_counter() - start:.0f} s", flush=True)
    stack_r = _concat(_one(rigid.params), an.lambda_designs(rigid, LAMBDAS))
    lt_r = an.load_transfer_batch(rigid, stack_r, an.LOW_AY_PAIR_G)
    stack_f = _concat(_one(flex.params), an.lambda_designs(flex, LAMBDAS), an.mode_stiffness_designs(flex, MUS))
    lt_f = an.load_transfer_batch(flex, stack_f, an.LOW_AY_PAIR_G)
    chi_r, chi_f = np.asarray(lt_r.chi_low_ay), np.asarray(lt_f.chi_low_ay)
    print(f"sweeps: {time.perf_counter() - start:.0f} s", flush=True)
    chi_modes = [float(chi_r[0])]
    for n in range(1, N_MODES):
        chi_modes.append(float(an.load_transfer(load_car(modes=n), an.LOW_AY_PAIR_G).chi_low_ay))
        print(f"{n} modes: chi {chi_modes[-1]:.4f} ({time.perf_counter() - start:.0f} s)", flush=True)
    chi_modes.append(float(chi_f[0]))

    # chapter 3 with the car's own parameters (kC: the FE frame's torsion test)
    p = an.chapter3_parameters(flex, kc)
    ay = np.asarray(an.AY_GRID_G)
    ay_line = np.linspace(0.0, 1.2, 25)
    eq_rigid = np.asarray(an.chapter3_load_transfer(p, ay_line * GRAVITY)[0])
    eq_flex = np.asarray(an.chapter3_load_transfer(p, ay_line * GRAVITY, flexible=True)[0])
    lam_eq = {"eq. 3.4 rigid": [], "eq. 3.5 flex.": [], "eq. 3.6 rigid (mean track)": [],
              "eq. 3.6 flex. (mean track)": []}
    for i in range(n_lam):
        pl = an.chapter3_parameters(_designs(flex, stack_f, 1 + i), kc)
        v = an.analytic_vehicle(pl)
        lam_eq["eq. 3.4 rigid"].append(float(an.chapter3_chi(pl)))
        lam_eq["eq. 3.5 flex."].append(float(an.chapter3_chi(pl, flexible=True)))
        lam_eq["eq. 3.6 rigid (mean track)"].append(float(analytic.chi_rigid(v)))
        lam_eq["eq. 3.6 flex. (mean track)"].append(float(analytic.chi(v)))
    v0 = an.analytic_vehicle(p)
    chi_mu = chi_f[1 + n_lam:].reshape(N_MODES, len(MUS))

    report = {
        "radius_m": an.SKID_PAD_RADIUS,
        "low_ay_g": an.LOW_AY_PAIR_G,
        "ay_g": ay,
        "chapter3_parameters": {k: float(getattr(p, k)) for k in p.__dataclass_fields__},
        "lam": float(p.lam),
        "mu": float(p.mu),
        "a": {
            "multib. rigid": {"front_n": curve_r.front, "rear_n": curve_r.rear, "chi_secant": curve_r.chi,
                              "ok": curve_r.ok},
            "multib. flex.": {"front_n": curve_f.front, "rear_n": curve_f.rear, "chi_secant": curve_f.chi,
                              "ok": curve_f.ok},
            "ay_line_g": ay_line, "analytical rigid": eq_rigid, "analytical flex.": eq_flex,
        },
        "b": {"lam": LAMBDAS, "multib. rigid": chi_r[1:], "multib. flex.": chi_f[1:1 + n_lam],
              "arb_rates_nm_per_rad": an.arb_rates_for_distribution(flex, jnp.asarray(LAMBDAS)), **lam_eq},
        "c": {"modes": list(range(N_MODES + 1)), "chi": chi_modes},
        "d": {"mu": MUS, "chi": chi_mu},
        "chi": {
            "multib. rigid": float(chi_r[0]), f"multib. {N_MODES} modes": float(chi_f[0]),
            "eq. 3.4 rigid": float(an.chapter3_chi(p)), "eq. 3.5 flex.": float(an.chapter3_chi(p, flexible=True)),
            "eq. 3.6 rigid (mean track)": float(analytic.chi_rigid(v0)),
            "eq. 3.6 flex. (mean track)": float(analytic.chi(v0)),
        },
        "thesis": THESIS,
        "all_converged": bool(all(np.all(x.ok) for x in (curve_r, curve_f, lt_r, lt_f))),
        "wall_time_s": time.perf_counter() - start,
    }
    write_json(report, out / "fig_7_2.json")
    save(plot(report), out / "fig_7_2.png")
    for k, val in report["chi"].items():
        print(f"chi {k:>28}: {val:.4f}")
    print(f"lambda {report['lam']:.3f}, mu {report['mu']:.3f}; thesis: chi {THESIS['chi_6_modes']} (6 modes) vs "
          f"{THESIS['chi_eq_3_6']} (eq. 3.6) at lambda {THESIS['lam']}; {report['wall_time_s']:.0f} s; wrote {out}")


def plot(r):
    fig, axes = figure(2, 2, figsize=(10, 8))
    (a, b), (c, d) = axes
    ay = np.asarray(r["ay_g"])
    for label, style in (("multib. rigid", "o-"), ("multib. flex.", "s-")):
        a.plot(ay, r["a"][label]["front_n"], style, label=label, ms=4)
    for label, style in (("analytical rigid", "--"), ("analytical flex.", ":")):
        a.plot(r["a"]["ay_line_g"], r["a"][label], style, label=label)
    a.set(xlabel="ay [g]", ylabel="ΔFz [N]", title="(a) front lateral load transfer")
    lam = np.asarray(r["b"]["lam"])
    for label, style in (("multib. rigid", "o-"), ("multib. flex.", "s-"), ("eq. 3.4 rigid", "--"),
                         ("eq. 3.5 flex.", ":")):
        b.plot(lam, r["b"][label], style, label=label.replace("eq. 3.4", "analytical").replace("eq. 3.5",
                                                                                              "analytical"), ms=4)
    b.set(xlabel="λ", ylabel="χ", title="(b) χ vs roll stiffness distribution")
    c.plot(r["c"]["modes"], r["c"]["chi"], "o-")
    c.set(xlabel="number of modes", ylabel="χ", title="(c) χ vs number of modes")
    mu = np.asarray(r["d"]["mu"])
    for i, row in enumerate(np.asarray(r["d"]["chi"])):
        d.semilogx(mu, row, "o-", label=f"mode {i + 1}", ms=3)
    d.set(xlabel="µ", ylabel="χ", title="(d) χ vs modal stiffness multiplier")
    for ax in (a, b, d):
        ax.legend(fontsize=8)
    for ax in (a, b, c, d):
        ax.grid(True, alpha=0.3)
    lo, hi = r["low_ay_g"]
    fig.suptitle(f"Fig. 7.2: lateral load transfer, skid-pad R = {r['radius_m']:g} m; χ between {lo:g} and {hi:g} g")
    return fig


if __name__ == "__main__":
    main()
