"""Every spec-note citation in navlib's docstrings resolves to an entry of docs/assumptions.md.

The docstrings cite modelling assumptions and paper readings by id: ``A11`` (the numbered
ambiguities of the España et al. note), ``launcher.md §6.2`` (a section of a technical
note), ``api.md "Claims"`` (a section of the public contract). Those notes are not part of
the repository, so each id must have a heading in ``docs/assumptions.md`` that contains it
exactly as cited. A new citation without an entry fails :func:`test_every_citation_has_an_entry`.
"""

import io
import re
import tokenize
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "navlib"
DOC = ROOT / "docs" / "assumptions.md"

NOTES = ("excitability", "launcher", "ssac", "api")
_SEC = r"\d+(?:\.\d+)*[a-z]?"
# ``launcher.md §6.3, §6.4, §7.3``, ``ssac.md §3–§5``, ``excitability.md §3-4``
_SECTIONS = rf"§{_SEC}(?:\s*(?:,|and|[-–])\s*§?{_SEC})*"
NOTE_SECTIONS = re.compile(rf"\b({'|'.join(NOTES)})\.md(?:``)?\s+({_SECTIONS})")
BARE_SECTIONS = re.compile(rf"\bspec\s+({_SECTIONS})")
SECTION = re.compile(rf"§?({_SEC})")
RANGE = re.compile(rf"§?({_SEC})\s*[-–]\s*§?({_SEC})")
# ``spec Eq. 1``, ``spec excitability.md Eq. 1``
EQUATION = re.compile(r"\bspec\s+(?:(excitability)\.md\s+)?Eq\.\s*(\d+)")
# ``api.md "Claims"``, ``api.md``, "Scale"``
API_SECTION = re.compile(r"\bapi\.md(?:``)?,?\s+\"([^\"]+)\"")
API_BARE = re.compile(r"\bapi\.md\b")
# ambiguity ids of the España et al. note: ``spec A11``, ``(A14)``, ``A4 (b)``
A_ID = re.compile(r"\bA(\d{1,2})\b(?!\s*(?:\[|\(k\)))")

# The note a bare ``spec §x`` / ``spec Eq. n`` refers to, from the citing module's name.
_CONTEXT = (("launcher", "launcher"), ("outliers", "launcher"), ("plots/observability", "launcher"),
            ("ssac", "ssac"), ("rocket", "excitability"), ("ecef", "excitability"),
            ("metrics", "excitability"), ("trajectory/fit", "excitability"),
            ("sensors", "excitability"), ("strapdown", "excitability"),
            ("earth", "excitability"), ("rotations", "excitability"),
            ("discretize", "excitability"))


def _context_note(rel: str) -> str | None:
    return next((note for key, note in _CONTEXT if key in rel), None)


def _text_tokens(source: str) -> str:
    """The docstrings, strings and comments of a module (code identifiers such as ``A0``
    are not citations)."""
    parts = []
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type in (tokenize.STRING, tokenize.COMMENT) or tok.type == getattr(
                tokenize, "FSTRING_MIDDLE", -1):
            parts.append(tok.string)
    return "\n".join(parts)


def _expand(sections: str) -> list[str]:
    """``§3.7, §10a`` -> ["3.7", "10a"]; ranges keep both ends (``§3-4`` -> ["3", "4"])."""
    return [m.group(1) for m in SECTION.finditer(RANGE.sub(r"\1, \2", sections))]


def citations_in(text: str, rel: str) -> tuple[set[str], list[str]]:
    """The ids cited in ``text`` (docstrings and comments of module ``rel``), and the bare
    ``spec §x`` / ``spec Eq. n`` citations whose note cannot be told from ``rel``."""
    ids: set[str] = set()
    unresolved: list[str] = []
    for m in NOTE_SECTIONS.finditer(text):
        ids.update(f"{m.group(1)}.md §{sec}" for sec in _expand(m.group(2)))
    for m in BARE_SECTIONS.finditer(text):
        note = _context_note(rel)
        if note is None:
            unresolved.append(f"{rel}: {m.group(0)!r}")
        else:
            ids.update(f"{note}.md §{sec}" for sec in _expand(m.group(1)))
    for m in EQUATION.finditer(text):
        note = m.group(1) or _context_note(rel)
        if note is None:
            unresolved.append(f"{rel}: {m.group(0)!r}")
        else:
            ids.add(f"{note}.md Eq. {m.group(2)}")
    ids.update(f'api.md "{m.group(1)}"' for m in API_SECTION.finditer(text))
    if API_BARE.search(text):
        ids.add("api.md")
    ids.update(f"A{m.group(1)}" for m in A_ID.finditer(text))
    return ids, unresolved


def collect_citations() -> dict[str, set[str]]:
    """Map each cited id (as it must appear in a heading) to the files citing it."""
    found: dict[str, set[str]] = {}
    unresolved: list[str] = []
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(ROOT).as_posix()
        ids, bad = citations_in(_text_tokens(path.read_text(encoding="utf-8")), rel)
        unresolved += bad
        for cid in ids:
            found.setdefault(cid, set()).add(rel)
    assert not unresolved, ("bare 'spec §x' citations in modules with no known note; add "
                            "the module to _CONTEXT or cite the note by name:\n"
                            + "\n".join(unresolved))
    return found


def headings() -> list[str]:
    return [line.lstrip("#").strip() for line in DOC.read_text(encoding="utf-8").splitlines()
            if line.startswith("#")]


def _covered(cid: str, heads: list[str]) -> bool:
    # the id as a whole token: "A1" must not be satisfied by "A11", "§6.2" not by "§6.2.1"
    pattern = re.compile(rf"(?<![\w.§]){re.escape(cid)}(?![\w.]*\d|\w)")
    return any(pattern.search(h) for h in heads)


def test_citation_scan_finds_the_known_forms():
    found = collect_citations()
    n_sites = sum(len(v) for v in found.values())
    assert len(found) > 50 and n_sites > 100, (len(found), n_sites)
    for cid in ("A11", "A14", "A19", "launcher.md §6.2", "ssac.md §4.4", "excitability.md §3",
                "launcher.md §10b"):
        assert cid in found, cid


def test_every_citation_has_an_entry():
    found = collect_citations()
    heads = headings()
    missing = {cid: sorted(files) for cid, files in found.items() if not _covered(cid, heads)}
    report = "\n".join(f"  {cid}  (cited in {', '.join(files)})"
                       for cid, files in sorted(missing.items()))
    print(f"{len(found)} cited ids; missing in docs/assumptions.md:\n{report}")
    assert not missing, f"citations without an entry in docs/assumptions.md:\n{report}"


def test_coverage_check_rejects_prefixes():
    heads = ["A11 — nu range", "launcher.md §6.2.1 — first item"]
    assert _covered("A11", heads) and not _covered("A1", heads)
    assert _covered("launcher.md §6.2.1", heads) and not _covered("launcher.md §6.2", heads)


def test_every_citation_form_is_recognised():
    text = (
        'Eq. 24 (spec A4, A5, A7) and (A14); "spec note A5"; spec excitability.md A10, '
        "spec launcher.md §6.3, §6.4 and §7.3; ssac.md §3–§5; excitability.md §3-4; "
        "launcher.md §6.2 item 6; spec §3.8, §10c; spec excitability.md Eq. 1; spec Eq. 3; "
        'spec ``api.md``, "Scale"; spec api.md, "Claims"; A2(k) and A1[0] are matrices'
    )
    ids, unresolved = citations_in(text, "navlib/studies/launcher.py")
    assert not unresolved
    assert ids == {
        "A4", "A5", "A7", "A14", "A10", "launcher.md §6.3", "launcher.md §6.4",
        "launcher.md §7.3", "ssac.md §3", "ssac.md §5", "excitability.md §3",
        "excitability.md §4", "launcher.md §6.2", "launcher.md §3.8", "launcher.md §10c",
        "excitability.md Eq. 1", "launcher.md Eq. 3", 'api.md "Scale"', 'api.md "Claims"',
        "api.md"}, ids
    _, unresolved = citations_in("see spec §4.2", "navlib/newmodule.py")
    assert unresolved == ["navlib/newmodule.py: 'spec §4.2'"]


def _slug(heading: str) -> str:
    """GitHub's anchor of a markdown heading."""
    return re.sub(r"[^\w\- ]", "", heading.lower()).replace(" ", "-")


def test_internal_links_resolve():
    anchors = {_slug(h) for h in headings()}
    links = re.findall(r"\]\(#([^)]+)\)", DOC.read_text(encoding="utf-8"))
    assert links and not set(links) - anchors, sorted(set(links) - anchors)
