"""Event measurement below the sampling step (rigidbench.signals) against exact answers."""

import sys

import numpy as np
import pytest

from rigidbench import params, signals


def test_crossings_of_a_sampled_sine_are_exact_to_step_to_the_fourth():
    h = 1e-3
    t = np.arange(0, 10, h)
    omega = 3.0
    found = signals.crossings(t, np.sin(omega * t + 0.3), direction=1)
    exact = (2 * np.pi * np.arange(1, 5) - 0.3) / omega
    assert np.abs(found - exact[: len(found)]).max() < (omega * h) ** 4


def test_extrema_from_exact_derivative_give_peak_values():
    t = np.arange(0, 5, 1e-3)
    y, dy = 2 * np.cos(4 * t - 0.1), -8 * np.sin(4 * t - 0.1)
    times, values = signals.extrema(t, y, dy, "max")
    assert np.allclose(values, 2.0, atol=1e-12)
    assert np.allclose(np.cos(4 * times - 0.1), 1.0, atol=1e-12)


def test_phase_rate_of_uniform_rotation():
    t = np.linspace(0, 20, 5001)
    assert signals.phase_rate(t, np.angle(np.exp(1j * (-2.5 * t + 1.0)))) == pytest.approx(-2.5, rel=1e-13)


def test_param_check_names_parameter_value_and_range():
    p = params.Param("mass", "kg", "mass", params.positive(10.0), params.BodyMass("b"))
    with pytest.raises(ValueError, match=r"'mass' = -1 kg is outside the valid range \(0, 10\] kg"):
        p.check(-1)
    with pytest.raises(ValueError, match="not finite"):
        p.check(float("inf"))
    with pytest.raises(ValueError, match="expected a number"):
        p.check([1.0, 2.0])
    assert p.parse("2.5") == 2.5


def test_a_signal_wrapped_by_the_code_it_landed_in_still_ends_in_one_line(monkeypatch, capsys):
    """A SIGINT during `import mujoco` lands inside a ctypes call, which turns the handler's exception into
    ctypes.ArgumentError("argument 1: Interrupted: 2"): the command still ends with the one line and 130."""
    import ctypes
    import signal

    from rigidbench import cli

    def parse(argv):
        try:
            cli._raise_interrupted(signal.SIGINT, None)
        except BaseException as exc:  # what ctypes does with an exception raised while converting an argument
            raise ctypes.ArgumentError(f"argument 1: {type(exc).__name__}: {exc}") from None

    monkeypatch.setattr(cli, "_main", parse)
    assert cli.main(["list"]) == 130
    assert capsys.readouterr().err == "rigidbench: interrupted by SIGINT\n"


@pytest.mark.parametrize("ends", ["returns", "raises"])
def test_a_signal_raised_inside_a_callback_is_not_printed_as_an_ignored_exception(monkeypatch, capsys, ends):
    """A SIGINT during an import can land in importlib's module-lock weakref callback, which cannot pass the
    handler's exception on: Python printed "Exception ignored in: <function _get_module_lock.<locals>.cb> ...
    Traceback" (CI's slow fault run, trial 19). The command ends with the one line and 130, nothing else, whether
    the command goes on to return normally or stops later for another reason."""
    import gc
    import signal
    import weakref

    from rigidbench import cli

    class Thing:
        pass

    def parse(argv):
        thing = Thing()
        ref = weakref.ref(thing, lambda _: cli._raise_interrupted(signal.SIGINT, None))
        del thing
        gc.collect()
        assert ref() is None  # the callback ran, and its exception went to sys.unraisablehook
        other = Thing()
        ref = weakref.ref(other, lambda _: 1 / 0)  # any other lost exception is still shown
        del other
        gc.collect()
        if ends == "raises":
            raise cli.UsageError("a later error")
        return cli.EXIT_OK

    printed = []  # what Python's own hook would have printed ("Exception ignored ... Traceback")
    monkeypatch.setattr(sys, "unraisablehook", printed.append)
    monkeypatch.setattr(cli, "_main", parse)
    assert cli.main(["list"]) == 130
    assert capsys.readouterr().err == "rigidbench: interrupted by SIGINT\n"
    assert [type(u.exc_value) for u in printed] == [ZeroDivisionError]
    assert sys.unraisablehook == printed.append  # given back after the command
