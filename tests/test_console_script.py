"""The ``navlib`` console script (``[project.scripts]`` of pyproject.toml) is the entry of
``python -m navlib``: the installed script answers ``--help`` for every command."""

import subprocess
import sys
import tomllib
from importlib.metadata import entry_points
from pathlib import Path

import pytest

import navlib.__main__

ROOT = Path(__file__).resolve().parents[1]


def test_pyproject_declares_the_script_on_the_module_entry():
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    assert scripts == {"navlib": "navlib.__main__:main"}


def test_installed_entry_point_loads_the_module_main():
    (point,) = entry_points(group="console_scripts", name="navlib")
    assert point.load() is navlib.__main__.main


@pytest.mark.parametrize("command", [[], ["assess"], ["plan"], ["report"], ["sweep"]])
def test_installed_script_answers_help(command):
    script = Path(sys.executable).parent / "navlib"
    assert script.is_file(), f"{script} missing: reinstall with `pip install -e .`"
    run = subprocess.run([str(script), *command, "--help"], capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout.startswith("usage:")
    if command:
        assert f" {command[0]} " in run.stdout.splitlines()[0] + " "


def test_entry_function_rejects_an_unknown_command(capsys):
    with pytest.raises(SystemExit) as exc:
        navlib.__main__.main(["no-such-command"])
    assert exc.value.code == 2
    assert "invalid choice" in capsys.readouterr().err
