"""Interactive panel for notebook 01: re-synthesise the sounding rocket and redraw.

Sliders for the spin rate and the ignition, burnout and de-spin times plus a launch-site
dropdown call :func:`navlib.trajectory.sounding_rocket` and redraw the Fig. 1 analogue,
height/speed and the profile-claim table. Impossible combinations (burnout before
ignition, de-spin outside the coast, ...) show the NavlibInputError message in the panel.
Figures go through the render path of :mod:`navlib.widgets.base` (detached, PNG images).
"""

from __future__ import annotations

import ipywidgets as widgets

from navlib.plots.trajectory import altitude_speed_figure, axial_imu_figure
from navlib.studies.claims import claims_frame
from navlib.studies.rocket import rocket_profile_claims
from navlib.trajectory import sounding_rocket
from navlib.widgets.base import Panel, look

__all__ = ["SITES", "RocketPanel", "rocket_panel"]

SITES = {
    "Barreira do Inferno, Natal (default)": {"lat_deg": -5.92, "lon_deg": -35.16, "alt_m": 30.0},
    "Alcântara": {"lat_deg": -2.316, "lon_deg": -44.368, "alt_m": 50.0},
    "São José dos Campos (LINCS/IAE)": {"lat_deg": -23.213, "lon_deg": -45.861, "alt_m": 629.0},
    "Churchill": {"lat_deg": 58.734, "lon_deg": -93.820, "alt_m": 30.0},
    "Andøya": {"lat_deg": 69.294, "lon_deg": 16.021, "alt_m": 10.0},
}
"""Launch sites offered by the dropdown (approximate coordinates, degrees and metres)."""


class RocketPanel(Panel):
    """Controls + status line + figures; ``update()`` re-synthesises and redraws.

    Attributes
    ----------
    controls : dict
        ``spin_hz``, ``ignition_s``, ``burnout_s``, ``despin_s`` sliders and ``site`` dropdown.
    status : ipywidgets.HTML
        "ok" summary or the NavlibInputError message of the last update.
    parts : dict
        ``axial_imu`` and ``altitude_speed`` images and the ``claims`` table of the last
        successful update.
    trajectory : Trajectory or None
        The last trajectory synthesised.
    """

    error_prefix = "Not a valid flight"

    def __init__(self, dpi: float = 72.0, **fixed):
        slider = dict(continuous_update=False, **look("28em"))
        controls = {
            "spin_hz": widgets.FloatSlider(value=2.0, min=0.0, max=4.0, step=0.1,
                                           description="spin [Hz]", **slider),
            "ignition_s": widgets.FloatSlider(value=18.0, min=0.0, max=40.0, step=0.5,
                                              description="ignition [s]", **slider),
            "burnout_s": widgets.FloatSlider(value=46.0, min=5.0, max=70.0, step=0.5,
                                             description="burnout [s]", **slider),
            "despin_s": widgets.FloatSlider(value=73.0, min=20.0, max=86.0, step=0.5,
                                            description="de-spin [s]", **slider),
            "site": widgets.Dropdown(options=list(SITES), description="site", **look("28em")),
        }
        self.fixed = dict(fixed)
        self.trajectory = None
        super().__init__(controls, dpi=dpi)

    def keywords(self) -> dict:
        """The keyword arguments the controls (and ``fixed``) give to ``sounding_rocket``."""
        kw = {name: c.value for name, c in self.controls.items() if name != "site"}
        kw.update(SITES[self.controls["site"].value])
        kw.update(self.fixed)
        return kw

    def refresh(self, changed: set) -> None:
        """Re-synthesise with the current controls and redraw."""
        traj = sounding_rocket(**self.keywords())
        self.trajectory = traj
        claims = claims_frame(rocket_profile_claims(traj))
        n_ok = int((claims["verdict"] == "reproduced").sum())
        self.status.value = (f"ok: {len(traj)} samples; paper profile claims reproduced: "
                             f"{n_ok}/{len(claims)}")
        self.show("axial_imu", axial_imu_figure(traj))
        self.show("altitude_speed", altitude_speed_figure(traj))
        self.show("claims", claims[["claim_id", "claim", "paper", "ours", "verdict"]])


def rocket_panel(**fixed) -> RocketPanel:
    """Build the sounding-rocket panel; ``fixed`` keywords go to every ``sounding_rocket``
    call (e.g. ``rate_hz=50`` for a lighter interactive session)."""
    return RocketPanel(**fixed)
