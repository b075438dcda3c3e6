"""Allan-deviation figure: measured deviation per axis with the fitted noise terms."""

from __future__ import annotations

import numpy as np

from navlib.errors import NavlibInputError
from navlib.plots.figure import subplots
from navlib.sensors.allan import TERMS, allan_model

__all__ = ["allan_figure"]

_SLOPES = {"random_walk": -0.5, "bias_instability": 0.0, "rate_random_walk": 0.5}


def allan_figure(fit, adev=None):
    """Log-log Allan deviation of the gyros (left) and accelerometers (right): the measured
    points, the fitted model and each resolved term's asymptote (slopes -1/2, 0, +1/2).

    ``fit`` is :func:`navlib.sensors.fit_allan`'s frame; ``adev`` defaults to the deviation
    it kept (``fit.attrs["adev"]``).
    """
    adev = fit.attrs.get("adev") if adev is None else adev
    if adev is None or "tau_s" not in adev.columns:
        raise NavlibInputError("adev: pass the frame allan_deviation returned (the fit keeps "
                               "it in attrs['adev'])")
    tau = adev["tau_s"].to_numpy(dtype=float)
    fig, axes = subplots(1, 2, figsize=(11, 4.4), layout="constrained")
    for ax, triad, unit in ((axes[0], "w", "rad/s"), (axes[1], "f", "m/s²")):
        for axis in [a for a in fit.index if str(a).startswith(triad)]:
            row = fit.loc[axis]
            line, = ax.loglog(tau, adev[axis], "o", markersize=2.5, label=f"{axis} measured")
            ax.loglog(tau, allan_model(tau, *(row[t] for t in TERMS)), "-",
                      color=line.get_color(), linewidth=1.0, label=f"{axis} fit")
            for term in TERMS:
                if np.isfinite(row[term]):
                    ax.loglog(tau, allan_model(tau, **{term: row[term]}), ":",
                              color=line.get_color(), linewidth=0.7)
        ax.set_xlabel("averaging time τ [s]")
        ax.set_ylabel(f"Allan deviation [{unit}]")
        ax.grid(True, which="both", linewidth=0.3)
        ax.legend(fontsize=7, ncol=2)
    slopes = ", ".join(f"{t.replace('_', ' ')} {s:+g}" for t, s in _SLOPES.items())
    fig.suptitle(f"Overlapping Allan deviation and fitted terms (dotted asymptotes, slopes: "
                 f"{slopes})", fontsize=10)
    return fig
