"""A paper's verdict: its central contributions, each judged from the claims of the committed
full-size reports (never typed by hand).

A paper declares its central contributions (:class:`PaperVerdict`, one module per paper under
``fusetrack.experiments``); each names the claims that decide it as the paper prints it, the
readings under which it may hold instead (a model detail the paper leaves open, with the claims
that decide it under that reading) and the best-possible ``diagnostic`` claims: "the paper's
number is not below the best possible estimator on the printed model", which fail when it is.
:func:`judge` computes the verdict word from whether those claims hold:

* every deciding claim holds: ``reproduced``;
* else a best-possible claim fails: ``impossible on the printed model``;
* else (or as well) every claim of a reading holds: ``reproduced under reading X``;
* else ``not reproduced``.

A deciding claim must be of kind ``paper``, a best-possible one ``diagnostic``; a claim id missing
from its experiment's summary is a :class:`~fusetrack.core.ConfigError` naming it, so a stale
definition fails as soon as the reports change.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from ..core import ConfigError, invalid

REPRODUCED = "reproduced"
NOT_REPRODUCED = "not reproduced"
IMPOSSIBLE = "impossible on the printed model"


@dataclass(frozen=True)
class ClaimRef:
    """One claim of one experiment's ``summary.json``."""

    experiment: str
    id: str

    def __str__(self) -> str:
        return f"{self.experiment} {self.id}"


def refs(experiment: str, *ids: str) -> tuple[ClaimRef, ...]:
    """``refs("nott2009-simulation", "H1-S1", "H1-S2")``: claims of one experiment."""
    if not ids:
        raise ConfigError(invalid(f"claim ids of {experiment}", ids, "at least one id"))
    return tuple(ClaimRef(experiment, i) for i in ids)


@dataclass(frozen=True)
class Reading:
    """A reading of what the paper leaves open (``name``, e.g. ``"sigma_v = 2"``) and the
    claims that decide the contribution under it."""

    name: str
    claims: tuple[ClaimRef, ...]


@dataclass(frozen=True)
class Contribution:
    """A central contribution: a one-line ``statement``, the claims that decide it as printed,
    the readings under which it may hold instead and the best-possible diagnostics (each holds
    while the paper's number is not below the best possible on the printed model)."""

    statement: str
    decided_by: tuple[ClaimRef, ...]
    readings: tuple[Reading, ...] = ()
    best_possible: tuple[ClaimRef, ...] = ()

    def __post_init__(self) -> None:
        if not self.decided_by:
            raise ConfigError(invalid(f"decided_by of {self.statement!r}", (), "claims"))

    @property
    def experiments(self) -> list[str]:
        """The experiments whose claims decide this contribution, in order."""
        every = [*self.decided_by, *(r for x in self.readings for r in x.claims)]
        return list(dict.fromkeys(r.experiment for r in [*every, *self.best_possible]))


@dataclass(frozen=True)
class PaperVerdict:
    """A paper's central contributions; ``prefix`` names its experiments (``lee2009`` for
    ``lee2009-*``)."""

    paper: str
    prefix: str
    contributions: tuple[Contribution, ...]


KindOf = Callable[[str, Mapping[str, Any], Mapping[str, Any]], str]


def _kind_in_claim(name: str, summary: Mapping[str, Any], claim: Mapping[str, Any]) -> str:
    if "kind" not in claim:
        raise ConfigError(invalid(f"{name}: kind of claim {claim['id']!r}", None, "a kind"))
    return str(claim["kind"])


@dataclass
class SummaryClaims:
    """The claims of several ``summary.json`` files (``{experiment: summary}``), looked up by
    :class:`ClaimRef`; ``kind_of(experiment, summary, claim)`` gives a claim's kind (default: the
    summary's own ``kind`` field)."""

    summaries: Mapping[str, Mapping[str, Any]]
    kind_of: KindOf = _kind_in_claim
    _index: dict[str, dict[str, Mapping[str, Any]]] = field(default_factory=dict, repr=False)

    def get(self, ref: ClaimRef) -> dict[str, Any]:
        """The claim (its ``kind`` filled in), or :class:`ConfigError` naming what is missing."""
        if ref.experiment not in self.summaries:
            raise ConfigError(
                invalid("experiment", ref.experiment, "one with a reports/NAME/summary.json")
            )
        if ref.experiment not in self._index:
            claims = self.summaries[ref.experiment]["claims"]
            self._index[ref.experiment] = {c["id"]: c for c in claims}
        found = self._index[ref.experiment].get(ref.id)
        if found is None:
            raise ConfigError(
                invalid(
                    f"claim id of {ref.experiment}",
                    ref.id,
                    f"one of its summary's claims {sorted(self._index[ref.experiment])}",
                )
            )
        kind = self.kind_of(ref.experiment, self.summaries[ref.experiment], found)
        return {**found, "kind": kind}


@dataclass(frozen=True)
class Evidence:
    """A deciding claim as the summary has it, and the role it plays."""

    ref: ClaimRef
    claim: Mapping[str, Any]
    role: str  # "printed", "reading NAME" or "best possible"

    @property
    def holds(self) -> bool:
        return bool(self.claim["holds"])


@dataclass(frozen=True)
class Judgement:
    """The verdict word on one contribution and the claims it rests on."""

    contribution: Contribution
    word: str
    evidence: tuple[Evidence, ...]


def _fetch(
    refs_: Sequence[ClaimRef], claims: SummaryClaims, role: str, kinds: tuple[str, ...]
) -> list[Evidence]:
    found = []
    for ref in refs_:
        claim = claims.get(ref)
        if claim["kind"] not in kinds:
            raise ConfigError(invalid(f"kind of {ref} ({role})", claim["kind"], f"one of {kinds}"))
        found.append(Evidence(ref, claim, role))
    return found


def judge(contribution: Contribution, claims: SummaryClaims) -> Judgement:
    """The verdict on ``contribution`` from ``claims`` (see the module docstring)."""
    printed = _fetch(contribution.decided_by, claims, "printed", ("paper",))
    readings = [
        (r.name, _fetch(r.claims, claims, f"reading {r.name}", ("paper", "diagnostic")))
        for r in contribution.readings
    ]
    best = _fetch(contribution.best_possible, claims, "best possible", ("diagnostic",))
    if all(e.holds for e in printed):
        return Judgement(contribution, REPRODUCED, tuple(printed))
    held = next(((name, ev) for name, ev in readings if all(e.holds for e in ev)), None)
    impossible = any(not e.holds for e in best)
    words = [IMPOSSIBLE] if impossible else []
    if held is not None:
        words.append(f"reproduced under reading {held[0]}")
    evidence = [*printed, *(held[1] if held else [e for _, ev in readings for e in ev]), *best]
    return Judgement(contribution, "; ".join(words) or NOT_REPRODUCED, tuple(evidence))


def judge_paper(verdict: PaperVerdict, claims: SummaryClaims) -> list[Judgement]:
    return [judge(c, claims) for c in verdict.contributions]


# -- markdown ------------------------------------------------------------------------------------

MAX_VALUE_CHARS = 90


def format_value(value: Any) -> str:
    """A claim's ``paper`` or ``ours`` value, short: floats to 3 significant digits."""
    if isinstance(value, bool) or value is None:
        text = "–" if value is None else str(value).lower()
    elif isinstance(value, float):
        text = f"{value:.3g}" if math.isfinite(value) else str(value)
    elif isinstance(value, Mapping):
        text = "{" + ", ".join(f"{k}: {format_value(v)}" for k, v in value.items()) + "}"
    elif isinstance(value, list | tuple):
        text = "[" + ", ".join(format_value(v) for v in value) + "]"
    else:
        text = str(value)
    text = text.replace("|", "/").replace("\n", " ")
    return text if len(text) <= MAX_VALUE_CHARS else text[: MAX_VALUE_CHARS - 1] + "…"


def evidence_line(e: Evidence, link: Callable[[str], str]) -> str:
    """``[exp](link) `id`: paper P; ours O (tolerance T) — holds``."""
    c = e.claim
    role = "" if e.role == "printed" else f" ({e.role})"
    return (
        f"[{e.ref.experiment}]({link(e.ref.experiment)}) `{e.ref.id}`{role}: paper "
        f"{format_value(c['paper'])}; ours {format_value(c['ours'])} (tolerance "
        f"{format_value(c['tolerance'])}) — {'holds' if e.holds else '**fails**'}"
    )


def judgement_markdown(
    j: Judgement, link: Callable[[str], str], with_evidence: bool = True
) -> list[str]:
    """A list item: the verdict word in bold and the statement, then one line per claim (or,
    without the evidence, the reports that decide it)."""
    head = f"- **{j.word[0].upper()}{j.word[1:]}**: {j.contribution.statement}"
    if not with_evidence:
        names = ", ".join(f"[{n}]({link(n)})" for n in j.contribution.experiments)
        return [f"{head} (decided in {names})"]
    return [head, *(f"    - {evidence_line(e, link)}" for e in j.evidence)]


def paper_markdown(
    verdict: PaperVerdict,
    judgements: Sequence[Judgement],
    link: Callable[[str], str],
    focus: str | None = None,
) -> list[str]:
    """The verdict block of one paper: one item per central contribution, with its evidence
    (given ``focus``, an experiment's name: only for the contributions it takes part in)."""
    lines = [
        f"**Verdict on {verdict.paper}'s central contributions**, computed from the claims of "
        "the committed full-size reports:",
        "",
    ]
    for j in judgements:
        shown = focus is None or focus in j.contribution.experiments
        lines += judgement_markdown(j, link, with_evidence=shown)
    return lines
