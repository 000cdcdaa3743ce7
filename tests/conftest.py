"""Shared fixtures. Importing rigidbench sets MUJOCO_GL=egl when there is no display."""

import pytest

import rigidbench
from rigidbench import registry


def pytest_generate_tests(metafunc):
    """Parametrise registry-wide tests over every scenario (`scenario`) or every (scenario, case) (`case_id`)."""
    if "scenario" in metafunc.fixturenames:
        metafunc.parametrize("scenario", list(registry.scenarios().values()), ids=lambda s: s.slug)
    if "case_id" in metafunc.fixturenames:
        ids = [f"{s.slug}:{c.name}" for s in registry.scenarios().values() for c in s.cases]
        metafunc.parametrize("case_id", ids)
    if "env_id" in metafunc.fixturenames:
        metafunc.parametrize("env_id", sorted(registry.env_classes()))
    # Validation envs (zero action = the textbook problem) and control task envs (rigidbench.envs.task).
    from rigidbench.envs.task import TaskEnv

    envs = registry.env_classes()
    if "validation_env_id" in metafunc.fixturenames:
        ids = sorted(i for i, cls in envs.items() if not issubclass(cls, TaskEnv))
        metafunc.parametrize("validation_env_id", ids)
    if "task_env_id" in metafunc.fixturenames:
        metafunc.parametrize("task_env_id", sorted(i for i, cls in envs.items() if issubclass(cls, TaskEnv)))


@pytest.fixture(scope="session")
def package():
    return rigidbench


@pytest.fixture(scope="session")
def gl_available():
    """Whether MuJoCo can create an offscreen GL context; in CI (RIGIDBENCH_REQUIRE_RENDER=1) it must."""
    import os

    import mujoco

    try:
        renderer = mujoco.Renderer(mujoco.MjModel.from_xml_string("<mujoco/>"), 8, 8)
        renderer.close()
        return True
    except Exception as exc:  # no EGL/OSMesa libraries, no display
        if os.environ.get("RIGIDBENCH_REQUIRE_RENDER") == "1":
            raise
        pytest.skip(f"no OpenGL backend for headless rendering ({exc}); install libegl1 libegl-mesa0 libgl1-mesa-dri")
