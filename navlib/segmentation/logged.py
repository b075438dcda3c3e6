"""A rocket's phases from its flight computer's own states, and its events logged and detected.

Rocket flight computers log the state their firmware is in; Altus Metrum AltOS exports it per
row (``state_name``: ``startup``, ``idle``, ``pad``, ``boost``, ``fast``, ``coast``,
``drogue``, ``main``, ``landed``, ``invalid``; :func:`navlib.io.read_altos` keeps each change
as ``attrs["flight_states"]``). :data:`LOGGED_WORDS` maps them to the rocket words of
:data:`navlib.vehicles.VEHICLE_PHASES` (``fast``, AltOS's coast above the speed where the
barometer can be trusted, is ``coast``); :func:`logged_segments` turns the changes into the
segment table; :func:`flight_events` puts the events (ignition, burnout, apogee, main
deployment, landing) the log gives beside those the kinematic segmentation detects.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from navlib.errors import NavlibInputError

__all__ = ["EVENTS", "LOGGED_WORDS", "flight_events", "logged_segments"]

LOGGED_WORDS = {"startup": "pad", "idle": "pad", "pad": "pad", "boost": "boost",
                "fast": "coast", "coast": "coast", "drogue": "drogue", "main": "main",
                "landed": "landed"}
"""Flight-computer state -> rocket phase word (AltOS names; others are not phases)."""

EVENTS = ("ignition", "burnout", "apogee", "main", "landing")
"""Events of :func:`flight_events`, in flight order."""


def _changes(flight_states) -> pd.DataFrame:
    """``t, phase`` at each change of the logged phase word (unknown states dropped)."""
    if isinstance(flight_states, pd.DataFrame):
        if not {"t", "state"} <= set(flight_states.columns):
            raise NavlibInputError(f"flight_states: expected columns 't' and 'state', got "
                                   f"{list(flight_states.columns)}")
        pairs = zip(flight_states["t"], flight_states["state"], strict=True)
    else:
        try:
            pairs = [(t, s) for s, t in flight_states]
        except (TypeError, ValueError):
            raise NavlibInputError(f"flight_states: expected a DataFrame 't, state' or "
                                   f"(state, t) pairs, got {flight_states!r}") from None
    rows = [(float(t), LOGGED_WORDS[str(s).strip().lower()]) for t, s in pairs
            if str(s).strip().lower() in LOGGED_WORDS and np.isfinite(float(t))]
    rows.sort(key=lambda r: r[0])
    kept = [r for k, r in enumerate(rows) if k == 0 or r[1] != rows[k - 1][1]]
    return pd.DataFrame(kept, columns=["t", "phase"])


def logged_segments(flight_states, t_start: float, t_end: float) -> pd.DataFrame | None:
    """The segment table ``phase, t_start, t_end, duration`` of the logged phases inside
    ``[t_start, t_end]`` (each phase from its first logged row to the next phase's; the
    first phase covers the span's start). None when the log names no phase there."""
    changes = _changes(flight_states)
    changes = changes[changes["t"] < t_end]
    if changes.empty:
        return None
    before = changes[changes["t"] <= t_start]
    inside = changes[changes["t"] > t_start]
    first = before["phase"].iloc[-1] if len(before) else inside["phase"].iloc[0]
    phases = [first, *inside["phase"]]
    starts = [t_start, *inside["t"]]
    keep = [k for k in range(len(phases)) if k == 0 or phases[k] != phases[k - 1]]
    phases = [phases[k] for k in keep]
    starts = [starts[k] for k in keep]
    table = pd.DataFrame({"phase": phases, "t_start": np.asarray(starts, dtype=float),
                          "t_end": np.asarray([*starts[1:], t_end], dtype=float)})
    table["duration"] = table["t_end"] - table["t_start"]
    return table


def _event_times(segments: pd.DataFrame, apogee: float | None) -> dict[str, list[float]]:
    """Event name -> times, from a rocket segment table (phase words) and an apogee."""
    phase = segments["phase"].to_numpy()
    start = segments["t_start"].to_numpy(dtype=float)
    end = segments["t_end"].to_numpy(dtype=float)
    boost = np.flatnonzero(phase == "boost")
    events = {"ignition": [float(start[k]) for k in boost],
              "burnout": [float(end[k]) for k in boost if k + 1 < len(phase)],
              "apogee": [] if apogee is None else [float(apogee)],
              "main": [float(start[k]) for k in np.flatnonzero(phase == "main")[:1]],
              "landing": [float(start[k]) for k in np.flatnonzero(phase == "landed")[:1]]}
    return events


def flight_events(detected: pd.DataFrame, apogee_detected: float | None,
                  logged: pd.DataFrame | None = None) -> pd.DataFrame:
    """The rocket's events, logged and detected side by side.

    Parameters
    ----------
    detected : DataFrame
        The kinematic segmentation in rocket words (``phase, t_start, t_end``).
    apogee_detected : float or None
        Time of the highest point of the fitted trajectory, s.
    logged : DataFrame, optional
        :func:`logged_segments`; the logged apogee is the start of ``drogue`` (AltOS fires
        the drogue charge at the apogee it detects), else the end of the last ``coast``.

    Returns
    -------
    DataFrame
        ``event`` (:data:`EVENTS`; a second burn's as ``ignition 2``, ``burnout 2``),
        ``t_logged``, ``t_detected`` (s; NaN where that source has none) and
        ``difference`` (detected minus logged, s).
    """
    found = _event_times(detected, apogee_detected)
    logs = {event: [] for event in EVENTS}
    if logged is not None:
        drogue = logged.loc[logged["phase"] == "drogue", "t_start"]
        coast = logged.loc[logged["phase"] == "coast", "t_end"]
        apogee = (float(drogue.iloc[0]) if len(drogue) else
                  float(coast.iloc[-1]) if len(coast) else None)
        logs = _event_times(logged, apogee)
    rows = []
    for event in EVENTS:
        a, b = logs[event], found[event]
        for k in range(max(len(a), len(b))):
            rows.append({"event": event if k == 0 else f"{event} {k + 1}",
                         "t_logged": a[k] if k < len(a) else np.nan,
                         "t_detected": b[k] if k < len(b) else np.nan})
    table = pd.DataFrame(rows, columns=["event", "t_logged", "t_detected"])
    table["difference"] = table["t_detected"] - table["t_logged"]
    return table
