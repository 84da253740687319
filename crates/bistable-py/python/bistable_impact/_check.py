"""Argument checks shared by the package's functions, run before any work.

Numbers are converted here (a Python ``int`` too large for the native types would otherwise
raise an ``OverflowError`` that does not name the argument); the model's rules (finite values,
``Ω``, ``V``, ``ζ``, ``e`` and ``tol`` ranges, the analyses' options) are checked by the native
module with the CLI's messages. Errors: ``TypeError`` for a wrong type, ``ValueError`` for a bad
value, both naming the argument (``invalid value '<value>' for '<name>': <rule>``).

The limits on work sizes (documented in the README's Python section) are defined here:
"""

from __future__ import annotations

import numbers
import operator
import os
from typing import Any, List, Optional, Sequence, Tuple

import numpy as np

from . import _native

#: Most values of one grid, and most points (cells) of one map: the CLI's cap on ranges.
MAX_POINTS: int = _native.MAX_POINTS
#: Most shaker periods of a transient (``settle``, ``transient``).
MAX_TRANSIENT = 1_000_000
#: Most shaker periods averaged for a Lyapunov exponent (``lyapunov_periods``).
MAX_LYAPUNOV_PERIODS = 1_000_000
#: Most dense-output samples per shaker period of the bifurcation maxima (``samples``).
MAX_CYCLE_SAMPLES = 4096
#: Most worker threads (``threads``; 0: one per core).
MAX_THREADS: int = _native.MAX_THREADS
#: Most periods of orbit branches (``branch_periods``) in one call.
MAX_BRANCHES = 64


def invalid(name: str, shown: str, rule: str) -> ValueError:
    """The CLI's message for a bad value of ``name``, shown as ``shown``."""
    return ValueError(f"invalid value '{shown}' for '{name}': {rule}")


def _type_error(name: str, what: str, value: Any) -> TypeError:
    return TypeError(f"'{name}' must be {what}, not {type(value).__name__}")


def integer(name: str, value: Any, lo: int, hi: int) -> int:
    """An integer in ``[lo, hi]`` (``bool`` is not one; numpy integers are)."""
    if isinstance(value, bool) or not hasattr(type(value), "__index__"):
        raise _type_error(name, "an integer", value)
    n = operator.index(value)
    if not lo <= n <= hi:
        raise invalid(name, str(n), f"must be in [{lo}, {hi}]")
    return n


def real(name: str, value: Any) -> float:
    """A real number as a float (not ``bool`` or ``str``; NaN and infinities pass, for the
    native checks to name)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise _type_error(name, "a real number", value)
    try:
        return float(value)
    except OverflowError:
        raise invalid(name, repr(value), "too large for a float") from None


def text(name: str, value: Any) -> str:
    if not isinstance(value, str):
        raise _type_error(name, "a str", value)
    return value


def optional_real(name: str, value: Any) -> Optional[float]:
    return None if value is None else real(name, value)


def pair(name: str, value: Any) -> Tuple[float, float]:
    """Two real numbers."""
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) != 2:
        raise invalid(name, repr(value), "must be two finite numbers")
    return (real(name, value[0]), real(name, value[1]))


def reals(name: str, values: Any) -> List[float]:
    """One real number or a sequence (list, tuple, numpy array) of them, as a list of at
    least one and at most :data:`MAX_POINTS` values."""
    if isinstance(values, (str, bytes, dict, set)):
        raise _type_error(name, "a number or a sequence of numbers", values)
    if isinstance(values, numbers.Real) or getattr(values, "ndim", None) == 0:
        values = [values]
    try:
        n = len(values)
    except TypeError:
        raise _type_error(name, "a number or a sequence of numbers", values) from None
    if n < 1:
        raise invalid(name, "[]", "must have at least one value")
    if n > MAX_POINTS:
        raise invalid(name, f"<{n} values>", f"must have at most {MAX_POINTS} values")
    if isinstance(values, np.ndarray) and values.ndim == 1 and values.dtype.kind in "fiu":
        return values.astype(float).tolist()  # numbers that fit a float: no check each
    out = []
    for v in values:
        if isinstance(v, (list, tuple)) or getattr(v, "ndim", 0) != 0:
            raise _type_error(name, "a flat sequence of numbers", values)
        out.append(real(name, v))
    return out


def grid(names: Tuple[str, str], a: Sequence[float], b: Sequence[float]) -> None:
    """A grid ``a × b`` of at most :data:`MAX_POINTS` points."""
    if len(a) * len(b) > MAX_POINTS:
        raise invalid(
            names[0],
            f"<{len(a)} values>",
            f"{names[0]} × {names[1]} must have at most {MAX_POINTS} points "
            f"({len(a)} × {len(b)})",
        )


def threads(value: Any) -> int:
    return integer("threads", value, 0, MAX_THREADS)


def lanes(value: Any) -> int:
    """A lane width: 1, 4 or 8 trajectories per thread in SIMD lanes."""
    n = integer("lanes", value, 1, 8)
    if n not in (1, 4, 8):
        raise invalid("lanes", str(n), "must be 1, 4 or 8")
    return n


def client(value: Any) -> Any:
    """``None`` or a ``dask.distributed`` Client (anything with ``map`` and ``gather``)."""
    if value is not None and not (
        callable(getattr(value, "map", None)) and callable(getattr(value, "gather", None))
    ):
        raise _type_error("client", "a dask.distributed Client or None", value)
    return value


#: Bounds of the points (or starts) per Dask task that ``chunk=None`` chooses.
AUTO_CHUNK = (16, 256)


def chunk(value: Any) -> Optional[int]:
    """``None`` (chosen per sweep by :func:`tasks`) or the points per Dask task, ``[1, 1e7]``."""
    return None if value is None else integer("chunk", value, 1, MAX_POINTS)


def tasks(items: list, size: Optional[int], client: Any) -> list:
    """``items`` cut into the Dask tasks of a sweep, ``size`` items each; ``size=None`` takes
    as many as give every worker thread of ``client`` about 8 tasks, at least 16 and at most
    256: few enough tasks that Dask's own work per task stays small, enough that the last ones
    still spread over the workers."""
    if size is None:
        nthreads = getattr(client, "nthreads", None)
        try:
            threads = max(1, sum(nthreads().values())) if callable(nthreads) else 1
        except Exception:  # a client-like object without a scheduler's view of its workers
            threads = 1
        lo, hi = AUTO_CHUNK
        size = max(lo, min(hi, -(-len(items) // (8 * threads))))
    return [items[i : i + size] for i in range(0, len(items), size)]


def path(name: str, value: Any) -> Optional[str]:
    """``None`` or a file path (``str`` or ``os.PathLike``; not a file descriptor)."""
    if value is None:
        return None
    if not isinstance(value, (str, os.PathLike)):
        raise _type_error(name, "a path (str or os.PathLike) or None", value)
    p = os.fspath(value)
    if not isinstance(p, str) or not p:
        raise invalid(name, repr(value), "must be a non-empty text path")
    return p


def classify_options(o: dict) -> dict:
    """The classification options of :func:`bistable_impact.classify` and the map, converted;
    their ranges are checked by the native module."""
    out = dict(o)
    for k in ("zeta", "restitution", "tol", "max_periods", "period_tol"):
        out[k] = real(k, o[k])
    for k in ("efoldings", "perturbation", "horizon", "repeat_periods"):
        out[k] = optional_real(k, o[k])
    out["chatter"] = text("chatter", o["chatter"])
    out["max_period"] = integer("max_period", o["max_period"], 1, 64)
    out["lyapunov_periods"] = integer(
        "lyapunov_periods", o["lyapunov_periods"], 1, MAX_LYAPUNOV_PERIODS
    )
    if o["repeats"] is not None:
        out["repeats"] = integer("repeats", o["repeats"], 0, 64)
    if o["lyapunov_windows"] is not None:
        out["lyapunov_windows"] = integer("lyapunov_windows", o["lyapunov_windows"], 0, 1024)
    return out


def model(**o: Any) -> dict:
    """The model's settings among ``o`` (``omega, velocity, zeta, restitution, tol, chatter``),
    converted."""
    out = dict(o)
    for k in ("omega", "velocity", "zeta", "restitution", "tol"):
        if k in o:
            out[k] = real(k, o[k])
    if "chatter" in o:
        out["chatter"] = text("chatter", o["chatter"])
    return out
