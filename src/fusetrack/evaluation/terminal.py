"""Terminal habits: progress that also reaches logs and pipes, and colour only where it belongs.

On a terminal, progress is a ``tqdm`` bar; anywhere else (a log file, a pipe, CI) a bar's
carriage returns are noise and hiding progress leaves a long run silent, so
:class:`PlainProgress` prints one plain line every few seconds: done / total and the time
left. Colour follows https://no-color.org: none when ``NO_COLOR`` is set to anything non-empty,
when the stream is not a terminal, or when ``TERM=dumb``.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable
from typing import IO, Any

from tqdm.auto import tqdm

from ..core import ConfigError, invalid

PROGRESS_INTERVAL = 5.0  # seconds between two plain progress lines (read at each call)
_ANSI = {"green": "32", "red": "31", "yellow": "33", "bold": "1"}


def is_terminal(stream: IO[str] | Any) -> bool:
    """``stream.isatty()``, False for a stream without it or a closed one."""
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


def colour_enabled(stream: IO[str] | Any) -> bool:
    """Whether ANSI colours may be written to ``stream`` (no-color.org, and terminals only)."""
    if os.environ.get("NO_COLOR", ""):
        return False
    return os.environ.get("TERM") != "dumb" and is_terminal(stream)


def coloured(text: str, colour: str, stream: IO[str] | Any) -> str:
    """``text`` in ``colour`` (green, red, yellow, bold) when :func:`colour_enabled`, else as is."""
    if colour not in _ANSI:
        raise ConfigError(invalid("colour", colour, f"one of {sorted(_ANSI)}"))
    return f"\x1b[{_ANSI[colour]}m{text}\x1b[0m" if colour_enabled(stream) else text


def _duration(seconds: float) -> str:
    seconds = max(round(seconds), 0)
    if seconds < 60:
        return f"{seconds} s"
    minutes, seconds = divmod(seconds, 60)
    if minutes < 60:
        return f"{minutes} min {seconds:02d} s"
    hours, minutes = divmod(minutes, 60)
    return f"{hours} h {minutes:02d} min"


class PlainProgress:
    """Progress as plain lines, for output that is not a terminal.

    ``update()`` counts work done; a line such as ``demo: runs: 12/40, 25 s elapsed, about 58 s
    left`` is written when ``interval`` seconds have passed since the start or the last line,
    and a closing line when the work ends, if any line was written and the last one did not
    already say it (a run shorter than ``interval`` stays silent). ``interval`` defaults to :data:`PROGRESS_INTERVAL`; ``total=None``
    counts without a total; ``clock`` is injectable (tests).
    """

    def __init__(
        self,
        total: int | None,
        desc: str,
        unit: str = "run",
        *,
        stream: IO[str] | None = None,
        interval: float | None = None,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        interval = PROGRESS_INTERVAL if interval is None else interval
        if total is not None and total < 0:
            raise ConfigError(invalid("total", total, "None or an integer >= 0"))
        if not interval >= 0:
            raise ConfigError(invalid("interval", interval, "seconds >= 0 (0: a line per update)"))
        self.total, self.desc, self.unit = total, desc, unit
        self.stream = stream
        self.interval, self.clock = interval, clock
        self.done = 0
        self.lines = 0
        self._shown = -1  # ``done`` at the last line
        self._start = self._last = clock()
        self._first: tuple[float, int] | None = None  # (time, done) at the first update

    def line(self) -> str:
        """The progress line for the work done so far."""
        elapsed = self.clock() - self._start
        units = "" if self.desc.endswith(f"{self.unit}s") else f" {self.unit}s"
        count = f"{self.done}" if self.total is None else f"{self.done}/{self.total}"
        text = f"{self.desc}: {count}{units}, {_duration(elapsed)} elapsed"
        if self.total is not None and 0 < self.done < self.total:
            text += f", about {_duration(self._seconds_per_unit() * (self.total - self.done))} left"
        return text

    def _seconds_per_unit(self) -> float:
        """The rate since the first update (the warm-up before it, e.g. JIT compilation or
        starting workers, does not repeat), or since the start while only one update came."""
        t0, n0 = self._first if self._first is not None else (self._start, 0)
        if self.done > n0:
            return (self.clock() - t0) / (self.done - n0)
        return (self.clock() - self._start) / self.done

    def _write(self) -> None:
        stream = self.stream if self.stream is not None else sys.stderr
        print(self.line(), file=stream, flush=True)
        self.lines += 1
        self._shown = self.done
        self._last = self.clock()

    def update(self, n: int = 1) -> None:
        self.done += n
        if self._first is None:
            self._first = (self.clock(), self.done)
        if self.clock() - self._last >= self.interval:
            self._write()

    def close(self) -> None:
        """The closing line, if progress was shown and the last line is not already it."""
        if self.lines and self.done != self._shown:
            self._write()

    def __enter__(self) -> PlainProgress:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def progress_bar(
    total: int | None,
    desc: str,
    show: bool | None = None,
    unit: str = "run",
    *,
    stream: IO[str] | None = None,
    interval: float | None = None,
) -> Any:
    """Progress over ``total`` units on ``stream`` (default: stderr): nothing when ``show`` is
    False (``-q``, ``--no-progress``), a ``tqdm`` bar on a terminal, :class:`PlainProgress`
    lines otherwise. All three have ``update(n)`` and work as context managers."""
    out = stream if stream is not None else sys.stderr
    if show is False:
        return tqdm(total=total, disable=True)
    if is_terminal(out):
        return tqdm(total=total, desc=desc, unit=unit, file=out, leave=False)
    return PlainProgress(total, desc, unit, stream=out, interval=interval)
