"""The four panels of Fig. B.1 for any tyre: Fx-kappa, Fy-alpha, Mz-alpha, Fx-Fy envelope."""

from pathlib import Path

import numpy as np

from ._curves import combined_slip_curves, pure_slip_curves
from ._model import MagicFormulaTyre

#: File names of the four panels, in the order of Fig. B.1 (a)-(d).
PANEL_FILES: tuple[str, ...] = ("fx_kappa.png", "fy_alpha.png", "mz_alpha.png", "fx_fy_combined.png")


def fig_b1_figures(tyre: MagicFormulaTyre, title: str = "", loads=None) -> dict:
    """The four panels of Fig. B.1 and a 2x2 overview as matplotlib figures, by file name.

    Loads [N] default FNOMIN x (1/3, 2/3, 1, 4/3) (Fig. B.1's 250/500/750/1000 N for the
    shipped tyre), camber 0; combined panel at FNOMIN with slip angles +-1..10 deg over
    kappa in [-0.3, 0.3]. Signs as computed (ISO-W). Constrained layout throughout.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    c = pure_slip_curves(tyre, loads)
    kappa, alpha_deg = np.asarray(c.kappa), np.rad2deg(np.asarray(c.alpha))
    alphas, _, cfx, cfy = combined_slip_curves(tyre)
    labels = [f"Fz = {fz:.0f} N" for fz in np.asarray(c.loads)]

    def panel(ax, which):
        if which == 0:
            for i, lab in enumerate(labels):
                ax.plot(kappa, np.asarray(c.fx[i]), label=lab)
            ax.set(xlabel="κ [-]", ylabel="Fx [N]", title="(a)")
        elif which == 1:
            for i, lab in enumerate(labels):
                ax.plot(alpha_deg, np.asarray(c.fy[i]), label=lab)
            ax.set(xlabel="α [deg]", ylabel="Fy [N]", title="(b)")
        elif which == 2:
            for i, lab in enumerate(labels):
                ax.plot(alpha_deg, np.asarray(c.mz[i]), label=lab)
            ax.set(xlabel="α [deg]", ylabel="Mz [Nm]", title="(c)")
        else:
            # One colour per |alpha| (the +alpha and -alpha curves mirror each other in Fy),
            # named in the legend: text labels at the curve ends would crowd at large alpha.
            alphas_deg = np.rad2deg(np.asarray(alphas))
            magnitudes = sorted({round(abs(float(a)), 6) for a in alphas_deg})
            colours = plt.get_cmap("viridis")(np.linspace(0.0, 0.9, len(magnitudes)))
            for j, a in enumerate(alphas_deg):
                k = magnitudes.index(round(abs(float(a)), 6))
                ax.plot(np.asarray(cfx[j]), np.asarray(cfy[j]), color=colours[k], lw=1.0,
                        label=f"α = ±{abs(a):g}°" if a > 0 else None)
            ax.legend(fontsize=7, loc="center", ncol=2)
            ax.set(xlabel="Fx [N]", ylabel="Fy [N]", title=f"(d) Fz = {float(tyre.fnomin):.0f} N")
            ax.set_aspect("equal", adjustable="datalim")
        if which < 3:
            ax.legend(fontsize=7)
        ax.grid(True, alpha=0.3)

    figures = {}
    for which, name in enumerate(PANEL_FILES):
        fig, ax = plt.subplots(figsize=(5, 4), layout="constrained")
        panel(ax, which)
        figures[name] = fig
    fig, axes = plt.subplots(2, 2, figsize=(10, 8), layout="constrained")
    for which, ax in enumerate(axes.flat):
        panel(ax, which)
    if title:
        fig.suptitle(title)
    figures["fig_b1.png"] = fig
    return figures


def plot_fig_b1(tyre: MagicFormulaTyre, out_dir: str | Path, title: str = "", loads=None) -> list[Path]:
    """Write the four panels of Fig. B.1 as PNGs (and one 2x2 overview) into ``out_dir``.

    Figures as :func:`fig_b1_figures`. Returns the written paths.
    """
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, fig in fig_b1_figures(tyre, title, loads).items():
        fig.savefig(out / name, dpi=120)
        plt.close(fig)
        paths.append(out / name)
    return paths
