"""Paper reproductions: each study composes library pieces into one paper's experiment,
evaluates its claims in code (claim, our number, checks) and returns tidy tables.

* ``claims``: the one claims engine (checks, the verdict rule, the registry) and
  :func:`all_claims`, the table of every claim of every study.
* ``launcher``: Beaudoin et al. (2018), Table 2, Fig. 1 and the covariance figures 2, 3, 5, 6
  (a package: experiment, claims, assumption set, reading).
* ``ssac``: Silva et al. (2017), stationary self-alignment and calibration (a package, as
  ``launcher``).
* ``rocket``: España, Carrizo & Giribet (2019), excitability and sensability (X1-X7, S1-S8).
* ``outliers``: Beaudoin et al. (2018) outlier tests T1-T4 and Figs. 7, 10, 11.
* ``rocket.profile``: the sounding-rocket profile of España et al. (2019) §5.1 / Fig. 1
  checked on a synthesised trajectory (by construction: the generator's inputs).
* ``assess``: the same analyses on a user's own recorded flight; ``plan``: on a planned
  mission.

Importing this package imports the studies that register named evaluations of
:func:`navlib.sweep.sweep` and joint claim searches (``rocket``, ``outliers``, ``ssac``,
``launcher``), so a name resolves after ``import navlib.studies``.
"""

# the registration order is the order of ``python -m navlib sweep --list``
# isort: off
from navlib.studies import rocket  # noqa: F401 - registers its named sweep evaluations
from navlib.studies import outliers  # noqa: F401 - registers its named sweep evaluations
from navlib.studies import ssac  # noqa: F401 - registers its sweep evaluation and search space
from navlib.studies import launcher  # noqa: F401 - registers its sweep evaluation and search space
# isort: on
from navlib.studies.claims import all_claims

__all__ = ["all_claims"]
