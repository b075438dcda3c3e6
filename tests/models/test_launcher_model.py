"""Launcher error models of Beaudoin et al. (2018) and the simplified GPS-bias model."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from navlib import NavlibInputError, earth
from navlib.models.launcher import (
    BIAS_SETS,
    SOLUTIONS,
    launcher,
    rt_dynamics_matrix,
    sensor_values,
    simplified_gps_bias,
    state_names,
)
from navlib.observability import analyze, local_observability, observability_matrix
from navlib.rotations import skew
from navlib.trajectory import Trajectory

S_T = 0.005


def synthetic_ascent(duration=0.5, pitch_rate_deg=1.0, lateral=0.05):
    """A short 200 Hz snapshot: body x at ~60 deg elevation, 20 m/s^2 axial (spec §10c)."""
    t = np.arange(0.0, duration + 1e-9, S_T)
    n = t.size
    lat, lon = np.radians(58.73), np.radians(-93.82)
    C_n_e = earth.ned_to_ecef_matrix(lat, lon)
    euler = np.column_stack([np.full(n, np.radians(20.0)),
                             np.radians(60.0 - pitch_rate_deg * t), np.zeros(n)])
    C_b_e = C_n_e @ Rotation.from_euler("ZYX", euler).as_matrix()
    f_b = np.column_stack([np.full(n, 20.0), np.full(n, lateral), np.zeros(n)])
    r = np.tile(earth.geodetic_to_ecef(lat, lon, 10.0), (n, 1))
    return Trajectory(t=t, position=r, velocity=np.zeros((n, 3)),
                      attitude=Rotation.from_matrix(C_b_e), specific_force=f_b,
                      angular_rate=np.zeros((n, 3)))


@pytest.fixture(scope="module")
def traj():
    return synthetic_ascent()


# ---------------------------------------------------------------- dimensions and order
DIMENSIONS = {  # spec §3.6: states for 0..3 biases, measurement dimension
    "ins_gps": ((9, 12, 15, 18), 6),
    "ins_gps_att": ((9, 12, 15, 18), 9),
    "ins_gps_rt": ((19, 22, 25, 28), 9),
    "ins_gps_att_rt": ((19, 22, 25, 28), 12),
}


@pytest.mark.parametrize("solution", SOLUTIONS)
@pytest.mark.parametrize("biases", BIAS_SETS)
def test_dimension_table(traj, solution, biases):
    bias_model = "markov" if biases else "none"
    model = launcher(solution, biases, bias_model, trajectory=traj)
    states, m = DIMENSIONS[solution]
    assert model.n == states[len(biases)]
    assert model.H.shape[-2:] == (m, model.n) and model.R.shape == (m, m)
    assert model.A.shape == (traj.t.size, model.n, model.n)
    assert model.G.shape[:2] == (traj.t.size, model.n)
    assert model.Qc.shape == (model.G.shape[2],) * 2
    assert len(model.measurement_names) == m


def test_state_order_follows_spec():
    names = state_names("ins_gps_att_rt", "PGA", "markov")       # letters in any order
    assert names[:9] == ("psi_x", "psi_y", "psi_z", "dv_x", "dv_y", "dv_z",
                         "dr_x", "dr_y", "dr_z")
    assert names[9:18] == ("bg_x", "bg_y", "bg_z", "ba_x", "ba_y", "ba_z",
                           "bp_x", "bp_y", "bp_z")
    assert names[18:] == ("x19", "x20", "x21", "x22", "x23", "x24", "x25",
                          "psi_ref_x", "psi_ref_y", "psi_ref_z")
    assert state_names("ins_gps", "", "none") == names[:9]


def test_subset_matches_building_the_smaller_model(traj):
    full = launcher("ins_gps_att_rt", "GAP", "markov", trajectory=traj)
    small = launcher("ins_gps_att_rt", "GP", "markov", trajectory=traj)
    sub = full.subset(small.state_names)
    np.testing.assert_array_equal(sub.A, small.A)
    np.testing.assert_array_equal(sub.H, small.H)
    np.testing.assert_array_equal(sub.P0, small.P0)
    d_sub, d_small = sub.discretize(method="euler"), small.discretize(method="euler")
    np.testing.assert_allclose(d_sub.F, d_small.F)
    np.testing.assert_allclose(d_sub.Q, d_small.Q, rtol=1e-12, atol=1e-30)


# ---------------------------------------------------------------- equations
def test_euler_form_is_the_papers_velocity_row(traj):
    model = launcher("ins_gps", "GAP", "markov", trajectory=traj)
    F = model.discretize(method="euler").F
    k = 17
    T = traj.attitude[k].as_matrix()
    a = traj.specific_force[k]
    W = skew(earth.EARTH_RATE_ECEF)
    idx = {name: i for i, name in enumerate(model.state_names)}
    v, psi, ba, bg = (slice(idx[f"{g}_x"], idx[f"{g}_x"] + 3) for g in ("dv", "psi", "ba", "bg"))
    np.testing.assert_allclose(F[k][v, psi], S_T * skew(T @ a), atol=1e-15)
    np.testing.assert_allclose(F[k][v, v], np.eye(3) - 2 * S_T * W, atol=1e-15)
    np.testing.assert_allclose(F[k][v, ba], S_T * T, atol=1e-15)
    np.testing.assert_allclose(F[k][psi, bg], -S_T * T, atol=1e-15)
    np.testing.assert_allclose(F[k][psi, psi], np.eye(3) - S_T * W, atol=1e-15)
    # GPS position measures dr + b_p (eq. 2)
    H = model.H
    np.testing.assert_array_equal(H[3:6, idx["dr_x"]:idx["dr_x"] + 3], np.eye(3))
    np.testing.assert_array_equal(H[3:6, idx["bp_x"]:idx["bp_x"] + 3], np.eye(3))


def test_markov_and_random_walk_differ_only_in_the_time_constants(traj):
    markov = launcher("ins_gps_rt", "GAP", "markov", trajectory=traj)
    walk = launcher("ins_gps_rt", "GAP", "random_walk", trajectory=traj)
    diff = markov.A - walk.A
    expected = np.zeros(markov.n)
    expected[9:18] = -1.0 / 100.0
    np.testing.assert_allclose(diff, np.broadcast_to(np.diag(expected), diff.shape))
    # driving noise kept (spec §3.2): bias block of Q = s_t 2 sigma^2 / c
    Q = walk.discretize(method="euler").Q[0]
    assert np.isclose(Q[9, 9], S_T * 2 * np.radians(0.05 / 3600) ** 2 / 100.0)   # Table 1
    assert np.isclose(Q[12, 12], S_T * 2 * (7500e-6 * 9.80665) ** 2 / 100.0)
    np.testing.assert_array_equal(markov.Qc, walk.Qc)


def test_rt_closed_loop_is_stable_with_minus_identity_feedback():
    M = rt_dynamics_matrix()
    eig = np.linalg.eigvals(M)
    for expected in (-0.25 + 0.733j, -2.818 + 3.686j, -0.394, -0.096):
        assert np.min(np.abs(eig - expected)) < 2e-3
    assert np.isclose(np.max(np.abs(np.linalg.eigvals(np.eye(10) + S_T * M))), 0.99952,
                      atol=1e-5)
    # pitch loop characteristic polynomial carries the printed coefficients (§10b)
    pitch = M[np.ix_([1, 3, 5, 8], [1, 3, 5, 8])]
    np.testing.assert_allclose(np.poly(pitch), [1, 6.1248, 24.3198, 10.7475, 0.8111],
                               rtol=1e-4)
    flipped = M.copy()
    flipped[0:3, 7:10] = np.eye(3)             # the +I_3 reading is unstable
    assert np.max(np.linalg.eigvals(flipped).real) > 0


def test_rt_blocks_pseudo_measurement_and_a1_sign(traj):
    plus = launcher("ins_gps_rt", "", "none", trajectory=traj)
    minus = launcher("ins_gps_rt", "", "none", trajectory=traj, a1_sign=-1)
    k = 5
    C_e_b = traj.attitude[k].as_matrix().T
    np.testing.assert_allclose(plus.A[k, 9:12, 0:3], C_e_b)
    np.testing.assert_allclose(minus.A[k, 9:12, 0:3], -C_e_b)
    np.testing.assert_allclose(plus.A[k, 9:19, 9:19], rt_dynamics_matrix())
    # eq. (8): noise-free T_E^B psi + psi_ref
    np.testing.assert_allclose(plus.H[k, 6:9, 0:3], C_e_b)
    np.testing.assert_array_equal(plus.H[k, 6:9, 16:19], np.eye(3))
    np.testing.assert_array_equal(plus.R[6:9, 6:9], np.zeros((3, 3)))
    assert np.all(np.diag(plus.R)[:6] > 0)
    # wind drives psi_ref only
    assert np.count_nonzero(plus.G[k, :, -3:]) == 3 and np.all(plus.G[k, 16:19, -3:] == np.eye(3))
    assert plus.P0[16, 16] == 0.0 and plus.P0[9, 9] == 0.0


def test_roll_error_does_not_reach_velocity_without_lateral_force():
    """Spec §3.8: with a_y = a_z = 0 the body-roll error does not enter dv."""
    tr = synthetic_ascent(duration=0.05, lateral=0.0)
    model = launcher("ins_gps", "", "none", trajectory=tr)
    C_b_e = tr.attitude[0].as_matrix()
    roll_axis_e = C_b_e[:, 0]
    np.testing.assert_allclose(model.A[0, 3:6, 0:3] @ roll_axis_e, 0.0, atol=1e-12)


def test_noise_values_come_from_the_table1_preset(traj):
    values = sensor_values()
    assert values["gyro_arw"] == pytest.approx(np.radians(0.72 / 3600))    # 0.72 deg/h/rtHz
    assert values["accel_vrw"] == pytest.approx(117e-6 * 9.80665)
    assert values["sigma_att"] == pytest.approx(np.radians(1.0))
    assert values["c_g"] == values["c_a"] == values["c_p"] == 100.0
    model = launcher("ins_gps_att", "", "none", trajectory=traj, sigma_gps_pos=7.0)
    assert model.R[0, 0] == pytest.approx(np.radians(1.0) ** 2)
    assert model.R[6, 6] == pytest.approx(49.0)
    assert model.parameters["sensors"] == "launcher_table1"
    assert model.Qc[0, 0] == pytest.approx(values["gyro_arw"] ** 2)


@pytest.mark.parametrize("kwargs, match", [
    ({"solution": "ins"}, "solution"),
    ({"biases": "GX"}, "biases"),
    ({"biases": "GG"}, "biases"),
    ({"biases": "GA", "bias_model": "none"}, "bias_model"),
    ({"biases": "", "bias_model": "markov"}, "bias_model"),
    ({"bias_model": "gauss_markov"}, "bias_model"),
    ({"a1_sign": 2.0}, "a1_sign"),
    ({"c_g": -1.0}, "c_g"),
    ({"sigma_gps": 1.0}, "unknown keyword"),
    ({"trajectory": "churchill"}, "trajectory"),
    ({"sensors": "no_such_preset"}, "preset|sensors"),
])
def test_launcher_rejects_bad_arguments(traj, kwargs, match):
    kwargs = {"trajectory": traj, **kwargs}
    with pytest.raises(NavlibInputError, match=match):
        launcher(**kwargs)


def test_local_observability_accepts_the_continuous_model(traj):
    model = launcher("ins_gps_att", "GA", "markov", trajectory=traj)
    lazy = local_observability(model, stride=7)
    full = local_observability(model.discretize(method="euler"), stride=7)
    np.testing.assert_allclose(lazy.singular_values, full.singular_values, rtol=1e-10)
    exact = local_observability(model, stride=7, method="expm")
    assert exact.rank_constant and exact.rank.min() == model.n


# ---------------------------------------------------------------- simplified model (§3.7)
@pytest.mark.parametrize("c_p, cond", [
    (0.01, 3.31), (0.1, 23.1), (1.0, 233.7), (10.0, 2342.0), (100.0, 2.342e4),
    (1000.0, 2.342e5), (1e4, 2.342e6),
])
def test_simplified_model_condition_number_table(c_p, cond):
    A, C = simplified_gps_bias(c_p)
    res = analyze(observability_matrix(A, C))
    assert res.rank == 6
    assert res.cond == pytest.approx(cond, rel=2e-3)


def test_simplified_model_proportional_to_c_p_and_rank_3_for_random_walk():
    conds = [analyze(observability_matrix(*simplified_gps_bias(c))).cond
             for c in (1e2, 1e3, 1e4)]
    for c_p, cond in zip((1e2, 1e3, 1e4), conds, strict=True):
        assert cond == pytest.approx(1.171 * c_p / S_T, rel=2e-3)
    A, C = simplified_gps_bias(np.inf)
    np.testing.assert_array_equal(A, np.eye(6))
    res = analyze(observability_matrix(A, C), state_names=[f"dr_{a}" for a in "xyz"]
                  + [f"bp_{a}" for a in "xyz"])
    assert res.rank == 3 and res.cond > 1e15
    assert sorted(res.unobservable_groups) == [["dr_x", "bp_x"], ["dr_y", "bp_y"],
                                               ["dr_z", "bp_z"]]
    # the null space is dr = -b_p on each axis
    np.testing.assert_allclose(np.abs(res.null_space[:3]), np.abs(res.null_space[3:]),
                               atol=1e-12)


@pytest.mark.parametrize("c_p, s_t", [(0.0, 0.005), (-1.0, 0.005), (np.nan, 0.005),
                                      ("x", 0.005), (10.0, 0.0)])
def test_simplified_model_rejects_bad_arguments(c_p, s_t):
    with pytest.raises(NavlibInputError):
        simplified_gps_bias(c_p, s_t)
