"""Resumable Monte Carlo runs: every finished run's rows are appended to a checkpoint file, so a
full-size reproduction that is stopped (a killed session, a reboot) resumes where it stopped.

A run is a pure function of its configuration and seed (:mod:`.montecarlo`), so rows saved by an
interrupted invocation equal the ones a fresh invocation would compute -- provided the code is the
same. Each record therefore carries the fingerprint of fusetrack's source (:func:`code_fingerprint`)
and is used only by the same code; records of other code are ignored. A record is written and
flushed to disk as soon as its run finishes; a record cut short by a kill is dropped (and the file
truncated to the last whole record) when the file is next opened.
"""

from __future__ import annotations

import hashlib
import json
import os
import pickle
from collections.abc import Callable, Mapping
from functools import cache
from pathlib import Path
from typing import Any

import fusetrack

from ..core import ConfigError

Rows = list[dict[str, Any]]

CHECKPOINT_NAME = ".monte_carlo_checkpoint.pkl"
"""The checkpoint file in a run's output folder (removed once the run's outputs are written)."""


@cache
def code_fingerprint() -> str:
    """SHA-256 over the paths and contents of every ``.py`` file of the installed fusetrack."""
    root = Path(fusetrack.__file__).parent
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        digest.update(path.relative_to(root).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def job_key(fn: Callable[..., Any], config: Mapping[str, Any], run: int, seed: int) -> str:
    """What identifies one Monte Carlo run: the function, its configuration, run index and seed."""
    text = json.dumps(
        [f"{fn.__module__}.{fn.__qualname__}", dict(config), run, seed],
        sort_keys=True,
        default=repr,
    )
    return hashlib.sha256(text.encode()).hexdigest()


_HEADER = pickle.dumps(None, protocol=pickle.HIGHEST_PROTOCOL)[:2]
"""How every record starts: the pickle protocol opcode and version."""


def _foreign(path: Path, err: Exception) -> bool:
    """A first record that failed to load is another program's file, not one cut short by a kill:
    it does not start like a record, or it is a whole pickle of another shape."""
    with path.open("rb") as f:
        start = f.read(len(_HEADER))
    return start != _HEADER[: len(start)] or isinstance(err, (ValueError, TypeError))


class Checkpoint:
    """The finished runs of one output folder: ``done[key]`` their rows; :meth:`save` adds one."""

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self.done: dict[str, Rows] = {}
        self._load()
        self.loaded = frozenset(self.done)
        """The runs an earlier invocation left (not those this one saves)."""

    def _load(self) -> None:
        """Read the whole records of this code; cut a partial last record off the file."""
        if not self.path.exists():
            return
        good = 0
        with self.path.open("rb") as f:
            while True:
                try:
                    fingerprint, key, rows = pickle.load(f)
                except EOFError:
                    break
                except (pickle.UnpicklingError, ValueError, TypeError, AttributeError) as err:
                    if good == 0 and _foreign(self.path, err):
                        raise ConfigError(
                            f"checkpoint={str(self.path)!r} is not a file fusetrack wrote (a "
                            "full-size run keeps its finished runs there): move it away, or pass "
                            "--no-resume to delete it"
                        ) from err
                    break  # a record cut short by a kill: keep what came before
                good = f.tell()
                if fingerprint == code_fingerprint():
                    self.done[key] = rows
        if good < self.path.stat().st_size:
            with self.path.open("r+b") as f:
                f.truncate(good)

    def save(self, key: str, rows: Rows) -> None:
        """Append one finished run and flush it to disk before returning."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        with self.path.open("ab") as f:
            pickle.dump((code_fingerprint(), key, rows), f, protocol=pickle.HIGHEST_PROTOCOL)
            f.flush()
            os.fsync(f.fileno())
        self.done[key] = rows

    def remove(self) -> None:
        """Delete the file (the run's outputs are written: nothing left to resume)."""
        self.path.unlink(missing_ok=True)


__all__ = ["CHECKPOINT_NAME", "Checkpoint", "code_fingerprint", "job_key"]
