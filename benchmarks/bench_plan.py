"""Benchmarks of mission planning.

* ``plan.from_mission_<example>``: build each example mission's trajectory with exact IMU
  (waypoint missions: 6000-7000 samples at 50 Hz; the rocket: 8601 at 100 Hz, its
  generator's own cache disabled by a fresh keyword). Goal 0.2 s (rocket 1 s).
* ``plan.plan_mission_<example>``: the whole plan (trajectory, 21-state model at the GNSS
  epochs, segments, metrics), warm model cache, as the notebook and the panel see it after
  the first run. Goal 1 s.
* ``plan.fit_allan_1h_100hz``: Allan deviation (allantools) and noise-term fit of a
  one-hour static record at 100 Hz, six axes. Goal 2 s.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from _harness import Case

from navlib.sensors import fit_allan, random_walk, white_noise
from navlib.studies.plan import plan_mission
from navlib.trajectory.mission import from_mission, list_missions, with_values

_STATIC: dict = {}


def _static():
    if not _STATIC:
        rng = np.random.default_rng(0)
        t = np.arange(360_000) / 100.0
        x = white_noise(t, 1e-3, rng, 6) + random_walk(t, 1e-3, rng, 6)
        frame = pd.DataFrame(x, columns=["w_x", "w_y", "w_z", "f_x", "f_y", "f_z"])
        frame.insert(0, "t", t)
        _STATIC["imu"] = frame
    return _STATIC["imu"]


def _rocket_uncached():
    # a new roll angle each call defeats the generator's memory cache
    _rocket_uncached.calls = getattr(_rocket_uncached, "calls", 0) + 1
    return from_mission(with_values("sounding_rocket",
                                    {"rocket.roll0_deg": 1e-6 * _rocket_uncached.calls}))


def cases() -> list[Case]:
    out = []
    for name in list_missions():
        build = _rocket_uncached if name == "sounding_rocket" else \
            (lambda name=name: from_mission(name))
        out.append(Case(f"plan.from_mission_{name}", name, build,
                        1.0 if name == "sounding_rocket" else 0.2))
    for name in list_missions():
        out.append(Case(f"plan.plan_mission_{name}", name,
                        lambda name=name: plan_mission(name), 1.0))
    out.append(Case("plan.fit_allan_1h_100hz", "360k samples x 6", lambda: fit_allan(_static()),
                    2.0))
    return out
