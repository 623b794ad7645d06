"""Figures read cleanly: no two visible texts overlap and nothing is cut off.

Every figure function of the chapter-3 plots, the tyre plots and the composite figures of
``experiments/fig_3_*.py`` is drawn with real (coarse) data and saved; then, with the
renderer's window extents, every pair of visible, non-empty texts (suptitle, titles, axis
labels, tick labels, legend texts, annotations, colour-bar labels) is checked for overlap,
and every text for lying inside the figure. ``test_checker_finds_overlaps`` shows the check
fails on a figure built to overlap.
"""

import itertools
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from jaxveh.analytic import _reports as reports  # noqa: E402
from jaxveh.analytic._maps import design_map  # noqa: E402
from jaxveh.params import load_analytic_vehicle  # noqa: E402
from jaxveh.plots import (  # noqa: E402
    plot_bode,
    plot_design_curves,
    plot_map,
    plot_preview,
    plot_root_locus,
    plot_skidpad,
    plot_step_steer,
)
from jaxveh.tyre import fig_b1_figures, load_fsae_tyre  # noqa: E402

EXPERIMENTS = Path(__file__).resolve().parents[1] / "experiments"
#: Boxes may touch: an overlap must exceed this many pixels in both directions to count
#: (anti-aliasing and rounding of the extents are below one pixel).
TOLERANCE_PX = 1.0


def _texts(fig):
    """(description, Text) of every visible, non-empty text the figure draws."""
    out = [("suptitle", t) for t in fig.texts]
    for i, ax in enumerate(fig.axes):
        tag = f"axes {i}"
        for loc in ("center", "left", "right"):
            out.append((f"{tag} title {loc}", ax.title if loc == "center" else getattr(ax, f"_{loc}_title")))
        out.append((f"{tag} xlabel", ax.xaxis.label))
        out.append((f"{tag} ylabel", ax.yaxis.label))
        for name, axis in (("x", ax.xaxis), ("y", ax.yaxis)):
            for tick in axis._update_ticks():  # the ticks drawn (inside the view interval)
                for label in (tick.label1, tick.label2):
                    out.append((f"{tag} {name}tick {label.get_text()!r}", label))
        legend = ax.get_legend()
        if legend is not None and legend.get_visible():
            out += [(f"{tag} legend {t.get_text()!r}", t) for t in legend.get_texts()]
            title = legend.get_title()
            out.append((f"{tag} legend title", title))
        out += [(f"{tag} text {t.get_text()!r}", t) for t in ax.texts]
    return [(d, t) for d, t in out if t.get_visible() and t.get_text().strip()]


def layout_problems(fig, path: Path) -> list[str]:
    """Save ``fig`` to ``path`` and return overlapping or cut-off texts (empty: clean)."""
    fig.savefig(path, dpi=100)
    renderer = fig.canvas.get_renderer()
    boxes = [(d, t.get_window_extent(renderer)) for d, t in _texts(fig)]
    problems = []
    width, height = fig.bbox.width, fig.bbox.height
    for d, b in boxes:
        if b.x0 < -TOLERANCE_PX or b.y0 < -TOLERANCE_PX or b.x1 > width + TOLERANCE_PX or b.y1 > height + TOLERANCE_PX:
            problems.append(f"cut off: {d} at {b.bounds}")
    for (d1, b1), (d2, b2) in itertools.combinations(boxes, 2):
        dx = min(b1.x1, b2.x1) - max(b1.x0, b2.x0)
        dy = min(b1.y1, b2.y1) - max(b1.y0, b2.y0)
        if dx > TOLERANCE_PX and dy > TOLERANCE_PX:
            problems.append(f"overlap: {d1} / {d2}")
    return problems


def _assert_clean(fig, tmp_path, name):
    problems = layout_problems(fig, tmp_path / f"{name}.png")
    plt.close(fig)
    assert not problems, f"{name}: " + "; ".join(problems[:10])


def test_checker_finds_overlaps(tmp_path):
    """Negative control: a crowded grid without layout management, long titles and labels."""
    fig, axes = plt.subplots(2, 2, figsize=(4, 3))
    for ax in axes.flat:
        ax.plot(np.arange(10) * 1e4)
        ax.set_title("a long panel title that will not fit")
        ax.set_xlabel("x label of a panel")
        ax.set_ylabel("y label of a panel")
    problems = layout_problems(fig, tmp_path / "bad.png")
    plt.close(fig)
    # x tick labels of the top-left panel run into the title of the panel below it ...
    assert any(p.startswith("overlap: axes 0 xtick") and p.endswith("axes 2 title center") for p in problems), problems
    # ... and without layout management the outer labels fall off the figure.
    assert any(p.startswith("cut off: axes 2 xlabel") for p in problems), problems
    fig, ax = plt.subplots(layout="constrained")
    ax.text(0.5, 0.5, "one label")
    ax.text(0.5, 0.5, "another label")
    problems = layout_problems(fig, tmp_path / "texts.png")
    plt.close(fig)
    assert problems == ["overlap: axes 0 text 'one label' / axes 0 text 'another label'"]


@pytest.fixture(scope="module")
def vehicle():
    return load_analytic_vehicle()


@pytest.mark.slow
def test_chapter3_figures(vehicle, tmp_path):
    lam = np.linspace(0.0, 1.0, 21)
    mus = (0.1, 1.0, 10.0)
    chi = np.asarray(design_map(vehicle, "chi", lam, mus))
    _assert_clean(plot_design_curves(lam, {f"µ = {m:g}": chi[:, j] for j, m in enumerate(mus)}, "λ", "χ"),
                  tmp_path, "design_curves")
    err = reports.map_report(vehicle, "chi_error", (0.0, 1.0), (0.1, 10.0), 11, 11)
    _assert_clean(plot_map(err, "|χ-χ0|/χ0", vmax=0.6), tmp_path, "map")
    skid = reports.skidpad_report(vehicle, variants=("rigid", "flexible"), n=9)
    _assert_clean(plot_skidpad(skid), tmp_path, "skidpad")
    step = reports.step_steer_report(vehicle, t_end=2.0, n_save=401)
    _assert_clean(plot_step_steer(step), tmp_path, "step_steer")
    loci = reports.root_locus(vehicle, 50.0, np.geomspace(0.1, 10.0, 12))
    modes = [(m["label"], complex(m["real"], m["imag"])) for m in reports.eig_report(vehicle, 50.0)["modes"]]
    _assert_clean(plot_root_locus({"eigenvalues": loci}, title="µ = 0.1 (□) ... 10 (○), 50 km/h", mode_labels=modes),
                  tmp_path, "root_locus")
    bode = reports.bode_report(vehicle, n=40)
    _assert_clean(plot_bode(bode), tmp_path, "bode")
    preview = reports.preview_report(vehicle, 100.0, n_preview=100)
    _assert_clean(plot_preview({"µ = 1": preview}), tmp_path, "preview")


def test_tyre_figures(tmp_path):
    for name, fig in fig_b1_figures(load_fsae_tyre(), title="FSAE 20.0x7.0-13").items():
        _assert_clean(fig, tmp_path, name.removesuffix(".png"))


@pytest.fixture(scope="module")
def experiments():
    sys.path.insert(0, str(EXPERIMENTS))
    yield
    sys.path.remove(str(EXPERIMENTS))


@pytest.mark.slow
def test_experiment_figures(vehicle, experiments, tmp_path):
    """The composite figures of experiments/fig_3_3, 3_4, 3_9 and 3_11, with coarse data."""
    import fig_3_3_load_transfer
    import fig_3_4_understeer
    import fig_3_9_root_locus
    import fig_3_11_preview

    _assert_clean(fig_3_3_load_transfer.figure(fig_3_3_load_transfer.compute(vehicle, n=21, n_map=11)),
                  tmp_path, "fig_3_3")
    _assert_clean(fig_3_4_understeer.figure(fig_3_4_understeer.compute(vehicle, n=21, n_map=11)),
                  tmp_path, "fig_3_4")
    _assert_clean(fig_3_9_root_locus.figure(vehicle, fig_3_9_root_locus.compute(vehicle, n=12)), tmp_path, "fig_3_9")
    _, panels = fig_3_11_preview.compute(vehicle, n_mu=3, extras=False)
    _assert_clean(fig_3_11_preview.figure(*panels), tmp_path, "fig_3_11")


def test_manoeuvre_figure(tmp_path):
    """The manoeuvre time histories, two runs overlaid (flexible with six modes, rigid)."""
    from jaxveh.plots import plot_manoeuvre

    t = np.linspace(0.0, 5.0, 101)
    run = {k: 10.0 * np.tanh(t - 0.5) for k in ("steering_wheel_angle", "ay", "yaw_rate", "roll", "sideslip")}
    runs = {"flexible, 6 modes": {"t_s": t, **run, "modes": 1e-3 * np.sin(np.outer(t, np.arange(1, 7)))},
            "rigid": {"t_s": t, **run, "modes": np.zeros((101, 0))}}
    fig = plot_manoeuvre(runs, title="step-steer at 90 km/h")
    # the six modes' legend sits above their curves (an earlier version drew it over them)
    fig.savefig(tmp_path / "manoeuvre_legend.png", dpi=100)
    modes = fig.axes[5]
    box = modes.get_legend().get_window_extent(fig.canvas.get_renderer())
    for line in modes.lines:
        x, y = modes.transData.transform(line.get_xydata()).T
        inside = (x > box.x0) & (x < box.x1) & (y > box.y0) & (y < box.y1)
        assert not np.any(inside), line.get_label()
    _assert_clean(fig, tmp_path, "manoeuvre")
    _assert_clean(plot_manoeuvre({"rigid": runs["rigid"]}, title="rigid"), tmp_path, "manoeuvre_rigid")


def test_skid_pad_figure(tmp_path):
    """The skid-pad curves (Fig. 7.5), two overlaid."""
    from jaxveh.plots import plot_skid_pad

    ay = np.linspace(0.05, 1.2, 24)
    curve = {"ay_g": ay, "delta_dynamic_deg": 0.7 * ay, "understeer_gradient_deg_per_g": 0.7 + ay,
             "sideslip_deg": 0.5 - 3 * ay, "roll_deg": 2 * ay}
    _assert_clean(plot_skid_pad({"rigid": curve, "flexible, 6 modes": curve}, title="skid-pad R = 50 m"), tmp_path,
                  "skid_pad")
