"""An interrupted full-size run resumes: finished runs are kept in a checkpoint and not run again,
the rows equal an uninterrupted run's, a record cut short by a kill is dropped, and records of
other code are ignored."""

from __future__ import annotations

import pickle

import numpy as np
import pandas as pd
import pytest

from fusetrack.cli import main
from fusetrack.core import ConfigError
from fusetrack.evaluation import checkpoint as ckpt
from fusetrack.evaluation.checkpoint import CHECKPOINT_NAME, Checkpoint, job_key
from fusetrack.evaluation.montecarlo import run_monte_carlo, run_seed
from fusetrack.evaluation.report import Outcome, RunContext, write_outputs

CALLS: list[tuple[float, int]] = []


def counted_mean(config, seed):
    """A pure run that also records that it ran (serial runs only: workers=1)."""
    CALLS.append((config["mu"], seed))
    rng = np.random.default_rng(seed)
    return [{"value": float(rng.normal(config["mu"], 1.0, size=20).mean())}]


CONFIGS = [{"mu": 0.0}, {"mu": 3.0}]


def _run(checkpoint=None):
    return run_monte_carlo(
        counted_mean, CONFIGS, runs=3, seed=5, workers=1, progress=False, checkpoint=checkpoint
    )


def test_a_resumed_run_runs_only_what_is_missing_and_gives_the_same_rows(tmp_path):
    CALLS.clear()
    fresh = _run()
    assert len(CALLS) == 6 and fresh.attrs["resumed_runs"] == 0
    path = tmp_path / CHECKPOINT_NAME
    partial = Checkpoint(path)  # an invocation killed after the first configuration's runs
    for r in range(3):
        s = run_seed(5, r)
        rows = [{"config": 0, "run": r, "seed": s, "mu": 0.0, **counted_mean(CONFIGS[0], s)[0]}]
        partial.save(job_key(counted_mean, CONFIGS[0], r, s), rows)
    CALLS.clear()
    resumed = _run(Checkpoint(path))
    assert sorted(CALLS) == sorted((3.0, run_seed(5, r)) for r in range(3))  # only the missing
    assert resumed.attrs["resumed_runs"] == 3
    pd.testing.assert_frame_equal(resumed, fresh)
    CALLS.clear()
    again = _run(Checkpoint(path))  # everything is in the checkpoint now
    assert CALLS == [] and again.attrs["resumed_runs"] == 6
    pd.testing.assert_frame_equal(again, fresh)


def test_a_record_cut_short_is_dropped_and_the_file_truncated(tmp_path):
    path = tmp_path / CHECKPOINT_NAME
    c = Checkpoint(path)
    c.save("a", [{"x": 1}])
    c.save("b", [{"x": 2}])
    whole = path.stat().st_size
    with path.open("r+b") as f:
        f.truncate(whole - 5)  # killed while writing "b"
    reopened = Checkpoint(path)
    assert reopened.done == {"a": [{"x": 1}]}
    reopened.save("c", [{"x": 3}])  # appended after the last whole record, readable again
    assert Checkpoint(path).done == {"a": [{"x": 1}], "c": [{"x": 3}]}


@pytest.mark.parametrize("cut", [1, 7])
def test_a_first_record_cut_short_leaves_an_empty_checkpoint(tmp_path, cut):
    path = tmp_path / CHECKPOINT_NAME
    Checkpoint(path).save("a", [{"x": 1}])
    with path.open("r+b") as f:
        f.truncate(cut)  # killed while writing the first record
    assert Checkpoint(path).done == {}
    assert path.stat().st_size == 0


@pytest.mark.parametrize(
    "content", [b"results of another program\n", pickle.dumps({"not": "a record"})]
)
def test_a_foreign_file_at_the_checkpoint_name_is_refused_not_emptied(tmp_path, content):
    path = tmp_path / CHECKPOINT_NAME
    path.write_bytes(content)
    with pytest.raises(ConfigError, match=r"checkpoint.*--no-resume"):
        Checkpoint(path)
    assert path.read_bytes() == content


def test_records_of_other_code_are_ignored(tmp_path, monkeypatch):
    path = tmp_path / CHECKPOINT_NAME
    with path.open("wb") as f:
        pickle.dump(("another version of the code", "a", [{"x": 1}]), f)
    assert Checkpoint(path).done == {}
    monkeypatch.setattr(ckpt, "code_fingerprint", lambda: "another version of the code")
    assert Checkpoint(path).done == {"a": [{"x": 1}]}


def test_the_key_tells_function_configuration_run_and_seed_apart():
    keys = {
        job_key(counted_mean, {"mu": 0.0}, 0, 1),
        job_key(counted_mean, {"mu": 0.0}, 1, 1),
        job_key(counted_mean, {"mu": 0.0}, 0, 2),
        job_key(counted_mean, {"mu": 1.0}, 0, 1),
        job_key(_run, {"mu": 0.0}, 0, 1),
    }
    assert len(keys) == 5
    assert job_key(counted_mean, {"a": 1, "b": 2}, 0, 1) == job_key(
        counted_mean, {"b": 2, "a": 1}, 0, 1
    )


def test_a_full_size_context_checkpoints_and_cleans_up_a_quick_one_does_not(tmp_path):
    full = RunContext("x", tmp_path / "full", workers=1, progress=False)
    df = full.monte_carlo(counted_mean, CONFIGS, 2)
    assert (tmp_path / "full" / CHECKPOINT_NAME).exists()
    summary = write_outputs(full, Outcome(df, [], "body", 2), 1.0, 1.0)
    assert not (tmp_path / "full" / CHECKPOINT_NAME).exists() and "resumed_runs" not in summary

    again = RunContext("x", tmp_path / "again", workers=1, progress=False)
    again.monte_carlo(counted_mean, CONFIGS, 2)  # killed before its outputs were written ...
    resumed = RunContext("x", tmp_path / "again", workers=1, progress=False)
    df = resumed.monte_carlo(counted_mean, CONFIGS, 2)  # ... and started again
    summary = write_outputs(resumed, Outcome(df, [], "body", 2), 1.0, 1.0)
    assert summary["resumed_runs"] == 4
    assert "Resumed: 4 Monte Carlo runs" in (tmp_path / "again" / "report.md").read_text()

    fresh = RunContext("x", tmp_path / "again", workers=1, progress=False, resume=False)
    fresh.monte_carlo(counted_mean, CONFIGS, 2)
    assert fresh.resumed_runs == 0

    quick = RunContext("x", tmp_path / "quick", quick=True, workers=1, progress=False)
    quick.monte_carlo(counted_mean, CONFIGS, 2)
    assert not (tmp_path / "quick" / CHECKPOINT_NAME).exists()


def test_the_cli_refuses_a_foreign_checkpoint_before_any_work(tmp_path, capsys):
    (tmp_path / CHECKPOINT_NAME).write_bytes(b"not ours")
    assert main(["run", "lee2009-network-traffic", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert CHECKPOINT_NAME in err and "--no-resume" in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == [CHECKPOINT_NAME]  # nothing ran
