"""Interactive panel for notebook 06: rerun the SSAC covariance study and redraw.

Sliders for the site latitude, the run duration and the P0 attitude scaling (1 = matched
P0, ssac.md §4.4) plus a P0-variant dropdown call :func:`navlib.studies.ssac.run` and redraw
the sigma panels, the normalised eigenvalues, the pair structure and the closed-form limits.
"""

from __future__ import annotations

import ipywidgets as widgets
import matplotlib.pyplot as plt
from IPython.display import display

from navlib.errors import NavlibInputError
from navlib.models.ssac import SITE_LAT_DEG
from navlib.plots.ssac import ssac_eigenvalues_figure, ssac_sigma_figure
from navlib.studies.ssac import closed_form_limits, pair_structure, run


class SSACPanel(widgets.VBox):
    """Controls + status line + output area; ``update()`` reruns the study and redraws.

    Attributes
    ----------
    controls : dict
        ``lat_deg``, ``duration_min``, ``attitude_scale`` sliders and ``P0`` dropdown.
    status : ipywidgets.HTML
    output : ipywidgets.Output
    study : SSACStudy or None
        The last study computed.
    """

    def __init__(self, duration_min: float = 60.0, **fixed):
        look = dict(style={"description_width": "10em"}, layout=widgets.Layout(width="30em"))
        slider = dict(continuous_update=False, **look)
        self.controls = {
            "lat_deg": widgets.FloatSlider(value=round(SITE_LAT_DEG, 3), min=-85.0, max=85.0,
                                           step=0.5, description="latitude [deg]", **slider),
            "duration_min": widgets.FloatSlider(value=duration_min, min=2.0, max=120.0,
                                                step=1.0, description="duration [min]",
                                                **slider),
            "attitude_scale": widgets.FloatLogSlider(value=1.0, base=10, min=-1, max=2,
                                                     step=0.1, description="P0 attitude x",
                                                     **slider),
            "P0": widgets.Dropdown(options=["matched", "generic"], value="matched",
                                   description="P0 variant", **look),
        }
        self.fixed = dict(fixed)
        self.status = widgets.HTML()
        self.output = widgets.Output()
        self.study = None
        for control in self.controls.values():
            control.observe(lambda _change: self.update(), names="value")
        super().__init__([widgets.VBox(list(self.controls.values())), self.status,
                          self.output])
        self.update()

    def keywords(self) -> dict:
        """Keyword arguments of :func:`navlib.studies.ssac.run` from the controls."""
        c = self.controls
        kw = {"lat_deg": c["lat_deg"].value, "duration_s": 60.0 * c["duration_min"].value,
              "attitude_scale": c["attitude_scale"].value, "P0": c["P0"].value,
              "track": False}
        kw.update(self.fixed)
        return kw

    def update(self) -> None:
        """Rerun the study with the current controls and redraw (errors go to ``status``)."""
        try:
            study = run(**self.keywords())
        except NavlibInputError as exc:
            self.status.value = f'<b style="color:#b00">Invalid input:</b> {exc}'
            return
        self.study = study
        lam = study.eigen.eigenvalues[-1]
        self.status.value = (f"ok: {study.t.size} epochs; six largest normalised eigenvalues "
                             f"sum to {lam[:6].sum():.3f}, 7th = {lam[6]:.1e}")
        limits = closed_form_limits(study)
        with self.output:
            self.output.clear_output(wait=True)
            for fig in (ssac_sigma_figure(study, limits), ssac_eigenvalues_figure(study)):
                display(fig)
                plt.close(fig)
            display(pair_structure(study.eigen).round(4))
            display(limits.round(5))


def ssac_panel(duration_min: float = 60.0, **fixed) -> SSACPanel:
    """Build the SSAC panel; ``fixed`` keywords go to every :func:`~navlib.studies.ssac.run`
    call (e.g. ``dt=2.0`` for a lighter session)."""
    return SSACPanel(duration_min=duration_min, **fixed)
