"""MkDocs hooks for the fusetrack site (``mkdocs.yml``: ``hooks:``).

Nothing on the site is typed twice; at build time this hook

* adds ``reports/`` (every ``report.md`` and figure) and ``benchmarks/`` (its ``*.md`` and
  figures) to the site under the same paths, so pages link ``../reports/NAME/fig.png`` and the
  reports render as pages with their figures;
* expands ``{{ cli_reference }}`` into the help of every ``fusetrack`` subcommand, from
  ``fusetrack.cli.build_parser()``, and ``{{ experiments PREFIX }}`` into a table of the
  experiments whose names start with ``PREFIX``: title from the registry, the claims that hold
  from ``reports/NAME/summary.json``;
* expands ``{{ verdicts PREFIX }}`` into the verdict on the central contributions of the paper
  whose experiments start with ``PREFIX`` (``fusetrack/experiments/PREFIX/verdict.py``, judged
  from ``reports/*/summary.json`` as in ``reports/README.md``);
* expands ``{{ readme_code "HEADING" }}`` into the first code block under that heading of
  ``README.md`` (the commands are written once), and ``{{ figure NAME/FILE.png "caption" }}`` into
  that figure of ``reports/`` or, while the report is missing, a note saying how to make it;
* expands ``{{ tutorial NAME }}`` into the tutorial ``docs/tutorials/NAME.py``: its module
  docstring as the page's text (the first line its title), its committed figure
  ``docs/tutorials/figures/NAME.png`` and the script itself without the docstring, so the page
  shows exactly the code the tests run;
* gives each API page's ``::: fusetrack.PACKAGE`` block (with no options of its own) the
  package's public names as ``members``: the packages re-export their names from submodules
  (``from .kalman import KalmanFilter as KalmanFilter``), which mkdocstrings lists only when
  named.
"""

from __future__ import annotations

import argparse
import ast
import json
import re
import sys
from pathlib import Path
from typing import Any

from mkdocs.structure.files import File, Files

ROOT = Path(__file__).resolve().parents[2]
COPIED = {"reports": ("*.md", "*.png"), "benchmarks": ("*.md", "*.png")}
HELP_WIDTH = 100


def on_config(config: Any) -> Any:
    """Import this tree's sources, not an installed copy (MkDocs restores ``sys.path`` after
    loading a hook module, so this is done here)."""
    if str(ROOT / "src") not in sys.path:
        sys.path.insert(0, str(ROOT / "src"))
    if "fusetrack" in sys.modules and not sys.modules["fusetrack"].__file__.startswith(str(ROOT)):
        raise RuntimeError(f"fusetrack was imported from {sys.modules['fusetrack'].__file__}")
    return config


def on_files(files: Files, config: Any) -> Files:
    """Add the reports and benchmarks (markdown and figures) under their repository paths."""
    for folder, patterns in COPIED.items():
        for pattern in patterns:
            for path in sorted((ROOT / folder).rglob(pattern)):
                uri = path.relative_to(ROOT).as_posix()
                if files.get_file_from_path(uri) is None:
                    files.append(
                        File(uri, str(ROOT), config["site_dir"], config["use_directory_urls"])
                    )
    return files


def on_page_markdown(markdown: str, page: Any, config: Any, files: Files) -> str:
    markdown = markdown.replace("{{ cli_reference }}", cli_reference())
    markdown = re.sub(
        r"\{\{ experiments ([\w-]+) \}\}",
        lambda m: experiments_table(m.group(1), page.file.src_uri),
        markdown,
    )
    markdown = re.sub(
        r"\{\{ verdicts ([\w-]+) \}\}",
        lambda m: verdicts(m.group(1), page.file.src_uri),
        markdown,
    )
    markdown = re.sub(
        r'\{\{ readme_code "([^"]+)" \}\}', lambda m: readme_code(m.group(1)), markdown
    )
    markdown = re.sub(
        r'\{\{ figure ([\w./-]+) "([^"]+)" \}\}',
        lambda m: figure(m.group(1), m.group(2), page.file.src_uri),
        markdown,
    )
    markdown = re.sub(r"\{\{ tutorial ([\w-]+) \}\}", lambda m: tutorial(m.group(1)), markdown)
    return re.sub(r"^::: (fusetrack\.\w+)\s*$(?!\n\s+options:)", _api_block, markdown, flags=re.M)


# --- the CLI reference ------------------------------------------------------------------------


def _help(parser: argparse.ArgumentParser) -> str:
    parser.formatter_class = lambda prog: argparse.HelpFormatter(prog, width=HELP_WIDTH)
    return parser.format_help()


def _subcommands(parser: argparse.ArgumentParser) -> dict[str, tuple[str, Any]]:
    """``{name: (one-line help, subparser)}`` in the parser's order."""
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    helps = {c.dest: c.help or "" for c in action._choices_actions}
    return {name: (helps.get(name, ""), sub) for name, sub in action.choices.items()}


def cli_reference() -> str:
    """Markdown: ``fusetrack --help`` and every subcommand's ``--help``, then the experiments."""
    from fusetrack.cli import build_parser

    parser = build_parser()
    parts = ["## fusetrack", "", "```text", _help(parser).rstrip(), "```", ""]
    for name, (summary, sub) in _subcommands(parser).items():
        parts += [f"## fusetrack {name}", "", summary, "", "```text", _help(sub).rstrip(), "```"]
        parts.append("")
    return "\n".join([*parts, _experiment_options()])


def _experiment_options() -> str:
    """Every experiment with its ``--set`` options (what ``run NAME --help`` adds)."""
    from fusetrack.evaluation import describe_options
    from fusetrack.experiments import REGISTRY, options_model

    parts = ["## Experiments and their options", ""]
    parts.append("`fusetrack run NAME --help` prints these after the options above.")
    for name, info in REGISTRY.items():
        options = describe_options(options_model(name))
        parts += ["", f"### {name}", "", info.title, "", "```text", options, "```"]
    return "\n".join(parts)


# --- README code and report figures ---------------------------------------------------------


def readme_code(heading: str) -> str:
    """The first fenced code block after the line ``heading`` in README.md, fences included."""
    text = (ROOT / "README.md").read_text()
    lines = text.splitlines()
    if heading not in lines:
        raise ValueError(f"README.md has no line {heading!r}")
    rest = "\n".join(lines[lines.index(heading) + 1 :])
    match = re.search(r"^```.*?^```$", rest, flags=re.M | re.S)
    if match is None:
        raise ValueError(f"README.md has no code block under {heading!r}")
    return match.group(0)


def figure(path: str, caption: str, page_uri: str) -> str:
    """``reports/PATH`` as an image with its caption, or a note while the report is missing."""
    name = path.split("/")[0]
    if (ROOT / "reports" / path).exists():
        up = "../" * page_uri.count("/")
        return f"![{caption}]({up}reports/{path})\n\n*{caption}* ({name})"
    return (
        f'!!! note "Figure not yet in reports/"\n    {caption}: `reports/{path}` appears after the '
        f"full-size run `fusetrack run {name} --out reports/{name}`."
    )


# --- tutorials ---------------------------------------------------------------------------------

TUTORIALS = ROOT / "docs" / "tutorials"


def tutorial(name: str) -> str:
    """Markdown for the page of ``docs/tutorials/NAME.py`` (a page in ``docs/tutorials/``): the
    docstring's first line as the title, the rest as text, the figure the script writes (run at
    full size and committed), a link to the script and its code without the docstring."""
    path = TUTORIALS / f"{name}.py"
    source = path.read_text()
    module = ast.parse(source)
    doc = ast.get_docstring(module, clean=True)
    first = module.body[0] if module.body else None
    if doc is None or first is None:
        raise ValueError(f"{path.relative_to(ROOT)} has no module docstring")
    title, _, text = doc.partition("\n")
    code = "\n".join(source.splitlines()[first.end_lineno :]).strip("\n")
    figure_path = TUTORIALS / "figures" / f"{name}.png"
    if not figure_path.exists():
        raise ValueError(
            f"{figure_path.relative_to(ROOT)} is missing: run the tutorial at full size"
        )
    return "\n".join(
        [
            f"# {title.strip().rstrip('.')}",
            "",
            text.strip(),
            "",
            f"![The figure {name}.py writes](figures/{name}.png)",
            "",
            f"## The script: [`{name}.py`]({name}.py)",
            "",
            "```python",
            code,
            "```",
        ]
    )


# --- experiments of one paper -----------------------------------------------------------------


def _verdict(name: str) -> tuple[str, str]:
    summary_path = ROOT / "reports" / name / "summary.json"
    if not summary_path.exists():
        return "no full-size report yet", ""
    summary = json.loads(summary_path.read_text())
    claims = summary["claims"]
    held = sum(bool(c["holds"]) for c in claims)
    runs = summary["runs"]
    return f"{held} of {len(claims)}", f"{runs} run{'s' * (runs != 1)}, {summary['seconds']:.0f} s"


def experiments_table(prefix: str, page_uri: str) -> str:
    """Markdown table of the experiments named ``PREFIX*`` with their full-size verdicts."""
    from fusetrack.experiments import REGISTRY

    up = "../" * page_uri.count("/")
    rows = ["| experiment | what | claims that hold (full size) | run |", "|---|---|---|---|"]
    for name, info in REGISTRY.items():
        if not name.startswith(prefix):
            continue
        held, run = _verdict(name)
        report = ROOT / "reports" / name / "report.md"
        link = f"[`{name}`]({up}reports/{name}/report.md)" if report.exists() else f"`{name}`"
        title = info.title.replace("|", "\\|")  # a bar inside a cell ends it
        rows.append(f"| {link} | {title} | {held} | {run} |")
    if len(rows) == 2:
        raise ValueError(f"no experiment starts with {prefix!r}")
    return "\n".join(rows)


def verdicts(prefix: str, page_uri: str) -> str:
    """Markdown: the verdict on the central contributions of the paper ``prefix``."""
    from fusetrack.experiments import paper_verdicts
    from fusetrack.tools.report_verdicts import paper_block, summary_claims

    up = "../" * page_uri.count("/")
    found = [v for v in paper_verdicts() if v.prefix == prefix]
    if not found:
        raise ValueError(f"no paper verdict has the prefix {prefix!r}")
    claims = summary_claims(ROOT / "reports")
    return "\n".join(paper_block(found[0], claims, lambda n: f"{up}reports/{n}/report.md"))


# --- API pages ---------------------------------------------------------------------------------


def public_names(package: str) -> tuple[list[str], list[str]]:
    """The names a package's ``__init__`` exports (``__all__``, else its imports and
    definitions without a leading underscore), split into (objects, submodules)."""
    init = ROOT / "src" / Path(*package.split(".")) / "__init__.py"
    tree = ast.parse(init.read_text())
    names: list[str] = []
    modules: list[str] = []
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(
            isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets
        ):
            names = [n for n in ast.literal_eval(node.value) if n not in modules]
            return names, modules
        if isinstance(node, ast.ImportFrom) and node.level == 1:
            found = [a.asname or a.name for a in node.names]
            (modules if node.module is None else names).extend(found)
        elif isinstance(node, ast.FunctionDef | ast.ClassDef):
            names.append(node.name)
        elif isinstance(node, ast.Assign | ast.AnnAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            names += [t.id for t in targets if isinstance(t, ast.Name)]
    keep = [n for n in dict.fromkeys(names) if not n.startswith("_")]
    return keep, [m for m in modules if not m.startswith("_")]


def api_block(package: str, heading_level: int = 2) -> str:
    """A ``:::`` block listing the package's public names, then one per exported subpackage."""
    names, modules = public_names(package)
    block = [f"::: {package}", "    options:", f"      members: {json.dumps(sorted(names))}"]
    if heading_level > 2:
        block += ["      show_root_heading: true", f"      heading_level: {heading_level - 1}"]
    for module in modules:
        block += ["", api_block(f"{package}.{module}", heading_level + 1)]
    return "\n".join(block)


def _api_block(match: re.Match[str]) -> str:
    return api_block(match.group(1))
