"""The generic best-possible judgement (issue 19 item 3): a paper number below the posterior
mean by more than three standard errors is impossible; two particle counts agree or not."""

import math

import numpy as np
import pytest

from fusetrack.core import ConfigError
from fusetrack.evaluation import (
    IMPOSSIBLE,
    POSSIBLE,
    ClaimKinds,
    agreement_claim,
    best_possible_verdict,
    mean_with_se,
    not_above,
    possible_claim,
)

KINDS = ClaimKinds({"BP_*": "diagnostic"})


def test_mean_with_se_by_hand():
    mean, se = mean_with_se([1.0, 3.0])  # std(ddof 1) = sqrt(2), / sqrt(2) = 1
    assert (mean, se) == (2.0, pytest.approx(1.0))
    assert np.isnan(mean_with_se([4.0])[1])


def test_one_run_has_no_margin():
    assert best_possible_verdict(1.99, 2.0, float("nan")) == IMPOSSIBLE
    assert best_possible_verdict(2.0, 2.0, float("nan")) == POSSIBLE
    claim = possible_claim(KINDS, "BP_x", "row", 1.69, (2.0, 0.1))  # 3 s.e. below is 1.7
    assert not claim.holds and IMPOSSIBLE in claim.ours


def test_agreement_within_three_combined_standard_errors():
    # combined s.e. = hypot(0.3, 0.4) = 0.5: 1.5 apart agrees, 1.6 apart does not
    assert agreement_claim(KINDS, "BP_a", "f", (2000, 3.0, 0.3), (5000, 4.5, 0.4)).holds
    far = agreement_claim(KINDS, "BP_b", "f", (2000, 3.0, 0.3), (5000, 4.6, 0.4))
    assert not far.holds and far.kind == "diagnostic" and "5000" in far.statement
    # one run: no s.e., only exact agreement holds
    assert not agreement_claim(KINDS, "BP_c", "f", (1, 3.0, np.nan), (2, 3.1, np.nan)).holds


def test_possible_claim_on_a_bound_alone():
    """No posterior mean (NaN): judged on the PCRB only, and the text names only the bound."""
    nan = (float("nan"), float("nan"))
    ok = possible_claim(KINDS, "BP_a", "x", 0.64, nan, 0.02)
    bad = possible_claim(KINDS, "BP_b", "x", 1.08, nan, 1.17, model="spec velocities")
    assert ok.holds and ok.ours == "PCRB 0.02: possible" and ok.tolerance == "paper >= PCRB"
    assert not bad.holds and bad.ours == "PCRB 1.17: impossible under 'spec velocities'"
    with pytest.raises(ConfigError, match="posterior mean or a PCRB"):
        possible_claim(KINDS, "BP_c", "x", 1.0, nan)
    # a static bound is named as what it is, in the value and the tolerance
    crlb = possible_claim(KINDS, "BP_d", "x", 0.1, (0.5, 0.1), 0.2, bound_label="CRLB")
    assert not crlb.holds and "CRLB 0.2" in crlb.ours and "PCRB" not in crlb.ours + crlb.tolerance
    assert crlb.tolerance.endswith(">= CRLB")


def test_not_above_allows_three_combined_standard_errors():
    assert not_above((1.0, 0.1), (1.0, 0.1))
    assert not_above((1.4, 0.1), (1.0, 0.1))  # 0.4 <= 3 * hypot(0.1, 0.1) = 0.42
    assert not not_above((1.5, 0.1), (1.0, 0.1))
    assert not not_above((1.01, math.nan), (1.0, math.nan))  # one run: no margin
