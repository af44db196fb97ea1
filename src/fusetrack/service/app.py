"""The node's web application (FastAPI on Starlette): ingest, tracks, status and the dashboard.

Reading (no key needed unless the config names ``readers``: then ``/tracks``, ``/sensors``,
``/health``, ``/metrics`` and ``/ws/tracks`` need a reader's or a node's bearer token, in the
``Authorization`` header or as ``?token=``; the dashboard passes on its own ``?token=``):

* ``GET /`` the dashboard, ``GET /static/dashboard.js`` its script (served here: no CDN);
* ``GET /tracks`` the latest track state and its recent trail; ``GET /sensors`` each sensor's
  geometry, last reading and its age; ``GET /health``; ``GET /metrics`` (Prometheus text);
* ``GET /schema`` the JSON Schema of sensor messages (``/openapi.json`` has it too);
* ``WS /ws/tracks`` one JSON text frame per fusion tick (``{"type": "tick", "track": ...}``).

Writing (``Authorization: Bearer <node token>``; see :func:`.auth.bearer_token`):

* ``POST /ingest`` a message or a batch, ``application/json`` or ``application/msgpack``;
  answers each message's outcome. 401 without a valid token (429 once the client's address
  has failed ``limits.auth_failure_burst`` times), 413 when too large, 400 when nothing
  parses, 503 (``Retry-After``) when the node is overloaded;
* ``WS /ws/ingest`` the same per frame (text: JSON, binary: MessagePack).

The lifespan runs the tick loop and, when given a socket, the UDP listener (:mod:`.udp`).
"""

from __future__ import annotations

import asyncio
import contextlib
import socket
from collections.abc import AsyncIterator, Callable
from importlib import resources
from typing import Any

from fastapi import Depends, FastAPI, HTTPException, Request, WebSocket, WebSocketDisconnect
from fastapi.responses import HTMLResponse, JSONResponse, Response
from pydantic.json_schema import models_json_schema

from .mqtt import MqttBridge
from .node import FusionNode, Outcome
from .schema import MessageBatch, SensorMessage, TrackState, message_json_schema
from .udp import UdpListener

_STATIC = resources.files(__package__) / "static"
_MSGPACK_TYPES = ("application/msgpack", "application/x-msgpack", "application/vnd.msgpack")


def _encoding_of(content_type: str | None) -> str:
    ct = (content_type or "application/json").split(";")[0].strip().lower()
    return "msgpack" if ct in _MSGPACK_TYPES else "json"


def _status(outcomes: list[Outcome]) -> int:
    reasons = {o.reason for o in outcomes if not o.accepted}
    if "overload" in reasons:
        return 503
    if "oversized" in reasons:
        return 413
    if len(outcomes) == 1 and reasons & {"malformed", "schema"}:
        return 400
    return 200


def _summary(outcomes: list[Outcome]) -> dict[str, Any]:
    n = sum(o.accepted for o in outcomes)
    return {
        "accepted": n,
        "rejected": len(outcomes) - n,
        "results": [o.as_dict() for o in outcomes],
    }


async def _read_limited(request: Request, limit: int) -> bytes | None:
    """The body, or None when it is longer than ``limit`` bytes (never reads much past it)."""
    length = request.headers.get("content-length")
    if length is not None and length.isdigit() and int(length) > limit:
        return None
    chunks, size = [], 0
    async for chunk in request.stream():
        size += len(chunk)
        if size > limit:
            return None
        chunks.append(chunk)
    return b"".join(chunks)


def create_app(node: FusionNode, udp_socket: socket.socket | None = None) -> FastAPI:
    """The ASGI application of ``node`` (and its UDP listener on ``udp_socket``, if given; and
    its MQTT bridge, :mod:`.mqtt`, when the config has an ``mqtt`` section)."""
    bridge = MqttBridge(node, node.cfg.mqtt) if node.cfg.mqtt is not None else None
    app = FastAPI(
        title="fusetrack fusion node",
        version="1",
        summary="Sensor nodes stream readings; the node fuses them and publishes tracks.",
        lifespan=_lifespan(node, udp_socket, bridge),
    )
    app.state.node = node
    _reading_routes(app, node)
    _ingest_routes(app, node)
    app.openapi = lambda: _openapi(app)  # type: ignore[method-assign]
    return app


def _lifespan(
    node: FusionNode, udp_socket: socket.socket | None, bridge: MqttBridge | None = None
) -> Callable[[FastAPI], contextlib.AbstractAsyncContextManager[None]]:
    """Runs the tick loop (and the UDP listener, and the MQTT bridge) while the app serves."""
    poll = min(0.05, node.cfg.fusion.period / 4)

    @contextlib.asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        listener = UdpListener(node, udp_socket).start() if udp_socket is not None else None
        if bridge is not None:
            bridge.start()

        async def ticker() -> None:
            while True:
                if listener is not None:
                    listener.drain()  # what has arrived counts for the ticks now due
                # one tick per turn: a node that fell behind still answers HTTP in between
                fired = node.advance(limit=1)
                wait = node.until_due()
                if fired:
                    wait = 0.0
                elif wait is None:  # data clock: look again soon
                    wait = poll
                else:  # wall clock: wake when the next tick falls due, not up to a poll late
                    wait = min(poll, max(wait, 0.0))
                await asyncio.sleep(wait)

        task = asyncio.create_task(ticker())
        try:
            yield
        finally:
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await task
            if listener is not None:
                listener.close()
            if bridge is not None:
                await bridge.stop()
            node.commit()

    return lifespan


def _reading_routes(app: FastAPI, node: FusionNode) -> None:
    """The dashboard, tracks, sensors, health, metrics, schema and the tracks' WebSocket (the
    data ones need a reader's token when the config names ``readers``)."""

    def reader(request: Request) -> None:
        header, token = request.headers.get("authorization"), request.query_params.get("token")
        if not node.may_read(header, token):
            raise HTTPException(
                401, "a reader's or a node's bearer token is needed", {"WWW-Authenticate": "Bearer"}
            )

    read = [Depends(reader)]

    @app.get("/", response_class=HTMLResponse, include_in_schema=False)
    async def dashboard() -> HTMLResponse:
        return HTMLResponse((_STATIC / "dashboard.html").read_text())

    @app.get("/static/dashboard.js", include_in_schema=False)
    async def dashboard_script() -> Response:
        return Response((_STATIC / "dashboard.js").read_text(), media_type="text/javascript")

    @app.get("/tracks", dependencies=read, summary="the latest track state and its recent trail")
    async def tracks(history: int = 200) -> dict[str, Any]:
        return node.tracks_view(max(0, min(history, node.cfg.limits.history)))

    @app.get(
        "/sensors", dependencies=read, summary="each sensor's geometry, last reading and its age"
    )
    async def sensors() -> dict[str, Any]:
        return {"area": node.cfg.area, "sensors": node.sensors_view()}

    @app.get(
        "/health",
        dependencies=read,
        summary="status, clock, counts of accepted and refused messages",
    )
    async def health() -> dict[str, Any]:
        return node.health()

    @app.get("/metrics", dependencies=read, summary="Prometheus text format")
    async def metrics() -> Response:
        return Response(node.metrics_text(), media_type="text/plain; version=0.0.4")

    @app.get("/schema", summary="JSON Schema of what a sensor node may send")
    async def schema() -> dict[str, Any]:
        return message_json_schema()

    @app.websocket("/ws/tracks")
    async def ws_tracks(ws: WebSocket) -> None:
        if not node.may_read(ws.headers.get("authorization"), ws.query_params.get("token")):
            await ws.close(code=1008, reason="unauthorized")
            return
        q = node.subscribe()
        if q is None:  # limits.max_subscribers: try again later (RFC 6455 close code 1013)
            await ws.close(code=1013)
            return
        await ws.accept()
        try:
            hello = {"type": "hello", **node.tracks_view(), "area": node.cfg.area}
            await ws.send_json(hello)
            while True:
                await ws.send_text(await q.get())
        except (WebSocketDisconnect, RuntimeError):
            pass
        finally:
            node.unsubscribe(q)


_BODY_SCHEMA = {
    "oneOf": [
        {"$ref": "#/components/schemas/SensorMessage"},
        {"$ref": "#/components/schemas/MessageBatch"},
    ]
}


def _ingest_routes(app: FastAPI, node: FusionNode) -> None:
    """``POST /ingest`` and ``WS /ws/ingest`` (a node's bearer token)."""
    limit = node.cfg.limits.max_message_bytes

    @app.post(
        "/ingest",
        summary="send readings (bearer token of the sending node)",
        openapi_extra={
            "requestBody": {
                "required": True,
                "content": {
                    "application/json": {"schema": _BODY_SCHEMA},
                    "application/msgpack": {"schema": _BODY_SCHEMA},
                },
            }
        },
    )
    async def ingest(request: Request) -> JSONResponse:
        who = node.authorize(request.headers.get("authorization"))
        if who is None:  # refused before the body is read
            source = request.client.host if request.client else None
            refused = node.refuse_unauthenticated(
                source, "unauthorized", "missing or unknown bearer token"
            )
            if refused.reason == "rate_limited":
                return JSONResponse({"error": refused.detail}, 429, {"Retry-After": "1"})
            return JSONResponse(
                {"error": "unauthorized: a node's bearer token is needed"},
                401,
                {"WWW-Authenticate": "Bearer"},
            )
        body = await _read_limited(request, limit)
        if body is None:
            node.reject("oversized", f"body over {limit} bytes")
            return JSONResponse({"error": f"body over {limit} bytes"}, 413)
        outcomes = node.ingest_payload(body, _encoding_of(request.headers.get("content-type")), who)
        node.commit()
        status = _status(outcomes)
        headers = {"Retry-After": "1"} if status == 503 else None
        return JSONResponse(_summary(outcomes), status, headers)

    @app.websocket("/ws/ingest")
    async def ws_ingest(ws: WebSocket) -> None:
        who = node.authorize(ws.headers.get("authorization"))
        if who is None:
            source = ws.client.host if ws.client else None
            refused = node.refuse_unauthenticated(
                source, "unauthorized", "missing or unknown bearer token (WebSocket)"
            )
            await ws.close(code=1008, reason=refused.reason)
            return
        await ws.accept()
        try:
            while True:
                msg = await ws.receive()
                if msg["type"] == "websocket.disconnect":
                    break
                if msg.get("bytes") is not None:
                    payload, encoding = msg["bytes"], "msgpack"
                else:
                    payload, encoding = (msg.get("text") or "").encode(), "json"
                outcomes = node.ingest_payload(payload, encoding, who)
                node.commit()
                await ws.send_json(_summary(outcomes))
        except WebSocketDisconnect:
            pass


def _openapi(app: FastAPI) -> dict[str, Any]:
    """The OpenAPI document, with the message and track schemas in its components."""
    if app.openapi_schema is None:
        from fastapi.openapi.utils import get_openapi

        doc = get_openapi(title=app.title, version=app.version, routes=app.routes)
        _, defs = models_json_schema(
            [
                (SensorMessage, "validation"),
                (MessageBatch, "validation"),
                (TrackState, "serialization"),
            ],
            ref_template="#/components/schemas/{model}",
        )
        doc.setdefault("components", {}).setdefault("schemas", {}).update(defs["$defs"])
        app.openapi_schema = doc
    return app.openapi_schema
