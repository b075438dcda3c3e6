"""Argument checking shared by user-facing calls; every failure is a NavlibInputError."""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np

from navlib.errors import NavlibInputError


def reject_unknown(options: Mapping[str, object], allowed: Iterable[str], where: str) -> None:
    """Raise if ``options`` holds a keyword not in ``allowed``."""
    allowed = set(allowed)
    unknown = sorted(set(options) - allowed)
    if unknown:
        raise NavlibInputError(
            f"{where}: unknown keyword(s) {unknown}; accepted: {sorted(allowed)}"
        )


def finite_array(value, name: str, shape: tuple | None = None, ndim: int | None = None):
    """Return ``value`` as a float array, checking finiteness and (optionally) shape.

    ``shape`` may contain ``None`` for free dimensions, e.g. ``(None, 3)``.
    """
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise NavlibInputError(f"{name}: expected numbers, got {type(value).__name__}") from exc
    if ndim is not None and arr.ndim != ndim:
        raise NavlibInputError(f"{name}: expected {ndim} dimension(s), got shape {arr.shape}")
    if shape is not None:
        ok = arr.ndim == len(shape) and all(
            want is None or want == got for want, got in zip(shape, arr.shape, strict=True)
        )
        if not ok:
            pretty = "(" + ", ".join("N" if s is None else str(s) for s in shape) + ")"
            raise NavlibInputError(f"{name}: expected shape {pretty}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise NavlibInputError(f"{name}: contains NaN or infinite values")
    return arr


def finite_scalar(value, name: str, low: float | None = None, high: float | None = None,
                  low_open: bool = False) -> float:
    """Return ``value`` as a finite float inside ``[low, high]`` (``(low, high]`` if open)."""
    try:
        x = float(value)
    except (TypeError, ValueError) as exc:
        raise NavlibInputError(f"{name}: expected a number, got {value!r}") from exc
    if not np.isfinite(x):
        raise NavlibInputError(f"{name}: must be finite, got {x}")
    if low is not None and (x < low or (low_open and x == low)):
        bound = f"> {low}" if low_open else f">= {low}"
        raise NavlibInputError(f"{name}: must be {bound}, got {x}")
    if high is not None and x > high:
        raise NavlibInputError(f"{name}: must be <= {high}, got {x}")
    return x


def latitude_deg(value, name: str = "lat_deg") -> float:
    """A geodetic latitude in degrees, inside [-90, 90]."""
    return finite_scalar(value, name, -90.0, 90.0)


def increasing_times(t, name: str = "t"):
    """A 1-D finite array of strictly increasing times."""
    t = finite_array(t, name, ndim=1)
    if t.size < 2:
        raise NavlibInputError(f"{name}: need at least 2 samples, got {t.size}")
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        k = int(bad[0]) + 1
        raise NavlibInputError(
            f"{name}: times must be strictly increasing; sample {k} ({t[k]}) "
            f"does not follow sample {k - 1} ({t[k - 1]})"
        )
    return t
