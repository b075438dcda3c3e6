"""The four outlier tests T1-T4 of Beaudoin et al. (2018) §4.2 with the paper's values
(docs/assumptions.md, launcher.md §5, §6.4)."""

from __future__ import annotations

from dataclasses import dataclass

from navlib.sensors.faults import Outlier

__all__ = ["PAPER_TESTS", "PaperTest"]

@dataclass(frozen=True)
class PaperTest:
    """One outlier test of Beaudoin et al. (2018) §4.2 (docs/assumptions.md, launcher.md §6.4).

    Attributes
    ----------
    test_id : str
        ``"T1"`` .. ``"T4"``.
    figure : str
        The paper's figure(s).
    solutions : tuple of str
        The navigation solutions compared.
    channel : str
    magnitude : float
        SI value (3 m/s, 0.002 rad/s, 0.002 rad).
    watch : str
        ``"bp"`` (GPS position bias, 3 ECEF components), ``"roll"`` (body-x attitude error)
        or ``"ref_roll"`` (launcher divergence, roll).
    reported : dict
        Solution -> outcome the paper reports (``"static error"``, ``"recovers"``,
        ``"affected"``/``"unaffected"``).
    description : str
    """

    test_id: str
    figure: str
    solutions: tuple[str, ...]
    channel: str
    magnitude: float
    watch: str
    reported: dict
    description: str
    time: float = 50.0

    def outlier(self, shape: str = "spike", time: float | None = None,
                magnitude: float | None = None, duration: float | None = None) -> Outlier:
        """The test's outlier with the paper's values unless overridden."""
        return Outlier(self.channel, self.time if time is None else time,
                       self.magnitude if magnitude is None else magnitude, shape, duration)


PAPER_TESTS = {
    "T1": PaperTest(
        "T1", "Fig. 4", ("ins_gps_att",), "gnss_vel", 3.0, "bp",
        {"ins_gps_att": "static error"},
        "+3 m/s on the three GPS velocity components at 50 s; GPS position bias (Markov) "
        "well estimated before, a static error remains afterwards"),
    "T2": PaperTest(
        "T2", "Fig. 8", ("ins_gps", "ins_gps_rt"), "gyro_x", 0.002, "roll",
        {"ins_gps": "static error", "ins_gps_rt": "static error"},
        "0.002 rad/s on the roll gyro at 50 s; both INS/GPS and INS/GPS + RT keep a static "
        "roll error"),
    "T3": PaperTest(
        "T3", "Fig. 9", ("ins_gps", "ins_gps_rt"), "rt_x", 0.002, "roll",
        {"ins_gps": "unaffected", "ins_gps_rt": "affected"},
        "0.002 on the roll of the reference trajectory at 50 s; only the RT solution is "
        "affected"),
    "T4": PaperTest(
        "T4", "Figs. 12-13", ("ins_gps_att", "ins_gps_att_rt"), "gyro_x", 0.002, "roll",
        {"ins_gps_att": "recovers", "ins_gps_att_rt": "recovers"},
        "0.002 rad/s on the roll gyro at 50 s with attitude sensors; both correct the roll "
        "error within the same time range (RT: faster capture, slower correction, "
        "divergence underestimated)"),
}
"""The four outlier tests T1-T4 with the paper's magnitudes (docs/assumptions.md,
launcher.md §5, §6.4)."""
