"""The report runner (navlib.reports, ``python -m navlib report``) on throwaway notebooks.

Kernel starts cost about a second each, so one good report is built per module and copied
into each test's own folder before a test modifies it.
"""

import dataclasses
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import nbformat
import pytest

from navlib import NavlibInputError, reports
from navlib.__main__ import main
from navlib.reports import execution, runner

PROBE = (
    "import os, sys  # probe-input-marker\n"
    "print('exe=' + sys.executable)\n"
    "print('cwd=' + os.getcwd())\n"
    "print('quick=%r scale=%r' % (quick, globals().get('scale')))"
)


def _write(path: Path, cells) -> None:
    """Write a notebook from (kind, source[, tag]) tuples."""
    nb = nbformat.v4.new_notebook()
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3",
                                 "language": "python"}
    for kind, source, *tags in cells:
        cell = (nbformat.v4.new_markdown_cell(source) if kind == "md"
                else nbformat.v4.new_code_cell(source))
        if tags:
            cell.metadata["tags"] = list(tags)
        nb.cells.append(cell)
    nbformat.write(nb, path)


def _make_notebooks(folder: Path) -> Path:
    folder.mkdir()
    _write(folder / "01_good.ipynb", [
        ("md", "# Good notebook\n**Question.** Does the probe *run* in the kernel?\n\nMore."),
        ("code", "quick = False\nscale = 2.0  # a factor", "parameters"),
        ("code", PROBE),
        ("code", "print('hidden-output-marker')", "report-hide-output"),
        ("code", "print('hidden-cell-marker')", "report-hide"),
        ("code", "from IPython.display import Markdown\nMarkdown('headline-marker: **yes**')",
         "headline"),
    ])
    _write(folder / "02_other.ipynb", [
        ("md", "# Other notebook"),
        ("code", "quick = False", "parameters"),
        ("code", PROBE),
    ])
    _write(folder / "03_bad.ipynb", [
        ("md", "# Failing notebook"),
        ("code", "quick = False", "parameters"),
        ("code", "x = 1"),
        ("code", "raise ValueError('boom ' + str(x))"),
    ])
    _write(folder / "scratch.ipynb", [("code", "raise SystemExit('not a report notebook')")])
    return folder


def _stdout(executed: Path) -> str:
    nb = nbformat.read(executed, as_version=4)
    return "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code"
                   for o in c.get("outputs", []) if o.get("output_type") == "stream")


def _snapshot(folder: Path) -> dict:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


@pytest.fixture(scope="module")
def good(tmp_path_factory):
    """A successful report of 01 and 02 with ``quick`` and ``scale=3`` requested."""
    root = tmp_path_factory.mktemp("reports")
    nbdir = _make_notebooks(root / "notebooks")
    out = root / "out"
    out.mkdir()
    (out / "README.md").write_text("keep me\n")
    events = []

    def progress(position, total, name, run):
        events.append((position, total, name, None if run is None else run.status))

    runs = reports.run_reports(nbdir, out, quick=True, only=["01", "02_other"],
                               parameters={"scale": 3}, progress=progress)
    return nbdir, out, runs, events


def test_success_writes_pages_index_and_manifest(good):
    _, out, runs, events = good
    assert [r.name for r in runs] == ["01_good", "02_other"]
    assert all(r.ok and r.seconds > 0 for r in runs)
    assert events == [(1, 2, "01_good", None), (1, 2, "01_good", "ok"),
                      (2, 2, "02_other", None), (2, 2, "02_other", "ok")]
    names = {p.name for p in out.iterdir()}
    assert names == {"README.md", "index.html", "manifest.json", "01_good.html",
                     "01_good.ipynb", "02_other.html", "02_other.ipynb"}
    assert (out / "README.md").read_text() == "keep me\n"
    index = (out / "index.html").read_text()
    assert 'href="01_good.html"' in index and 'href="02_other.html"' in index
    assert "Good notebook" in index and "quick" in index and "scale=3" in index
    assert "Does the probe <em>run</em> in the kernel?" in index  # what the page answers
    assert "headline-marker: <strong>yes</strong>" in index  # its tagged headline
    page = (out / "01_good.html").read_text()
    assert "<html" in page and "quick=True scale=3" in page  # outputs are shown,
    assert "probe-input-marker" not in page  # code is not,
    assert "hidden-output-marker" not in page and "hidden-cell-marker" not in page  # nor tagged
    executed = (out / "01_good.ipynb").read_text()  # the executed notebook keeps it all
    assert all(marker in executed for marker in (
        "probe-input-marker", "hidden-output-marker", "hidden-cell-marker"))
    manifest = json.loads((out / "manifest.json").read_text())["notebooks"]
    assert manifest["01_good"]["status"] == "ok" and manifest["01_good"]["quick"] is True
    assert not list(out.parent.glob(".out.*")), "staging folder left behind"


def test_parameters_kernel_and_working_directory(good):
    nbdir, out, runs, _ = good
    assert runs[0].parameters == {"quick": True, "scale": 3}
    assert runs[1].parameters == {"quick": True}  # scale is not a parameter of 02
    first, second = _stdout(out / "01_good.ipynb"), _stdout(out / "02_other.ipynb")
    assert "quick=True scale=3" in first
    assert "quick=True scale=None" in second
    assert f"exe={sys.executable}" in first
    assert f"cwd={nbdir.resolve()}" in first


def test_failure_names_notebook_and_cell_and_keeps_old_report(good, tmp_path):
    nbdir, good_out, _, _ = good
    out = tmp_path / "out"
    shutil.copytree(good_out, out)
    before = _snapshot(out)
    with pytest.raises(reports.ReportError) as info:
        reports.run_reports(nbdir, out, only=["02", "03"])
    err = info.value
    assert [r.status for r in err.runs] == ["ok", "failed"]
    failure = err.runs[1].failure
    assert (failure.cell_index, failure.ename, failure.evalue) == (3, "ValueError", "boom 1")
    assert "boom" in failure.traceback
    assert "03_bad" in str(err) and "cell 3" in str(err) and "raise ValueError" in str(err)
    assert _snapshot(out) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


def test_only_refreshes_selected_pages_and_keeps_the_rest(good, tmp_path):
    nbdir, good_out, _, _ = good
    out = tmp_path / "out"
    shutil.copytree(good_out, out)
    before = _snapshot(out)
    runs = reports.run_reports(nbdir, out, only=["02_other.ipynb"])
    assert [r.name for r in runs] == ["02_other"]
    after = _snapshot(out)
    assert after["01_good.html"] == before["01_good.html"]
    assert after["02_other.ipynb"] != before["02_other.ipynb"]
    assert "quick=False" in _stdout(out / "02_other.ipynb")
    manifest = json.loads(after["manifest.json"])["notebooks"]
    assert manifest["01_good"]["quick"] is True and manifest["02_other"]["quick"] is False
    assert 'href="01_good.html"' in after["index.html"].decode()


def test_full_run_drops_pages_of_removed_notebooks(good, tmp_path):
    nbdir = tmp_path / "notebooks"
    nbdir.mkdir()
    shutil.copy(good[0] / "02_other.ipynb", nbdir / "02_other.ipynb")
    out = tmp_path / "out"
    shutil.copytree(good[1], out)
    reports.run_reports(nbdir, out)
    assert sorted(p.name for p in out.iterdir()) == [
        "02_other.html", "02_other.ipynb", "README.md", "index.html", "manifest.json"]
    assert "01_good" not in (out / "index.html").read_text()


def test_fail_fast_stops_at_first_failure(good, tmp_path):
    nbdir = tmp_path / "notebooks"
    nbdir.mkdir()
    shutil.copy(good[0] / "03_bad.ipynb", nbdir / "01_bad.ipynb")
    shutil.copy(good[0] / "01_good.ipynb", nbdir / "02_good.ipynb")
    with pytest.raises(reports.ReportError) as info:
        reports.run_reports(nbdir, tmp_path / "out", fail_fast=True)
    assert [r.name for r in info.value.runs] == ["01_bad"]
    assert not (tmp_path / "out").exists()


def test_listing_and_selection(good):
    infos = reports.list_notebooks(good[0])
    assert [i.name for i in infos] == ["01_good", "02_other", "03_bad"]  # scratch skipped
    assert infos[0].title == "Good notebook"
    assert infos[0].parameters == {"quick": "False", "scale": "2.0"}
    pick = lambda only: [i.name for i in reports.select_notebooks(infos, only)]  # noqa: E731
    assert pick(None) == ["01_good", "02_other", "03_bad"]
    assert pick(["3", "01_good"]) == ["01_good", "03_bad"]
    assert pick("notebooks/02_other.ipynb") == ["02_other"]
    with pytest.raises(NavlibInputError, match="available: 01_good, 02_other, 03_bad"):
        pick(["07"])


def test_parameter_parsing(tmp_path):
    (tmp_path / "flight.csv").write_text("t\n")
    got = reports.parse_parameters(
        [("a", "2.5"), ("b", "true"), ("c", "[1, 2]"), ("d", "None"), ("e", "Churchill"),
         ("f", "flight.csv"), ("g", "missing.csv"), ("h", "'7'")], cwd=tmp_path)
    assert got == {"a": 2.5, "b": True, "c": [1, 2], "d": None, "e": "Churchill",
                   "f": str((tmp_path / "flight.csv").resolve()), "g": "missing.csv", "h": "7"}
    with pytest.raises(NavlibInputError, match=r"write: -p x 3"):
        reports.parse_parameters([("x=3", "1")])
    with pytest.raises(NavlibInputError, match="does not parse"):
        reports.parse_parameters([("x", "[1, 2")])
    with pytest.raises(NavlibInputError, match=r"imu_path: 'nope.csv' not found \(looked in"):
        reports.parse_parameters([("imu_path", "nope.csv")], cwd=tmp_path)


def test_bad_requests_fail_before_running(good, tmp_path):
    nbdir = good[0]
    with pytest.raises(NavlibInputError, match=r"\['nope'\] defined by none.*'quick', 'scale'"):
        reports.run_reports(nbdir, tmp_path / "out", parameters={"nope": 1})
    foreign = tmp_path / "mine"
    foreign.mkdir()
    (foreign / "thesis.tex").write_text("x")
    with pytest.raises(NavlibInputError, match="not a navlib report"):
        reports.run_reports(nbdir, foreign, only=["01"])
    with pytest.raises(NavlibInputError, match="would replace the notebooks"):
        reports.run_reports(nbdir, nbdir.parent, only=["01"])
    assert not (tmp_path / "out").exists() and (foreign / "thesis.tex").exists()


def test_cli_input_errors_exit_2(good, tmp_path, capsys):
    nbdir = str(good[0])
    assert main(["report", "--notebooks", nbdir, "--output", str(tmp_path / "o"),
                 "--only", "9"]) == 2
    assert "available: 01_good, 02_other, 03_bad" in capsys.readouterr().err
    assert main(["report", "--notebooks", nbdir, "-p", "scale=3", "01"]) == 2
    assert "write: -p scale 3" in capsys.readouterr().err
    assert main(["report", "--notebooks", nbdir, "--list", "--only", "01"]) == 0
    assert "scale = 2.0" in capsys.readouterr().out
    with pytest.raises(SystemExit) as info:  # argparse: -p needs two words
        main(["report", "-p", "scale"])
    assert info.value.code == 2


def _cli(*args, cwd):
    env = dict(os.environ, PYTHONWARNINGS="ignore")
    return subprocess.run([sys.executable, "-m", "navlib", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=120)


def test_cli_help():
    proc = _cli("report", "--help", cwd=Path.cwd())
    assert proc.returncode == 0
    for option in ("--quick", "--only", "--output", "-p KEY VALUE", "--list"):
        assert option in proc.stdout


def test_cli_failure_exits_nonzero_naming_notebook_and_cell(good, tmp_path):
    nbdir = good[0]
    proc = _cli("report", "--notebooks", str(nbdir), "--output", "out", "--quick",
                "--only", "03", cwd=tmp_path)
    assert proc.returncode == 1
    assert "[1/1] 03_bad ... failed (" in proc.stderr
    assert "03_bad: cell 3 (0-based) `raise ValueError('boom ' + str(x))`: ValueError: boom 1" \
        in proc.stderr
    assert not (tmp_path / "out").exists()



# ---------------------------------------------------------------------- parallel runs

TIMED = """\
import json, os, time
start = time.time()
open({pid_file!r}, "w").write(str(os.getpid()))
time.sleep({sleep})
print(json.dumps({{"start": start, "end": time.time(),
                   "omp": os.environ.get("OMP_NUM_THREADS")}}))
"""


def _timed(folder: Path, name: str, sleep: float, *extra: str) -> Path:
    pid_file = folder.parent / f"{name}.pid"
    _write(folder / f"{name}.ipynb", [
        ("md", f"# {name}"),
        ("code", "quick = False", "parameters"),
        ("code", TIMED.format(pid_file=str(pid_file), sleep=sleep)),
        *(("code", source) for source in extra),
    ])
    return pid_file


def _gone(pid: int) -> bool:
    import psutil

    return not psutil.pid_exists(pid) or psutil.Process(pid).status() == "zombie"


@pytest.mark.notebook
def test_parallel_runs_overlap_and_publish_both(tmp_path, monkeypatch):
    for name in reports.BLAS_THREAD_VARIABLES:
        monkeypatch.delenv(name, raising=False)
    _no_warm_up(monkeypatch)
    nbdir = tmp_path / "notebooks"
    nbdir.mkdir()
    _timed(nbdir, "01_first", 4.0)
    _timed(nbdir, "02_second", 4.0)
    events = []
    runs = reports.run_reports(nbdir, tmp_path / "out", jobs=2,
                               progress=lambda p, t, n, r: events.append(
                                   (n, None if r is None else r.status)))
    assert [r.name for r in runs] == ["01_first", "02_second"] and all(r.ok for r in runs)
    assert [e[1] for e in events[:2]] == [None, None]  # both started before either ended
    spans = [json.loads(_stdout(tmp_path / "out" / f"{r.name}.ipynb")) for r in runs]
    assert max(s["start"] for s in spans) < min(s["end"] for s in spans)  # they overlapped
    threads = str(max(1, reports.available_cpus() // 2))
    assert {s["omp"] for s in spans} == {threads}
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())["notebooks"]
    assert sorted(manifest) == ["01_first", "02_second"]
    assert all((tmp_path / "out" / f"{r.name}.html").exists() for r in runs)


def _no_warm_up(monkeypatch) -> None:
    """Two workers without the shared kernels' compile (a process of a few seconds, or of
    half a minute on a machine's first run) before the second starts: for the tests that
    time notebooks against each other."""
    monkeypatch.setattr(runner, "_compile_shared_kernels", lambda stopped: None)


def _bad_and_slow(good, tmp_path: Path, sleep: float) -> tuple[Path, Path]:
    """Notebooks 01_bad (fails at cell 3) and 02_slow (sleeps; writes its kernel's pid)."""
    nbdir = tmp_path / "notebooks"
    nbdir.mkdir()
    shutil.copy(good[0] / "03_bad.ipynb", nbdir / "01_bad.ipynb")
    return nbdir, _timed(nbdir, "02_slow", sleep)


@pytest.mark.notebook
def test_parallel_failure_keeps_the_old_report_and_stops_the_kernels(good, tmp_path):
    nbdir, pid_file = _bad_and_slow(good, tmp_path, 3.0)
    out = tmp_path / "out"
    shutil.copytree(good[1], out)
    before = _snapshot(out)
    with pytest.raises(reports.ReportError) as info:
        reports.run_reports(nbdir, out, jobs=2)
    assert [(r.name, r.status) for r in info.value.runs] == [("01_bad", "failed"),
                                                             ("02_slow", "ok")]
    assert "01_bad" in str(info.value) and "cell 3" in str(info.value)
    assert _snapshot(out) == before
    assert _gone(int(pid_file.read_text()))
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".out.")]


@pytest.mark.notebook
def test_parallel_fail_fast_stops_the_other_kernel(good, tmp_path):
    nbdir, pid_file = _bad_and_slow(good, tmp_path, 300.0)
    # the bad notebook waits until the slow one's kernel runs, so both are running
    nb = nbformat.read(nbdir / "01_bad.ipynb", as_version=4)
    nb.cells[2].source = (f"import os, time\nwhile not os.path.exists({str(pid_file)!r}):\n"
                          "    time.sleep(0.1)\nx = 1")
    nbformat.write(nb, nbdir / "01_bad.ipynb")
    start = time.monotonic()
    with pytest.raises(reports.ReportError) as info:
        reports.run_reports(nbdir, tmp_path / "out", jobs=2, fail_fast=True)
    assert time.monotonic() - start < 90.0
    assert [r.name for r in info.value.runs] == ["01_bad"]  # the stopped one is not a failure
    assert _gone(int(pid_file.read_text()))
    assert not (tmp_path / "out").exists()


@pytest.mark.notebook
def test_sigterm_with_two_kernels_running_stops_both(tmp_path):
    nbdir = tmp_path / "notebooks"
    nbdir.mkdir()
    pid_files = [_timed(nbdir, name, 300.0) for name in ("01_long", "02_long")]
    out = tmp_path / "out"
    out.mkdir()
    (out / "manifest.json").write_text("{}")
    (out / "old.html").write_text("previous report")
    proc = subprocess.Popen([sys.executable, "-m", "navlib", "report", "--notebooks",
                             str(nbdir), "--output", str(out), "--jobs", "2"], cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 90
    while (not all(p.exists() and p.read_text() for p in pid_files)
           and time.monotonic() < deadline):
        time.sleep(0.2)
    pids = [int(p.read_text()) for p in pid_files]
    proc.send_signal(signal.SIGTERM)
    _, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 128 + signal.SIGTERM, stderr
    assert "interrupted by SIGTERM" in stderr
    assert all(_gone(pid) for pid in pids)
    assert sorted(p.name for p in out.iterdir()) == ["manifest.json", "old.html"]
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".out.")]


def test_queue_is_longest_first_by_the_previous_manifest(good, tmp_path, monkeypatch):
    infos = reports.list_notebooks(good[0])
    out, default = tmp_path / "out", tmp_path / "reports"
    out.mkdir()
    default.mkdir()
    monkeypatch.setattr(runner, "default_output_dir", lambda: default)
    order = lambda: [i.name for i in runner.queue_order(infos, out)]  # noqa: E731
    assert order() == ["01_good", "02_other", "03_bad"]  # no manifest: name order
    (default / "manifest.json").write_text(json.dumps({"notebooks": {
        "01_good": {"seconds": 9.0}, "02_other": {"seconds": 1.0}, "03_bad": {"seconds": 5.0}}}))
    assert order() == ["01_good", "03_bad", "02_other"]  # a new folder: the last make report
    (out / "manifest.json").write_text(json.dumps({"notebooks": {
        "01_good": {"seconds": 2.0}, "02_other": {"seconds": 30.0}}}))
    assert order() == ["03_bad", "02_other", "01_good"]  # untimed first: it may be long


def test_queue_puts_what_a_waiting_notebook_needs_first(good, tmp_path, monkeypatch):
    """The longest path first: a notebook plus the longest of those that wait for it."""
    infos = reports.list_notebooks(good[0])
    waits = dataclasses.replace(infos[0], after=("03",))  # 01_good starts after 03_bad
    infos = [waits, *infos[1:]]
    out = tmp_path / "out"
    out.mkdir()
    monkeypatch.setattr(runner, "default_output_dir", lambda: tmp_path / "none")
    order = lambda: [i.name for i in runner.queue_order(infos, out)]  # noqa: E731
    assert order() == ["03_bad", "01_good", "02_other"]  # no manifest: 03 is waited for
    (out / "manifest.json").write_text(json.dumps({"notebooks": {
        "01_good": {"seconds": 9.0}, "02_other": {"seconds": 12.0}, "03_bad": {"seconds": 5.0}}}))
    assert order() == ["03_bad", "02_other", "01_good"]  # 5 + 9 s before 12 s before 9 s


def test_kernel_environment_shares_the_cores(monkeypatch):
    for name in (*reports.BLAS_THREAD_VARIABLES, *reports.MALLOC_VARIABLES,
                 *reports.HUGEPAGE_VARIABLES):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setattr(execution, "available_cpus", lambda: 4)
    assert reports.kernel_environment(2) == {
        **dict.fromkeys(reports.BLAS_THREAD_VARIABLES, "2"), **reports.MALLOC_VARIABLES,
        "NUMPY_MADVISE_HUGEPAGE": "0"}
    monkeypatch.setenv("MALLOC_TRIM_THRESHOLD_", "0")
    assert "MALLOC_TRIM_THRESHOLD_" not in reports.kernel_environment(2)
    assert reports.kernel_environment(8)["OMP_NUM_THREADS"] == "1"
    assert reports.kernel_environment(1, cache=False)["NAVLIB_NO_CACHE"] == "1"
    monkeypatch.setenv("OMP_NUM_THREADS", "3")  # the user's own setting is kept
    assert "OMP_NUM_THREADS" not in reports.kernel_environment(2)


def test_progress_lines_stay_whole_when_notebooks_interleave(capsys):
    from navlib.__main__ import _ProgressPrinter

    def run(name, status, seconds=1.0):
        failure = reports.CellFailure(2, "KernelStalled", "idle") if status == "restarting" \
            else None
        return reports.NotebookRun(name, status, seconds, {}, failure=failure)

    printer = _ProgressPrinter()
    printer(1, 3, "00_a", None)
    printer(2, 3, "01_b", None)
    printer(2, 3, "01_b", run("01_b", "ok", 2.0))
    printer(3, 3, "02_c", None)
    printer(1, 3, "00_a", run("00_a", "restarting"))
    printer(1, 3, "00_a", run("00_a", "failed", 9.0))
    printer(3, 3, "02_c", run("02_c", "ok", 3.0))
    assert capsys.readouterr().err.splitlines() == [
        "[1/3] 00_a ... running",
        "[2/3] 01_b ... ok (2.0 s)",
        "[3/3] 02_c ... running",
        "[1/3] 00_a ... stalled at cell 2 (0-based): KernelStalled: idle; restarting the "
        "kernel and re-running 00_a ... failed (9.0 s)",
        "[3/3] 02_c ... ok (3.0 s)",
    ]


def test_jobs_option(good, tmp_path, capsys):
    from navlib.__main__ import _parser

    args = _parser().parse_args(["report"])
    assert args.jobs is None and args.no_cache is False  # None: the number of CPUs
    assert _parser().parse_args(["report", "--jobs", "3", "--no-cache"]).no_cache is True
    assert main(["report", "--notebooks", str(good[0]), "--output", str(tmp_path / "o"),
                 "--jobs", "0"]) == 2
    assert "jobs: expected a whole number >= 1, got 0" in capsys.readouterr().err
    proc = _cli("report", "--help", cwd=Path.cwd())
    assert "--jobs N" in proc.stdout and "--no-cache" in proc.stdout


def test_a_notebook_after_others_starts_when_they_have_finished(tmp_path, monkeypatch):
    """00 (metadata navlib.after: 01) reads what 01 wrote: with two workers it would
    otherwise start beside 01; 02, which it does not wait for, runs beside 01."""
    _no_warm_up(monkeypatch)
    nbdir = tmp_path / "notebooks"
    nbdir.mkdir()
    stamp = f"import pathlib, time\nstamps = pathlib.Path({str(tmp_path)!r})\n"
    _write(nbdir / "01_slow.ipynb", [("code", stamp + "time.sleep(3)\n"
                                      "(stamps / '01').write_text(str(time.time()))")])
    _write(nbdir / "02_fast.ipynb", [("code", stamp + "(stamps / '02').write_text("
                                      "str(time.time()))")])
    _write(nbdir / "00_summary.ipynb", [("code", stamp + "assert (stamps / '01').exists()\n"
                                         "(stamps / '00').write_text(str(time.time()))")])
    nb = nbformat.read(nbdir / "00_summary.ipynb", as_version=4)
    nb.metadata["navlib"] = {"after": ["01"]}
    nbformat.write(nb, nbdir / "00_summary.ipynb")
    infos = reports.list_notebooks(nbdir)
    assert [i.after for i in infos] == [("01",), (), ()]
    # no manifest: 01, which 00 waits for, first; 00 keeps its place before 02, and the
    # workers skip it until 01 has finished
    assert [i.name for i in runner.queue_order(infos, tmp_path / "out")] == [
        "01_slow", "00_summary", "02_fast"]
    runs = reports.run_reports(nbdir, tmp_path / "out", jobs=2)
    assert all(r.ok for r in runs)
    stamps = {n: float((tmp_path / n).read_text()) for n in ("00", "01", "02")}
    assert stamps["00"] >= stamps["01"] > stamps["02"]
    # without 01 in the run, 00 does not wait for it (and fails on its missing stamp)
    (tmp_path / "01").unlink()
    with pytest.raises(reports.ReportError):
        reports.run_reports(nbdir, tmp_path / "out", only=["00", "02"], jobs=2)


def test_bad_after_metadata_is_named(tmp_path):
    nbdir = tmp_path / "notebooks"
    nbdir.mkdir()
    _write(nbdir / "01_a.ipynb", [("code", "x = 1")])
    nb = nbformat.read(nbdir / "01_a.ipynb", as_version=4)
    nb.metadata["navlib"] = {"after": "02"}
    nbformat.write(nb, nbdir / "01_a.ipynb")
    with pytest.raises(NavlibInputError, match=r"navlib\.after"):
        reports.list_notebooks(nbdir)


def test_notebook_stack_loads_without_the_iri_grammars(tmp_path):
    # a fresh process: reading and validating a notebook imports neither rfc3987-syntax nor
    # lark (their grammars cost ~2 CPU-s per report process), and validation still works
    path = tmp_path / "01_a.ipynb"
    _write(path, [("code", "x = 1")])
    script = (
        "import sys\n"
        "from navlib.reports.discovery import notebook_format, read_notebook\n"
        f"nb = read_notebook({str(path)!r})\n"
        "notebook_format().validate(nb)\n"
        "import papermill, nbconvert\n"
        "print(sorted(m for m in ('lark', 'rfc3987_syntax') if sys.modules.get(m)))\n")
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "[]"


def test_the_shared_kernels_compile_beside_the_first_notebook(tmp_path, monkeypatch):
    """With two workers the head of the queue starts at once while the other worker warms
    the shared kernels up; the next notebook starts after the warm-up."""
    nbdir = tmp_path / "notebooks"
    nbdir.mkdir()
    stamp = f"import pathlib, time\nstamps = pathlib.Path({str(tmp_path)!r})\n"
    for name in ("01_head", "02_next"):
        _write(nbdir / f"{name}.ipynb", [("code", stamp + f"(stamps / {name[:2]!r})"
                                          ".write_text(str(time.time()))")])

    def warm_up(stopped):  # returns once the head notebook has run its cell
        deadline = time.time() + 120
        while not (tmp_path / "01").exists() and time.time() < deadline and not stopped():
            time.sleep(0.05)
        (tmp_path / "warm").write_text(str(time.time()))

    monkeypatch.setattr(runner, "_compile_shared_kernels", warm_up)
    runs = reports.run_reports(nbdir, tmp_path / "out", jobs=2)
    assert all(r.ok for r in runs)
    stamps = {n: float((tmp_path / n).read_text()) for n in ("01", "warm", "02")}
    assert stamps["01"] <= stamps["warm"] <= stamps["02"]
