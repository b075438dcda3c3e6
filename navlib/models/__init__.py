"""Linear error models (docs/library.md).

``LinearModel`` (continuous, with ``subset`` and ``discretize``) and ``DiscreteModel``
(``t, F, Q, H, R`` at epochs), and their builders:

* ``ecef21`` / ``ecef21_at_epochs``: the 21-state ECEF model of España et al. (2019);
* ``launcher`` / ``simplified_gps_bias``: the launcher models of Beaudoin et al. (2018);
* ``ssac``: the stationary local-level models of Silva et al. (2017).

``ErrorStateModel`` is what the closed-loop EKF needs from a model (layout, reset states,
``jacobians``, ``correct``); ``LauncherErrorState`` and ``Ecef21ErrorState`` implement it.
"""

from navlib.models.base import DiscreteModel, ErrorStateModel, LinearModel, Nominal
from navlib.models.ecef import Ecef21ErrorState, ecef21, ecef21_at_epochs
from navlib.models.launcher import LauncherErrorState, launcher, simplified_gps_bias
from navlib.models.ssac import ssac

__all__ = [
    "DiscreteModel", "Ecef21ErrorState", "ErrorStateModel", "LauncherErrorState", "LinearModel",
    "Nominal", "ecef21", "ecef21_at_epochs", "launcher", "simplified_gps_bias", "ssac",
]
