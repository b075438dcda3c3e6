"""Fuzz test of the readers and the assessment: every damaged log is assessed or refused with
:class:`navlib.NavlibInputError` within a time limit, and a fleet run of damaged logs keeps a
row of ``summary.csv`` for each (issue 39).

The mutants (``mutants.py``: seeded, so a failure names a reproducible file and damage) are
made from small valid logs of every kind navlib reads. The standing tests take a few of each
(bounded to stay well inside ``make test``); the ``slow`` campaign takes more, adds the
shared public logs when present (``../shared/data``, mutated in the test's temporary folder)
and prints its counts (run it with ``-s`` to see them).
"""

from __future__ import annotations

import collections
import zlib

import mutants
import numpy as np
import pandas as pd
import pytest
from support.flights import multicopter, records

from navlib.reports import fleet

LIMIT_S = 120.0
"""Wall time allowed to read and assess one mutant, s: an unmutated original takes 1-3 s
(0.5-4 s on the shared 2-core machine under load), so a mutant over 40 times that hangs."""
SEED = 39
FAST_PER_ORIGINAL = 3
CAMPAIGN_PER_ORIGINAL = 6
FLEET_ASSESSED = 4
KINDS = ("csv pair", "csv imu+baro", "dataflash", "altos version", "altos legacy",
         "altos easymega", "ulog (cut)")


@pytest.fixture(scope="module")
def originals(tmp_path_factory):
    return {o.name: o for o in mutants.generated_originals(tmp_path_factory.mktemp("valid"))}


def _failures(results) -> str:
    return "\n".join(f"{outcome}: {m.what}: {text}" for m, (outcome, text, _) in results
                     if outcome not in ("assessed", "refused"))


@pytest.mark.parametrize("name", KINDS)
def test_mutants_are_assessed_or_refused(originals, tmp_path, name):
    if name not in originals:
        pytest.skip("the ULog original is cut from ../shared/data/px4/sample_log_small.ulg, "
                    "absent here")
    original = originals[name]
    outcome, text, _ = mutants.run(",".join(str(f) for f in original.files), LIMIT_S)
    assert outcome == "assessed", text          # else every mutant would be refused trivially
    made = mutants.mutants([original], tmp_path, FAST_PER_ORIGINAL,
                           SEED + zlib.crc32(name.encode()))
    results = [(m, mutants.run(m.spec, LIMIT_S)) for m in made]
    assert not _failures(results), _failures(results)


@pytest.fixture(scope="module")
def frames():
    """The records of the CSV pair as DataFrames (a small simulated multicopter flight)."""
    truth = multicopter(24.0, 50.0, pad_s=6.0)
    return records(truth, seed=5)


def _frame_results(frames, per_damage: int, seed: int):
    rng = np.random.default_rng(seed)
    results = []
    for damage in mutants.FRAME_DAMAGES * per_damage:
        imu, gnss, what = mutants.frame_mutant(rng, *frames, damage)
        results.append((mutants.Mutant("DataFrames", what),
                        mutants.run_frames(imu, gnss, LIMIT_S)))
    return results


def test_damaged_dataframes_are_assessed_or_refused(frames):
    """The records a user hands to assess_flight without a reader: rows out of order,
    NaN or infinite cells, repeated times, few rows, scaled, constant, missing or string
    columns, shifted times, an odd barometer record."""
    results = _frame_results(frames, 2, SEED)
    assert not _failures(results), _failures(results)
    assert {"assessed", "refused"} == {outcome for _, (outcome, _, _) in results}


def _fleet_rows(specs, folder) -> pd.DataFrame:
    table, pages = fleet.assess_logs(specs, scheduler="synchronous")
    path = fleet.write_fleet(table, pages, folder)
    return pd.read_csv(path, keep_default_na=False)


def test_a_fleet_of_mutants_keeps_a_row_for_each(originals, tmp_path):
    """Mutants that are assessed, refused by the reader and refused by the assessment, a
    file that does not exist and a name of no known kind: one row each, in order."""
    picked = [originals[n] for n in ("csv pair", "altos legacy")]
    made = mutants.mutants(picked, tmp_path / "mutants", 2, SEED)
    imu_path, gnss_path = originals["csv pair"].files
    imu = pd.read_csv(imu_path)
    imu[[c for c in imu.columns if c.startswith("f_")]] = 0.0     # read, then refused
    imu.to_csv(tmp_path / "zero_imu.csv", index=False)
    specs = [m.spec for m in made] + [f"{tmp_path / 'zero_imu.csv'},{gnss_path}",
                                      str(tmp_path / "missing.ulg"), str(tmp_path / "a.txt")]
    rows = _fleet_rows(specs, tmp_path / "out")
    assert rows["log"].tolist() == specs
    assert set(rows["status"]) == {"ok", "failed"}
    failed = rows[rows["status"] == "failed"]
    assert failed["error"].str.startswith("NavlibInputError: ").all(), failed["error"].tolist()
    assert (rows["page"] != "").tolist() == (rows["status"] == "ok").tolist()
    assert rows["status"].iloc[-3:].tolist() == ["failed"] * 3
    assert "gravity alone reads 9.8 m/s^2 at rest" in rows["error"].iloc[-3]  # names f_x


@pytest.mark.slow
def test_campaign(originals, frames, tmp_path):
    """Every original, generated and shared, :data:`CAMPAIGN_PER_ORIGINAL` times, and every
    DataFrame damage 6 times: the counts per outcome printed; no bare error and no hang; a
    fleet run of every refused mutant and the first :data:`FLEET_ASSESSED` assessed ones
    (each assessed flight costs its HTML page, several seconds) agrees row by row
    (assessed: ok; refused: failed with the same NavlibInputError)."""
    pool = list(originals.values()) + mutants.real_originals()
    made = mutants.mutants(pool, tmp_path / "mutants", CAMPAIGN_PER_ORIGINAL, SEED)
    results = [(m, mutants.run(m.spec, LIMIT_S)) for m in made]
    counts = collections.Counter(outcome for _, (outcome, _, _) in results)
    slowest = max(seconds for _, (_, _, seconds) in results)
    print(f"\nfuzz campaign: {len(made)} mutants of {len(pool)} logs (seed {SEED}): "
          + ", ".join(f"{counts[k]} {k}" for k in mutants.OUTCOMES)
          + f"; slowest {slowest:.1f} s")
    frame_results = _frame_results(frames, 6, SEED + 1)
    counts = collections.Counter(outcome for _, (outcome, _, _) in frame_results)
    print(f"fuzz campaign: {len(frame_results)} damaged DataFrame pairs: "
          + ", ".join(f"{counts[k]} {k}" for k in mutants.OUTCOMES))
    assert not _failures(results + frame_results), _failures(results + frame_results)
    assessed = [r for r in results if r[1][0] == "assessed"][:FLEET_ASSESSED]
    fleet_run = [r for r in results if r[1][0] == "refused" or r in assessed]
    rows = _fleet_rows([m.spec for m, _ in fleet_run], tmp_path / "out")
    assert rows["log"].tolist() == [m.spec for m, _ in fleet_run]
    for (m, (outcome, text, _)), row in zip(fleet_run, rows.itertuples(index=False),
                                            strict=True):
        assert row.status == ("ok" if outcome == "assessed" else "failed"), m.what
        if outcome == "refused":
            assert row.error == f"NavlibInputError: {text}", m.what
