"""Regenerate the shipped sample flight ``data/sample_flight/`` (deterministic, seeded).

The flight is :func:`navlib.trajectory.sounding_rocket` (the VS30-like profile: pad
0-18 s, boost 18-46 s, coast to ``end_s``) seen through the errors of a sensor preset by
:func:`navlib.sensors.simulate_imu` (IMU at the trajectory's 100 Hz) and
:func:`navlib.sensors.simulate_gnss` (ECEF position and velocity at the preset's 1 Hz).
The CSV files are written with :func:`navlib.io.write_imu_csv` / ``write_gnss_csv``
(units in the headers), rounded well below the simulated noise to keep them small: IMU to
6 significant digits (1e-3 m/s^2 at the 110 m/s^2 peak against 0.017 m/s^2 white noise per
sample), GNSS to the millimetre.

Usage (from the repository root)::

    .venv/bin/python scripts/make_sample_flight.py [--out DIR] [--seed N] [--end-s S]
"""

from __future__ import annotations

import argparse
from pathlib import Path

from navlib import io, sensors
from navlib.trajectory import sounding_rocket

ROOT = Path(__file__).resolve().parents[1]
DEFAULTS = {"out": ROOT / "data" / "sample_flight", "seed": 20190607, "end_s": 86.0,
            "preset": "motionpak_tactical"}
IMU_FORMAT = "%.6g"
GNSS_FORMAT = "%.3f"

README = """\
# Sample flight (simulated)

A small noisy flight that `notebooks/07_assess_flight.ipynb` assesses by default, so that the
report always regenerates without outside data. **Simulated, not recorded.**

* `imu.csv`: time, specific force f^b (m/s^2) and angular rate omega_ib^b (rad/s), body axes,
  {imu_rate:g} Hz, {n_imu} rows; read with `navlib.io.read_imu_csv`.
* `gnss.csv`: time, ECEF position (m), ECEF velocity (m/s) and position sigma (m),
  {gnss_rate:g} Hz, {n_gnss} rows; read with `navlib.io.read_gnss_csv`.

Provenance: made by `scripts/make_sample_flight.py` (seed {seed}) from
`navlib.trajectory.sounding_rocket(end_s={end_s:g})` (VS30-like: pad 0-18 s, boost 18-46 s,
coast afterwards; site, thrust and spin are the generator's documented assumptions), with the
errors of the sensor preset `{preset}` (`data/sensors/{preset}.toml`: turn-on biases and scale
factors, their random walks, white noise; all values assumed, see that file) applied by
`navlib.sensors.simulate_imu` and `simulate_gnss`. Values rounded to {imu_format} (IMU) and
{gnss_format} (GNSS), far below the noise. Regenerate with

    .venv/bin/python scripts/make_sample_flight.py --seed {seed} --end-s {end_s:g}
"""


def make_sample_flight(out: Path, seed: int, end_s: float, preset: str) -> dict:
    """Simulate the flight and write ``imu.csv``, ``gnss.csv`` and ``README.md`` to ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    truth = sounding_rocket(end_s=end_s)
    spec = sensors.load_preset(preset)
    imu_seed, gnss_seed = seed, seed + 1
    imu = sensors.simulate_imu(truth, spec, seed=imu_seed).to_frame()
    gnss = sensors.simulate_gnss(truth, spec, seed=gnss_seed)
    io.write_imu_csv(imu, out / "imu.csv", float_format=IMU_FORMAT)
    io.write_gnss_csv(gnss, out / "gnss.csv", float_format=GNSS_FORMAT)
    info = {"seed": seed, "end_s": end_s, "preset": preset, "n_imu": len(imu),
            "n_gnss": len(gnss), "imu_rate": truth.rate_hz, "gnss_rate": spec.gnss.rate_hz,
            "imu_format": IMU_FORMAT, "gnss_format": GNSS_FORMAT}
    (out / "README.md").write_text(README.format(**info), encoding="utf-8")
    return info


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=DEFAULTS["out"])
    parser.add_argument("--seed", type=int, default=DEFAULTS["seed"])
    parser.add_argument("--end-s", type=float, default=DEFAULTS["end_s"])
    parser.add_argument("--preset", default=DEFAULTS["preset"])
    args = parser.parse_args(argv)
    info = make_sample_flight(args.out, args.seed, args.end_s, args.preset)
    sizes = {p.name: p.stat().st_size for p in sorted(args.out.iterdir())}
    print(f"wrote {args.out}: {info['n_imu']} IMU rows, {info['n_gnss']} GNSS rows; "
          f"sizes {sizes}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
