"""The EKF's compiled loop (navlib.filters.ekf_loop) against the Python loop of
navlib.filters.ekf on the 86 s sounding rocket: the same results to rounding (the golden
tolerances of tests/regression/tolerances.toml ``[ekf.*]`` on every estimate, far inside
them in practice), for GNSS position and position + velocity, both attitude errors, the kept
covariances and windows with updates inside them; runs it does not serve take the Python
loop."""

import importlib
import tomllib
from pathlib import Path

import numpy as np
import pytest

from navlib import sensors, strapdown
from navlib.filters import ekf
from navlib.filters.ekf_loop import compiled_run
from navlib.trajectory import sounding_rocket

ekf_module = importlib.import_module("navlib.filters.ekf")
TOLERANCES = {group: entry["tolerance"] for group, entry in tomllib.loads(
    (Path(__file__).resolve().parents[1] / "regression" / "tolerances.toml").read_text()
)["ekf"].items() if isinstance(entry, dict)}


@pytest.fixture(scope="module")
def flight():
    traj = sounding_rocket()
    spec = sensors.load_preset("motionpak_tactical")
    return (traj, sensors.simulate_imu(traj, spec, seed=1),
            sensors.simulate_gnss(traj, spec, seed=2))


def _run(flight, **keywords):
    traj, imu, gnss = flight
    return ekf(imu, gnss, initial=strapdown.StrapdownState.from_trajectory(traj),
               model="ecef21", **keywords)


def _python_loop(flight, monkeypatch, **keywords):
    with monkeypatch.context() as patch:
        patch.setattr(ekf_module, "compiled_run", lambda *args: None)
        return _run(flight, **keywords)


def _spy(monkeypatch) -> list:
    """The results of :func:`compiled_run` in the runs that follow (None: not served)."""
    seen = []

    def spied(*args):
        seen.append(compiled_run(*args))
        return seen[-1]

    monkeypatch.setattr(ekf_module, "compiled_run", spied)
    return seen


def _close(got, want, rtol):
    scale = np.nanmax(np.abs(want))
    assert np.nanmax(np.abs(got - want)) <= rtol * scale


@pytest.mark.parametrize("keywords", [
    {"model_options": {"sensors": "motionpak_tactical"}},
    {"model_options": {"sensors": "motionpak_tactical", "attitude_error": "body"},
     "gnss_velocity_sigma": 0.2, "keep_covariance": True},
    {"model_options": {"sensors": "motionpak_tactical"}, "window_s": 2.5},
], ids=["position", "position+velocity, body, P", "updates inside windows"])
def test_compiled_loop_equals_python_loop(flight, monkeypatch, keywords):
    want = _python_loop(flight, monkeypatch, **keywords)
    seen = _spy(monkeypatch)
    got = _run(flight, **keywords)
    assert seen and seen[0] is not None                  # the compiled loop ran
    np.testing.assert_array_equal(got.t, want.t)
    _close(got.position, want.position, TOLERANCES["position"])
    _close(got.velocity, want.velocity, TOLERANCES["velocity"])
    _close(got.C_b_e, want.C_b_e, TOLERANCES["attitude"] * 1e-3)
    _close(got.nis, want.nis, TOLERANCES["nis"])
    _close(got.innovation, want.innovation, TOLERANCES["position"])
    np.testing.assert_array_equal(np.isnan(got.innovation), np.isnan(want.innovation))
    np.testing.assert_array_equal(got.nis_dof, want.nis_dof)
    assert np.max(np.abs(got.sigma - want.sigma) / want.sigma) < 1e-6
    for group, value in want.parameters.items():
        _close(got.parameters[group], value, 1e-6)
    assert got.kept.shape == want.kept.shape and got.measurement_names == want.measurement_names
    if want.P is not None:
        _close(got.P, want.P, 1e-6)
    else:
        assert got.P is None


def test_other_runs_take_the_python_loop(flight, monkeypatch):
    """A snapshot, the Euler discretisation and the launcher models are not served."""
    seen = _spy(monkeypatch)
    options = {"model_options": {"sensors": "motionpak_tactical"}}
    _run(flight, snapshot_before=40.0, **options)
    _run(flight, method="euler", **options)
    assert seen == [None, None]
