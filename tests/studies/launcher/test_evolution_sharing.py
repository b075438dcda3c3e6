"""The covariance-evolution assumption set shares F, Q, H, R between its
sigma0_att variants; every table must equal the one a separate run builds."""

import numpy as np
import pandas as pd

from navlib.studies import launcher as study
from navlib.trajectory import launcher_ascent

CASES = {k: study.EVOLUTION_CASES[k] for k in
         ("gps/none", "ins-only/none", "att/GAP/markov", "att/GAP/markov x1000")}


def test_shared_steps_equal_separate_runs():
    traj = launcher_ascent(duration_s=20.0, rate_hz=10.0)
    kws = [{}, {"sigma0_att": np.radians(0.03)}, {"sigma0_att": np.radians(0.3)}]
    shared = study.evolution._evolution_tables(traj, CASES, False, kws)
    assert len(shared) == 3
    for kw, table in zip(kws, shared, strict=True):
        separate = study.covariance_evolution(traj, CASES, **kw)
        pd.testing.assert_frame_equal(table, separate, check_exact=True)
    # the variants differ (the test would not see a P0 left at the baseline)
    assert not np.allclose(shared[1].roll_0, shared[2].roll_0)


def test_evolution_claims_unchanged_quick():
    study.evolution_variants.cache_clear()
    claims = study.robustness.baseline_evolution_claims(quick=True)
    direct = study.evolution_claims(study.covariance_evolution(quick=True))
    assert [(c.claim_id, c.verdict, c.ours) for c in claims] == \
        [(c.claim_id, c.verdict, c.ours) for c in direct]


def test_rows_equal_those_of_the_full_public_recursion():
    """The evolution keeps the posteriors of the first and the last epoch only, with Q
    formed a block at a time: its rows equal those read off the whole histories of
    :func:`navlib.covariance.kalman_covariances`, to the bit, for each aiding."""
    from navlib.covariance import kalman_covariances
    from navlib.filters import linear_steps
    from navlib.models.launcher import launcher

    traj = launcher_ascent(duration_s=20.0, rate_hz=10.0)
    C_e_b = np.swapaxes(traj.attitude.as_matrix(), 1, 2)
    steps = linear_steps(launcher("ins_gps_att", "GAP", "markov", traj))
    P0s = [steps.P0, 4.0 * steps.P0]
    for aiding in ("kf", "ins_only", "ideal"):
        case = ("case", "ins_gps_att", "GAP", "markov", aiding, 1.0)
        H, R = (None, None) if aiding == "ins_only" else \
            (steps.H, steps.R if aiding == "kf" else np.zeros_like(steps.R))
        covs = kalman_covariances(steps.F, steps.Q, H, R, np.stack(P0s), t=steps.t)
        want = [study.evolution._evolution_row(*case, steps.state_names, cov.P_post[[0, -1]], C_e_b)
                for cov in covs]
        assert study.evolution._evolution_rows(case, steps, P0s, C_e_b) == want
