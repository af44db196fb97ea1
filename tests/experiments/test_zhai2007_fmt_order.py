"""Printed orderings carry the true relation of the numbers (issue 19, item 7)."""

import pandas as pd

from fusetrack.experiments.zhai2007.common import fmt_order, join_with_relations


def test_fmt_order_prints_the_true_relation():
    values = pd.Series({"A": 304.0, "B": 53.6, "C": 53.6, "D": 60.0})
    assert fmt_order(values, ["A", "B", "C", "D"]) == "A 304 > B 53.6 = C 53.6 < D 60"
    assert fmt_order(values, ["B", "D"]) == "B 53.6 < D 60"


def test_join_with_relations_keeps_the_texts():
    assert join_with_relations([3.0, 2.0, 1.0], ["x", "y", "z"]) == "x > y > z"
