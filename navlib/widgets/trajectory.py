"""Interactive panel for notebook 01: re-synthesise the sounding rocket and redraw.

Sliders for the spin rate and the ignition, burnout and de-spin times plus a launch-site
dropdown call :func:`navlib.trajectory.sounding_rocket` and redraw the Fig. 1 analogue,
height/speed and the profile-claim table. Impossible combinations (burnout before
ignition, de-spin outside the coast, ...) show the NavlibInputError message in the panel.
"""

from __future__ import annotations

import ipywidgets as widgets
import matplotlib.pyplot as plt
from IPython.display import display

from navlib.errors import NavlibInputError
from navlib.plots.trajectory import altitude_speed_figure, axial_imu_figure
from navlib.studies.rocket_profile import rocket_profile_claims
from navlib.studies.verdict import claims_frame
from navlib.trajectory import sounding_rocket

SITES = {
    "Barreira do Inferno, Natal (default)": {"lat_deg": -5.92, "lon_deg": -35.16, "alt_m": 30.0},
    "Alcântara": {"lat_deg": -2.316, "lon_deg": -44.368, "alt_m": 50.0},
    "São José dos Campos (LINCS/IAE)": {"lat_deg": -23.213, "lon_deg": -45.861, "alt_m": 629.0},
    "Churchill": {"lat_deg": 58.734, "lon_deg": -93.820, "alt_m": 30.0},
    "Andøya": {"lat_deg": 69.294, "lon_deg": 16.021, "alt_m": 10.0},
}
"""Launch sites offered by the dropdown (approximate coordinates, degrees and metres)."""


class RocketPanel(widgets.VBox):
    """Controls + status line + output area; ``update()`` re-synthesises and redraws.

    Attributes
    ----------
    controls : dict
        ``spin_hz``, ``ignition_s``, ``burnout_s``, ``despin_s`` sliders and ``site`` dropdown.
    status : ipywidgets.HTML
        "ok" summary or the NavlibInputError message of the last update.
    output : ipywidgets.Output
        The figures and the claim table of the last successful update.
    trajectory : Trajectory or None
        The last trajectory synthesised.
    """

    def __init__(self, **fixed):
        look = dict(style={"description_width": "8em"}, layout=widgets.Layout(width="28em"))
        slider = dict(continuous_update=False, **look)
        self.controls = {
            "spin_hz": widgets.FloatSlider(value=2.0, min=0.0, max=4.0, step=0.1,
                                           description="spin [Hz]", **slider),
            "ignition_s": widgets.FloatSlider(value=18.0, min=0.0, max=40.0, step=0.5,
                                              description="ignition [s]", **slider),
            "burnout_s": widgets.FloatSlider(value=46.0, min=5.0, max=70.0, step=0.5,
                                             description="burnout [s]", **slider),
            "despin_s": widgets.FloatSlider(value=73.0, min=20.0, max=86.0, step=0.5,
                                            description="de-spin [s]", **slider),
            "site": widgets.Dropdown(options=list(SITES), description="site", **look),
        }
        self.fixed = dict(fixed)
        self.status = widgets.HTML()
        self.output = widgets.Output()
        self.trajectory = None
        for control in self.controls.values():
            control.observe(lambda _change: self.update(), names="value")
        super().__init__([widgets.HBox([widgets.VBox(list(self.controls.values()))]),
                          self.status, self.output])
        self.update()

    def keywords(self) -> dict:
        """The keyword arguments the controls (and ``fixed``) give to ``sounding_rocket``."""
        kw = {name: c.value for name, c in self.controls.items() if name != "site"}
        kw.update(SITES[self.controls["site"].value])
        kw.update(self.fixed)
        return kw

    def update(self) -> None:
        """Re-synthesise with the current controls and redraw (errors go to ``status``)."""
        try:
            traj = sounding_rocket(**self.keywords())
        except NavlibInputError as exc:
            self.status.value = f'<b style="color:#b00">Not a valid flight:</b> {exc}'
            return
        self.trajectory = traj
        claims = claims_frame(rocket_profile_claims(traj))
        n_ok = int((claims["verdict"] == "reproduced").sum())
        self.status.value = (f"ok: {len(traj)} samples; paper profile claims reproduced: "
                             f"{n_ok}/{len(claims)}")
        with self.output:
            self.output.clear_output(wait=True)
            for fig in (axial_imu_figure(traj), altitude_speed_figure(traj)):
                display(fig)
                plt.close(fig)
            display(claims[["claim_id", "claim", "paper", "ours", "verdict"]])


def rocket_panel(**fixed) -> RocketPanel:
    """Build the sounding-rocket panel; ``fixed`` keywords go to every ``sounding_rocket``
    call (e.g. ``rate_hz=50`` for a lighter interactive session)."""
    return RocketPanel(**fixed)
