"""Notebook 05 and the claims engine's outlier study show what they showed before the
outlier study shared its work (commit 26b6891).

The reference tables in ``data/outliers_*.csv`` were captured with ``outlier_tables.py``:
every table, text and widget status notebook 05 shows (and the same results unrounded), and
every claim (id, our number, verdict, checks) of the engine's outlier study with its
robustness fractions. Numbers are compared at the tolerances of ``tolerances.toml`` (relative
to the largest number of their item and column), texts word for word with the numbers in
them to their printed precision.
"""

import golden
import outlier_tables as tables
import pytest


def _same(got, reference: str, name: str):
    want = tables.reference(reference)
    diff = tables.differences(got.astype(str).reset_index(drop=True), want,
                              rtol=golden.tolerance(name))
    assert not diff, f"{len(diff)} differences from {reference}:\n" + "\n".join(diff[:20])


@pytest.mark.notebook
@pytest.mark.parametrize("quick", [True, pytest.param(False, marks=pytest.mark.slow)],
                         ids=["quick", "full"])
def test_notebook_05_shows_the_reference_tables(quick):
    mode = "quick" if quick else "full"
    _same(tables.notebook_values(quick), f"outliers_{mode}.csv", f"outliers_{mode}")


@pytest.mark.parametrize("quick", [True, False], ids=["quick", "full"])
def test_outlier_claims_and_robustness_are_the_reference(quick):
    mode = "quick" if quick else "full"
    _same(tables.claim_values(quick), f"outliers_claims_{mode}.csv", f"outlier_claims_{mode}")


def test_the_comparison_can_fail():
    """A number moved by 10 tolerances, a changed verdict and a number in a text moved by
    two units of its last printed digit are each caught; a move within one unit is not."""
    want = tables.reference("outliers_claims_quick.csv")
    rtol = golden.tolerance("outlier_claims_quick")
    got = want.copy()
    number = next(i for i, v in enumerate(got.value) if v.replace(".", "").isdigit()
                  and float(v) > 0)
    scale = tables._scales(want)[number]
    got.loc[number, "value"] = repr(float(got.value[number]) + 10 * rtol * scale)
    text = int(got.index[got.column == "verdict"][0])
    got.loc[text, "value"] = "partly" if got.value[text] != "partly" else "reproduced"
    diff = tables.differences(got, want, rtol)
    assert len(diff) == 2
    assert len(tables.differences(got.iloc[1:], want, rtol)) == 1       # rows differ
    checks = int(next(i for i, (c, v) in enumerate(zip(want.column, want.value, strict=True))
                      if c == "checks" and "0." in v))
    words, numbers = golden.split_numbers(want.value[checks])
    k = next(i for i, n in enumerate(numbers) if "." in n)
    unit = golden._last_digit_unit(numbers[k])
    for moved, caught in ((unit, False), (2 * unit, True)):
        shifted = [repr(float(n) + moved) if i == k else n for i, n in enumerate(numbers)]
        text = "".join(w + n for w, n in zip(words, [*shifted, ""], strict=True))
        assert bool(golden.text_differences(text, want.value[checks])) == caught
