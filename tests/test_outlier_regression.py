"""Notebook 05 and the claims engine's outlier study show what they showed before issue 14.

The reference tables in ``tests/data/outliers_*.csv`` were captured with
``tests/outlier_tables.py`` at commit 26b6891 (before the outlier study shared its work):
every table, text and widget status notebook 05 shows (and the same results unrounded), and
every claim (id, our number, verdict, checks) of the engine's outlier study with its
robustness fractions. Text must match exactly; numbers to a relative 1e-9 (the responses are
now unit responses scaled by the magnitude, which reorders a few floating-point products).
"""

import outlier_tables as tables
import pytest


def _same(got, reference: str):
    want = tables.reference(reference)
    diff = tables.differences(got.astype(str).reset_index(drop=True), want)
    assert not diff, f"{len(diff)} differences from {reference}:\n" + "\n".join(diff[:20])


@pytest.mark.notebook
@pytest.mark.parametrize("quick", [True, False], ids=["quick", "full"])
def test_notebook_05_shows_the_reference_tables(quick):
    _same(tables.notebook_values(quick), f"outliers_{'quick' if quick else 'full'}.csv")


@pytest.mark.parametrize("quick", [True, False], ids=["quick", "full"])
def test_outlier_claims_and_robustness_are_the_reference(quick):
    _same(tables.claim_values(quick), f"outliers_claims_{'quick' if quick else 'full'}.csv")


def test_the_comparison_can_fail():
    want = tables.reference("outliers_claims_quick.csv")
    got = want.copy()
    number = next(i for i, v in enumerate(got.value) if v.replace(".", "").isdigit()
                  and float(v) > 0)
    got.loc[number, "value"] = repr(float(got.value[number]) * (1 + 1e-8))
    text = int(got.index[got.column == "verdict"][0])
    got.loc[text, "value"] = "partly" if got.value[text] != "partly" else "reproduced"
    diff = tables.differences(got, want)
    assert len(diff) == 2
    assert len(tables.differences(got.iloc[1:], want)) == 1       # rows differ
