"""Planning with the sensors a rocket carries: GNSS, barometer, or both (plan_mission's
``aiding`` and the mission's ``[gnss] aiding``; navlib.models.baro)."""

from __future__ import annotations

import tomllib

import pandas as pd
import pytest
from support.locations import REPO

from navlib import NavlibInputError
from navlib.__main__ import main
from navlib.studies.assess.aiding import ned_sigmas
from navlib.studies.plan import plan_mission


@pytest.fixture(scope="module")
def plans():
    return {a: plan_mission("hpr_rocket", aiding=a) for a in ("gnss", "baro", "gnss+baro")}


def test_a_rocket_planned_with_and_without_gnss(plans):
    assert plans["baro"].model.measurement_names == ("baro_h", "zupt_x", "zupt_y", "zupt_z")
    assert plans["gnss+baro"].model.measurement_names[:2] == ("gnss_n", "gnss_e")
    assert {a: p.options["aiding"] for a, p in plans.items()} == {
        a: a for a in ("gnss", "baro", "gnss+baro")}
    end = {a: ned_sigmas(p.model, p.trajectory) for a, p in plans.items()}
    horizontal = {a: s["position_m"][-1, :2] for a, s in end.items()}
    vertical = {a: s["position_m"][-1, 2] for a, s in end.items()}
    # without GNSS the horizontal position is carried by the IMU only: far above the GNSS sigma
    assert all(horizontal["baro"] > 50 * horizontal["gnss"])
    assert all(horizontal["gnss+baro"] < 2 * horizontal["gnss"])
    # the barometer keeps the vertical as well as GNSS does
    assert vertical["baro"] < 2 * vertical["gnss"]
    assert any("unobservable" in n for n in plans["baro"].notes)


def test_the_mission_file_names_its_aiding():
    with open(REPO / "data" / "missions" / "hpr_rocket.toml", "rb") as fh:
        table = tomllib.load(fh)
    table["gnss"]["aiding"] = "baro"
    assert plan_mission(table).options["aiding"] == "baro"
    table["gnss"]["aiding"] = "lidar"
    with pytest.raises(NavlibInputError, match="aiding: expected one of"):
        plan_mission(table)


def test_plan_command_compares_aidings_in_one_run(tmp_path):
    out = tmp_path / "plans"
    assert main(["plan", "hpr_rocket", "--output", str(out), "-p", "aiding", "gnss,baro"]) == 0
    table = pd.read_csv(out / "summary.csv", keep_default_na=False)
    assert table.log.tolist() == ["hpr_rocket (aiding gnss)", "hpr_rocket (aiding baro)"]
    assert table.aiding.tolist() == ["gnss", "baro"]
    assert "P_x" in table.sensible.iloc[0] and "P_x" not in table.sensible.iloc[1]
