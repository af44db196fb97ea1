"""Options of an experiment and YAML configuration files, described by pydantic models.

An experiment declares its options near the top of its module::

    class Options(ExperimentOptions):
        occluders: int = Field(40, ge=0, description="moving occluders M")

``fusetrack run NAME --set occluders=20`` is checked against that model before any work
(:func:`parse_options`: an unknown key or a bad value raises :class:`ConfigError` naming the key,
the value and what is valid) and the experiment reads ``Options.of(ctx).occluders``. A YAML file is
read into a model the same way (:func:`load_yaml`). ``fusetrack run NAME --help`` prints
:func:`describe_options`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Literal, TypeVar, get_args, get_origin

from pydantic import BaseModel, ConfigDict, ValidationError
from pydantic_core import PydanticUndefined

from ..core import ConfigError, invalid

M = TypeVar("M", bound=BaseModel)
OptionsT = TypeVar("OptionsT", bound="ExperimentOptions")


class ExperimentOptions(BaseModel):
    """Base of every experiment's options: no unknown keys, frozen, finite numbers.

    An experiment without options uses this class itself (it has no fields)."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    @classmethod
    def of(cls: type[OptionsT], ctx: Any) -> OptionsT:
        """The validated options of the run ``ctx`` (a :class:`~.report.RunContext`): those the
        registry checked before the run, or ``ctx.extra`` checked now (a context built in code)."""
        opts = getattr(ctx, "options", None)
        if isinstance(opts, cls):
            return opts
        return parse_options(cls, getattr(ctx, "extra", {}))


def _flag(key: str, where: str) -> str:
    """How the user wrote ``key``: ``--config`` and ``--measurements`` are flags of their own."""
    if where == "--set" and key in ("config", "measurements"):
        return f"--{key}"
    return f"{where} {key}" if where == "--set" else f"{where}.{key}"


def _valid_keys(model: type[BaseModel]) -> str:
    keys = sorted(model.model_fields)
    return f"one of {', '.join(keys)}" if keys else "no option (this one takes none)"


def _submodel(model: type[BaseModel], loc: Sequence[str]) -> type[BaseModel]:
    """The (nested) model that holds the key at ``loc``, e.g. ``cameras.0.yaw`` -> the camera's."""
    for part in loc[:-1]:
        field = model.model_fields.get(part)
        if field is None:
            continue  # a list index
        inner = [field.annotation, *get_args(field.annotation)]
        models = [t for t in inner if isinstance(t, type) and issubclass(t, BaseModel)]
        if not models:
            return model
        model = models[0]
    return model


def validation_error(
    err: ValidationError, model: type[BaseModel], where: str, raw: Mapping[str, Any]
) -> ConfigError:
    """One :class:`ConfigError` for the first problem pydantic found: field, value, what is valid.
    A ``--set`` value is shown whole (``periods='1,x'``), a YAML one where the problem is."""
    first = err.errors()[0]
    loc = [str(p) for p in first["loc"]] or ["?"]
    if where == "--set":  # flat KEY=VALUE strings: the key and the value as typed
        loc, first["input"] = loc[:1], raw.get(loc[0], first.get("input"))
    key = loc[-1]
    flag = _flag(".".join(loc) if where != "--set" else key, where)
    owner = _submodel(model, loc)
    if first["type"] == "extra_forbidden":
        return ConfigError(f"{flag} is not a known key: expected {_valid_keys(owner)}")
    field = owner.model_fields.get(key)
    if first["type"] == "missing":
        what = f": {field.description}" if field is not None and field.description else ""
        return ConfigError(f"{flag} is missing: it is required{what}")
    about = f" ({key}: {field.description})" if field is not None and field.description else ""
    msg = first["msg"].removeprefix("Value error, ")
    return ConfigError(invalid(flag, first.get("input"), f"{msg[:1].lower()}{msg[1:]}{about}"))


def parse_options(model: type[M], raw: Mapping[str, Any], where: str = "--set") -> M:
    """``raw`` (``KEY -> value`` strings from ``--set``, or a parsed YAML mapping) validated
    against ``model``; raise :class:`ConfigError` on an unknown key or a bad value."""
    if not isinstance(raw, Mapping):
        raise ConfigError(invalid(where, type(raw).__name__, f"a mapping of {_valid_keys(model)}"))
    try:
        return model.model_validate(dict(raw))
    except ValidationError as err:
        raise validation_error(err, model, where, raw) from None


def load_yaml(model: type[M], path: str | Path, where: str = "config") -> M:
    """A YAML file read into ``model``; a missing file, bad YAML or bad content is a ConfigError."""
    import yaml

    p = Path(path)
    if not p.is_file():
        raise ConfigError(invalid(where, str(p), "an existing YAML file"))
    try:
        spec = yaml.safe_load(p.read_text())
    except yaml.YAMLError as err:
        raise ConfigError(invalid(where, str(p), f"valid YAML ({err})")) from None
    return parse_options(model, spec, where)


def _metavar(annotation: Any) -> str:
    """``int | None`` -> ``INT``, ``Literal['a', 'b']`` -> ``a|b``, ``tuple[int, ...]`` -> ``INT,...``."""
    args = [a for a in get_args(annotation) if a is not type(None)]
    if get_origin(annotation) is Literal:
        return "|".join(map(str, args))
    if get_origin(annotation) is tuple:
        return f"{_metavar(args[0])},..."
    if args and get_origin(annotation) is not tuple:  # a union with None
        return _metavar(args[0])
    return getattr(annotation, "__name__", str(annotation)).upper()


def describe_options(model: type[BaseModel]) -> str:
    """The options of ``model`` as help text: one line per key with its default and meaning."""
    if not model.model_fields:
        return "  (none)"
    lines = []
    for key, field in model.model_fields.items():
        flag = _flag(key, "--set")
        sep = "=" if flag.startswith("--set") else " "
        default = field.get_default(call_default_factory=True)
        shown = "" if default is None or default is PydanticUndefined else f" (default {default})"
        lines.append(f"  {flag}{sep}{_metavar(field.annotation)}{shown}")
        if field.description:
            lines.append(f"      {field.description}")
    return "\n".join(lines)


__all__ = ["ExperimentOptions", "describe_options", "load_yaml", "parse_options"]
