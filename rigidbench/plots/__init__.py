"""The plot registry: each scenario's figures for the HTML report, one function per scenario, keyed by slug.

Adding a scenario's plots is a one-function job: in a module of this package (``rigidbench/plots/<family>.py``;
modules are discovered, no list to edit) write

.. code-block:: python

    from rigidbench.plots import Figure, PlotContext, plot

    @plot("struck-stick")
    def struck_stick(ctx: PlotContext) -> list[Figure]:
        run = ctx.run("cusp")                  # simulated like `rigidbench run`, trajectory and prediction kept
        fig, ax = ctx.subplots()
        ax.plot(...)                           # simulation over theory, units on the axes
        return [Figure("Cusp path of the struck stick", "what the reader should see", fig)]

`ctx.run(case)` simulates the case under the report's settings (those of the results being reported, else the
model file's reference settings) and keeps the trajectory (`CaseRun.trajectory`) and the prediction
(`CaseRun.prediction`, including the analytic solution object under ``"_theory"`` where the scenario keeps one).
Every figure should draw the simulation over the theory, with the caption saying what agreement looks like.
Convergence plots from a sweep are generic (`rigidbench.plots.convergence`) and need no per-scenario code.
"""

from __future__ import annotations

import functools
import importlib
import pkgutil
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from rigidbench.scenario import CaseRun, Scenario
from rigidbench.settings import Settings


class MissingDependency(RuntimeError):
    """An optional dependency (matplotlib) is not installed; the message says how to install it."""


def pyplot():
    """matplotlib's pyplot on the non-interactive Agg backend, imported on first use.

    Raises
    ------
    MissingDependency
        If matplotlib is not installed (it is an optional extra: ``pip install 'rigidbench[report]'``).
    """
    try:
        import matplotlib
    except ImportError:
        raise MissingDependency(
            "the report's plots need matplotlib, which the core install does not include: "
            "pip install 'rigidbench[report]' (or pip install matplotlib)"
        ) from None
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


@dataclass
class Figure:
    """One figure of the report: a title, a caption saying what it shows, and a matplotlib figure."""

    title: str
    caption: str
    figure: Any


@dataclass
class PlotContext:
    """What a plot function gets: its scenario, the settings to simulate under, and a cached case runner."""

    scenario: Scenario
    settings: Settings | None = None
    _runs: dict[str, CaseRun] = field(default_factory=dict, repr=False)

    def run(self, case: str, overrides: dict | None = None) -> CaseRun:
        """Simulate `case` (as `rigidbench run` does) and keep its trajectory and prediction; cached per case."""
        key = f"{case}:{sorted((overrides or {}).items())}"
        if key not in self._runs:
            self._runs[key] = self.scenario.run(case, overrides, self.settings, keep_trajectory=True)
        return self._runs[key]

    def model(self, case: str, overrides: dict | None = None):
        """The compiled model of `case` (what `run` simulated)."""
        params = self.scenario.resolve(self.scenario.case(case), overrides)
        return self.scenario.build(params, self.settings)

    def subplots(self, *args, **kwargs):
        """`matplotlib.pyplot.subplots` with the report's default size and layout."""
        kwargs.setdefault("figsize", (8.0, 4.5))
        kwargs.setdefault("layout", "constrained")
        return pyplot().subplots(*args, **kwargs)


PlotFunction = Callable[[PlotContext], list[Figure]]
_PLOTS: dict[str, list[PlotFunction]] = {}


def plot(slug: str) -> Callable[[PlotFunction], PlotFunction]:
    """Register a function as (one of) the plots of the scenario `slug`."""

    def register(fn: PlotFunction) -> PlotFunction:
        _PLOTS.setdefault(slug, []).append(fn)
        return fn

    return register


@functools.cache
def _discover() -> None:
    import rigidbench.plots

    for info in sorted(pkgutil.iter_modules(rigidbench.plots.__path__), key=lambda i: i.name):
        importlib.import_module(f"rigidbench.plots.{info.name}")


def plots_for(slug: str) -> list[PlotFunction]:
    """The plot functions registered for a scenario (empty if it has none yet)."""
    _discover()
    return list(_PLOTS.get(slug, []))


def registered() -> list[str]:
    """Slugs with at least one plot function."""
    _discover()
    return sorted(_PLOTS)


# ---- helpers shared by the figure modules ---------------------------------------------------------------------

THEORY_STYLE = {"color": "k", "lw": 1.0}


def simulated(run: CaseRun) -> bool:
    """Whether a run kept its trajectory and did not diverge (so it can be drawn)."""
    return run.trajectory is not None and run.diverged_at is None


def try_run(ctx: PlotContext, case: str, overrides: dict | None = None) -> CaseRun | None:
    """The case's run, or None if its parameters or these settings are refused (ValueError) or it diverged."""
    try:
        run = ctx.run(case, overrides)
    except ValueError:
        return None
    return run if simulated(run) else None


def settings_text(run: CaseRun) -> str:
    """The settings a figure's title names: integrator, timestep, MuJoCo version."""
    s = run.settings
    return f"{s['integrator']}, dt = {s['timestep']:g} s, mujoco {s['mujoco']}"


def measured_value(run: CaseRun, check: str) -> float:
    """The measured value of a check in a run (NaN if the run did not score it)."""
    return next((o.measured for o in run.outcomes if o.check.name == check), float("nan"))


def thin(n: int, target: int = 400) -> slice:
    """A stride that keeps about `target` of `n` samples for drawing markers."""
    return slice(None, None, max(1, n // target))
