"""``fusetrack`` command line: ``list``, ``run NAME``, ``demo [--live]``, ``track``,
``make-sample``, ``track-video``, ``serve``, ``replay``, ``log check|recover``, ``reproduce
[NAME ...|--all]`` and ``reports tally|verdicts``; ``--version``, ``-v``/``-q`` (the ``logging`` level;
before or after any subcommand), ``run NAME --help`` (the experiment's own options). Progress
goes to stderr (a bar on a terminal, plain lines elsewhere); colour only on a terminal and never
with ``NO_COLOR``."""

from __future__ import annotations

import argparse
import logging
import os
import sys
from collections.abc import Sequence
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

from .core import ConfigError, FusetrackError, invalid


def _version() -> str:
    try:
        return version("fusetrack")
    except PackageNotFoundError:  # pragma: no cover - running from a source tree
        from . import __version__

        return __version__


class _RunHelp(argparse.Action):
    """``run NAME --help``: the usual help, then the options of experiment NAME with defaults."""

    def __init__(self, option_strings: list[str], dest: str, **kwargs: Any) -> None:
        kwargs.update(nargs=0, default=argparse.SUPPRESS)
        super().__init__(option_strings, dest, **kwargs)

    def __call__(self, parser: argparse.ArgumentParser, namespace: Any, *_: Any) -> None:
        parser.print_help()
        name = getattr(namespace, "name", None)
        if name:
            from .core import UnknownExperimentError
            from .evaluation import describe_options
            from .experiments import options_model

            try:
                text = describe_options(options_model(name))
            except UnknownExperimentError as err:
                text = f"  {err}"
            print(f"\noptions of {name} (--set KEY=VALUE):\n{text}")
        parser.exit()


def _add_verbosity(p: argparse.ArgumentParser, default: Any) -> None:
    p.add_argument(
        "-v", "--verbose", action="count", default=default, help="more log lines (-vv: debug)"
    )
    p.add_argument(
        "-q", "--quiet", action="count", default=default, help="only warnings and errors"
    )


def _add_run_options(p: argparse.ArgumentParser, default_out: str | None) -> None:
    p.add_argument(
        "--quick", action="store_true", help="small run (< 1 min), every claim still checked"
    )
    p.add_argument("--runs", type=int, default=None, help="Monte Carlo runs (default: the paper's)")
    p.add_argument(
        "--seed", type=int, default=0, help="base seed; a seed reproduces a run bit for bit"
    )
    p.add_argument(
        "--engine", choices=["local", "dask"], default="local", help="where runs execute"
    )
    p.add_argument(
        "--scheduler", default=None, help="dask scheduler address (default: a LocalCluster)"
    )
    p.add_argument(
        "--workers", type=int, default=None, help="worker processes (default: all cores)"
    )
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar (also -q)")
    p.add_argument(
        "--no-resume",
        action="store_true",
        help="start afresh: ignore the runs an interrupted full-size run left in --out",
    )
    p.add_argument(
        "--out",
        type=Path,
        required=default_out is None,
        default=default_out,
        help="output directory",
    )


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fusetrack",
        description="Tracking with networks of different sensors, fused in Bayesian filters.",
    )
    parser.add_argument("--version", action="version", version=f"fusetrack {_version()}")
    _add_verbosity(parser, 0)
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("list", help="name every experiment")
    run = sub.add_parser(
        "run",
        help="run one experiment and write results.parquet, summary.json, report.md",
        description="Run one experiment; `fusetrack run NAME --help` also lists NAME's options.",
        add_help=False,
    )
    run.add_argument("-h", "--help", action=_RunHelp, help="show this help and NAME's options")
    run.add_argument("name")
    _add_verbosity(run, argparse.SUPPRESS)
    _add_run_options(run, None)
    run.add_argument(
        "--config",
        type=Path,
        default=None,
        help="experiment-specific YAML file (e.g. your room and cameras for ercan2013-selection)",
    )
    run.add_argument(
        "--set",
        dest="options",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="experiment option (repeatable; checked before the run: NAME --help lists them)",
    )
    run.add_argument(
        "--measurements",
        default=None,
        help="where simulated acoustic angles come from, for experiments that offer it: "
        "gaussian (the paper's noise model) or audio (= --set measurements=audio)",
    )
    demo = sub.add_parser("demo", help="= fusetrack run demo (--live: a live fusion node)")
    _add_run_options(demo, "out/demo")
    _add_verbosity(demo, argparse.SUPPRESS)
    from .service import add_live_options, add_service_parsers
    from .tools import add_reports_parser, add_reproduce_parser, add_track_video_parser

    add_live_options(demo)
    add_service_parsers(sub)
    add_track_video_parser(sub)
    _add_track_parsers(sub)
    add_reproduce_parser(sub)
    add_reports_parser(sub)
    _verbosity_after_subcommands(parser)
    return parser


def _verbosity_after_subcommands(parser: argparse.ArgumentParser) -> None:
    """-v/-q after any subcommand too, nested ones included (``log check FILE -q``)."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for command in action.choices.values():
                if "--verbose" not in command._option_string_actions:
                    _add_verbosity(command, argparse.SUPPRESS)
                _verbosity_after_subcommands(command)


def _add_track_parsers(sub: Any) -> None:
    """``track`` (scene YAML -> tracks, report, animation) and ``make-sample``."""
    from .tools import add_make_sample_parser, add_track_parser

    add_track_parser(sub)
    add_make_sample_parser(sub)


def _run_track_commands(args: argparse.Namespace) -> int | None:
    """Run ``track`` or ``make-sample``; None for any other command."""
    if args.command == "track":
        from .tools import run_track_command

        _check_output_dir(args.out)
        return run_track_command(args)
    if args.command == "make-sample":
        from .tools import run_make_sample_command

        _check_output_dir(args.out)
        return run_make_sample_command(args)
    return None


def _print_summary(summary: dict, out: Path) -> None:
    from .evaluation import Claim, coloured, verdict_line

    claims = summary["claims"]
    print(
        f"\n{summary['experiment']}: {verdict_line([Claim(**c) for c in claims])} "
        f"({summary['runs']} runs, {summary['seconds']:.1f} s, peak {summary['peak_memory_mb']:.0f} MiB)"
    )
    for c in claims:
        ours = f"{c['ours']:.4g}" if isinstance(c["ours"], float) else c["ours"]
        word, colour = ("ok ", "green") if c["holds"] else ("NO ", "red")
        mark = coloured(word, colour, sys.stdout)
        paper = "" if c["paper"] is None else f", paper {c['paper']}"  # None: our own check
        print(f"  [{mark}] {c['id']} ({c['kind']}): {c['statement']} — ours {ours}{paper}")
    print(f"report: {out / 'report.md'}")


def _extra_options(args: argparse.Namespace) -> dict[str, str]:
    """``ctx.extra`` from ``--config``, ``--set KEY=VALUE`` and ``--measurements``."""
    extra = {"config": str(args.config)} if getattr(args, "config", None) else {}
    for item in getattr(args, "options", []):
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise ConfigError(invalid("--set", item, "KEY=VALUE, e.g. measurements=audio"))
        extra[key.strip()] = value.strip()
    if getattr(args, "measurements", None) is not None:
        extra["measurements"] = args.measurements
    return extra


def _log_to_stderr(args: argparse.Namespace) -> tuple[logging.Handler, int]:
    """``fusetrack`` log lines to stderr: INFO by default, ``-v`` DEBUG, ``-q`` WARNING. Returns
    the handler and the logger's previous level, for :func:`main` to restore."""
    level = logging.INFO + 10 * (getattr(args, "quiet", 0) - getattr(args, "verbose", 0))
    logger = logging.getLogger("fusetrack")
    handler = logging.StreamHandler(sys.stderr)  # the stderr of this call (tests capture it)
    handler.setFormatter(logging.Formatter("%(message)s"))
    previous = logger.level
    logger.addHandler(handler)
    logger.setLevel(min(max(level, logging.DEBUG), logging.CRITICAL))
    return handler, previous


def _check_output_dir(out: str | Path) -> None:
    """Check ``--out`` before any work (nothing is created): the path, or its nearest existing
    ancestor, must be a directory fusetrack may write in; a path under a file used to fail
    only after the whole run."""
    path = Path(out).absolute()
    existing = next(p for p in (path, *path.parents) if p.exists())
    problem = None
    if not existing.is_dir():
        problem = f"{existing} is not a directory"
    elif not os.access(existing, os.W_OK | os.X_OK):
        problem = f"no permission to write in {existing}"
    if problem is not None:
        raise ConfigError(
            invalid("--out", str(out), f"a directory fusetrack can create and write ({problem})")
        )


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    handler, previous = _log_to_stderr(args)
    try:
        return _dispatch(args)
    except FusetrackError as err:
        from .evaluation import coloured

        print(f"fusetrack: {coloured('error', 'red', sys.stderr)}: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # Ctrl-C: a one-line note and the shell's 128 + SIGINT, no traceback
        print(f"fusetrack: interrupted ({args.command})", file=sys.stderr)
        return 130
    finally:
        logging.getLogger("fusetrack").removeHandler(handler)
        logging.getLogger("fusetrack").setLevel(previous)


def _dispatch(args: argparse.Namespace) -> int:
    """Run the parsed command; a :class:`FusetrackError` becomes exit status 2 in :func:`main`."""
    from .evaluation import RunContext
    from .experiments import REGISTRY, run_experiment

    if args.command in ("serve", "replay", "log") or getattr(args, "live", False):
        from .service import run_service_command

        return run_service_command(args)
    if (status := _run_track_commands(args)) is not None:
        return status
    if args.command == "track-video":
        from .tools import run_track_video_command

        return run_track_video_command(args)
    if args.command == "reports":
        from .tools import run_reports_command

        return run_reports_command(args)
    if args.command == "reproduce":
        from .tools import run_reproduce_command

        _check_output_dir(args.out)
        return run_reproduce_command(args)
    if args.command == "list":
        width = max(len(n) for n in REGISTRY)
        for name, info in REGISTRY.items():
            print(f"{name:<{width}}  {info.title}")
        return 0
    name = "demo" if args.command == "demo" else args.name
    _check_output_dir(args.out)
    ctx = RunContext(
        name=name,
        out_dir=args.out,
        quick=args.quick,
        runs=args.runs,
        seed=args.seed,
        engine=args.engine,
        scheduler=args.scheduler,
        workers=args.workers,
        progress=False if args.no_progress or getattr(args, "quiet", 0) else None,
        extra=_extra_options(args),
        resume=not getattr(args, "no_resume", False),
    )
    summary = run_experiment(ctx)
    _print_summary(summary, ctx.out_dir)
    if not ctx.quick:  # a full-size run into reports/NAME: the tally and verdicts follow it
        from .tools import refresh_reports_folder

        note = refresh_reports_folder(ctx.out_dir)
        if note:
            print(note, file=sys.stderr)
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
