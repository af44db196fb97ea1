"""One way to configure (issue 16 item 4): every experiment's options are a pydantic model checked
before any work; ``--version``; ``-v``/``-q`` set the logging level; ``run NAME --help`` shows the
options with their defaults."""

from __future__ import annotations

import ast
import logging
import sys
import types
from importlib.metadata import version
from pathlib import Path

import pandas as pd
import pytest
from pydantic import Field

from fusetrack.cli import main
from fusetrack.core.errors import ConfigError
from fusetrack.evaluation.options import ExperimentOptions, describe_options, parse_options
from fusetrack.evaluation.report import Claim, Outcome, RunContext
from fusetrack.experiments import REGISTRY, ExperimentInfo, options_model
from fusetrack.experiments import registry as registry_module

EXPERIMENTS = Path(registry_module.__file__).parent


@pytest.mark.parametrize("name", sorted(REGISTRY))
def test_unknown_key_fails_before_any_work_naming_the_valid_keys(name, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", name, "--set", "unknown=1", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "unknown" in err and "not a known key" in err and name in err
    keys = options_model(name).model_fields
    assert all(k in err for k in keys) if keys else "takes none" in err
    assert not out.exists()  # nothing ran, nothing was written


def test_every_options_class_of_an_experiment_module_is_registered():
    """The registry names each experiment's options model: a class deriving from an ``*Options``
    class in a target module and not named there would be silently unused (read without import)."""
    declared: set[tuple[str, str]] = set()
    for module in {info.target.split(":")[0] for info in REGISTRY.values()}:
        tree = ast.parse((EXPERIMENTS / (module.replace(".", "/") + ".py")).read_text())
        declared |= {
            (module, node.name)
            for node in tree.body
            if isinstance(node, ast.ClassDef)
            and any(getattr(b, "id", "").endswith("Options") for b in node.bases)
        }
    named = {(i.target.split(":")[0], i.options) for i in REGISTRY.values() if i.options}
    assert declared == named
    for name, info in REGISTRY.items():
        if info.options:
            assert options_model(name).__name__ == info.options


@pytest.mark.parametrize(
    "name,option,field",
    [
        ("ercan2013-selection", "occluders=-1", "occluders"),
        ("ercan2013-selection", "sigma_psi=x", "sigma_psi"),
        ("ercan2013-lab", "steps=0", "steps"),
        ("lee2009-periodic-sweep", "periods=5", "periods"),
        ("lee2009-periodic-sweep", "periods=1,x", "periods"),
        ("lee2009-projected-planes", "measurements=radar", "measurements"),
        ("kushwaha2010-harmonic-sources", "seconds=-3", "seconds"),
    ],
)
def test_bad_value_is_refused_naming_the_field(name, option, field, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", name, "--set", option, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert field in err and option.split("=")[1] in err and "expected" in err
    assert not out.exists()


def test_config_flag_is_an_option_too(tmp_path, capsys):
    """``--config`` on an experiment that reads no YAML file is refused, not ignored."""
    assert main(["run", "zhai2007-scalar", "--config", "x.yaml", "--out", str(tmp_path)]) == 2
    assert "--config is not a known key" in capsys.readouterr().err


def test_values_are_typed_and_defaults_are_todays():
    sweep = parse_options(options_model("lee2009-periodic-sweep"), {"periods": "100, 1,10,1"})
    assert sweep.periods == (1, 10, 100)  # type: ignore[attr-defined]
    sel = parse_options(options_model("ercan2013-selection"), {"occluders": "5"})
    assert sel.occluders == 5 and sel.sigma_psi == 31.0 and sel.steps is None  # type: ignore[attr-defined]
    assert options_model("lee2009-projected-planes")().measurements == "gaussian"  # type: ignore[attr-defined]


def test_options_of_a_context_built_in_code_are_validated_too(tmp_path):
    model = options_model("lee2009-periodic-sweep")
    assert model.of(RunContext("x", tmp_path)).periods is None  # type: ignore[attr-defined]
    with pytest.raises(ConfigError, match="periods"):
        model.of(RunContext("x", tmp_path, extra={"periods": "0,1"}))


def test_version(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.strip() == f"fusetrack {version('fusetrack')}"


def test_help_shows_options_with_defaults_and_descriptions(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["run", "ercan2013-selection", "--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert "--set sigma_psi=FLOAT (default 31.0)" in out
    assert "--set occluders=INT" in out and "40 in the L room" in out and "--config PATH" in out
    with pytest.raises(SystemExit):
        main(["run", "lee2009-projected-planes", "--help"])
    assert "--measurements gaussian|audio (default gaussian)" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        main(["run", "zhai2007-scalar", "--help"])
    out = capsys.readouterr().out
    assert "--quick" in out and "options of zhai2007-scalar" in out and "(none)" in out


class _ToyOptions(ExperimentOptions):
    size: int = Field(3, ge=1, description="rows to write")


_SEEN: list[RunContext] = []


def _toy_run(ctx: RunContext) -> Outcome:
    opts = _ToyOptions.of(ctx)
    _SEEN.append(ctx)
    logging.getLogger("fusetrack.experiments.toy").info("toy: progress line")
    logging.getLogger("fusetrack.experiments.toy").debug("toy: debug line")
    df = pd.DataFrame({"run": range(opts.size)})
    return Outcome(df, [Claim("c", "toy", 1, 1, 0, True, "paper")], "body", opts.size)


@pytest.fixture
def toy(monkeypatch):
    module = types.ModuleType("fusetrack.experiments._toy")
    module.run, module.Options = _toy_run, _ToyOptions  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, module.__name__, module)
    info = ExperimentInfo("toy", "_toy:run", "A toy", "none", options="Options")
    monkeypatch.setitem(REGISTRY, "toy", info)
    return "toy"


@pytest.mark.parametrize(
    "flags,info,debug", [([], True, False), (["-q"], False, False), (["-v"], True, True)]
)
def test_verbosity_sets_the_logging_level(toy, flags, info, debug, tmp_path, capsys):
    assert main([*flags, "run", toy, "--set", "size=2", "--out", str(tmp_path)]) == 0
    captured = capsys.readouterr()
    assert ("toy: progress line" in captured.err) is info
    assert ("toy: debug line" in captured.err) is debug
    assert (_SEEN[-1].progress is False) is (flags == ["-q"])  # -q: no progress bar either
    # the summary is the product: always printed
    assert "1 of 1 paper claims hold (2 runs" in captured.out
    assert "--set size=2`" in (tmp_path / "report.md").read_text().splitlines()[2]
    assert main(["run", toy, *flags, "--out", str(tmp_path)]) == 0  # after the command, too
    assert ("toy: progress line" in capsys.readouterr().err) is info


def test_describe_options_of_a_model_without_options():
    assert describe_options(ExperimentOptions) == "  (none)"


def test_every_example_yaml_is_described_by_a_pydantic_model(tmp_path):
    """Each file in examples/ validates against its model; an unknown key is refused by name."""
    from fusetrack.evaluation.options import load_yaml
    from fusetrack.experiments.ercan2013.scenes import RoomConfig
    from fusetrack.service.config import load_config

    examples = sorted((Path(__file__).resolve().parents[2] / "examples").glob("*.yaml"))
    assert examples
    for path in examples:
        if path.name.startswith("ercan2013_room"):
            assert len(load_yaml(RoomConfig, path).cameras) == 6
        else:
            assert load_config(path) is not None
    bad = tmp_path / "room.yaml"
    bad.write_text((examples[0].parent / "ercan2013_room.yaml").read_text() + "colour: red\n")
    with pytest.raises(
        ConfigError, match=r"config.colour is not a known key: expected one of .*cameras"
    ):
        load_yaml(RoomConfig, bad)


def test_out_under_a_file_fails_before_any_work(tmp_path, capsys, monkeypatch):
    """Issue 18: ``--out`` under a file used to fail with a traceback after the whole run."""
    import fusetrack.experiments as experiments
    from fusetrack.cli import main

    a_file = tmp_path / "report.md"
    a_file.write_text("not a directory")
    ran = []
    monkeypatch.setattr(experiments, "run_experiment", lambda *a, **k: ran.append(a))
    code = main(["run", "ercan2013-occluders", "--quick", "--out", str(a_file / "x")])
    assert code == 2 and not ran
    err = capsys.readouterr().err
    assert "--out" in err and "is not a directory" in err and "Traceback" not in err


def test_ctrl_c_ends_any_command_without_a_traceback(capsys, monkeypatch):
    """Issue 18: Ctrl-C on a busy ``serve`` printed a KeyboardInterrupt traceback; any command
    interrupted now exits 130 with one line."""
    import fusetrack.cli as cli

    def interrupted(args):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "_dispatch", interrupted)
    assert cli.main(["list"]) == 130
    err = capsys.readouterr().err
    assert err.strip() == "fusetrack: interrupted (list)"
