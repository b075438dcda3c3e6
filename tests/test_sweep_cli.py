"""``python -m navlib sweep``: the same table as navlib.sweep.sweep, saved and resumed."""

import pandas as pd
import pytest

from navlib import sweep
from navlib.__main__ import main


def test_cli_sweep_equals_the_python_call_and_resumes(tmp_path, capsys):
    out = tmp_path / "study.parquet"
    argv = ["sweep", "excitability", "-g", "eta", "1e-1", "1e-4", "--scheduler",
            "synchronous", "--output", str(out)]
    assert main(argv) == 0
    printed = capsys.readouterr()
    assert "2 point(s), 2 computed" in printed.err
    saved = sweep.read(out)
    direct = sweep.sweep({"eta": [1e-1, 1e-4]}, "excitability", scheduler="synchronous")
    pd.testing.assert_frame_equal(saved.reset_index(drop=True), direct.reset_index(drop=True),
                                  check_like=False)
    assert main(argv) == 0  # a rerun takes every point from the saved table
    assert "2 point(s), 0 computed" in capsys.readouterr().err


@pytest.mark.parametrize("argv, message", [
    (["sweep", "-g", "eta", "1"], "evaluation"),
    (["sweep", "excitability"], "grid"),
    (["sweep", "excitability", "-g", "eta"], "no values"),
    (["sweep", "excitability", "-g", "eta", "1", "-g", "eta", "2"], "twice"),
    (["sweep", "no_such_thing", "-g", "eta", "1", "--scheduler", "synchronous"],
     "no_such_thing"),
])
def test_cli_sweep_bad_input_exits_2(argv, message, capsys):
    assert main(argv) == 2
    assert message in capsys.readouterr().err


def test_cli_sweep_lists_the_evaluations(capsys):
    assert main(["sweep", "--list"]) == 0
    listed = capsys.readouterr().out
    assert all(name in listed for name in sweep.EVALUATIONS)
