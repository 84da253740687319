"""Bad arguments raise ValueError/TypeError naming the argument (the CLI's rule texts); nothing
crashes the interpreter."""

import math

import pytest

import bistable_impact as bi

NAN, INF = float("nan"), float("inf")


@pytest.mark.parametrize(
    "kwargs, name, rule",
    [
        ({"omega": -1.0}, "omega", "must be in [1e-6, 1e6]"),
        ({"omega": NAN}, "omega", "must be in [1e-6, 1e6]"),
        ({"omega": 0.0}, "omega", "must be in [1e-6, 1e6]"),
        ({"omega": 1.0000000000000002e6}, "omega", "must be in [1e-6, 1e6]"),
        ({"velocity": -0.1}, "velocity", "must be in [0, 1e6]"),
        ({"velocity": 1.0000000000000002e6}, "velocity", "must be in [0, 1e6]"),
        ({"velocity": INF}, "velocity", ""),
        ({"zeta": -0.1}, "zeta", "must be finite and >= 0"),
        ({"restitution": 1.5}, "restitution", "must be finite and in [0, 1]"),
        ({"restitution": NAN}, "restitution", ""),
        ({"tol": 0.0}, "tol", "must be finite and in [1e-18, 1e-3]"),
        ({"tol": 1.0}, "tol", ""),
        ({"t_end": -5.0}, "t_end", "must be finite and > 0"),
        ({"t_end": NAN}, "t_end", ""),
        ({"t_end": None, "periods": 0.0}, "periods", "must be finite and > 0"),
        ({"t_end": None, "periods": 1e308}, "periods", "too large"),
        ({"trace_dt": 0.0}, "trace_dt", "must be finite and > 0"),
        ({"trace_dt": 1e-300}, "trace_dt", "too small"),
        ({"chatter": "sometimes"}, "chatter", "must be 'accumulation' or 'paper'"),
    ],
)
def test_simulate_names_the_bad_argument(kwargs, name, rule):
    args = {"omega": 1.75, "velocity": 0.07, "t_end": 10.0}
    args.update(kwargs)
    with pytest.raises(ValueError) as e:
        bi.simulate(**args)
    msg = str(e.value)
    assert f"for '{name}'" in msg and rule in msg, msg


def test_cli_message_format():
    with pytest.raises(ValueError) as e:
        bi.simulate(-1.0, 0.07, t_end=1.0)
    assert str(e.value) == "invalid value '-1.0' for 'omega': must be in [1e-6, 1e6]"


def test_duration_exactly_one():
    with pytest.raises(ValueError, match="exactly one of 't_end' and 'periods'"):
        bi.simulate(1.75, 0.07)
    with pytest.raises(ValueError, match="exactly one"):
        bi.simulate(1.75, 0.07, t_end=1.0, periods=1.0)


@pytest.mark.parametrize(
    "call",
    [
        lambda: bi.simulate("fast", 0.07, t_end=1.0),
        lambda: bi.simulate(1.75, None, t_end=1.0),
        lambda: bi.simulate(1.75, 0.07, t_end="10"),
        lambda: bi.simulate(1.75, 0.07, t_end=1.0, chatter=3),
        lambda: bi.classify(1.75, [0.07]),
        lambda: bi.classify(1.75, 0.07, max_period=2.5),
        lambda: bi.Simulator(1.75, object()),
    ],
)
def test_wrong_types_raise_type_error(call):
    with pytest.raises(TypeError):
        call()


def test_huge_integers_raise_value_error_naming_the_argument():
    with pytest.raises(ValueError, match="for 'periods': too large for a float"):
        bi.simulate(1.75, 0.07, periods=10**400)
    with pytest.raises(ValueError, match="for 'max_period': must be in"):
        bi.classify(1.75, 0.07, max_period=2**40)
    with pytest.raises(ValueError, match="for 'lyapunov_periods': must be in"):
        bi.classify(1.75, 0.07, lyapunov_periods=-1)
    with pytest.raises(ValueError, match="for 'omega': too large for a float"):
        bi.Simulator(10**400, 0.07)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"max_periods": 0.5}, "max_periods"),
        ({"max_periods": NAN}, "max_periods"),
        ({"max_period": 65}, "max_period"),
        ({"max_period": 0}, "max_period"),
        ({"period_tol": 0.1}, "period_tol"),
        ({"lyapunov_periods": 0}, "lyapunov_periods"),
        ({"repeats": 65}, "repeats"),
        ({"efoldings": 0.0}, "efoldings"),
        ({"perturbation": 1e-2}, "perturbation"),
        ({"horizon": 0.5}, "horizon"),
        ({"repeat_periods": NAN}, "repeat_periods"),
        ({"lyapunov_windows": 1025}, "lyapunov_windows"),
        ({"omega": -2.0}, "omega"),
        ({"restitution": -1.0}, "restitution"),
    ],
)
def test_classify_names_the_bad_argument(kwargs, name):
    args = {"omega": 1.75, "velocity": 0.07}
    args.update(kwargs)
    with pytest.raises(ValueError, match=f"for '{name}'"):
        bi.classify(**args)


def test_simulator_and_thresholds_arguments():
    with pytest.raises(ValueError, match="for 'x0'"):
        bi.Simulator(1.75, 0.07, x0=NAN)
    with pytest.raises(ValueError, match="for 'restitution': must be in \\[0, 1\\)"):
        bi.thresholds(1.0)
    with pytest.raises(ValueError, match="for 'omega'"):
        bi.thresholds(0.5, omega=-1.0)


def test_shakers_beyond_the_ranges_are_refused_and_the_corners_run():
    # Beyond [1e-6, 1e6] the free flight's error grows with Ω: refused before any work.
    for omega, v in [(1e-300, 1e300), (1e300, 1e-300), (5e-324, 0.0), (1e10, 0.07)]:
        with pytest.raises(ValueError, match=r"for 'omega': must be in \[1e-6, 1e6\]"):
            bi.simulate(omega, v, t_end=1.0)
    # The corners of the ranges run to the end, the mass never below the plate.
    for omega, v in [(1e6, 1e6), (1e-6, 1e6), (1e-6, 0.0), (1e6, 0.0)]:
        fs = bi.simulate(omega, v, t_end=1.0).final_state
        assert fs["t"] == 1.0 and math.isfinite(fs["x"]) and fs["x"] >= fs["z"], (omega, v, fs)
