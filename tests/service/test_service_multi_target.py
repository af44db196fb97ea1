"""Several targets through the association layer: a radar's plots of two targets streamed into
the node give two tracks, equal to an offline MCMCDA run over the same plots; over UDP too."""

from __future__ import annotations

import math
import time

import httpx
import numpy as np
import pytest

from fusetrack.association.mcmcda import MCMCDA, MCMCDAConfig
from fusetrack.core import ConfigError
from fusetrack.service.config import parse_config
from fusetrack.service.log import DurableLog, replay_log
from fusetrack.service.node import FusionNode
from fusetrack.service.replay import Recorded, replay
from fusetrack.service.schema import SensorMessage, reading_from_vector
from fusetrack.service.server import RunningNode, build_node

RADAR = (50.0, -10.0)
RATE = 4.0
N_MC = 150


def _network(**extra):
    return parse_config(
        {
            "area": [0, 100, 0, 60],
            "sensors": [
                {
                    "id": "radar",
                    "kind": "range_bearing",
                    "position": list(RADAR),
                    "sigma_range": 0.5,
                    "sigma_bearing": 0.01,
                }
            ],
            "nodes": [
                {"id": "radar-node", "key": "test-key-radar-node-00001", "sensors": ["radar"]}
            ],
            "fusion": {"rate_hz": RATE, "clock": "data", "lag": 0.5, "idle_flush": 0.3},
            "tracker": {
                "prior_mean": [50, 30, 0, 0],
                "prior_std": [50, 30, 5, 5],
                "association": {"method": "mcmcda", "n_mc": N_MC, "p_detect": 0.95},
            },
            **extra,
        }
    )


def _truth(t):
    return np.array([[20 + 2.0 * t, 20 + 0.5 * t], [80 - 1.5 * t, 40 - 0.3 * t]])


def _plots(duration, seed=0):
    """Both targets seen by the radar once per tick, 0.05 s before it (range, bearing)."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(1, round(duration * RATE) + 1):
        t = k / RATE - 0.05
        for p in _truth(t):
            d = p - RADAR
            r = math.hypot(*d) + 0.5 * rng.standard_normal()
            b = math.atan2(d[1], d[0]) + 0.01 * rng.standard_normal()
            out.append(Recorded(t, "radar", (r, b)))
    return out


def _offline(plots, ticks):
    """MCMCDA straight from the association module: the plots as positions, one step per tick."""
    mc = MCMCDA(MCMCDAConfig(dt=1 / RATE, window=8, n_mc=N_MC, p_detect=0.95, area=100 * 60.0))
    state, rng = mc.initial_state(), np.random.default_rng(0)
    out = []
    for k in ticks:
        y = [
            [
                RADAR[0] + p.value[0] * math.cos(p.value[1]),
                RADAR[1] + p.value[0] * math.sin(p.value[1]),
            ]
            for p in plots
            if (k - 1) / RATE < p.time <= k / RATE
        ]
        state = mc.step(state, np.array(y).reshape(-1, 2), rng)
        out.append({i + 1: x for i, (x, _) in mc.current_tracks(state).items()})
    return out


def test_two_targets_give_two_tracks_like_the_offline_association(tmp_path):
    cfg = _network()
    plots = _plots(12.0)
    clock = [0.0]
    node = FusionNode(cfg, wall=lambda: clock[0], log=DurableLog(tmp_path / "log.sqlite"))
    for i, p in enumerate(plots):
        m = SensorMessage(
            node="radar-node",
            seq=i + 1,
            sensor="radar",
            time=p.time,
            reading=reading_from_vector("range_bearing", p.value),
        )
        assert node.ingest_message(m, "radar-node").accepted
    states = node.advance()
    clock[0] += 1.0
    states += node.advance()  # the stream has paused: the last ticks
    assert node.aligner.last_tick == 47  # the last plot is at 11.95 s
    offline = _offline(plots, range(1, 48))
    live: list[dict[int, list[float]]] = [{} for _ in range(47)]
    for s in states:
        live[s.tick - 1][s.track] = s.state
    assert [sorted(d) for d in live] == [sorted(d) for d in offline]
    for got, want in zip(live, offline):
        for ident in want:
            np.testing.assert_allclose(got[ident], want[ident], rtol=0, atol=1e-9)
    # two tracks at the end, one on each target, with distinct ids
    view = node.tracks_view()
    assert [t["track"] for t in view["tracks"]] == [1, 2]  # two tracks, ids kept throughout
    assert all(len(d) == 2 for d in live[8:])
    final = np.array([t["position"] for t in view["tracks"]])
    err = np.linalg.norm(final[:, None, :] - _truth(11.75)[None], axis=2)
    assert sorted(err.argmin(axis=1).tolist()) == [0, 1] and err.min(axis=1).max() < 2.5
    assert node.health()["tracks"] == 2
    # the durable log (several states per tick) replays exactly
    _, again = replay_log(cfg, node.log)
    assert [s.model_dump() for s in again] == [s.model_dump() for s in states]
    assert [s.model_dump() for s, _ in node.log.ticks()] == [s.model_dump() for s in states]
    node.log.close()


def test_two_targets_over_udp_and_rest():
    cfg = _network()
    plots = _plots(6.0, seed=1)
    with RunningNode(build_node(cfg)) as running:
        host, port = running.udp
        out = replay(plots, cfg, f"udp://{host}:{port}", speed=float("inf"), encoding="msgpack")
        assert out["sent"] == len(plots)
        for _ in range(200):
            h = httpx.get(running.url + "/health").json()
            if h["tick"] >= 23:
                break
            time.sleep(0.05)
        tracks = httpx.get(running.url + "/tracks").json()
    assert h["accepted"] == len(plots) and h["tick"] >= 23
    assert len(tracks["tracks"]) == 2
    assert {e["track"] for e in tracks["history"]} >= {t["track"] for t in tracks["tracks"]}


def test_association_needs_position_detections():
    with pytest.raises(ConfigError, match="position detections"):
        parse_config(
            {
                "sensors": [{"id": "mic", "kind": "bearing", "position": [0, 0], "sigma": 0.1}],
                "nodes": [{"id": "n", "key": "test-key-n-0000000000001", "sensors": ["mic"]}],
                "tracker": {
                    "prior_mean": [0, 0, 0, 0],
                    "prior_std": [1, 1, 1, 1],
                    "association": {"method": "mcmcda"},
                },
            }
        )


@pytest.mark.parametrize(
    ("name", "network"), [("network-targets.yaml", "two-targets"), ("network-grid.yaml", "grid")]
)
def test_example_configs_are_the_scenario_networks(name, network):
    from fusetrack.service.config import load_config
    from fusetrack.service.scenarios import NETWORKS

    cfg, code = load_config(f"examples/{name}"), NETWORKS[network]()
    assert [s.model_dump() for s in cfg.sensors] == [s.model_dump() for s in code.sensors]
    assert cfg.tracker == code.tracker and cfg.fusion == code.fusion and cfg.area == code.area
    assert cfg.owner() == code.owner()


def test_two_targets_scenario_is_tracked_with_misses_and_false_plots():
    """The replayable scenario (radar with 5 % misses and false plots, one tag): two tracks, each
    on its target, ids kept from the first seconds to the end."""
    from fusetrack.service.scenarios import two_targets_network, two_targets_scenario

    cfg = two_targets_network(idle_flush=0.3)
    scn = two_targets_scenario(cfg, seed=2, duration=20.0)
    clock = [0.0]
    node = FusionNode(cfg, wall=lambda: clock[0])
    owner, kinds = cfg.owner(), {s.id: s.kind for s in cfg.sensors}
    for i, r in enumerate(scn.readings):
        m = SensorMessage(
            node=owner[r.sensor],
            seq=i + 1,
            sensor=r.sensor,
            time=r.time,
            reading=reading_from_vector(kinds[r.sensor], r.value),
        )
        assert node.ingest_message(m, owner[r.sensor]).accepted
    states = node.advance()
    clock[0] += 1.0
    states += node.advance()
    late = [s for s in states if s.time >= 5.0]
    assert {s.track for s in late} == {1, 2}  # no track lost, split or renamed after 5 s
    for s in late:
        k = int(abs(scn.truth_times - s.time).argmin())
        err = np.linalg.norm(scn.truth[k].reshape(2, 2) - s.position, axis=1)
        assert err.min() < 2.5, (s.tick, s.track, err)
    ticks = {s.tick for s in late}
    assert all(sum(s.tick == k for s in late) == 2 for k in ticks)


def test_forgetting_the_past_keeps_the_current_tracks_and_memory_flat():
    plots = _plots(10.0, seed=3)
    runs = []
    for forget in (False, True):
        mc = MCMCDA(MCMCDAConfig(dt=1 / RATE, window=6, n_mc=60, p_detect=0.95, area=6000.0))
        state, rng = mc.initial_state(), np.random.default_rng(0)
        now = []
        for k in range(1, 41):
            y = [
                [
                    RADAR[0] + p.value[0] * math.cos(p.value[1]),
                    RADAR[1] + p.value[0] * math.sin(p.value[1]),
                ]
                for p in plots
                if (k - 1) / RATE < p.time <= k / RATE
            ]
            state = mc.step(state, np.array(y).reshape(-1, 2), rng)
            if forget:
                state = mc.forget_past(state)
                assert len(state.observations) <= 6 and not state.committed
            now.append({i: x.tolist() for i, (x, _) in mc.current_tracks(state).items()})
        runs.append(now)
    assert runs[0] == runs[1]
