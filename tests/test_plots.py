"""The report's figures (`rigidbench.plots`): every registered scenario has at least one; each plot function runs
under the report's default settings and returns figures with a title, a caption, labelled axes and a PNG that
decodes; and where a scenario cannot be simulated under the report's settings, its figures are left out rather
than the report failing."""

import io

import pytest

from rigidbench import plots, registry, report
from rigidbench.settings import Settings

# Scenarios whose figures take more than ~4 s (long cases, extra points, a Monte Carlo beam): run in CI only.
SLOW = {"struck-stick", "cushion-rebound", "hard-spheres", "cross-section", "coupled-pendulums"}
# Contact scenarios whose stiff contacts the checks refuse at a 2 ms step (a report from mujoco-default results
# re-simulates at the results' integrator and timestep).
CONTACT = ("ball-stick", "cue-strike", "cushion-rebound", "marble-shot", "hard-spheres", "cross-section")


def test_every_registered_scenario_has_figures():
    missing = sorted(set(registry.scenarios()) - set(plots.registered()))
    assert missing == [], f"scenarios without a plot function in rigidbench/plots/: {missing}"


def _check(figures: list[plots.Figure]) -> None:
    from PIL import Image

    for fig in figures:
        assert fig.title and len(fig.caption) > 80, fig.title
        axes = [ax for ax in fig.figure.axes if ax.has_data()]
        assert axes, f"{fig.title}: nothing drawn"
        assert any(ax.get_xlabel() for ax in axes) and any(ax.get_ylabel() for ax in axes), fig.title
        data = report.png(fig.figure, dpi=30)
        with Image.open(io.BytesIO(data)) as im:
            assert im.format == "PNG" and min(im.size) > 60
            im.load()


@pytest.mark.parametrize(
    "slug", [pytest.param(s, marks=pytest.mark.slow) if s in SLOW else s for s in sorted(registry.scenarios())]
)
def test_plot_functions_run_and_draw_labelled_figures(slug):
    ctx = plots.PlotContext(registry.get(slug))
    figures = [fig for fn in plots.plots_for(slug) for fig in fn(ctx)]
    assert figures, f"{slug}: its plot functions returned no figure"
    _check(figures)


@pytest.mark.parametrize("slug", CONTACT)
def test_figures_are_left_out_not_failed_where_the_settings_are_refused(slug):
    ctx = plots.PlotContext(registry.get(slug), Settings(integrator="Euler", timestep=0.002))
    with pytest.raises(ValueError):
        ctx.run(registry.get(slug).cases[0].name)
    figures = [fig for fn in plots.plots_for(slug) for fig in fn(ctx)]
    _check(figures)  # cue-strike keeps its hop figure: its mujoco-default panel brings its own contact
    assert len(figures) <= 1
