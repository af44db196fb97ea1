"""A paper's verdict is computed from its claims: every deciding claim holds -> reproduced; only
a reading's claims hold -> reproduced under that reading; a best-possible diagnostic fails (the
paper's number is below the best possible) -> impossible on the printed model; a claim id
missing from the summary is an error naming it."""

import pytest

from fusetrack.core import ConfigError
from fusetrack.evaluation import (
    Contribution,
    PaperVerdict,
    Reading,
    SummaryClaims,
    judge,
    paper_markdown,
    refs,
)
from fusetrack.evaluation.verdict import format_value, judge_paper


def _claim(cid, holds, kind="paper", paper=1.0, ours=1.0, tolerance="+-10%"):
    return {
        "id": cid,
        "holds": holds,
        "kind": kind,
        "paper": paper,
        "ours": ours,
        "tolerance": tolerance,
    }


def _claims(*claims, name="x2000-a"):
    return SummaryClaims({name: {"claims": list(claims)}})


CENTRAL = Contribution(
    "A beats B",
    refs("x2000-a", "gain", "order"),
    readings=(
        Reading("sigma = 1", refs("x2000-a", "gain_sigma1")),
        Reading("sigma = 2", refs("x2000-a", "gain_sigma2", "order_sigma2")),
    ),
    best_possible=refs("x2000-a", "paper_not_below_best"),
)


def _summary(gain, order, s1, s2, o2, impossible):
    return _claims(
        _claim("gain", gain, paper=2.34, ours=1.51),
        _claim("order", order),
        _claim("gain_sigma1", s1, kind="diagnostic"),
        _claim("gain_sigma2", s2, kind="diagnostic"),
        _claim("order_sigma2", o2, kind="diagnostic"),
        _claim("paper_not_below_best", not impossible, kind="diagnostic"),
        _claim("other", False),
    )


def test_all_deciding_claims_hold_is_reproduced():
    j = judge(CENTRAL, _summary(True, True, False, False, False, False))
    assert j.word == "reproduced"
    assert [e.ref.id for e in j.evidence] == ["gain", "order"]  # readings not needed


def test_held_only_under_a_reading():
    j = judge(CENTRAL, _summary(False, True, False, True, True, False))
    assert j.word == "reproduced under reading sigma = 2"
    assert [e.ref.id for e in j.evidence] == [
        "gain",
        "order",
        "gain_sigma2",
        "order_sigma2",
        "paper_not_below_best",
    ]
    # a reading holds only if all its claims hold
    assert judge(CENTRAL, _summary(False, True, False, True, False, False)).word == "not reproduced"


def test_paper_number_below_the_best_possible_is_impossible():
    assert judge(CENTRAL, _summary(False, True, False, False, False, True)).word == (
        "impossible on the printed model"
    )
    both = judge(CENTRAL, _summary(False, False, True, False, False, True))
    assert both.word == "impossible on the printed model; reproduced under reading sigma = 1"


def test_none_holds_is_not_reproduced():
    assert judge(CENTRAL, _summary(False, False, False, False, False, False)).word == (
        "not reproduced"
    )


def test_a_missing_claim_id_is_an_error_naming_it():
    claims = _claims(_claim("gain", True))
    with pytest.raises(ConfigError, match="claim id of x2000-a='order'"):
        judge(CENTRAL, claims)
    with pytest.raises(ConfigError, match="experiment='y2001-b'"):
        judge(Contribution("s", refs("y2001-b", "gain")), claims)


def test_kinds_are_checked():
    """A verdict is decided by paper claims; a best-possible claim is a diagnostic."""
    with pytest.raises(ConfigError, match="kind of x2000-a gain"):
        judge(Contribution("s", refs("x2000-a", "gain")), _claims(_claim("gain", True, "beyond")))
    best = Contribution("s", refs("x2000-a", "gain"), best_possible=refs("x2000-a", "b"))
    with pytest.raises(ConfigError, match="best possible"):
        judge(best, _claims(_claim("gain", False), _claim("b", True, "paper")))


def test_kinds_from_a_resolver():
    """Old summaries carry no kind: the resolver (the tally's table lookup) gives it."""
    claims = SummaryClaims(
        {
            "x2000-a": {
                "claims": [{"id": "gain", "holds": True, "paper": 1, "ours": 1, "tolerance": "-"}]
            }
        },
        kind_of=lambda name, summary, claim: "paper",
    )
    assert judge(Contribution("s", refs("x2000-a", "gain")), claims).word == "reproduced"
    bare = SummaryClaims(claims.summaries)
    with pytest.raises(ConfigError, match="kind of claim 'gain'"):
        judge(Contribution("s", refs("x2000-a", "gain")), bare)


def test_markdown_quotes_the_numbers_and_links_the_reports():
    verdict = PaperVerdict("X 2000", "x2000", (CENTRAL, Contribution("C", refs("x2000-b", "c"))))
    claims = SummaryClaims(
        {
            "x2000-a": _summary(False, True, False, True, True, False).summaries["x2000-a"],
            "x2000-b": {"claims": [_claim("c", True, paper=[1, 2.5], ours={"A": 0.123456})]},
        }
    )
    lines = paper_markdown(verdict, judge_paper(verdict, claims), lambda n: f"{n}/report.md")
    text = "\n".join(lines)
    assert "- **Reproduced under reading sigma = 2**: A beats B" in text
    assert (
        "[x2000-a](x2000-a/report.md) `gain`: paper 2.34; ours 1.51 (tolerance +-10%) — **fails**"
        in text
    )
    assert "`c`: paper [1, 2.5]; ours {A: 0.123} (tolerance +-10%) — holds" in text
    focused = "\n".join(
        paper_markdown(verdict, judge_paper(verdict, claims), lambda n: n, focus="x2000-b")
    )
    assert (
        "- **Reproduced under reading sigma = 2**: A beats B (decided in [x2000-a](x2000-a))"
        in focused
    )
    assert "`gain`" not in focused and "`c`: paper" in focused


def test_format_value_is_short():
    assert format_value(float("nan")) == "nan" and format_value(None) == "–"
    assert format_value("a|b") == "a/b"
    assert len(format_value(list(range(100)))) == 90
