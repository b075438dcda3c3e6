"""Paper reproductions: each module composes library pieces into one paper's experiment,
evaluates its claims in code (claim, our number, verdict) and returns tidy tables.

* ``launcher``: Beaudoin et al. (2018), Table 2, Fig. 1, covariance and correlation.
* ``ssac``: Silva et al. (2017), stationary self-alignment and calibration.
* ``rocket``: España, Carrizo & Giribet (2019), excitability and sensability (X1-X7, S1-S8).
* ``outliers``: Beaudoin et al. (2018) outlier tests T1-T4.
* ``rocket_profile``: the sounding-rocket profile of España et al. (2019) §5.1 / Fig. 1
  checked on a synthesised trajectory.
* ``assess``: the same analyses on a user's own recorded flight.
* ``verdict``: the shared claim/verdict record.
"""
