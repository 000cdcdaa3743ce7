"""The scenario registry: every `Scenario` subclass defined in a module of `rigidbench.envs`.

Scenarios are discovered, not listed: adding ``envs/<stem>.py`` with a `Scenario` subclass (and
``models/<stem>.xml``) adds it to the CLI, the gymnasium registry and every registry-wide test.
"""

from __future__ import annotations

import functools
import importlib
import pkgutil

import rigidbench.envs
from rigidbench.scenario import Scenario


@functools.cache
def scenarios() -> dict[str, Scenario]:
    """All scenarios, by slug, in module order."""
    found: dict[str, Scenario] = {}
    for info in sorted(pkgutil.iter_modules(rigidbench.envs.__path__), key=lambda i: i.name):
        module = importlib.import_module(f"rigidbench.envs.{info.name}")
        for obj in vars(module).values():
            if (
                isinstance(obj, type)
                and issubclass(obj, Scenario)
                and obj.__module__ == module.__name__
                and "slug" in vars(obj)
            ):
                found[obj.slug] = obj()
    return found


def get(slug: str) -> Scenario:
    """The scenario with this slug.

    Raises
    ------
    ValueError
        Naming the unknown slug and listing the known ones.
    """
    table = scenarios()
    if slug not in table:
        raise ValueError(f"unknown scenario '{slug}'; valid: {', '.join(table)}")
    return table[slug]


def parse_target(target: str) -> tuple[Scenario, list[str]]:
    """``"heavy-top"`` -> all its cases; ``"heavy-top:nutation"`` -> that case.

    Raises
    ------
    ValueError
        For an unknown scenario or case.
    """
    slug, _, case = target.partition(":")
    scenario = get(slug)
    if case:
        return scenario, [scenario.case(case).name]
    return scenario, [c.name for c in scenario.cases]


def env_classes() -> dict[str, type]:
    """Every gymnasium env class defined next to a scenario, by gymnasium id.

    A class that sets `scenario_cls` is the validation env of that scenario (id ``scenario_cls.env_id``); a
    class that also sets its own ``env_id`` (a control task on the scenario, `rigidbench.envs.task`) is
    registered under that id instead.
    """
    from rigidbench.envs.base import ScenarioEnv

    scenarios()  # imports every env module
    found = {}
    stack = list(ScenarioEnv.__subclasses__())
    while stack:
        cls = stack.pop()
        stack.extend(cls.__subclasses__())
        if "scenario_cls" in vars(cls) or "env_id" in vars(cls):
            found[vars(cls).get("env_id", cls.scenario_cls.env_id)] = cls
    return found


def register_envs() -> None:
    """Register every env with gymnasium (idempotent)."""
    import gymnasium

    from rigidbench.envs.task import TaskEnv
    from rigidbench.envs.vector import vector_entry_point

    for env_id, cls in env_classes().items():
        if env_id not in gymnasium.registry:
            # The validation envs also have a batched vector env (`rigidbench.envs.vector`); the control tasks run
            # under gymnasium's sync and async vector envs.
            batched = None if issubclass(cls, TaskEnv) else vector_entry_point(cls)
            gymnasium.register(
                id=env_id, entry_point=f"{cls.__module__}:{cls.__qualname__}", vector_entry_point=batched
            )
