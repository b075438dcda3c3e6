"""The one claims engine: every paper claim of every study, one verdict rule, one table.

A claim is an id, the paper's statement and value, our number(s) and a list of explicit
:class:`Check` s, each a measured value against a tolerance written in the paper's own terms
("GPS barely improves roll" -> ``roll sigma ratio >= 0.5``). The verdict is never typed: it
follows from the checks by the single rule of :func:`verdict_of`:

* **reproduced**: every check passes;
* **partly**: the headline check(s) pass and a secondary one fails;
* **not reproduced**: a headline check fails.

A claim whose checks could not be evaluated on the given input (e.g. a 30-40 min claim on a
10 min quick run) is **not evaluated**; that is a status, not a verdict.

Each claim also carries a **basis**:

* ``measured``: our number is computed from the model, the paper's statement is tested;
* ``by construction``: the claim is an input of ours (e.g. the rocket profile R1-R6, which
  the trajectory generator takes as parameters): shown, never counted as reproduced;
* ``fitted``: the claim holds at an assumption chosen to make it hold (e.g. SSAC's 45°
  eigenvector pairs from a P0 built for them).

Every study registers itself with :func:`register` (a :class:`Study`: a function returning
its baseline claims, its declared assumption set as data, and a function evaluating the
claims over that set). :func:`all_claims` runs every registered study and returns the one
table of the contract (docs/library.md), with the **robustness** of each measured or
fitted claim: the fraction of the points of its study's declared set, varying exactly the
assumptions the claim declares in ``depends_on``, at which it is reproduced
(:func:`robustness_over`; NaN for claims by construction, where the set varies none of its
assumptions, and where its number and verdict do not move: "insensitive"), and the
**explanation** of each partly / not reproduced claim (:func:`explain`). :func:`joint_search`
reads a sweep of a whole assumption space: the point reproducing the most claims at once and
the claims that hold together nowhere; the spaces searched are registered as
:class:`SearchSpace` (:mod:`.search`: :func:`run_search`, :func:`stored_search`).

Modules: :mod:`.records` (checks, the verdict rule, the claim record), :mod:`.robustness`
(robustness, explanations, joint search), :mod:`.registry` (studies, :func:`all_claims`) and
:mod:`.summary` (counts, summary page, generated readings).
"""

from navlib.studies.claims.records import (
    BASES,
    NOT_EVALUATED,
    OPS,
    STATUSES,
    VERDICTS,
    Check,
    ClaimResult,
    check,
    claim,
    claims_frame,
    not_evaluated,
    verdict_of,
    with_failed_headline,
)
from navlib.studies.claims.registry import (
    COLUMNS,
    STUDY_MODULES,
    Study,
    factorial_search,
    register,
    studies,
    study_frame,
    study_robustness,
)
from navlib.studies.claims.robustness import (
    CAUSES,
    KINDS,
    JointSearch,
    Robustness,
    cause_of,
    explain,
    joint_search,
    robustness_over,
)
from navlib.studies.claims.search import (
    SEARCH_SPACES,
    SearchSpace,
    SearchTable,
    joint_searches,
    paper_joint_summary,
    register_search,
    run_search,
    search_space,
    stored_search,
)
from navlib.studies.claims.summary import (
    counts,
    full_text,
    paper_summary,
    reading_markdown,
    summary_markdown,
)
from navlib.studies.claims.table import all_claims

__all__ = [
    "BASES", "CAUSES", "COLUMNS", "KINDS", "NOT_EVALUATED", "OPS", "SEARCH_SPACES", "STATUSES",
    "STUDY_MODULES",
    "VERDICTS", "Check", "ClaimResult", "JointSearch", "Robustness", "SearchSpace", "SearchTable",
    "Study", "all_claims", "cause_of", "check", "claim", "claims_frame", "counts", "explain",
    "factorial_search", "full_text", "joint_search", "joint_searches", "not_evaluated",
    "paper_joint_summary",
    "paper_summary", "reading_markdown", "register", "register_search", "robustness_over",
    "run_search", "search_space", "stored_search", "studies", "study_frame", "study_robustness",
    "summary_markdown", "verdict_of", "with_failed_headline",
]
