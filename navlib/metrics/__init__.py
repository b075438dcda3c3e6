"""Excitability and sensability of navigation states (España, Carrizo & Giribet 2019).

Both metrics take plain arrays in physical units (docs/library.md), so any
model can feed them, and both work in the normalised coordinates of the corrected Eq. 11
(docs/assumptions.md A10)::

    D0 = diag(diag(P0)),   F~ = D0^-1/2 F D0^1/2,   H~ = R0^-1/2 H D0^1/2,
    P~ = D0^-1/2 P D0^-1/2,   Q~ = D0^-1/2 Q D0^-1/2,   I~ = P~^-1 = D0^1/2 I D0^1/2.

* :func:`excitability` (Eqs. 17-22, Defs. 3-4): SVD of the normalised extended observability
  matrix ``O~ = [H~0; H~1 F~0; ...]``; the energy spectrum ``S(u^i) = n sigma^i / tr M``;
  ``ne`` from ``eta`` (A14); ``e^j`` = norm of the projection of the canonical vector ``e_j``
  on the excited subspace ``span{u^i : i < ne}``.
* :func:`sensability` (Eqs. 10, 12-16, Defs. 1-2): the Kalman information recursion, the
  eigen-decomposition of ``I~_k`` at every epoch, ``r^i_k`` (Eq. 15), ``nr_k`` from ``nu``
  and ``s^j_k`` = norm of the projection of ``e_j`` on the practically sensible subspace.

Helpers: :func:`nu_for` / :func:`nu_range` (docs/assumptions.md A11), model wrappers
:func:`excitability_segment` / :func:`excitability_segments` (segments, D0 choice of A19) and
:func:`sensability_model`, and :func:`physical_bands` (the k-sigma bands of Figs. 3-5).

:class:`SegmentedAnalysis` is the paper's whole analysis of one discretised model (§4-6):
excitability per segment, sensability per epoch, the thresholds that read them (eta, nu and
the shares :data:`E_THRESHOLD`, :data:`S_THRESHOLD`, :data:`MIN_FRACTION`), tidy frame views
and :meth:`SegmentedAnalysis.with_settings`, which re-reads other segments or thresholds on
the same model. The rocket study (:class:`navlib.studies.rocket.RocketAnalysis`) and the
flight assessment (:class:`navlib.studies.assess.FlightAssessment`) are thin subclasses.

Modules: :mod:`~navlib.metrics.excitation`, :mod:`~navlib.metrics.sensing` (the two
metrics on plain arrays), :mod:`~navlib.metrics.segments` (model wrappers, segments and
thresholds) and :mod:`~navlib.metrics.segmented` (:class:`SegmentedAnalysis`); every public
name is re-exported here.
"""

from navlib.metrics._arrays import D0_CHOICES
from navlib.metrics.excitation import ExcitabilityResult, excitability
from navlib.metrics.segmented import SegmentedAnalysis
from navlib.metrics.segments import (
    E_THRESHOLD,
    LOW,
    MIN_FRACTION,
    S_THRESHOLD,
    THRESHOLD_KEYS,
    check_segments,
    check_thresholds,
    excitability_segment,
    excitability_segments,
    in_segment,
    sensability_model,
)
from navlib.metrics.sensing import (
    SensabilityResult,
    nu_for,
    nu_range,
    physical_bands,
    sensability,
)

__all__ = [
    "D0_CHOICES",
    "E_THRESHOLD",
    "LOW",
    "MIN_FRACTION",
    "S_THRESHOLD",
    "THRESHOLD_KEYS",
    "ExcitabilityResult",
    "SegmentedAnalysis",
    "SensabilityResult",
    "check_segments",
    "check_thresholds",
    "excitability",
    "excitability_segment",
    "excitability_segments",
    "in_segment",
    "nu_for",
    "nu_range",
    "physical_bands",
    "sensability",
    "sensability_model",

]
