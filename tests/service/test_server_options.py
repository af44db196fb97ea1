"""uvicorn's options: the WebSocket frame limit from the config, log colours only on a terminal
and never with NO_COLOR."""

from __future__ import annotations

import io
from types import SimpleNamespace

from fusetrack.service import server


def _node(limit: int = 1234) -> SimpleNamespace:
    return SimpleNamespace(cfg=SimpleNamespace(limits=SimpleNamespace(max_message_bytes=limit)))


class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_frame_limit_and_colours(monkeypatch):
    monkeypatch.delenv("NO_COLOR", raising=False)
    monkeypatch.setenv("TERM", "xterm")
    monkeypatch.setattr(server.sys, "stderr", _Tty())
    opts = server.uvicorn_options(_node())  # type: ignore[arg-type]
    assert opts["ws_max_size"] == 1234 and opts["use_colors"] is True
    monkeypatch.setenv("NO_COLOR", "1")
    assert server.uvicorn_options(_node())["use_colors"] is False  # type: ignore[arg-type]
    monkeypatch.delenv("NO_COLOR")
    monkeypatch.setattr(server.sys, "stderr", io.StringIO())  # not a terminal
    assert server.uvicorn_options(_node())["use_colors"] is False  # type: ignore[arg-type]
