"""Measure how far each golden result moves under changes that must not matter.

Each golden of ``tests/regression/tolerances.toml`` is recomputed in a subprocess per
variant: the BLAS kernel (``OPENBLAS_CORETYPE`` unset, Haswell with ``OPENBLAS_L2_SIZE=512``,
Sandybridge), the BLAS thread count (1 and 2) and a 1-ulp perturbation of the trajectories
(every position, velocity, specific force and angular rate sample times ``1 + 2**-52``,
applied to the trajectory generators before any study imports them). The spread is the
largest distance of a variant from the stored reference, in the golden's own measure (see
``tests/regression/golden.py``)::

    python scripts/golden_spread.py                 # every golden, every variant
    python scripts/golden_spread.py ekf claims_quick --variants threads1 haswell
    python scripts/golden_spread.py --variants gnss_sigma_1pct   # a real change: caught?

A table is printed: golden, variant, spread, tolerance, margin. The tolerances themselves are
chosen by hand from these numbers and written in ``tolerances.toml`` with the spread.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TESTS = ROOT / "tests"

VARIANTS = {
    "native": {},
    "threads1": {"OPENBLAS_NUM_THREADS": "1"},
    "haswell": {"OPENBLAS_CORETYPE": "Haswell", "OPENBLAS_L2_SIZE": "512"},
    "sandybridge": {"OPENBLAS_CORETYPE": "Sandybridge"},
    "ulp": {"GOLDEN_SPREAD_ULP": "1"},
    "gnss_sigma_1pct": {"GOLDEN_SPREAD_GNSS_SIGMA": "1.01"},
}
"""Variant name -> environment it adds (``OPENBLAS_*`` removed from the inherited one).
``gnss_sigma_1pct`` is not a change that must not matter but a real one (every preset's GNSS
position noise 1 % larger): a golden must move by more than its tolerance under it."""
REAL_CHANGES = ("gnss_sigma_1pct",)

GOLDENS = ("ekf", "claims_quick", "outliers_quick", "outlier_claims_quick", "outliers_full",
           "outlier_claims_full")


def _nudge_trajectories() -> None:
    """Make the trajectory generators return every sample nudged by one ulp (relative)."""
    import dataclasses

    import navlib.trajectory as trajectory_package

    factor = 1.0 + 2.0**-52

    def nudged(generator):
        def build(*args, **kwargs):
            traj = generator(*args, **kwargs)
            return dataclasses.replace(
                traj, **{k: getattr(traj, k) * factor for k in
                         ("position", "velocity", "specific_force", "angular_rate")})
        return build

    for name in ("sounding_rocket", "launcher_ascent", "stationary"):
        generator = getattr(trajectory_package, name)
        _rebind(name, generator, nudged(generator))


def _rebind(name: str, old, new) -> None:
    """Replace ``old`` by ``new`` in every navlib module that bound it as ``name``."""
    for module in list(sys.modules.values()):
        if getattr(module, "__name__", "").startswith("navlib") \
                and getattr(module, name, None) is old:
            setattr(module, name, new)


def _scale_gnss_sigma(factor: float) -> None:
    """Make every sensor preset's GNSS position noise ``factor`` times larger."""
    import dataclasses

    import navlib.sensors

    load = navlib.sensors.load_preset

    def scaled(name_or_path):
        spec = load(name_or_path)
        if spec.gnss is None:
            return spec
        return dataclasses.replace(spec, gnss=dataclasses.replace(
            spec.gnss, position_sigma=spec.gnss.position_sigma * factor))

    _rebind("load_preset", load, scaled)


def emit(golden: str, out: Path) -> None:
    """Compute ``golden`` in this process and write its values as JSON to ``out``."""
    sys.path[:0] = [str(TESTS), str(TESTS / "regression"), str(ROOT / "scripts")]
    os.environ["NAVLIB_NO_CACHE"] = "1"
    import matplotlib

    matplotlib.use("Agg")
    if os.environ.get("GOLDEN_SPREAD_ULP"):
        _nudge_trajectories()
    if os.environ.get("GOLDEN_SPREAD_GNSS_SIGMA"):
        import navlib.models  # noqa: F401  (the models bind load_preset at import)

        _scale_gnss_sigma(float(os.environ["GOLDEN_SPREAD_GNSS_SIGMA"]))
    import golden as g

    if golden == "ekf":
        values = {case: g.ekf_values(case, g.ekf_trajectory(case)).tolist()
                  for case in g.EKF_SNAPSHOT}
    elif golden == "claims_quick":
        import claims_reference

        values = claims_reference.current_rows(quick=True)
    else:
        import outlier_tables

        quick = golden.endswith("quick")
        frame = outlier_tables.claim_values(quick) if "claims" in golden \
            else outlier_tables.notebook_values(quick)
        values = frame.astype(str).to_dict("records")
    out.write_text(json.dumps(values))


def spread(golden: str, values) -> float:
    """Distance of ``values`` from the stored reference in the golden's measure."""
    sys.path[:0] = [str(TESTS), str(TESTS / "regression"), str(ROOT / "scripts")]
    import golden as g

    if golden == "ekf":
        spreads = [g.grouped_spread(values[case], g.ekf_reference(case))
                   for case in g.EKF_SNAPSHOT]
        return {group: max(s[group] for s in spreads) for group in g.EKF_GROUPS}
    if golden == "claims_quick":
        import claims_reference

        reference = claims_reference.read_rows(claims_reference.reference_path(quick=True))
        return g.rows_spread(values, reference, key="claim_id")
    import outlier_tables
    import pandas as pd

    name = f"outliers_{golden.removeprefix('outliers_').removeprefix('outlier_')}.csv"
    want = outlier_tables.reference(name)
    return outlier_tables.spread(pd.DataFrame(values), want)


def _run_variant(golden: str, variant: str) -> tuple[float | dict, float]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("OPENBLAS_")}
    env.update(VARIANTS[variant])
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "values.json"
        start = time.perf_counter()
        subprocess.run([sys.executable, __file__, "--emit", golden, str(out)], env=env,
                       check=True, cwd=ROOT)
        elapsed = time.perf_counter() - start
        return spread(golden, json.loads(out.read_text())), elapsed


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("goldens", nargs="*", help=f"any of {', '.join(GOLDENS)} (default: all)")
    parser.add_argument("--variants", nargs="+", choices=VARIANTS,
                        default=[v for v in VARIANTS if v not in REAL_CHANGES])
    parser.add_argument("--emit", nargs=2, metavar=("GOLDEN", "OUT"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.emit:
        emit(args.emit[0], Path(args.emit[1]))
        return 0
    unknown = set(args.goldens) - set(GOLDENS)
    if unknown:
        parser.error(f"unknown golden(s) {sorted(unknown)}; expected any of {GOLDENS}")
    sys.path[:0] = [str(TESTS / "regression")]
    import golden as g

    print(f"{'golden':22s} {'variant':16s} {'spread':>10s} {'tolerance':>10s} "
          f"{'margin':>8s} {'time s':>7s}", flush=True)
    for golden in args.goldens or GOLDENS:
        tolerances = g.ekf_tolerances() if golden == "ekf" else {"": g.tolerance(golden)}
        for variant in args.variants:
            values, elapsed = _run_variant(golden, variant)
            values = values if isinstance(values, dict) else {"": values}
            for part, value in values.items():
                tol = tolerances[part]
                margin = tol / value if value > 0 else float("inf")
                name = f"{golden} {part}".strip()
                note = ("  caught" if margin < 1 else "  NOT CAUGHT") \
                    if variant in REAL_CHANGES else ""
                print(f"{name:22s} {variant:16s} {value:10.3g} {tol:10.3g} {margin:8.3g} "
                      f"{elapsed:7.1f}{note}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
