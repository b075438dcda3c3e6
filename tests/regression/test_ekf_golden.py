"""The EKF's final navigation errors and mean NIS stay those of the snapshot
(``golden.EKF_SNAPSHOT``) at the measured tolerances of ``tolerances.toml`` (``[ekf.*]``),
and those tolerances still catch a real change of the filter or its inputs."""

import dataclasses

import golden
import numpy as np
import pytest

from navlib.sensors import load_preset


@pytest.mark.parametrize("case", list(golden.EKF_SNAPSHOT))
def test_ekf_numbers_unchanged(case):
    got = golden.ekf_values(case, golden.ekf_trajectory(case))
    assert golden.grouped_differences(got, golden.ekf_reference(case),
                                      golden.ekf_tolerances()) == []


def _gnss_sigma_scaled(case: str, factor: float):
    spec = load_preset(golden.EKF_SNAPSHOT[case][0].get("sensors", "launcher_table1"))
    return dataclasses.replace(spec, gnss=dataclasses.replace(
        spec.gnss, position_sigma=spec.gnss.position_sigma * factor))


@pytest.mark.parametrize(("case", "change"), [
    ("launcher GAP random walk", "gnss sigma"),
    ("launcher att_rt outliers", "window"),
    ("ecef21", "gnss sigma"),
    ("ecef21", "attitude error frame"),
])
def test_ekf_tolerance_catches_a_real_change(case, change):
    """A GNSS position noise 1 % larger in the simulation, IMU integration windows of 0.05 s
    instead of 0.1 s, or the attitude error taken on the body side instead of the ECEF side
    each move the snapshot by more than its tolerance (tolerances.toml lists the sizes)."""
    changes = {"gnss sigma": {"sensors": _gnss_sigma_scaled(case, 1.01)},
               "window": {"window_s": 0.05},
               "attitude error frame": {"model_options": {
                   "sensors": "motionpak_tactical", "attitude_error": "body"}}}[change]
    got = golden.ekf_values(case, golden.ekf_trajectory(case), **changes)
    assert golden.grouped_differences(got, golden.ekf_reference(case),
                                      golden.ekf_tolerances()) != []


def test_tolerances_are_measured_with_margin():
    """Every golden states its measured spread, the perturbations it was measured over and
    what it still catches; a relative tolerance is at least 10 times the spread, one in
    printed digits (texts) covers the spread."""
    entries = {name: entry for name, entry in golden.TOLERANCES.items() if name != "ekf"}
    entries.update({f"ekf.{group}": golden.TOLERANCES["ekf"][group]
                    for group in golden.EKF_GROUPS})
    for name, entry in entries.items():
        assert np.isfinite(entry["spread"]), name
        if name.startswith("ekf.") or golden.TOLERANCES[name]["measure"] == "relative":
            assert entry["tolerance"] >= 10 * entry["spread"], name
        else:
            assert entry["tolerance"] >= entry["spread"], name
    for name, entry in golden.TOLERANCES.items():
        assert len(entry["perturbations"]) >= 3, name
        assert entry["catches"], name
