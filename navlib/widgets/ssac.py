"""Interactive panel for notebook 06: rerun the SSAC covariance study and redraw.

Sliders for the site latitude, the run duration and the P0 attitude scaling (1 = matched
P0, docs/assumptions.md, ssac.md §4.4) plus a P0-variant dropdown call
:func:`navlib.studies.ssac.covariance_run` and redraw the sigma panels, the normalised
eigenvalues, the pair structure and the closed-form limits (render path of
:mod:`navlib.widgets.base`: detached figures shown as PNG images).
"""

from __future__ import annotations

import ipywidgets as widgets

from navlib.models.ssac import SITE_LAT_DEG
from navlib.plots.ssac import (
    ssac_eigenvalues_figure,
    ssac_sigma_figure,
    update_ssac_eigenvalues_figure,
    update_ssac_sigma_figure,
)
from navlib.studies.ssac import closed_form_limits, covariance_run, pair_structure
from navlib.widgets.base import Panel, look, table_html

__all__ = ["SSACPanel", "ssac_panel"]


class SSACPanel(Panel):
    """Controls + status line + figures and tables; ``update()`` reruns the study and redraws.

    Attributes
    ----------
    controls : dict
        ``lat_deg``, ``duration_min``, ``attitude_scale`` sliders and ``P0`` dropdown.
    status : ipywidgets.HTML
    parts : dict
        ``sigma`` and ``eigenvalues`` images, ``pairs`` and ``limits`` tables.
    study : SSACStudy or None
        The last study computed.
    """

    def __init__(self, duration_min: float = 60.0, dpi: float = 72.0, **fixed):
        slider = dict(continuous_update=False, **look("30em"))
        controls = {
            "lat_deg": widgets.FloatSlider(value=round(SITE_LAT_DEG, 3), min=-85.0, max=85.0,
                                           step=0.5, description="latitude [deg]", **slider),
            "duration_min": widgets.FloatSlider(value=duration_min, min=2.0, max=120.0,
                                                step=1.0, description="duration [min]",
                                                **slider),
            "attitude_scale": widgets.FloatLogSlider(value=1.0, base=10, min=-1, max=2,
                                                     step=0.1, description="P0 attitude x",
                                                     **slider),
            "P0": widgets.Dropdown(options=["matched", "generic"], value="matched",
                                   description="P0 variant", **look("30em")),
        }
        self.fixed = dict(fixed)
        self.study = None
        super().__init__(controls, dpi=dpi)

    def keywords(self) -> dict:
        """Keyword arguments of :func:`navlib.studies.ssac.covariance_run` from the controls."""
        c = self.controls
        kw = {"lat_deg": c["lat_deg"].value, "duration_s": 60.0 * c["duration_min"].value,
              "attitude_scale": c["attitude_scale"].value, "P0": c["P0"].value,
              "track": False}
        kw.update(self.fixed)
        return kw

    def refresh(self, changed: set) -> None:
        """Rerun the study with the current controls and redraw."""
        study = covariance_run(**self.keywords())
        self.study = study
        lam = study.spectrum.eigenvalues[-1]
        self.status.value = (f"ok: {study.t.size} epochs; six largest normalised eigenvalues "
                             f"sum to {lam[:6].sum():.3f}, 7th = {lam[6]:.1e}")
        limits = closed_form_limits(study)
        kept = self.figures.figure("sigma"), self.figures.figure("eigenvalues")
        if None in kept:
            self.show("sigma", ssac_sigma_figure(study, limits))
            self.show("eigenvalues", ssac_eigenvalues_figure(study))
        else:  # the controls change numbers, not states: new data in the kept figures
            update_ssac_sigma_figure(kept[0], study, limits)
            update_ssac_eigenvalues_figure(kept[1], study)
            self.show("sigma", self.figures.redrawn("sigma"))
            self.show("eigenvalues", self.figures.redrawn("eigenvalues"))
        self.show("pairs", table_html(pair_structure(study.final_eigen).round(4), index=True))
        self.show("limits", table_html(limits.round(5), index=True))


def ssac_panel(duration_min: float = 60.0, **fixed) -> SSACPanel:
    """Build the SSAC panel; ``fixed`` keywords go to every
    :func:`~navlib.studies.ssac.covariance_run` call (e.g. ``dt_s=2.0`` for a lighter
    session)."""
    return SSACPanel(duration_min=duration_min, **fixed)
