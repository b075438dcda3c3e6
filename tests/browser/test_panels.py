"""Every navlib panel of notebooks 01-08, in JupyterLab (default settings: kernel comms over
subshells) in headless Chromium: Run All in quick mode, then each slider, dropdown and
text box moved by keyboard and by mouse (issue 13).

A move passes when the panel's figures change (or the panel shows the refusal of an
invalid input and keeps its figures) and no figure is blank or partly drawn against the
first render; the page must show no widget error and the browser console
no error. The moves' latencies (release -> new image) are collected for the table printed
at the end of the session (``conftest.pytest_terminal_summary``).
"""

from __future__ import annotations

import pytest
from labharness import MOVES, PANEL_NOTEBOOKS, NotebookPage

pytestmark = pytest.mark.browser

LATENCY_MOVES = {
    "03_excitability": ("η", "τ2 [s]"),
    "04_sensability": ("ν",),
    "07_assess_flight": ("η (excitability)", "ν (sensability)", "boundaries [s]"),
}
"""Controls moved ten more times (keyboard) for the latency table."""
REPEATS = 10


def _check_first_render(state: dict) -> list[str]:
    shown = [img for img in state["images"] if img["visible"]]
    if not shown:
        return ["no figure shown"]
    return [f"{img['name']} not drawn" for img in shown if not img.get("ink")]


@pytest.mark.parametrize("name", PANEL_NOTEBOOKS)
def test_panels_move_in_jupyterlab(lab, browser, name):
    nb = NotebookPage.open(browser, lab, name)
    try:
        seconds = nb.run_all()
        assert nb.page_errors() == [], f"{name}: errors on the page after Run All"
        assert nb.scroll_to_widgets() >= 1, f"{name}: no widget output"
        print(f"\n{name}: Run All in {seconds:.0f} s")
        count = nb.panel_count()
        assert count >= 1, f"{name}: no navlib panel on the page"
        failures: list[str] = []
        for index in range(count):
            first = nb.panel_state(index)
            controls = nb.controls(index)
            if first["manual"]:
                failures += _move_manual_panel(nb, index, controls)
                continue
            failures += [f"panel {index}: {p}" for p in _check_first_render(first)]
            for control in controls:
                outcomes = []
                for how in ("keyboard", "mouse"):
                    move = nb.move(index, control, how, first=first)
                    if move is None:
                        continue
                    MOVES.append(move)
                    outcomes.append(move.outcome)
                    if move.failed():
                        failures.append(f"panel {index} {control['description']!r} "
                                        f"{move.how}: {move.outcome}")
                if outcomes and "changed" not in outcomes and not any(
                        o not in ("changed", "refused") for o in outcomes):
                    failures.append(f"panel {index} {control['description']!r}: every move "
                                    f"was refused, no figure change seen")
            for control in controls:
                if control["description"] in LATENCY_MOVES.get(name, ()):
                    failures += _repeat_moves(nb, index, control, first)
        assert not failures, f"{name}:\n" + "\n".join(failures)
        assert nb.page_errors() == [], f"{name}: errors on the page after the moves"
        assert nb.console_errors == [], f"{name}: browser console errors"
    finally:
        nb.page.close()
        lab.shutdown_kernels()


def _move_manual_panel(nb: NotebookPage, index: int, controls: list) -> list[str]:
    """A panel that computes on a button (the Monte Carlo run): move each slider (by
    keyboard, then by mouse) and press the button after each move; the figure must
    appear, then change."""
    failures = []
    button = next(c for c in controls if c["kind"] == "button")
    for control in [c for c in controls if c["kind"] == "slider"]:
        for how in ("keyboard", "mouse"):
            nb._act(index, control, how)
            move = nb.move(index, button, "mouse")
            move.control = f"{control['description']} + run"
            MOVES.append(move)
            if move.failed():
                failures.append(f"panel {index} (button after moving "
                                f"{control['description']!r} by {how}): {move.outcome}")
    return failures


def _repeat_moves(nb: NotebookPage, index: int, control: dict, first: dict) -> list[str]:
    failures = []
    for k in range(REPEATS):
        move = nb.move(index, control, "keyboard", first=first, undo=k % 2 == 1)
        MOVES.append(move)
        if move.failed():
            failures.append(f"panel {index} {control['description']!r} repeat {k}: "
                            f"{move.outcome}")
    return failures
