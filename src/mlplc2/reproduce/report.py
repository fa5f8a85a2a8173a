"""What :func:`mlplc2.reproduce.reproduce` produced (:class:`ReproduceResult`) and its two
report files, ``report.json`` and ``report.md`` (see docs/reproduce.md)."""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from pathlib import Path

from .. import _files
from ..models.base import REPEAT_THRESHOLD
from .claims import STATUS_KNOWN

__all__ = ["ReproduceResult", "write_json", "write_markdown"]


@dataclass
class ReproduceResult:
    """What :func:`reproduce` produced."""

    out: Path
    claims: list
    files: dict
    source: str
    quick: bool
    skipped: list
    seconds: float
    damaged: list = field(default_factory=list)
    """The inputs skipped because they could not be read to their end (also in ``skipped``)."""
    params: dict = field(default_factory=dict)
    """The parameter overrides used (``{}``: the defaults), as ``mlplc2 batch --params`` reads
    them: ``Params`` fields, and ``{"lgmd2": {...}}`` for LGMD2's own."""

    @property
    def n_pass(self) -> int:
        return sum(c.status == "PASS" for c in self.claims)

    @property
    def n_fail(self) -> int:
        """Claims that fail and are not known deviations (``n_pass + n_fail + n_known`` = all)."""
        return sum(c.status == "FAIL" for c in self.claims)

    @property
    def n_known(self) -> int:
        """Claims that fail as a known deviation (:data:`KNOWN_DEVIATIONS`)."""
        return sum(c.status == STATUS_KNOWN for c in self.claims)

    @property
    def summary(self) -> str:
        """``71 PASS / 0 FAIL / 4 FAIL (known deviation)``: the line printed and in the report."""
        return f"{self.n_pass} PASS / {self.n_fail} FAIL / {self.n_known} {STATUS_KNOWN}"

    @property
    def parameters(self) -> str:
        """Which parameter set was used, in words (for the report)."""
        if not self.params:
            return "the defaults (mlplc2.Params(), and LGMD2Params() for LGMD2)"
        flat = {k: v for k, v in self.params.items() if not isinstance(v, dict)}
        parts = [", ".join(f"{k}={v!r}" for k, v in sorted(flat.items()))] if flat else []
        parts += [f"{m}: " + ", ".join(f"{k}={v!r}" for k, v in sorted(sec.items()))
                  for m, sec in sorted(self.params.items()) if isinstance(sec, dict)]
        return "the defaults except " + "; ".join(parts)


def write_json(result: ReproduceResult, path: Path) -> Path:
    """``report.json``: the summary, the parameters, what was skipped and every claim (``Claim.to_dict``)."""
    doc = {
        "command": "mlplc2 reproduce",
        "source": result.source,
        "quick": result.quick,
        "parameters": {"defaults": not result.params, "overrides": result.params,
                       "description": f"{result.parameters}; one parameter set for every input"},
        "seconds": round(result.seconds, 1),
        "summary": {"claims": len(result.claims), "pass": result.n_pass, "fail": result.n_fail,
                    "known_deviation": result.n_known, "line": result.summary},
        "skipped": result.skipped,
        "figures": sorted(k for k in result.files if k.endswith(".png")),
        "claims": [c.to_dict() for c in result.claims],
    }
    _files.write_json(path, doc, indent=2)
    return Path(path)


def _cell(text) -> str:
    return "-" if text is None else str(text).replace("|", "\\|")


def write_markdown(result: ReproduceResult, path: Path) -> Path:
    """``report.md``: the summary, then one table per section of Sec. IV, one line per claim."""
    lines = ["# mLPLC2 reproduction of Sec. IV", "",
             f"Input: {result.source}. Parameters: {result.parameters}, one set for every input; "
             f"duplicated frames held (`repeat_threshold={REPEAT_THRESHOLD:g}`, docs/model.md)."
             + (" **Quick run** (reduced set, see below)." if result.quick else ""), "",
             f"**{result.summary}** of {len(result.claims)} claims. A {STATUS_KNOWN} is a failure that "
             f"docs/reproduce.md \"Known deviations\" lists, explained in the section its note names. "
             f"Run time {result.seconds:.0f} s.", ""]
    if result.skipped:
        lines += ["Not run:", ""] + [f"- {s}" for s in result.skipped] + [""]
    figs = sorted(k for k in result.files if k.endswith(".png"))
    if figs:
        lines += ["Figures: " + ", ".join(f"[{f}]({f})" for f in figs), ""]
    for section, claims in itertools.groupby(result.claims, key=lambda c: c.section):
        lines += [f"## {section}", "", "| status | claim | measured | criterion | authors' figure | note |",
                  "|---|---|---|---|---|---|"]
        for c in claims:
            status = c.status if c.known_deviation else f"**{c.status}**"
            lines.append(f"| {status} | {_cell(c.claim)} | {_cell(c.measured)} | {_cell(c.criterion)} | "
                         f"{_cell(c.paper)} | {_cell(c.note)} |")
        lines.append("")
    lines += ["Claim ids, values and flags are in `report.json`. Thresholds and the meaning of each line: "
              "docs/reproduce.md.", ""]
    _files.write_text(path, "\n".join(lines))
    return Path(path)

