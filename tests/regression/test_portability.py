"""The golden subset does not depend on the BLAS thread count or kernel of this machine.

A subprocess recomputes the EKF snapshot cases and the quick claims with the other BLAS
thread count (1 when this process runs more, else 2) and, on x86-64, with another OpenBLAS
kernel (``OPENBLAS_CORETYPE``); its results must equal this process's at the tolerances of
``tolerances.toml``. A result that depends on the thread count or the kernel beyond them fails
here on every machine, not only on the one with another CPU.
"""

import json
import os
import platform
import subprocess
import sys
from pathlib import Path

import golden
import pytest
from threadpoolctl import threadpool_info

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]


def _blas() -> dict:
    return next((i for i in threadpool_info() if i["user_api"] == "blas"), {})


def _variants() -> list[dict]:
    threads = _blas().get("num_threads", 1)
    variants = [{"OPENBLAS_NUM_THREADS": "2" if threads == 1 else "1"}]
    if platform.machine().lower() in ("x86_64", "amd64") and _blas().get(
            "internal_api") == "openblas":
        other = "Sandybridge" if _blas().get("architecture") != "Sandybridge" else "Haswell"
        variants.append({"OPENBLAS_CORETYPE": other})
    return variants


_CHILD = """
import json, sys
sys.path[:0] = [{tests!r}, {scripts!r}]
import golden, claims_reference
print(json.dumps({{
    "ekf": {{case: golden.ekf_values(case, golden.ekf_trajectory(case)).tolist()
             for case in golden.EKF_SNAPSHOT}},
    "claims": claims_reference.current_rows(quick=True)}}))
"""


def _child(env_change: dict) -> dict:
    env = {k: v for k, v in os.environ.items() if not k.startswith("OPENBLAS_CORETYPE")}
    env.update(env_change, NAVLIB_NO_CACHE="1")
    code = _CHILD.format(tests=str(HERE), scripts=str(ROOT / "scripts"))
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                          text=True, timeout=600, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def here() -> dict:
    sys.path.insert(0, str(ROOT / "scripts"))
    import claims_reference

    return {"ekf": {case: golden.ekf_values(case, golden.ekf_trajectory(case))
                    for case in golden.EKF_SNAPSHOT},
            "claims": claims_reference.current_rows(quick=True)}


@pytest.mark.slow
@pytest.mark.parametrize("env_change", _variants(), ids=lambda e: ",".join(
    f"{k}={v}" for k, v in e.items()))
def test_golden_subset_is_portable(here, env_change):
    other = _child(env_change)
    for case, values in other["ekf"].items():
        assert golden.grouped_differences(values, here["ekf"][case],
                                          golden.ekf_tolerances()) == [], case
    assert golden.rows_differences(other["claims"], here["claims"], "claim_id",
                                   golden.tolerance("claims_quick")) == []
