"""Linear error models (spec api.md "Models").

``LinearModel`` (continuous, with ``subset`` and ``discretize``) and ``DiscreteModel``
(``t, F, Q, H, R`` at epochs). Builders: ``ssac``, ``launcher``, ``simplified_gps_bias``,
``ecef21`` live in their own modules and are exported here.
"""

from navlib.models.base import DiscreteModel, LinearModel
from navlib.models.ecef import ecef21, ecef21_at_epochs
from navlib.models.launcher import launcher, simplified_gps_bias
from navlib.models.ssac import ssac

__all__ = ["DiscreteModel", "LinearModel"]
__all__ += ["ecef21", "ecef21_at_epochs"]
__all__ += ["ssac"]
__all__ += ["launcher", "simplified_gps_bias"]
