"""The quick-mode claims of the rocket, covariance and SSAC studies are the stored reference
(``data/claims_reference_quick.csv``, written by ``scripts/claims_reference.py --write``):
words exactly, numbers to one unit of their last printed digit (``tolerances.toml``,
``[claims_quick]``)."""

import importlib.util
from pathlib import Path

import golden

ROOT = Path(__file__).resolve().parents[2]


def _reference_script():
    spec = importlib.util.spec_from_file_location("claims_reference",
                                                  ROOT / "scripts" / "claims_reference.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_quick_claims_equal_the_reference():
    script = _reference_script()
    reference = script.read_rows(script.reference_path(quick=True))
    assert reference, "empty reference"
    units = golden.tolerance("claims_quick")
    current = script.current_rows(quick=True)
    assert golden.rows_differences(current, reference, "claim_id", units) == []
    altered = [dict(reference[0], verdict="partly"), *reference[1:]]
    assert golden.rows_differences(altered, reference, "claim_id", units) != []


def test_text_comparison_rounds_to_the_printed_digit():
    """One unit in the last printed digit is round-off at a rounding boundary; two units, a
    changed word or a changed count of numbers are differences."""
    want = "*min e(P, V) over tau1-tau3: 0.5232 >= 0.7071 -> FAIL; next < 1e-14 of the largest"
    assert golden.text_differences(want.replace("0.5232", "0.5233"), want) == []
    assert golden.text_differences(want.replace("0.5232", "0.5234"), want) != []
    assert golden.text_differences(want.replace("FAIL", "pass"), want) != []
    assert golden.text_differences(want.replace("0.5232 ", "0.5232 0.1 "), want) != []
    assert golden.text_differences("rank 7, next 2e-17", "rank 7, next 1e-17") == []
    assert golden.text_differences("rank 8, next 1e-17", "rank 7, next 1e-17") != []
