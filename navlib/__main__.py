"""Command line: ``python -m navlib report [--quick] [--only NAME ...] [-p key value ...]
[--jobs N] [--no-cache]``
``python -m navlib assess LOG [LOG ...] [--output DIR] [--scheduler ADDR] [--preset NAME]
[--vehicle CLASS] [--initial-attitude YAW,PITCH,ROLL] [--launch-elevation DEG]
[--launch-azimuth DEG] [--read KEY VALUE ...] [-p key value ...]`` (default DIR:
``./assessments``),
``python -m navlib plan MISSION [MISSION ...] [--sensors PRESET_OR_FILE] [--flight LOG]
[--read KEY VALUE ...] [--output DIR] [-p key value ...]`` (default DIR: ``./plans``) and
``python -m navlib sweep EVALUATION -g NAME VALUE [VALUE ...] ... [--output FILE]``.

Exit status: 0 on success, 1 when a notebook failed (notebook and cell named on stderr),
2 for bad command-line input, 128 + signal number when interrupted (130 Ctrl-C, 143 SIGTERM).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from navlib import reports
from navlib.errors import NavlibInputError
from navlib.reports.terminal import warning_lines
from navlib.vehicles import VEHICLES

_TRACEBACK_LINES = 12
DEFAULT_ASSESS_DIR = "assessments"
"""Folder (in the current folder) ``assess`` writes to when ``--output`` is not given."""
DEFAULT_PLAN_DIR = "plans"
"""Folder (in the current folder) ``plan`` writes to when ``--output`` is not given."""
LOG_FORMS = """LOG forms (navlib.io.read_log):
  flight.ulg             PX4 ULog (sensor_combined, vehicle_gps_position or sensor_gps)
  flight.bin             ArduPilot DataFlash log (IMU, GPS, ATT)
  flight.csv             Altus Metrum AltOS CSV export (TeleMega: IMU and GPS in one file;
                         recognised by its first line, whatever its name)
  imu.csv,gnss.csv       a CSV pair joined by a comma (one shell word): IMU (t, f_x, f_y, f_z,
                         w_x, w_y, w_z) and GNSS (t and lat_deg, lon_deg, alt or ECEF x, y, z)
  imu.csv,baro.csv       IMU and barometer (t and pressure_pa or altitude_m): no GNSS
  imu.csv,gnss.csv,baro.csv   all three (a GNSS record without height takes the barometer's)
  firm.csv               FIRM flight computer CSV (IMU and barometer; recognised by its header)
  imu.csv                CATS Vega export (baro.csv and gnssInfo.csv found beside it)
  flight.csv             AltOS EasyMega export (IMU and barometer, no GPS)
Example: python -m navlib assess data/sample_flight/imu.csv,data/sample_flight/gnss.csv

Reader options (--read KEY VALUE, repeatable; or -p read_options '{"KEY": VALUE, ...}'):
keywords of the LOG's reader (navlib.io.read_log), e.g.
  --read max_rate_rad_s 60       a tumble above the default 35 rad/s (2000 deg/s) limit
  --read max_outlier_fraction 0.05   --read on_gap split   --read imu_max_gap_s 0.5
  --read gyro_unit deg/s         (CSV files)   --read keep_held true   (GNSS CSV: keep held rows)
A keyword the LOG's reader does not take is refused, naming those it takes. The
data-quality thresholds (data/quality.toml) are an assess keyword, e.g. the share of the
GNSS record's time faulty fixes may cover:
  -p quality_thresholds '{"gnss": {"max_faulty_time_fraction": 0.8}}'"""


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m navlib",
                                     description="navlib workbook commands")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    rep = sub.add_parser(
        "report", help="execute the notebooks and write HTML reports",
        description="Execute notebooks/NN_*.ipynb with papermill (working directory: the "
                    "notebooks folder) and write executed notebooks, HTML pages and an "
                    "index.html. The output folder is replaced only when every notebook "
                    "succeeds.")
    rep.add_argument("--quick", action="store_true",
                     help="inject quick=True: shrunken durations for a fast smoke run")
    rep.add_argument("--only", nargs="+", action="extend", metavar="NAME",
                     help="run only these notebooks: stem (07_assess_flight), number (07) "
                          "or file name; other pages of an existing report are kept")
    _add_parameter_option(rep, "inject a parameter into the notebooks whose parameters cell "
                               "defines KEY; VALUE is parsed as JSON or a Python literal, else "
                               "taken as a string; existing relative paths are made absolute")
    rep.add_argument("--output", type=Path, default=None, metavar="DIR",
                     help="report folder (default: reports/ of the navlib checkout)")
    rep.add_argument("--notebooks", type=Path, default=None, metavar="DIR",
                     help="notebooks folder (default: notebooks/ of the navlib checkout)")
    rep.add_argument("--list", action="store_true",
                     help="list the notebooks and their parameters, run nothing")
    rep.add_argument("--fail-fast", action="store_true",
                     help="stop at the first failing notebook")
    rep.add_argument("--timeout", type=float, default=reports.DEFAULT_CELL_TIMEOUT_S,
                     metavar="S",
                     help="per-cell time limit in seconds; a cell over it fails its notebook "
                          f"(default: {reports.DEFAULT_CELL_TIMEOUT_S:.0f}; 0: no limit). "
                          "A kernel that stops answering is restarted once whatever the "
                          "limit")
    rep.add_argument("--jobs", type=int, default=None, metavar="N",
                     help="run up to N notebooks at once, each in its own kernel with "
                          "cpus/N BLAS threads (default: the number of CPUs, "
                          f"{reports.available_cpus()} here; 1: one after the other)")
    rep.add_argument("--no-cache", action="store_true",
                     help="rebuild every trajectory and model: the kernels run with "
                          "NAVLIB_NO_CACHE=1 and read or write no cache entry")
    _add_assess(sub)
    _add_plan(sub)
    _add_sweep(sub)
    return parser


def _add_parameter_option(parser, help_text: str, nargs: int | str = 2) -> None:
    """The repeatable ``-p KEY VALUE`` option of the ``report``, ``assess`` and ``plan``
    commands (``nargs="+"``: a JSON value may be split over several shell words)."""
    parser.add_argument("-p", "--parameter", nargs=nargs, action="append", default=[],
                        metavar=("KEY", "VALUE"), help=help_text)


def _add_scheduler(parser) -> None:
    """The ``--scheduler`` option of the Dask commands (``assess``, ``sweep``)."""
    parser.add_argument("--scheduler", default=None, metavar="ADDR",
                        help="Dask scheduler address (tcp://host:8786) or processes, threads, "
                             "synchronous (default: $NAVLIB_SCHEDULER, else a local cluster)")


def _add_assess(sub) -> None:
    ass = sub.add_parser(
        "assess", help="assess one or many flights (Dask tasks) into a summary table",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Assess each flight with navlib.studies.assess.assess_flight as a Dask "
                    "task;\nwrite DIR/summary.csv (one row per flight) and one HTML page per "
                    "assessed flight.\nA failed flight is reported in the table; the exit "
                    "status is 1 when any failed.\n\n" + LOG_FORMS)
    ass.add_argument("logs", nargs="+", metavar="LOG",
                     help="a flight log, in one of the forms listed above")
    ass.add_argument("--output", type=Path, default=Path(DEFAULT_ASSESS_DIR), metavar="DIR",
                     help="folder for summary.csv and the flight pages (default: "
                          f"./{DEFAULT_ASSESS_DIR} in the current folder)")
    _add_scheduler(ass)
    ass.add_argument("--preset", default=None, metavar="NAME_OR_FILE",
                     help="sensor preset (data/sensors/*.toml name or a .toml file); default: "
                          "the Pixhawk-class preset for PX4/ArduPilot logs, else "
                          "motionpak_tactical")
    ass.add_argument("--vehicle", default=None, choices=VEHICLES,
                     help="vehicle class, naming the phases (rockets: rest/powered/coast/"
                          "descent; others: rest/hover/climb/descent/turn/cruise); default: "
                          "what the log says, else recognised from the kinematics")
    ass.add_argument("--initial-attitude", default=None, metavar="YAW,PITCH,ROLL",
                     help="initial attitude in degrees, body to local North-East-Down "
                          "(fit option initial_attitude_deg), e.g. --initial-attitude -30,80,0")
    ass.add_argument("--launch-elevation", type=float, default=None, metavar="DEG",
                     help="launch-rail elevation above the horizon, degrees (fit option "
                          "launch_elevation_deg)")
    ass.add_argument("--launch-azimuth", type=float, default=None, metavar="DEG",
                     help="launch-rail azimuth from North, degrees (fit option "
                          "launch_azimuth_deg)")
    ass.add_argument("--read", nargs=2, action="append", default=[], metavar=("KEY", "VALUE"),
                     help="a keyword of the LOG's reader (see 'Reader options' above), "
                          "VALUE parsed as JSON or a Python literal, else a string; "
                          "repeatable")
    _add_parameter_option(ass, "a keyword of assess_flight (eta, nu, gnss_rate_hz, "
                               "fit_options, segment_options, quality_thresholds, ...) or "
                               "read_options; VALUE parsed as JSON or a Python literal, else a "
                               "string; a JSON value may be split over several shell words "
                               "(they are joined with spaces)", nargs="+")


def _parameter_words(key: str, words: list[str]):
    """The value of ``-p KEY WORD [WORD ...]``: the words joined with spaces, parsed."""
    if not words:
        raise NavlibInputError(f"-p {key}: no value given (write: -p {key} VALUE)")
    value = reports.parse_parameter_value(" ".join(words))
    if len(words) > 1 and isinstance(value, str):
        raise NavlibInputError(
            f"-p {key}: the value came as {len(words)} shell words {words} that do not join "
            "into one JSON or Python value; quote it as one word, and give each -p one "
            "KEY and one VALUE")
    return value


def assess_options(args) -> dict:
    """The :func:`navlib.studies.assess.assess_flight` keywords of an ``assess`` command
    line: the ``-p`` pairs with ``--preset``, ``--vehicle`` and the fit options
    ``initial_attitude_deg`` (yaw, pitch, roll), ``launch_elevation_deg`` and
    ``launch_azimuth_deg`` of the flags merged in (a keyword given both ways is refused), and
    ``read_options``, the log reader's keywords of ``--read KEY VALUE`` and ``-p
    read_options``, for :func:`navlib.reports.fleet.assess_log`."""
    options = {}
    for key, *words in args.parameter:
        if key in options:
            raise NavlibInputError(f"-p {key}: given twice")
        options[key] = _parameter_words(key, words)
    fit_options = options.get("fit_options") or {}
    if not isinstance(fit_options, dict):
        raise NavlibInputError(f"-p fit_options: expected a JSON object, got {fit_options!r}")
    fit_options = dict(fit_options)
    flags = {}
    if args.initial_attitude is not None:
        parts = args.initial_attitude.split(",")
        try:
            angles = tuple(float(x) for x in parts)
        except ValueError:
            angles = ()
        if len(angles) != 3:
            raise NavlibInputError(f"--initial-attitude: expected YAW,PITCH,ROLL in degrees "
                                   f"(three numbers), got {args.initial_attitude!r}")
        flags["initial_attitude_deg"] = angles
    if args.launch_elevation is not None:
        flags["launch_elevation_deg"] = args.launch_elevation
    if args.launch_azimuth is not None:
        flags["launch_azimuth_deg"] = args.launch_azimuth
    for key, value in flags.items():
        if key in fit_options:
            raise NavlibInputError(f"fit_options: {key} given both in -p fit_options and as "
                                   "a flag")
        fit_options[key] = value
    if fit_options:
        options["fit_options"] = fit_options
    read_options = _read_options(options.get("read_options"), args.read)
    if read_options:
        options["read_options"] = read_options
    for key in ("preset", "vehicle"):
        value = getattr(args, key)
        if value is not None:
            if key in options:
                raise NavlibInputError(f"--{key}: also given as -p {key}; give it once")
            options[key] = value
    return options


def _read_options(given, pairs) -> dict:
    """The reader options of ``-p read_options {...}`` and the ``--read KEY VALUE`` pairs
    merged (a keyword given twice, or both ways, is refused)."""
    given = given or {}
    if not isinstance(given, dict):
        raise NavlibInputError(f"-p read_options: expected a JSON object of reader keyword -> "
                               f"value, e.g. '{{\"max_rate_rad_s\": 60}}', got {given!r}")
    out = dict(given)
    for key, text in pairs or ():
        if key in out:
            raise NavlibInputError(f"--read {key}: given twice (or also in -p read_options)")
        out[key] = reports.parse_parameter_value(text)
    return out


def _outcome(table, path: Path, done: str, describe_ok=None) -> int:
    """Print the outcome of an ``assess`` or ``plan`` table on stderr: one line per failed
    row, one per ok row when ``describe_ok(row)`` is given, then ``K of N <done>; summary:
    <path>``. Returns the exit status: 1 when any row failed."""
    failed = table[table["status"] != "ok"]
    for row in failed.itertuples(index=False):
        print(f"failed: {row.log}: {row.error}", file=sys.stderr)
    if describe_ok is not None:
        for row in table[table["status"] == "ok"].itertuples(index=False):
            print(describe_ok(row), file=sys.stderr)
    print(f"{len(table) - len(failed)} of {len(table)} {done}; summary: {path.resolve()}",
          file=sys.stderr)
    return 1 if len(failed) else 0


def _assess(args) -> int:
    from navlib.reports import fleet  # the studies are heavy: loaded by the commands using them

    options = assess_options(args)
    table, pages = fleet.assess_logs(args.logs, options, scheduler=args.scheduler,
                                     progress=True)
    path = fleet.write_fleet(table, pages, args.output)
    return _outcome(table, path, "flight(s) assessed")


def _add_plan(sub) -> None:
    pln = sub.add_parser(
        "plan", help="plan missions: which states will be estimable, and when",
        description="Build each mission file's trajectory (navlib.trajectory.from_mission) "
                    "and assess it with navlib.studies.plan.plan_mission; write "
                    "DIR/summary.csv (one row per mission) and one HTML page per mission, "
                    "with the timeline of when each state becomes excitable and sensible. "
                    "The exit status is 1 when any mission failed.")
    pln.add_argument("missions", nargs="+", metavar="MISSION",
                     help="a mission TOML file or the name of an example mission "
                          "(data/missions)")
    pln.add_argument("--sensors", default=None, metavar="PRESET_OR_FILE",
                     help="sensor preset name or TOML file (default: the mission's, else "
                          "the default of its vehicle class)")
    pln.add_argument("--output", type=Path, default=Path(DEFAULT_PLAN_DIR), metavar="DIR",
                     help="folder for summary.csv and the mission pages (default: "
                          f"./{DEFAULT_PLAN_DIR} in the current folder)")
    pln.add_argument("--flight", default=None, metavar="LOG",
                     help="a recorded flight of the same vehicle (a LOG as for assess: .ulg, "
                          ".bin, AltOS .csv or an imu.csv,gnss.csv pair): its "
                          "assessment is shown beside each plan, per phase")
    pln.add_argument("--read", nargs=2, action="append", default=[], metavar=("KEY", "VALUE"),
                     help="a keyword of the --flight LOG's reader, as for assess (e.g. --read "
                          "max_rate_rad_s 60); repeatable")
    _add_parameter_option(pln, "a keyword of plan_mission (eta, nu, gnss_rate_hz, outages, "
                               "s_threshold, ...) or read_options; VALUE parsed as JSON or a "
                               "Python literal, else a string")


def _plan(args) -> int:
    from navlib.reports import fleet  # the studies are heavy: loaded by the commands using them

    options = {key: reports.parse_parameter_value(text) for key, text in args.parameter}
    read_options = _read_options(options.get("read_options"), args.read)
    if read_options:
        options["read_options"] = read_options
    if args.sensors is not None:
        options["sensors_preset"] = args.sensors
    table, pages = fleet.plan_missions(args.missions, options, flight=args.flight)
    path = fleet.write_fleet(table, pages, args.output)
    return _outcome(table, path, "mission(s) planned", lambda row: (
        f"{row.log}: {row.vehicle}, {row.n_segments} segment(s), {row.seconds:.1f} s"))


def _add_sweep(sub) -> None:
    swp = sub.add_parser(
        "sweep", help="sweep a named evaluation over a grid of parameters (Dask tasks)",
        description="Map a named evaluation of navlib.sweep over the product of the given "
                    "parameter values and print the table; with --output it is saved as "
                    "Parquet as it runs and a rerun resumes. --list shows the evaluations "
                    "and their parameters.")
    swp.add_argument("evaluation", nargs="?", help="a name of navlib.sweep.EVALUATIONS")
    swp.add_argument("-g", "--grid", nargs="+", action="append", default=[],
                     metavar=("NAME", "VALUE"),
                     help="a parameter and its values, e.g. -g spin_hz 0.5 1 2; each VALUE "
                          "parsed as JSON or a Python literal, else a string")
    swp.add_argument("--output", type=Path, default=None, metavar="FILE.parquet",
                     help="save the results (resumable)")
    _add_scheduler(swp)
    swp.add_argument("--list", action="store_true", help="list the evaluations, run nothing")


def _sweep(args) -> int:
    # the sweep loads the studies (heavy): only when this command runs
    import pandas as pd

    import navlib.studies  # noqa: F401 - the studies register their named evaluations
    from navlib import sweep

    if args.list:
        for row in sweep.evaluations_frame().itertuples(index=False):
            print(f"{row.name}\n    {row.description}\n    parameters: {row.parameters}\n"
                  f"    shared input built once per value of: {row.shared}")
        return 0
    if not args.evaluation:
        raise NavlibInputError("evaluation: name one (python -m navlib sweep --list)")
    grid = {}
    for name, *values in args.grid:
        if not values:
            raise NavlibInputError(f"grid: {name} has no values (write: -g {name} V1 V2 ...)")
        if name in grid:
            raise NavlibInputError(f"grid: {name} given twice")
        grid[name] = [reports.parse_parameter_value(v) for v in values]
    if not grid:
        raise NavlibInputError("grid: give at least one parameter, e.g. -g eta 1e-2 1e-3")
    table = sweep.sweep(grid, args.evaluation, scheduler=args.scheduler, output=args.output)
    with pd.option_context("display.width", 200, "display.max_columns", 30):
        print(table.to_string(index=False))
    stats = table.attrs.get("sweep", {})
    where = f"; saved: {Path(args.output).resolve()}" if args.output else ""
    print(f"{stats.get('n_points', len(table))} point(s), {stats.get('n_computed', '?')} "
          f"computed in {stats.get('wall_s', float('nan')):.1f} s{where}", file=sys.stderr)
    return 0


class _ProgressPrinter:
    """Progress lines on stderr: ``[k/N] name ... ok (12.3 s)``.

    One notebook at a time, its line is completed in place as now. When another notebook
    starts while a line is open (parallel runs), that line is ended with ``running`` and
    every later event of it gets a line of its own, so lines never mix.
    """

    def __init__(self):
        self._open: str | None = None  # the notebook whose line awaits its end

    def _write(self, text: str) -> None:
        print(text, end="", file=sys.stderr, flush=True)

    def __call__(self, position: int, total: int, name: str, run) -> None:
        prefix = f"[{position}/{total}] {name} ... "
        if run is None:
            if self._open is not None:
                self._write("running\n")
            self._write(prefix)
            self._open = name
            return
        if self._open != name:
            if self._open is not None:
                self._write("running\n")
            self._write(prefix)
        self._open = None
        if run.status == "restarting":
            self._write(f"stalled at {run.failure.describe()}; restarting the kernel and "
                        f"re-running {name} ... ")
            self._open = name
        else:
            self._write(f"{run.status} ({run.seconds:.1f} s)\n")


def _list(notebooks: Path, only) -> None:
    for info in reports.select_notebooks(reports.list_notebooks(notebooks), only):
        print(f"{info.name}  {info.title}")
        for key, default in info.parameters.items():
            print(f"    {key} = {default}")


def _report(args) -> int:
    notebooks = args.notebooks or reports.default_notebooks_dir()
    output = args.output or reports.default_output_dir()
    if args.list:
        _list(notebooks, args.only)
        return 0
    parameters = reports.parse_parameters(args.parameter)
    start = time.perf_counter()
    try:
        runs = reports.run_reports(notebooks, output, quick=args.quick, only=args.only,
                                   parameters=parameters, progress=_ProgressPrinter(),
                                   fail_fast=args.fail_fast,
                                   timeout_s=None if args.timeout == 0 else args.timeout,
                                   jobs=reports.available_cpus() if args.jobs is None
                                   else args.jobs, cache=not args.no_cache)
    except reports.ReportInterrupted as exc:
        print(f"\n{exc}", file=sys.stderr)
        return 128 + exc.signum
    except reports.ReportError as exc:
        for run in exc.runs:
            if run.failure and run.failure.traceback:
                tail = run.failure.traceback.strip().splitlines()[-_TRACEBACK_LINES:]
                print(f"\n--- {run.name} traceback (last lines) ---", file=sys.stderr)
                print("\n".join(tail), file=sys.stderr)
        print(f"\nerror: {exc}", file=sys.stderr)
        return 1
    total = sum(r.seconds for r in runs)
    index = Path(output).resolve() / reports.INDEX
    print(f"{len(runs)} notebook(s) ok in {total:.1f} s of kernel time, "
          f"{time.perf_counter() - start:.1f} s wall; report: {index}", file=sys.stderr)
    return 0


def _negative_angles(argv: list[str]) -> list[str]:
    """``--initial-attitude -30,80,0`` as ``--initial-attitude=-30,80,0``: argparse would
    take a value starting with a minus sign for an option."""
    out = []
    for word in argv:
        if out and out[-1] == "--initial-attitude" and word[:1] == "-" and word[1:2].isdigit():
            out[-1] = f"--initial-attitude={word}"
        else:
            out.append(word)
    return out


@warning_lines   # library warnings as one line each, without a source location
def main(argv: list[str] | None = None) -> int:
    """Entry point of ``python -m navlib``; returns the exit status."""
    args = _parser().parse_args(_negative_angles(sys.argv[1:] if argv is None else list(argv)))
    try:
        if args.command == "report":
            return _report(args)
        if args.command == "sweep":
            return _sweep(args)
        if args.command == "assess":
            return _assess(args)
        if args.command == "plan":
            return _plan(args)
    except NavlibInputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 2  # pragma: no cover - argparse rejects unknown commands


if __name__ == "__main__":
    sys.exit(main())
