"""A non-editable install works: the wheel carries the presets, Table 2, the sample flight
and the notebooks (navlib.data, navlib.notebooks), and runs a report outside the checkout."""

import os
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_every_subpackage_is_listed_for_the_wheel():
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
                 ["packages"])
    found = {".".join(p.parent.relative_to(ROOT).parts)
             for p in (ROOT / "navlib").rglob("__init__.py")}
    assert found <= listed, f"add to [tool.setuptools] packages: {sorted(found - listed)}"


@pytest.mark.notebook
@pytest.mark.slow
def test_wheel_installs_and_reports_outside_the_checkout(tmp_path):
    wheels = tmp_path / "wheels"
    build = subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps",
                            str(ROOT), "-w", str(wheels)], capture_output=True, text=True,
                           timeout=600)
    assert build.returncode == 0, build.stderr[-2000:]
    (wheel,) = wheels.glob("navlib_workbook-*.whl")
    # a fresh virtual environment outside the checkout: the wheel's declared dependencies
    # are resolved from the package index, so a missing one fails here
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, timeout=300)
    python = venv / "bin" / "python"
    install = subprocess.run([str(python), "-m", "pip", "install", "--quiet",
                              "--disable-pip-version-check", str(wheel)],
                             capture_output=True, text=True, timeout=1200)
    assert install.returncode == 0, install.stderr[-2000:]
    work = tmp_path / "elsewhere"
    work.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    probe = subprocess.run(
        [str(python), "-c", "import navlib, navlib.resources as r, navlib.sensors as s;"
         "print(navlib.__file__); print(r.notebooks_dir()); print(s.list_presets())"],
        cwd=work, env=env, capture_output=True, text=True, timeout=120)
    assert probe.returncode == 0, probe.stderr
    module, notebooks, presets = probe.stdout.splitlines()
    assert module.startswith(str(venv)) and notebooks.startswith(str(venv))
    assert "motionpak_tactical" in presets
    report = subprocess.run([str(python), "-m", "navlib", "report", "--quick", "--only",
                             "01", "07"], cwd=work, env=env, capture_output=True, text=True,
                            timeout=900)
    assert report.returncode == 0, report.stderr[-3000:]
    assert (work / "reports" / "index.html").is_file()
    assert (work / "reports" / "07_assess_flight.html").is_file()  # read ../data/sample_flight
    assert not (venv / "reports").exists()
