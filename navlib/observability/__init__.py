"""Observability matrices, their rank / condition / null space, and the local test per step.

Contract: docs/library.md. The package re-exports its public names:

* :mod:`~navlib.observability.matrix`: :func:`observability_matrix` and :func:`analyze` of
  one matrix (:class:`ObservabilityResult`);
* :mod:`~navlib.observability.local`: :func:`local_observability` at every (or every
  ``stride``-th) step of a mission (:class:`LocalObservability`) and :func:`local_matrix`;
* :mod:`~navlib.observability.sliding`: the compiled two-stack sliding window behind every
  step of eq. (6).
"""

from navlib.observability.local import (
    VARIANTS,
    LocalObservability,
    local_matrix,
    local_observability,
)
from navlib.observability.matrix import ObservabilityResult, analyze, observability_matrix

__all__ = ["VARIANTS", "LocalObservability", "ObservabilityResult", "analyze", "local_matrix",
           "local_observability", "observability_matrix"]
