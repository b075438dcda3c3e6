"""JupyterLab in headless Chromium: the harness of the browser tests and of
``benchmarks/bench_browser.py``.

* :func:`quick_copies` writes the notebooks with ``quick = True`` injected (papermill's
  ``parameterize_notebook``) into a temporary folder beside a link to ``data/``;
* :class:`LabServer` starts ``jupyter lab`` on 127.0.0.1 with a free port and a token,
  with fresh config, settings, workspace and runtime folders (JupyterLab's default
  settings: kernel comms over subshells on), and stops it by its PID;
* :func:`launch_chromium` starts Debian's ``chromium`` through Playwright
  (``executable_path``; Playwright's own browser download is not used) with a fresh
  profile;
* :class:`NotebookPage` opens a notebook, runs all cells, finds the navlib panels and moves
  their controls by keyboard and by mouse, measuring each move in the page: from the
  release (``pointerup``, ``keydown`` or ``change``) to the ``load`` of each new image.

A move is judged on the panel's images, read back in the page from a canvas: "ink" is the
fraction of dark grey pixels (text, tick labels, axes: what a blank or partly drawn figure
lacks, and what data changes barely move; coloured bars and curves are not counted),
``hash`` a checksum of all pixels.
"""

from __future__ import annotations

import contextlib
import json
import os
import secrets
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
CHROMIUM = os.environ.get("NAVLIB_CHROMIUM", "/usr/bin/chromium")
CHROMIUM_ARGS = ["--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                 "--disable-background-networking", "--disable-component-update",
                 "--disable-sync", "--no-first-run", "--no-default-browser-check",
                 "--disable-extensions", "--mute-audio"]
PANEL_NOTEBOOKS = ("01_trajectory_synthesis", "02_observability_matrix", "03_excitability",
                   "04_sensability", "05_outlier_sensitivity", "06_stationary_alignment",
                   "07_assess_flight", "08_design_study", "09_plan_mission")
"""The notebooks that show a navlib panel (each is opened, run and moved)."""
MOVES: list = []
"""Every move of the test session (:class:`Move`), for the latency table."""
WIDGET_ERRORS = ("Error displaying widget", "model not found", "Model not found",
                 "Traceback (most recent call last)")

INSTRUMENT_JS = """
(() => {
  if (window.__navlib) return;
  const state = {release: 0, loads: []};
  window.__navlib = state;
  for (const type of ["pointerup", "keydown", "change"]) {
    document.addEventListener(type, () => { state.release = performance.now(); }, true);
  }
  document.addEventListener("load", (event) => {
    if (event.target instanceof HTMLImageElement) {
      state.loads.push({t: performance.now(), img: event.target});
    }
  }, true);
})();
"""

PANEL_JS = """
([index, since]) => {
  const panel = document.querySelectorAll(".navlib-panel")[index];
  if (!panel) return null;
  const mark = panel.querySelector(".navlib-status .navlib-update");
  const status = panel.querySelector(".navlib-status");
  const images = [...panel.querySelectorAll(".navlib-view img")].map((img) => {
    const name = [...img.classList].find((c) => c.startsWith("navlib-part-")) || "?";
    const visible = img.offsetParent !== null && getComputedStyle(img).display !== "none";
    const out = {name: name.slice(12), visible, complete: img.complete,
                 w: img.naturalWidth, h: img.naturalHeight, src: img.src};
    if (!visible || !img.complete || !img.naturalWidth) return out;
    const canvas = document.createElement("canvas");
    canvas.width = img.naturalWidth; canvas.height = img.naturalHeight;
    const ctx = canvas.getContext("2d");
    ctx.drawImage(img, 0, 0);
    const d = ctx.getImageData(0, 0, canvas.width, canvas.height).data;
    let ink = 0, hash = 0;
    for (let k = 0; k < d.length; k += 4) {
      const r = d[k], g = d[k + 1], b = d[k + 2];
      if (Math.max(r, g, b) - Math.min(r, g, b) < 24 && r + g + b < 420) ink++;
      hash = (Math.imul(hash, 31) + d[k] + 7 * d[k + 1] + 13 * d[k + 2]) | 0;
    }
    out.ink = ink / (canvas.width * canvas.height);
    out.hash = hash;
    return out;
  });
  const state = window.__navlib;
  const loads = state.loads.filter((l) => l.t > since && panel.contains(l.img))
                           .map((l) => l.t);
  return {
    count: mark ? Number(mark.dataset.count) : 0,
    kernel_ms: mark && mark.dataset.ms ? Number(mark.dataset.ms) : null,
    status: status ? status.textContent : "",
    refused: !!(status && status.querySelector("b[style*='color']")),
    error: !!panel.querySelector(".navlib-panel-error"),
    manual: panel.classList.contains("navlib-panel-manual"),
    images, loads, release: state.release, now: performance.now(),
  };
}
"""

CONTROLS_JS = """
(index) => {
  const panel = document.querySelectorAll(".navlib-panel")[index];
  const out = [];
  panel.querySelectorAll(".navlib-controls > .widget-inline-hbox, .navlib-controls > *")
    .forEach((el, k) => {
      const label = el.querySelector(".widget-label");
      const description = label ? label.textContent.trim() : "";
      let kind = null;
      if (el.querySelector(".noUi-handle")) kind = "slider";
      else if (el.querySelector("select[multiple]")) kind = "multiselect";
      else if (el.querySelector("select")) kind = "dropdown";
      else if (el.querySelector("input")) kind = "text";
      else if (el.matches("button") || el.querySelector("button")) kind = "button";
      if (kind) out.push({k, kind, description,
                          handles: el.querySelectorAll(".noUi-handle").length});
    });
  return out;
}
"""


def free_port() -> int:
    """A TCP port free on 127.0.0.1 now."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def quick_copies(root: Path, names=PANEL_NOTEBOOKS) -> list[Path]:
    """Copies of ``notebooks/<name>.ipynb`` under ``root/notebooks`` with ``quick = True``
    injected after the parameters cell; ``root/data`` links to the checkout's data."""
    import nbformat
    from papermill.iorw import load_notebook_node
    from papermill.parameterize import parameterize_notebook

    (root / "notebooks").mkdir(parents=True, exist_ok=True)
    data = root / "data"
    if not data.exists():
        data.symlink_to(REPO / "data", target_is_directory=True)
    paths = []
    for name in names:
        nb = load_notebook_node(str(REPO / "notebooks" / f"{name}.ipynb"))
        nb = parameterize_notebook(nb, {"quick": True})
        nb.metadata["kernelspec"] = {"name": "python3", "language": "python",
                                     "display_name": "Python 3 (ipykernel)"}
        path = root / "notebooks" / f"{name}.ipynb"
        nbformat.write(nb, path)
        paths.append(path)
    return paths


class LabServer:
    """``jupyter lab`` on 127.0.0.1 serving ``root``; :meth:`stop` ends it by its PID."""

    def __init__(self, root: Path, python: str = sys.executable):
        self.root = Path(root)
        self.python = python
        self.port = free_port()
        self.token = secrets.token_hex(16)
        self.process: subprocess.Popen | None = None
        self.log_path = self.root / "jupyterlab.log"

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.port}"

    def start(self, timeout_s: float = 180.0) -> LabServer:
        home = self.root / ".lab"
        env = {**os.environ,
               "JUPYTER_CONFIG_DIR": str(home / "config"),
               "JUPYTERLAB_SETTINGS_DIR": str(home / "settings"),
               "JUPYTERLAB_WORKSPACES_DIR": str(home / "workspaces"),
               "JUPYTER_RUNTIME_DIR": str(home / "runtime"),
               "IPYTHONDIR": str(home / "ipython"),
               "MPLBACKEND": "module://matplotlib_inline.backend_inline",
               "PYDEVD_DISABLE_FILE_VALIDATION": "1",
               # the kernels cache builders on disk as a user's do, in a folder of their
               # own that starts empty (the test suite's NAVLIB_NO_CACHE isolates its tests)
               "NAVLIB_CACHE_DIR": str(home / "navlib-cache")}
        env.pop("NAVLIB_NO_CACHE", None)
        cmd = [self.python, "-m", "jupyter", "lab", "--no-browser",
               "--ServerApp.ip=127.0.0.1", f"--ServerApp.port={self.port}",
               "--ServerApp.port_retries=0", f"--IdentityProvider.token={self.token}",
               f"--ServerApp.root_dir={self.root}", "--LabApp.news_url=None",
               "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate",
               "--LabApp.extension_manager=readonly",
               "--LabApp.expose_app_in_browser=True"]  # window.jupyterapp, as galata does
        if os.geteuid() == 0:  # CI runs as root
            cmd.append("--allow-root")
        log = self.log_path.open("w")
        self.process = subprocess.Popen(cmd, cwd=self.root, env=env, stdout=log,
                                        stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                        start_new_session=True)
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                raise RuntimeError(f"jupyter lab exited ({self.process.returncode}); log:\n"
                                   + self.log_path.read_text()[-3000:])
            with contextlib.suppress(OSError):
                with urllib.request.urlopen(f"{self.url}/api/status?token={self.token}",
                                            timeout=2) as reply:
                    json.load(reply)
                    return self
            time.sleep(0.5)
        self.stop()
        raise RuntimeError(f"jupyter lab did not answer within {timeout_s:g} s")

    def stop(self, timeout_s: float = 30.0) -> None:
        """SIGTERM to the server's PID (it shuts its kernels down), SIGKILL to its process
        group if it is still there after ``timeout_s``."""
        if self.process is None or self.process.poll() is not None:
            return
        pid = self.process.pid
        os.kill(pid, signal.SIGTERM)
        try:
            self.process.wait(timeout_s)
        except subprocess.TimeoutExpired:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(pid, signal.SIGKILL)  # the group start_new_session made for it
            self.process.wait(10)

    def shutdown_kernels(self) -> int:
        """Shut down every running kernel (REST API), as a user who closes a notebook and
        its kernel before opening the next: a kernel left behind (Dask workers, threads)
        would share the cores the next notebook's moves are timed on. Returns how many."""
        headers = {"Authorization": f"token {self.token}"}
        request = urllib.request.Request(f"{self.url}/api/kernels", headers=headers)
        with urllib.request.urlopen(request, timeout=10) as reply:
            kernels = json.load(reply)
        for kernel in kernels:
            request = urllib.request.Request(f"{self.url}/api/kernels/{kernel['id']}",
                                             headers=headers, method="DELETE")
            with contextlib.suppress(OSError), urllib.request.urlopen(request, timeout=30):
                pass
        return len(kernels)

    def notebook_url(self, name: str) -> str:
        return f"{self.url}/lab/tree/notebooks/{name}.ipynb?token={self.token}&reset"


def launch_chromium(playwright, profile: Path):
    """Debian's chromium (``CHROMIUM``) with a fresh profile, headless."""
    if not Path(CHROMIUM).exists():
        raise RuntimeError(f"{CHROMIUM} not found: `make test-browser` installs Debian's "
                           "chromium with apt-get (as root), or set NAVLIB_CHROMIUM")
    return playwright.chromium.launch_persistent_context(
        str(profile), executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS,
        viewport={"width": 1400, "height": 1000})


@dataclass
class Move:
    """One control move and what the page showed after it."""

    notebook: str
    panel: int
    control: str
    how: str
    outcome: str = ""          # "changed", "refused" or a failure text
    first_ms: float | None = None
    all_ms: float | None = None
    kernel_ms: float | None = None   # the panel's own update time (status mark data-ms)

    def failed(self) -> bool:
        return self.outcome not in ("changed", "refused")


@dataclass
class NotebookPage:
    """One notebook open in JupyterLab, run and driven through Playwright."""

    page: object
    name: str
    console_errors: list = field(default_factory=list)
    _typed: dict = field(default_factory=dict)

    @classmethod
    def open(cls, context, server: LabServer, name: str) -> NotebookPage:
        page = context.new_page()
        page.add_init_script(INSTRUMENT_JS)
        self = cls(page, name)
        page.on("console", lambda msg: msg.type == "error" and self.console_errors.append(
            f"console: {msg.text}"))
        page.on("pageerror", lambda exc: self.console_errors.append(f"page error: {exc}"))
        page.goto(server.notebook_url(name), wait_until="domcontentloaded")
        page.wait_for_selector(".jp-Notebook .jp-Cell", timeout=120_000)
        self.dismiss_dialogs()
        self.wait_kernel_idle(180_000)
        return self

    def dismiss_dialogs(self, wait_ms: float = 3000) -> None:
        """Accept the kernel dialog (the notebook's own kernel, preselected) and decline
        the news notification, as a new user would."""
        accept = self.page.locator(".jp-Dialog .jp-mod-accept")
        with contextlib.suppress(Exception):
            accept.wait_for(timeout=wait_ms)
            accept.click()
        news = self.page.locator(".jp-toast-button:text-is('No')")
        if news.count():
            news.first.click()

    def wait_kernel_idle(self, timeout_ms: float) -> None:
        self.page.wait_for_function(
            """() => { const el = document.querySelector(
                   ".jp-NotebookPanel:not(.lm-mod-hidden) .jp-Notebook-ExecutionIndicator");
                 return el && el.getAttribute("data-status") === "idle"; }""",
            timeout=timeout_ms)

    def run_all(self, timeout_ms: float = 1_800_000) -> float:
        """Run > Run All Cells; wait until every code cell has an execution count and the
        kernel is idle (read from the notebook model: with JupyterLab's windowed notebook,
        cells out of view are not all in the DOM). Returns the seconds it took."""
        start = time.perf_counter()
        page = self.page
        page.click(".lm-MenuBar-itemLabel:text-is('Run')")
        page.click(".lm-Menu-itemLabel:text-is('Run All Cells')")
        page.wait_for_function(
            """() => { const panel = window.jupyterapp.shell.currentWidget;
                 const cells = [...panel.content.model.cells].filter((c) => c.type === "code");
                 const kernel = panel.sessionContext.session?.kernel;
                 const errors = cells.some((c) => c.outputs.toJSON().some(
                     (o) => o.output_type === "error"));
                 return errors || (kernel && kernel.status === "idle" &&
                        cells.every((c) => c.executionCount !== null)); }""",
            timeout=timeout_ms, polling=1000)
        return time.perf_counter() - start

    def cell_errors(self) -> list[str]:
        """``ename: evalue`` of every error output in the notebook model."""
        return self.page.evaluate(
            """() => [...window.jupyterapp.shell.currentWidget.content.model.cells]
                 .flatMap((c) => c.type === "code" ? c.outputs.toJSON() : [])
                 .filter((o) => o.output_type === "error")
                 .map((o) => `${o.ename}: ${o.evalue}`)""")

    def scroll_to_widgets(self) -> int:
        """Scroll to the first cell with a widget output; returns how many cells have one."""
        cells = self.page.evaluate(
            """() => [...window.jupyterapp.shell.currentWidget.content.model.cells]
                 .map((c, i) => [i, c.type === "code" && c.outputs.toJSON().some(
                     (o) => o.data && "application/vnd.jupyter.widget-view+json" in o.data)])
                 .filter(([, w]) => w).map(([i]) => i)""")
        if cells:
            self.page.evaluate(
                """(i) => { const nb = window.jupyterapp.shell.currentWidget.content;
                     nb.activeCellIndex = i;
                     return nb.scrollToItem(i, "start"); }""", cells[0])
            self.page.wait_for_selector(".navlib-panel .navlib-view img", timeout=60_000)
        return len(cells)

    def page_errors(self) -> list[str]:
        """Widget errors and tracebacks shown in the notebook, and error outputs."""
        text = self.page.evaluate(
            "() => document.querySelector('.jp-NotebookPanel:not(.lm-mod-hidden) "
            ".jp-Notebook').textContent")
        return [e for e in WIDGET_ERRORS if e in text] + self.cell_errors()

    def panel_count(self) -> int:
        return self.page.evaluate("document.querySelectorAll('.navlib-panel').length")

    def panel_state(self, index: int, since: float = 0.0) -> dict:
        return self.page.evaluate(PANEL_JS, [index, since])

    def controls(self, index: int) -> list[dict]:
        return self.page.evaluate(CONTROLS_JS, index)

    def control_element(self, index: int, k: int):
        return self.page.locator(".navlib-panel").nth(index).locator(
            ".navlib-controls > *").nth(k)

    # -- moves ---------------------------------------------------------------------------
    def _act(self, index: int, control: dict, how: str, step: int = 1,
             undo: bool = False) -> str:
        """Perform one move; returns a description, or "" when the control cannot move
        (disabled). ``undo``: the opposite keyboard move (sliders), the text typed before
        the last nudge (text boxes)."""
        el = self.control_element(index, control["k"])
        el.scroll_into_view_if_needed()
        kind = control["kind"]
        if kind == "button":
            el.click()  # the Button widget's element is the <button> itself
            return "click"
        if kind == "slider":
            handle = el.locator(".noUi-handle").last if how == "keyboard" else \
                el.locator(".noUi-handle").first
            if el.locator("[disabled]").count():
                return ""
            now, high = (float(handle.get_attribute(a) or 0) for a in
                         ("aria-valuenow", "aria-valuemax"))
            if how == "keyboard":
                handle.focus()
                key = "ArrowRight" if now < high and not undo else "ArrowLeft"
                for _ in range(step):
                    self.page.keyboard.press(key)
                return f"{key} x{step}"
            box = handle.bounding_box()
            track = el.locator(".noUi-target").bounding_box()
            dx = 0.08 * track["width"] * step
            x0, y0 = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
            if x0 + dx > track["x"] + track["width"] - 2:
                dx = -dx
            self.page.mouse.move(x0, y0)
            self.page.mouse.down()
            for i in range(1, 6):
                self.page.mouse.move(x0 + dx * i / 5, y0)
            self.page.mouse.up()
            return f"drag {dx:+.0f} px"
        if kind in ("dropdown", "multiselect"):
            select = el.locator("select")
            if select.is_disabled():
                return ""
            options = select.locator("option").all_inner_texts()
            current = select.evaluate("s => s.selectedIndex")
            if how == "keyboard":
                # not possible in JupyterLab 4.6: with the focus on a widget's <select>,
                # the notebook's command-mode shortcuts (arrows, letters, Enter, Space)
                # take the key and prevent its default, so neither the value nor the
                # pop-up list moves, and a letter would edit the notebook ("a" inserts a
                # cell). Drop-downs are moved by mouse only.
                return ""
            target = (current + 2) % len(options) if len(options) > 2 else \
                (current + 1) % len(options)
            if kind == "multiselect":
                select.locator("option").nth(target).click()
            else:
                select.select_option(index=target)
            return f"choose {options[target]!r}"
        if kind == "text":
            box = el.locator("input")
            if box.is_disabled() or how != "keyboard":
                return ""
            value = box.input_value()
            key = (index, control["k"])
            text = self._typed.pop(key) if undo and key in self._typed else \
                nudge_numbers(value)
            self._typed[key] = value
            box.click()
            self.page.keyboard.press("Control+A")
            self.page.keyboard.type(text)
            self.page.keyboard.press("Enter")
            return f"type {text!r}"
        return ""

    def move(self, index: int, control: dict, how: str, *, first: dict | None = None,
             timeout_ms: float = 180_000, step: int = 1, undo: bool = False) -> Move | None:
        """Move one control and wait for the panel's update; None if it cannot move."""
        before = self.panel_state(index)
        since = before["now"]
        action = self._act(index, control, how, step, undo)
        if not action:
            return None
        move = Move(self.name, index, control["description"], f"{how}: {action}")
        try:
            self.page.wait_for_function(
                """([i, c]) => { const p = document.querySelectorAll(".navlib-panel")[i];
                     const m = p.querySelector(".navlib-status .navlib-update");
                     return m && Number(m.dataset.count) > c; }""",
                arg=[index, before["count"]], timeout=timeout_ms, polling=20)
        except Exception:  # a move without an update is a failed move
            move.outcome = "no update of the panel"
            return move
        self.page.wait_for_function(
            """(i) => [...document.querySelectorAll(".navlib-panel")[i]
                       .querySelectorAll(".navlib-view img")].every((img) => img.complete)""",
            arg=index, timeout=30_000)
        self.page.wait_for_timeout(150)
        after = self.panel_state(index, since)
        move.outcome = judge(before, after, first)
        release = after["release"]
        loads = [t - release for t in after["loads"] if t > release]
        if loads:
            move.first_ms, move.all_ms = min(loads), max(loads)
        move.kernel_ms = after["kernel_ms"]
        return move


def nudge_numbers(text: str) -> str:
    """The text with its last number multiplied by 0.9 (``"18, 45.7"`` -> ``"18, 41.13"``)."""
    parts = [p.strip() for p in text.replace(";", ",").split(",")]
    try:
        parts[-1] = f"{0.9 * float(parts[-1]):.6g}"
    except ValueError:
        return text
    return ", ".join(parts)


def judge(before: dict, after: dict, first: dict | None = None,
          min_ink_ratio: float = 0.6) -> str:
    """"changed", "refused", or what is wrong with the panel after a move.

    Every visible image must be complete and carry at least ``min_ink_ratio`` of the ink
    (a fraction of its area) it had at the first render (``first``, a panel state;
    else ``before``): a blank or partly drawn figure has far less. At least one image must
    differ from before, unless the panel refused the input (its status shows the refusal
    and the last good figures stay).
    """
    reference = {img["name"]: img for img in (first or before)["images"]
                 if "ink" in img}
    if after["error"]:
        return f"panel error: {after['status']}"
    old = {img["name"]: img for img in before["images"] if img.get("visible")}
    changed = False
    for img in after["images"]:
        if not img["visible"]:
            continue
        if not img["complete"] or not img["w"]:
            return f"image {img['name']} not drawn"
        prev = old.get(img["name"])
        if prev is None or "hash" not in prev:
            changed = True
            continue
        ref = reference.get(img["name"], prev)
        if img["ink"] < min_ink_ratio * ref["ink"]:
            return (f"image {img['name']} blank or partly drawn: ink {img['ink']:.4f}, "
                    f"{ref['ink']:.4f} at the first render")
        changed |= img["hash"] != prev["hash"]
    if after["refused"]:
        return "refused"
    return "changed" if changed else "figures unchanged"


THRESHOLD_CONTROLS = ("η", "ν", "rtol", "e ≥", "s ≥")
"""Controls that only move a threshold over computed numbers (eta, nu, the rank tolerance,
the e and s thresholds of the plan)."""
LATENCY_GOALS_MS = {"threshold": 100.0, "control": 300.0}
"""Goals of issue 37 (first set for some controls by issues 13 and 26): every control of
every panel redraws in under 300 ms in the browser, a threshold in under 100 ms."""


def goal_of(control: str) -> float:
    kind = "threshold" if any(key in control for key in THRESHOLD_CONTROLS) else "control"
    return LATENCY_GOALS_MS[kind]


def latency_table(moves) -> str:
    """Median and max of first-image and all-images latency per notebook and control, and
    the median of the panel's own update time in the kernel (``kernel``: compute, figures,
    PNG encoding; the rest of the latency is the message to the page and the image load),
    beside its goal (:func:`goal_of`); ``over`` marks a control whose slowest image came
    later than its goal."""
    import numpy as np

    groups: dict = {}
    for m in moves:
        if m.first_ms is not None and m.outcome == "changed":
            groups.setdefault((m.notebook[:2], m.control, m.how.split(":")[0]), []).append(m)
    load = os.getloadavg()
    lines = [f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} on {os.cpu_count()} "
             f"cores",
             f"{'nb':<3} {'control':<18} {'how':<9} {'n':>3} {'first med':>10} "
             f"{'first max':>10} {'all med':>8} {'all max':>8} {'kernel':>7} {'goal':>6}"]
    for (nb, control, how), ms in sorted(groups.items()):
        first = np.array([m.first_ms for m in ms])
        every = np.array([m.all_ms for m in ms])
        kernel = [m.kernel_ms for m in ms if m.kernel_ms is not None]
        goal = goal_of(control)
        lines.append(f"{nb:<3} {control[:18]:<18} {how:<9} {len(ms):>3} "
                     f"{np.median(first):>10.0f} {first.max():>10.0f} "
                     f"{np.median(every):>8.0f} {every.max():>8.0f} "
                     f"{f'{np.median(kernel):.0f}' if kernel else '':>7} "
                     f"{goal:>6.0f}{'  over' if every.max() > goal else ''}")
    return "\n".join(lines)
