"""Terminal habits (issue 20; ``--version`` is tested in test_cli_options): ``-v``/``-q`` after
any subcommand, progress as plain lines when stderr is not a terminal (the demo used to print
nothing for 76 s in a log), and ``NO_COLOR``. No test here measures time: the progress clock is
a fake or the interval 0."""

from __future__ import annotations

import argparse
import io
import logging
import os
import pty
import sys
import types

import pytest
from tqdm import tqdm

import fusetrack.evaluation.terminal as terminal
from fusetrack.cli import build_parser, main
from fusetrack.core import ConfigError
from fusetrack.evaluation import (
    Claim,
    Outcome,
    PlainProgress,
    RunContext,
    colour_enabled,
    coloured,
    progress_bar,
    run_monte_carlo,
)
from fusetrack.experiments import REGISTRY, ExperimentInfo


class _Terminal(io.StringIO):
    """A stream that says it is a terminal."""

    def isatty(self) -> bool:
        return True


class _Clock:
    """A fake clock: ``now`` seconds, moved by the test."""

    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


# --- -v / -q on every subcommand ---------------------------------------------------------------

REQUIRED = {  # the least each subcommand needs to parse
    "list": [],
    "run": ["demo", "--out", "o"],
    "demo": [],
    "serve": ["--config", "n.yaml"],
    "replay": ["demo", "--to", "udp://127.0.0.1:9000", "--config", "n.yaml"],
    "track": ["scene.yaml", "--out", "o"],
    "make-sample": [],
    "track-video": ["v.mp4", "--radio", "r.csv", "--calibration", "c.yaml", "--out", "o"],
    "log": ["check", "node.sqlite"],
    "reproduce": ["--all", "--out", "o"],
    "reports": ["tally"],
}


def test_every_subcommand_takes_v_and_q_after_it():
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    assert set(sub.choices) == set(REQUIRED)  # a new subcommand: add it above
    for name, args in REQUIRED.items():
        quiet = parser.parse_args([name, *args, "-q"])
        assert (quiet.quiet, quiet.verbose) == (1, 0), name
        loud = parser.parse_args([name, *args, "-vv"])
        assert (loud.quiet, loud.verbose) == (0, 2), name
        before = parser.parse_args(["-q", name, *args])
        assert before.quiet == 1, name


def test_quiet_after_list_sets_the_logging_level(monkeypatch, capsys):
    seen = []
    monkeypatch.setattr(
        "fusetrack.cli._dispatch",
        lambda args: seen.append(logging.getLogger("fusetrack").level) or 0,
    )
    assert main(["list", "-q"]) == 0
    assert main(["list", "-v"]) == 0
    assert seen == [logging.WARNING, logging.DEBUG]


# --- progress when stderr is not a terminal ----------------------------------------------------


def test_plain_progress_writes_a_line_per_interval_with_the_time_left():
    clock, out = _Clock(), io.StringIO()
    with PlainProgress(40, "demo: runs", stream=out, interval=5.0, clock=clock) as bar:
        for _ in range(4):
            clock.now += 1.0
            bar.update()  # 4 s: no line yet
        assert out.getvalue() == ""
        clock.now += 6.0
        bar.update()  # 10 s, 5 of 40 done: 9 s for 4 runs since the first, 35 left
        clock.now += 2.0
        bar.update()  # 2 s after the last line: none
        clock.now += 68.0
        bar.update(34)  # 80 s: all done
    assert out.getvalue().splitlines() == [
        "demo: runs: 5/40, 10 s elapsed, about 1 min 19 s left",
        "demo: runs: 40/40, 1 min 20 s elapsed",  # the last line; no repeat on closing
    ]


def test_plain_progress_time_left_leaves_out_the_warm_up_before_the_first_run():
    clock, out = _Clock(), io.StringIO()
    with PlainProgress(10, "x", stream=out, interval=5.0, clock=clock) as bar:
        clock.now += 30.0
        bar.update()  # the first run took 30 s (compilation); a line: only one run to go by
        for _ in range(4):
            clock.now += 1.0
            bar.update()
        clock.now += 1.0
        bar.update()  # 6 runs, 1 s each since the first: 4 left -> 4 s, not 35 s / 6 * 4
    assert out.getvalue().splitlines() == [
        "x: 1/10 runs, 30 s elapsed, about 4 min 30 s left",
        "x: 6/10 runs, 35 s elapsed, about 4 s left",
    ]


def test_plain_progress_is_silent_for_short_work_and_counts_without_a_total():
    clock, out = _Clock(), io.StringIO()
    with PlainProgress(3, "x", stream=out, interval=5.0, clock=clock) as bar:
        for _ in range(3):
            clock.now += 1.0
            bar.update()
    assert out.getvalue() == ""  # a run shorter than the interval prints nothing
    with PlainProgress(None, "track-video", "frame", stream=out, interval=5.0, clock=clock) as bar:
        clock.now += 3725.0
        bar.update(120)
    assert out.getvalue().splitlines()[0] == "track-video: 120 frames, 1 h 02 min elapsed"


def test_progress_bar_is_a_bar_on_a_terminal_lines_elsewhere_nothing_when_hidden():
    bar = progress_bar(10, "x", stream=_Terminal())
    assert isinstance(bar, tqdm) and not bar.disable
    bar.close()
    assert isinstance(progress_bar(10, "x", stream=io.StringIO()), PlainProgress)
    assert isinstance(progress_bar(10, "x", True, stream=io.StringIO()), PlainProgress)
    hidden = progress_bar(10, "x", False, stream=_Terminal())
    assert isinstance(hidden, tqdm) and hidden.disable
    hidden.close()
    with pytest.raises(ConfigError, match="interval"):
        PlainProgress(10, "x", interval=-1.0)


def _one_row(config, seed):
    return [{"value": seed % 7}]


def test_monte_carlo_progress_reaches_a_log(monkeypatch, capsys):
    monkeypatch.setattr(terminal, "PROGRESS_INTERVAL", 0.0)  # a line per run, no waiting
    run_monte_carlo(_one_row, [{}], runs=3, workers=1, desc="toy: runs")
    lines = capsys.readouterr().err.splitlines()
    assert [line.split(",")[0] for line in lines] == [
        "toy: runs: 1/3",
        "toy: runs: 2/3",
        "toy: runs: 3/3",
    ]
    assert "left" in lines[0] and "\r" not in "".join(lines)
    run_monte_carlo(_one_row, [{}], runs=3, workers=1, progress=False)
    assert capsys.readouterr().err == ""


def _toy_run(ctx: RunContext) -> Outcome:
    df = ctx.monte_carlo(_one_row, [{}], 2)
    return Outcome(
        df,
        [Claim("a", "holds", 1, 1, 0, True, "paper"), Claim("b", "fails", 1, 2, 0, False, "paper")],
        "body",
        2,
    )


@pytest.fixture
def toy(monkeypatch):
    module = types.ModuleType("fusetrack.experiments._toy_terminal")
    module.run = _toy_run  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, module.__name__, module)
    info = ExperimentInfo("toy", "_toy_terminal:run", "A toy", "none")
    monkeypatch.setitem(REGISTRY, "toy", info)
    monkeypatch.setattr(terminal, "PROGRESS_INTERVAL", 0.0)
    return "toy"


def test_run_shows_progress_lines_unless_quiet(toy, tmp_path, capsys):
    assert main(["run", toy, "--workers", "1", "--out", str(tmp_path)]) == 0
    assert "toy: runs: 2/2" in capsys.readouterr().err
    assert main(["run", toy, "--workers", "1", "-q", "--out", str(tmp_path)]) == 0
    assert "2/2" not in capsys.readouterr().err


# --- NO_COLOR ----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "env,terminal_stream,expected",
    [
        ({}, True, True),
        ({"NO_COLOR": "1"}, True, False),
        ({"NO_COLOR": ""}, True, True),  # no-color.org: set *and* not empty
        ({"TERM": "dumb"}, True, False),
        ({}, False, False),  # a file or a pipe
    ],
)
def test_colour_only_on_a_terminal_and_never_with_no_color(
    env, terminal_stream, expected, monkeypatch
):
    monkeypatch.delenv("NO_COLOR", raising=False)
    monkeypatch.setenv("TERM", "xterm")
    for key, value in env.items():
        monkeypatch.setenv(key, value)
    stream = _Terminal() if terminal_stream else io.StringIO()
    assert colour_enabled(stream) is expected
    assert (coloured("ok", "green", stream) == "\x1b[32mok\x1b[0m") is expected


@pytest.mark.parametrize("no_color", [False, True])
def test_summary_colours_on_a_terminal_unless_no_color(toy, no_color, tmp_path, monkeypatch):
    monkeypatch.setenv("TERM", "xterm")
    if no_color:
        monkeypatch.setenv("NO_COLOR", "1")
    else:
        monkeypatch.delenv("NO_COLOR", raising=False)
    out = _Terminal()
    monkeypatch.setattr(sys, "stdout", out)
    assert main(["run", toy, "--workers", "1", "-q", "--out", str(tmp_path)]) == 0
    text = out.getvalue()
    assert "1 of 2 paper claims hold" in text
    if no_color:
        assert "\x1b" not in text and "[ok ] a" in text and "[NO ] b" in text
    else:
        assert "[\x1b[32mok \x1b[0m] a" in text and "[\x1b[31mNO \x1b[0m] b" in text


def _stderr_of_main_on_a_pty(args: list[str], monkeypatch) -> tuple[int, str]:
    """``main(ARGS)`` with stderr on a real pseudo-terminal (``isatty()`` is the kernel's)."""
    main_fd, child_fd = pty.openpty()
    with os.fdopen(child_fd, "w", closefd=True) as tty:
        monkeypatch.setattr(sys, "stderr", tty)
        code = main(args)
        tty.flush()
        monkeypatch.undo()
    out = os.read(main_fd, 65536).decode()
    os.close(main_fd)
    return code, out


@pytest.mark.parametrize("no_color", [False, True])
def test_no_color_on_a_real_terminal(no_color, tmp_path, monkeypatch):
    """On a pseudo-terminal the error word is red, and plain with ``NO_COLOR``."""
    env = {"TERM": "xterm", **({"NO_COLOR": "1"} if no_color else {})}
    with monkeypatch.context() as m:
        m.delenv("NO_COLOR", raising=False)
        for key, value in env.items():
            m.setenv(key, value)
        args = ["run", "zhai2007-scalar", "--set", "bad=1", "--out", str(tmp_path / "o")]
        code, err = _stderr_of_main_on_a_pty(args, monkeypatch)
        assert code == 2 and "bad is not a known key" in err
        if no_color:
            assert "fusetrack: error:" in err and "\x1b" not in err
        else:
            assert "fusetrack: \x1b[31merror\x1b[0m:" in err
