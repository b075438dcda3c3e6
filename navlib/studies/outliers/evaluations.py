"""The launcher ascent's named evaluations of :func:`navlib.sweep.sweep` (Beaudoin et al.
2018): "observability" (local observability of a launcher configuration) and "outliers"
(the recovery verdict of the linear filter after one outlier). The launcher trajectory is
kept per process (too big to move between workers at 200 Hz), and so are the prepared
filters of the outlier study."""

from __future__ import annotations

from navlib import observability
from navlib.cache import memoized
from navlib.models.launcher import launcher_steps
from navlib.sensors.faults import Outlier
from navlib.studies.outliers.response import FilterCache, outlier_response
from navlib.sweep import Evaluation, register
from navlib.trajectory import launcher_ascent

__all__: list[str] = []  # nothing to import: importing the module registers its evaluations

_LAUNCHER = {"solution": "ins_gps_att", "biases": "GAP", "bias_model": "markov",
             "duration_s": 150.0, "rate_hz": 200.0}


@memoized(maxsize=2)
def _launcher_trajectory(duration_s: float, rate_hz: float):
    return launcher_ascent(duration_s=duration_s, rate_hz=rate_hz)


def _observability_run(_, *, solution, biases, bias_model, duration_s, rate_hz, stride,
                       variant) -> dict:
    traj = _launcher_trajectory(float(duration_s), float(rate_hz))
    # the Euler steps computed at the strided windows only, not the model at every sample
    model = launcher_steps(solution, biases, bias_model, trajectory=traj)
    res = observability.local_observability(model, variant=variant, stride=int(stride),
                                            n_jobs=1)
    k = int(res.step[res.step.size // 2])
    mid = observability.analyze(observability.local_matrix(model, k, variant=variant),
                                rtol=res.rtol, state_names=model.state_names)
    out = {"n_states": int(model.n), "n_unobservable": int(res.n_unobservable),
           "log10_cond": float(res.log10_max_cond), "rank_constant": bool(res.rank_constant)}
    out.update({f"unobs_{s}": float(v) for s, v in zip(model.state_names,
                                                       mid.unobservable_share, strict=True)})
    return out


@memoized(maxsize=1)
def _outlier_cache(duration_s: float, rate_hz: float):
    return FilterCache(_launcher_trajectory(duration_s, rate_hz), size=1)


def _outliers_run(_, *, solution, biases, bias_model, duration_s, rate_hz, channel, magnitude,
                  time_s, shape, pulse_s, watch, window_s) -> dict:
    outlier = Outlier(channel, float(time_s), float(magnitude), shape,
                      None if shape != "pulse" else float(pulse_s))
    res = outlier_response(solution, outlier, watch, biases=biases, bias_model=bias_model,
                           window=float(window_s),
                           cache=_outlier_cache(float(duration_s), float(rate_hz)))
    score = res.score
    return {"applied": bool(res.applied), "verdict": str(score.verdict),
            "recovers": score.verdict == "recovers", "peak": float(score.peak),
            "residual": float(score.residual), "retained": float(score.retained)}


register(Evaluation("observability", "launcher ascent: local observability (unobservable "
                    "states, log10 max condition number; unobservable share per state at "
                    "mid-mission)", {**_LAUNCHER, "stride": 200, "variant": "time_varying"},
                    ("duration_s", "rate_hz"), _observability_run))
register(Evaluation("outliers", "launcher ascent: outlier recovery verdict of the linear "
                    "filter (recovers / static error, peak, residual, retained)",
                    {**_LAUNCHER, "channel": "gyro_x", "magnitude": 0.002, "time_s": 50.0,
                     "shape": "spike", "pulse_s": 1.0, "watch": "roll", "window_s": 100.0},
                    ("duration_s", "rate_hz", "solution", "biases", "bias_model"),
                    _outliers_run))
