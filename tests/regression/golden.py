"""Golden references and the tolerances they are compared at.

Every golden comparison of the suite reads its tolerance from ``tolerances.toml`` beside this
file, where each entry states the spread measured under changes that must not matter (BLAS
kernel, BLAS thread count, a 1-ulp perturbation of the inputs) and the change of the
algorithm it still catches; ``scripts/golden_spread.py`` measures both. Two kinds of
comparison:

* numbers: :func:`number_differences`, relative to a scale (the largest value of the group a
  number belongs to, so a component near zero is not held to a relative bound it cannot
  meet);
* text (claim texts, readings): :func:`text_differences` compares the words exactly and
  every number in them to the precision it is printed with (one unit in its last printed
  digit), so a rounding boundary crossed by round-off is not a difference.
"""

from __future__ import annotations

import functools
import math
import re
import tomllib
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
TOLERANCES = tomllib.loads((HERE / "tolerances.toml").read_text(encoding="utf-8"))
"""Golden name -> measured spread, tolerance and what it still catches."""


def tolerance(name: str) -> float:
    """The tolerance of golden ``name`` (``tolerances.toml``)."""
    return float(TOLERANCES[name]["tolerance"])


# --------------------------------------------------------------------------------------- EKF

EKF_COLUMNS = [f"{g}_{a}" for g in ("pos", "vel", "att") for a in "xyz"]
EKF_GROUPS = {"position": slice(0, 3), "velocity": slice(3, 6), "attitude": slice(6, 9),
              "nis": slice(9, 10)}
"""Final position, velocity and attitude errors and the mean NIS: each compared at its own
scale (the largest |value| of the group) and tolerance (``tolerances.toml``, ``[ekf.*]``)."""


def ekf_tolerances() -> dict[str, float]:
    """Group -> relative tolerance of the EKF snapshot."""
    return {group: float(TOLERANCES["ekf"][group]["tolerance"]) for group in EKF_GROUPS}

# Final navigation errors (pos_x..z m, vel_x..z m/s, att_x..z rad) and mean NIS of simulated
# EKF runs, captured from commit ef4a730 (the filter before it moved onto the error-state
# protocol and the measurement classes; 18 configurations were compared bitwise equal then).
# Change them only with a deliberate change of the filter, and say why.
EKF_SNAPSHOT = {
    "launcher att_rt GAP markov": (
        dict(solution="ins_gps_att_rt", biases="GAP", seed=1),
        [0.33751461684005335, -0.3914420516230166, -1.0047781458124518, -0.006258563293666697,
         0.014292199429000618, 0.03963316665723937, 7.897106524152112e-06,
         -1.1916385726865254e-05, -2.1955698218437876e-05],
        11.950605917859717),
    "launcher GAP random walk": (
        dict(solution="ins_gps", biases="GAP", bias_model="random_walk", seed=3),
        [1.1045498281018808, 1.6486936216242611, -0.42363415844738483, -0.006755900592467334,
         -0.014832405940900628, 0.015175560095912033, 0.000507023598344311,
         0.0002801552648661272, -0.001093950213218891],
        6.301066262914556),
    "launcher att_rt outliers": (
        dict(solution="ins_gps_att_rt", biases="GA", seed=7,
             outliers=[("gyro_x", 5.0, 0.01), ("att_y", 8.0, 0.05)]),
        [0.23915159975877032, -0.16458245972171426, -0.030917061492800713, 0.0491185291868641,
         0.031026861913431958, -0.006004382503007832, 1.785095805420134e-05,
         0.0001648583891582478, -0.0002684824966537055],
        12.290871536152348),
    "ecef21": (
        dict(model="ecef21", sensors="motionpak_tactical", seed=1,
             model_options={"sensors": "motionpak_tactical"}),
        [-0.04844780173152685, -0.46478814259171486, 0.8383820111630484,
         -0.015623651292116847, -0.03605669366334041, 0.046900878338249186,
         0.22401245040419232, -0.08953890954304045, -0.034688536752755614], 2.927279428381619),
    "ecef21 body attitude": (
        dict(model="ecef21", sensors="motionpak_tactical", seed=2,
             model_options={"sensors": "motionpak_tactical", "attitude_error": "body"}),
        [2.6929621398448944, -1.362143391277641, 0.8676653756992891, 0.1629895890894204,
         -0.07431464022488399, 0.011767158239052833, 0.0018196698200303775,
         -0.0010626856780364396, -0.0005840536425840392], 2.747767367785697),
    "ecef21 GNSS velocity": (
        dict(model="ecef21", sensors="motionpak_tactical", seed=3, gnss_velocity_sigma=0.2,
             model_options={"sensors": "motionpak_tactical"}),
        [0.49899641424417496, -0.33237233897671103, -0.7107805780833587, 0.05270739669435898,
         -0.008843363575465446, 0.003962551095497702, 0.0914776763211603,
         -0.03432303955514515, -0.014926301793450584], 4.060955823918659),
}
"""Case -> (``simulate_ekf`` keywords, final errors, mean NIS)."""


def ekf_trajectory(case: str):
    """The truth of an EKF snapshot case: the 86 s rocket or a 20 s, 20 Hz launcher ascent."""
    return _truth("rocket" if EKF_SNAPSHOT[case][0].get("model") == "ecef21" else "launcher")


@functools.cache
def _truth(kind: str):
    from navlib.trajectory import launcher_ascent, sounding_rocket

    return sounding_rocket() if kind == "rocket" else launcher_ascent(duration_s=20.0,
                                                                     rate_hz=20.0)


def ekf_values(case: str, trajectory, **changes) -> np.ndarray:
    """Final errors and mean NIS (10 numbers) of an EKF snapshot case; ``changes`` override
    its ``simulate_ekf`` keywords (to show that a real change is caught)."""
    from navlib import filters
    from navlib.sensors.faults import Outlier

    kw = dict(EKF_SNAPSHOT[case][0])
    kw["outliers"] = [Outlier(*o) for o in kw.get("outliers", [])] or None
    if kw.get("model") != "ecef21":
        kw["gnss_rate_hz"] = 20.0
    kw.update(changes)
    run = filters.simulate_ekf(trajectory, **kw)
    final = run.errors[EKF_COLUMNS].to_numpy()[-1]
    return np.append(final, np.mean(run.result.nis))


def ekf_reference(case: str) -> np.ndarray:
    _, final, nis = EKF_SNAPSHOT[case]
    return np.append(final, nis)


def grouped_spread(got, want) -> dict[str, float]:
    """Group -> largest ``|got - want|`` relative to the group's largest ``|want|``."""
    got, want = np.asarray(got, float), np.asarray(want, float)
    return {name: float(np.abs(got[g] - want[g]).max() / np.abs(want[g]).max())
            for name, g in EKF_GROUPS.items()}


def grouped_differences(got, want, rtol: dict[str, float]) -> list[str]:
    """Groups of ``got`` farther from ``want`` than their tolerance ``rtol[group]``
    (relative to the group's largest ``|want|``)."""
    return [f"{name}: {got[EKF_GROUPS[name]]} != {want[EKF_GROUPS[name]]} (relative "
            f"{value:.3g} > {rtol[name]:g})"
            for name, value in grouped_spread(got, want).items() if not value <= rtol[name]]


# ------------------------------------------------------------------------------------ text

_NUMBER = re.compile(r"(?<![\w.])[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?(?!\w|\.\d)")


def _last_digit_unit(token: str) -> float:
    """One unit in the last printed digit of a number as written (``0.5232`` -> 1e-4,
    ``2e-17`` -> 1e-17, ``1500`` -> 1)."""
    mantissa, _, exponent = token.lower().lstrip("+-").partition("e")
    decimals = len(mantissa.partition(".")[2])
    return 10.0 ** (int(exponent or 0) - decimals)


def split_numbers(text: str) -> tuple[list[str], list[str]]:
    """The words between the numbers of ``text`` and the numbers as written."""
    return _NUMBER.split(text), _NUMBER.findall(text)


def text_differences(got: str, want: str, units: float = 1.0) -> list[str]:
    """Differences between two printed texts: the words exactly, plain integers exactly, and
    each other number to ``units`` units in the last digit printed in ``want`` (1: a value
    that rounds either way at a boundary still matches; a change of two units does not)."""
    words_got, numbers_got = split_numbers(got)
    words_want, numbers_want = split_numbers(want)
    if words_got != words_want or len(numbers_got) != len(numbers_want):
        return [f"{got!r} != {want!r}"]
    out = []
    for a, b in zip(numbers_got, numbers_want, strict=True):
        x, y = float(a), float(b)
        if not (x == y or (_rounded(b) and
                           abs(x - y) <= units * _last_digit_unit(b) * (1 + 1e-9))):
            out.append(f"{a} != {b} in {want!r}")
    return out


def _rounded(token: str) -> bool:
    """A number printed with a decimal point or an exponent (a rounded float); a plain
    integer (a count, a rank) is compared exactly."""
    return any(c in token.lower() for c in ".e")


def text_spread(got: str, want: str) -> float:
    """Largest difference of the numbers of two texts with the same words, in units of the
    last digit printed in ``want`` (inf when the words differ)."""
    words_got, numbers_got = split_numbers(got)
    words_want, numbers_want = split_numbers(want)
    if words_got != words_want or len(numbers_got) != len(numbers_want):
        return math.inf
    return max((abs(float(a) - float(b)) / _last_digit_unit(b) if _rounded(b)
                else (0.0 if float(a) == float(b) else math.inf)
                for a, b in zip(numbers_got, numbers_want, strict=True)), default=0.0)


# ------------------------------------------------------------------------------ claim rows

def rows_differences(got: list[dict], want: list[dict], key: str, units: float = 1.0
                     ) -> list[str]:
    """Rows of two tables of printed strings, matched by ``key``: every field compared with
    :func:`text_differences` (a float field such as a robustness fraction is one number)."""
    ref = {r[key]: r for r in want}
    cur = {r[key]: r for r in got}
    out = [f"{k}: missing" for k in ref if k not in cur]
    out += [f"{k}: not in the reference" for k in cur if k not in ref]
    for k in sorted(ref.keys() & cur.keys()):
        for field, value in ref[k].items():
            out += [f"{k}.{field}: {d}" for d in
                    text_differences(str(cur[k][field]), str(value), units)]
    return out


def rows_spread(got: list[dict], want: list[dict], key: str) -> float:
    """Largest :func:`text_spread` over the fields of rows matched by ``key``."""
    ref = {r[key]: r for r in want}
    cur = {r[key]: r for r in got}
    if ref.keys() != cur.keys():
        return math.inf
    return max((text_spread(str(cur[k][f]), str(v)) for k in ref for f, v in ref[k].items()),
               default=0.0)
