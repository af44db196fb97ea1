"""The simulated urban road of Kushwaha 2010, Ch. III, from sound and pixels to fused likelihoods.

The paper's deployment (6 acoustic nodes and 3 cameras on both sides of a road, a 35 m × 20 m
field, 0.5 m cells) is not published in coordinates; spec 003 §3.2 fixes a layout: the road runs
along x at y = 10 m (lanes at y = 8.5 m and 11.5 m), three acoustic nodes at y = 4 m and three
at y = 16 m (x = 5, 17.5, 30 m), and three cameras at (0, 2), (35, 18) and (17.5, 0), 3 m high,
looking at the road centre with a 60° field of view. This module simulates one pass end to end:

* acoustic nodes: harmonic engine + tyre noise propagated to the 4 microphones of each node
  (:mod:`fusetrack.world.acoustics`), pink background noise, band-pass + 36-beam delay-and-sum +
  smoothing every 250 ms of the node's clock (:mod:`fusetrack.perception.audio_beamforming`);
* video nodes: rendered 320×240 frames at 4 fps (:mod:`fusetrack.world.road_video`), MOG2,
  median, column counts and post-filters (:mod:`fusetrack.perception.video_detection`);
* time: every node has its own clock; audio timestamps are translated hop by hop to the
  gateway, then to the RBS timescale; video timestamps by RBS (:mod:`fusetrack.world.clocks`);
  packets are lost with probability ``packet_loss`` and arrive after 10–50 ms per hop;
* fusion node: ring buffers and the 4 Hz closest-timestamp scheduler
  (:mod:`fusetrack.management.fusion_scheduler`), then per-cell likelihoods from the cell arcs
  (:mod:`fusetrack.sensors.detection_function`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...filters import DirectionalMotion, GridFilter, GridSpec, SensorLikelihoods, map_sensors
from ...management import FusionScheduler, IntakeStats, Packet
from ...perception import (
    Beamformer,
    MicrophoneArray,
    VideoDetector,
    fit_angle_mixture,
    pack_audio_message,
    unpack_audio_message,
)
from ...sensors import (
    AngularSampling,
    PinholeCamera,
    arc_mean_matrix,
    cell_arcs,
    detection_quality,
    mixture_arc_mean,
    normalize_likelihood,
)
from ...world import (
    HopTranslation,
    NodeClock,
    RbsDomain,
    RoadRenderer,
    Vehicle,
    fit_clock_map,
    harmonic_engine,
    pink_noise,
    propagate,
)
from .sync_bound import chained_variance, hop_variance, map_value_variance

FS = 100e3
DT = 0.25
GATEWAY_JITTER = 20e-6  # the gateway's mote and PC readings of a serial pair (s, std)
LATENCY_ALLOWANCE = 0.15  # the scheduler fires this long after each fusion timestamp
MIC_HEIGHT = 1.0
ENGINE_HEIGHT = 0.5
CAMERA_HEIGHT = 3.0
CAMERA_FOV = np.deg2rad(60.0)
ROAD_CENTRE = (17.5, 10.0)


@dataclass(frozen=True)
class Layout:
    """Where the nodes are. Audio: id → (x, y, heading); cameras: id → (x, y, yaw)."""

    audio: tuple[tuple[str, float, float, float], ...]
    video: tuple[tuple[str, float, float, float], ...]
    grid: GridSpec = field(default_factory=GridSpec)

    @property
    def sensor_ids(self) -> tuple[str, ...]:
        return tuple(a[0] for a in self.audio) + tuple(v[0] for v in self.video)

    def subset(
        self, audio: tuple[str, ...] | None = None, video: tuple[str, ...] | None = None
    ) -> Layout:
        return replace(
            self,
            audio=tuple(a for a in self.audio if audio is None or a[0] in audio),
            video=tuple(v for v in self.video if video is None or v[0] in video),
        )


def default_layout() -> Layout:
    headings = [0.3, 1.9, -0.8, 2.6, -2.2, 1.1]  # manual placement: arbitrary but known
    audio = []
    k = 0
    for y in (4.0, 16.0):
        for x in (5.0, 17.5, 30.0):
            audio.append((f"A{k + 1}", x, y, headings[k]))
            k += 1
    video = []
    for i, (x, y) in enumerate([(0.0, 2.0), (35.0, 18.0), (17.5, 0.0)]):
        video.append((f"V{i + 1}", x, y, float(np.arctan2(ROAD_CENTRE[1] - y, ROAD_CENTRE[0] - x))))
    return Layout(tuple(audio), tuple(video))


@dataclass(frozen=True)
class VehiclePass:
    """A vehicle on a lane: centre of mass at ``x0`` at t = 0, constant ``speed`` (signed, m/s)."""

    x0: float
    lane_y: float
    speed: float
    f0: float = 50.0
    grey: float = 40.0
    engine_offset: float = 1.5  # m ahead of the centre of mass

    def centre(self, t: NDArray[np.float64] | float) -> NDArray[np.float64]:
        tt = np.asarray(t, float)
        return np.stack([self.x0 + self.speed * tt, np.full_like(tt, self.lane_y)], axis=-1)

    def engine(self, t: NDArray[np.float64] | float) -> NDArray[np.float64]:
        """The engine (the acoustic source) sits ``engine_offset`` (1.5 m) ahead of the centre
        of mass."""
        c = self.centre(t)
        c[..., 0] += self.engine_offset * np.sign(self.speed)
        z = np.full((*c.shape[:-1], 1), ENGINE_HEIGHT)
        return np.concatenate([c, z], axis=-1)

    def box(self, t: float) -> Vehicle:
        c = self.centre(t)
        return Vehicle((float(c[0]), float(c[1])), 0.0 if self.speed > 0 else np.pi, grey=self.grey)

    def field_interval(self, grid: GridSpec) -> tuple[float, float]:
        """Times at which the centre of mass enters and leaves [x0, x1]."""
        a = (grid.x0 - self.x0) / self.speed
        b = (grid.x1 - self.x0) / self.speed
        return (min(a, b), max(a, b))


def random_pass(rng: np.random.Generator, grid: GridSpec | None = None) -> VehiclePass:
    """A single-vehicle pass at 20–30 mph (9–13.4 m/s) in either direction (spec 003 §3.2)."""
    g = grid or GridSpec()
    speed = rng.uniform(9.0, 13.4)
    east = bool(rng.random() < 0.5)
    return VehiclePass(
        x0=g.x0 - 2.0 if east else g.x1 + 2.0,
        lane_y=8.5 if east else 11.5,
        speed=speed if east else -speed,
        f0=float(rng.uniform(30, 80)),
        grey=float(rng.choice([35.0, 60.0, 200.0, 230.0])),
    )


ADC_FULL_SCALE = 1.0  # per-channel amplitude at the 8-bit ADC's full scale (simulation units)
ACCUMULATOR_MAX = 2**32 - 1  # the FPGA's 32-bit energy register


def audio_on_the_wire(lam: NDArray[np.float64], window: int = 2**14) -> NDArray[np.float64]:
    """λ as the fusion node receives it from an acoustic node (spec 003 §2.1 step 6, A-III-4).

    The FPGA accumulates ``B(α) = Σ_n r_α[n]²`` over ``window`` samples of 8-bit counts in a
    32-bit register (Kushwaha 2010, Ch. IV), and the radio message carries 36 ``uint16(B >> s)``
    with the smallest shift ``s`` that fits (72 bytes). ``lam`` is the per-sample mean power in
    simulation units (full scale ``ADC_FULL_SCALE`` = 128 counts); it is converted to counts,
    saturated at the register's maximum, packed and unpacked (:func:`pack_audio_message`), and
    converted back. The error is at most ``max(B) / 2^15`` per beam.
    """
    lsb2 = (ADC_FULL_SCALE / 128.0) ** 2
    counts = np.clip(np.asarray(lam, float) * window / lsb2, 0.0, float(ACCUMULATOR_MAX))
    *_, back = unpack_audio_message(pack_audio_message(0, 0, 0, 0, counts))
    return back * lsb2 / window


@dataclass(frozen=True)
class SceneConfig:
    """Conditions of one simulated pass (defaults: the paper's deployment, spec 003 [C] choices)."""

    snr_db: float = 12.0  # per microphone, engine vs background noise, at 10 m
    clutter: float = 1.0  # tree and glint rate of the cameras
    camera_yaw_error: tuple[float, ...] = (0.0, 0.0, 0.0)  # true - assumed yaw (rad) per camera
    # a false moving-foreground object (swaying tree, reflection) at (x, y) from t0 to t1, seen by
    # every camera whose field of view holds it: (x, y, t0, t1)
    false_video_peak: tuple[float, float, float, float] | None = None
    second_source: tuple[float, float] | None = None  # a stationary sound source (x, y)
    beam_alpha: float = 0.5
    filter_band: tuple[float, float] | None = (100.0, 4000.0)  # band-pass before beamforming (Hz)
    engine_offset: float = 1.5  # the engine's distance ahead of the centre of mass (m)
    quantise_audio: bool = True  # send λ as the FPGA does: 32-bit sums, 16-bit on the radio
    preroll: float = (
        0.5  # seconds simulated before the vehicle enters the field (smoothing warm-up)
    )


@dataclass
class Recording:
    """Everything the nodes sent during one simulated pass (before losses), and the truth."""

    packets: list[Packet]  # sorted by arrival time at the fusion node
    vehicles: list[VehiclePass]
    t_start: float
    t_end: float
    sync_residuals: NDArray[np.float64]  # translated - true timestamp of every packet (s)
    audio_threshold: float
    # per packet, the CRLB variance (s²) of its timestamp: with the RBS window's beacons, with
    # every beacon before it (:mod:`.sync_bound`); empty for a recording built by hand
    sync_bounds: NDArray[np.float64] = field(default_factory=lambda: np.empty((0, 2)))

    @property
    def ticks(self) -> NDArray[np.float64]:
        """The 4 Hz fusion timestamps."""
        return np.arange(self.t_start, self.t_end + 1e-9, DT)

    def truth(self) -> list[NDArray[np.float64]]:
        """Per tick: the vehicles' centres of mass (n, 2) (the paper's ground truth)."""
        return [np.array([v.centre(t) for v in self.vehicles]) for t in self.ticks]


@dataclass
class FusionInput:
    """What the fusion node took at each tick."""

    ticks: NDArray[np.float64]
    taken: list[dict[str, Packet]]
    stats: IntakeStats


def fusion_input(
    rec: Recording,
    rng: np.random.Generator,
    packet_loss: float = 0.02,
    sync_offset: float = 0.0,
    sensors: tuple[str, ...] | None = None,
    layout: Layout | None = None,
) -> FusionInput:
    """Run the fusion node's intake on a recording: drop packets with probability ``packet_loss``
    (paper: "less than 2% packet loss"), shift every node's timestamps by ±``sync_offset``
    (an unsynchronised node; random sign per node), fill the ring buffers in arrival order and
    take the closest packet per sensor at each 4 Hz tick."""
    lay = layout or default_layout()
    ids = lay.sensor_ids  # the fusion node knows its sensors; anything else is "unknown"
    shift = {k: float(rng.choice([-1.0, 1.0]) * sync_offset) for k in ids}
    lengths = {a[0]: 36 for a in lay.audio} | {v[0]: 160 for v in lay.video}
    lengths = {k: n for k, n in lengths.items() if sensors is None or k in sensors}
    sched = FusionScheduler(lengths, max_offset=DT)
    keep = rng.random(len(rec.packets)) >= packet_loss
    packets = [
        replace(p, timestamp=p.timestamp + shift.get(p.sensor_id, 0.0))
        for p, k in zip(rec.packets, keep)
        if k
    ]
    taken = []
    k = 0
    for t in rec.ticks:
        while k < len(packets) and packets[k].arrival <= t + LATENCY_ALLOWANCE:
            if sensors is None or packets[k].sensor_id in sensors:
                sched.receive(packets[k])
            k += 1
        taken.append(sched.take(float(t)))
    return FusionInput(rec.ticks, taken, sched.stats)


# ---------------------------------------------------------------------------------------------
# Fusion-node geometry, computed once per layout (2800 cells × 9 sensors).


@dataclass(frozen=True, eq=False)
class SensorGeometry:
    kind: str  # "audio" | "video"
    audio_w: NDArray[np.float64] | None = None  # (cells, 36)
    lo: NDArray[np.float64] | None = None  # camera-frame arcs
    hi: NDArray[np.float64] | None = None
    in_fov: NDArray[np.bool_] | None = None


@lru_cache(maxsize=64)
def _geometry(kind: str, x: float, y: float, heading: float, grid: GridSpec) -> SensorGeometry:
    lo, hi, inside = cell_arcs((x, y), heading, grid.centres, grid.cell / 2)
    if kind == "audio":
        return SensorGeometry("audio", audio_w=arc_mean_matrix(AngularSampling.beams(36), lo, hi))
    mid = 0.5 * (lo + hi)
    return SensorGeometry("video", lo=lo, hi=hi, in_fov=(np.abs(mid) <= CAMERA_FOV / 2) & ~inside)


def sensor_geometry(layout: Layout) -> dict[str, SensorGeometry]:
    """Per-sensor cell arcs (and the audio arc-mean matrices), computed once per sensor pose."""
    out = {sid: _geometry("audio", x, y, h, layout.grid) for sid, x, y, h in layout.audio}
    out |= {sid: _geometry("video", x, y, h, layout.grid) for sid, x, y, h in layout.video}
    return out


VIDEO_ANGLES = AngularSampling.camera_bins(CAMERA_FOV, 160).angles


def sensor_likelihood(
    geo: SensorGeometry, values: NDArray[np.float64]
) -> tuple[NDArray[np.float64], float] | None:
    """Per-cell likelihood (unit sum, floored) and quality q_k = max λ̃ (Kushwaha 2010, Eqs. 31–32);
    None when the sensor detects nothing (a camera with an empty mixture)."""
    v = np.asarray(values, float)
    quality = detection_quality(v)  # r_k = 1 (spec 003 A-III-11)
    if quality is None:
        return None
    if geo.kind == "audio":
        assert geo.audio_w is not None
        return normalize_likelihood(geo.audio_w @ v), quality
    mix = fit_angle_mixture(v, VIDEO_ANGLES, min_mass=20.0)
    if mix.empty:
        return None
    assert geo.lo is not None and geo.hi is not None and geo.in_fov is not None
    cell = mixture_arc_mean(mix.weights, mix.means, mix.sigmas, geo.lo, geo.hi)
    # Cells the camera cannot see get the mean of the cells it can (spec 003 A-III-6).
    cell = np.where(geo.in_fov, cell, cell[geo.in_fov].mean())
    return normalize_likelihood(cell), quality


def tick_likelihoods(layout: Layout, taken: dict[str, Packet]) -> SensorLikelihoods:
    geo = sensor_geometry(layout)
    rows, qual, mods, ids = [], [], [], []
    for sid in layout.sensor_ids:
        if sid not in taken:
            continue
        res = sensor_likelihood(geo[sid], taken[sid].values)
        if res is None:
            continue
        rows.append(res[0])
        qual.append(res[1])
        mods.append(geo[sid].kind)
        ids.append(sid)
    return SensorLikelihoods(
        np.array(rows).reshape(-1, layout.grid.size), np.array(qual), tuple(mods), tuple(ids)
    )


# ---------------------------------------------------------------------------------------------
# Simulation of one recording.


def _audio_threshold(layout: Layout, config: SceneConfig, rng: np.random.Generator) -> float:
    """99th percentile of max_θ λ over target-free windows (spec 003 §2.5 step 5, [C])."""
    noise_std = 0.1 / 10 ** (config.snr_db / 20)
    bf = Beamformer(alpha=0.0, filter_band=config.filter_band)
    n = bf.window + bf.preroll
    maxima = [bf.energies(noise_std * pink_noise((4, n), rng)).max() for _ in range(24)]
    return float(np.quantile(maxima, 0.99) * 1.5)


def simulate_recording(
    layout: Layout,
    vehicles: list[VehiclePass],
    t_start: float,
    t_end: float,
    config: SceneConfig,
    rng: np.random.Generator,
) -> Recording:
    """Simulate every node from ``t_start - preroll`` to ``t_end`` and return what the fusion node
    takes at each 4 Hz tick in [t_start, t_end]."""
    t_sim0 = t_start - config.preroll
    emit_t0 = t_sim0 - 0.5
    sources = _sound_sources(vehicles, config, emit_t0, t_end - emit_t0 + 0.1, rng)
    net = _Network(layout, t_sim0, t_end, rng)
    _audio_packets(layout, config, sources, emit_t0, t_sim0, t_end, net, rng)
    _video_packets(layout, vehicles, config, t_sim0, t_end, net, rng)
    order = np.argsort([p.arrival for p in net.packets], kind="stable")
    return Recording(
        [net.packets[i] for i in order],
        list(vehicles),
        t_start,
        t_end,
        np.array(net.residuals)[order],
        _audio_threshold(layout, config, rng),
        np.array(net.bounds).reshape(-1, 2)[order],
    )


Source = tuple[NDArray[np.float64], Callable[[Any], NDArray[np.float64]]]


def _sound_sources(
    vehicles: list[VehiclePass],
    config: SceneConfig,
    emit_t0: float,
    duration: float,
    rng: np.random.Generator,
) -> list[Source]:
    """Each vehicle's engine (emitted from ``emit_t0`` on) and the optional stationary source:
    (emitted signal, position at emission time since ``emit_t0``)."""
    sources: list[Source] = []
    for v in vehicles:
        em = harmonic_engine(duration, rng, FS, f0=v.f0)
        sources.append((em, (lambda vv: lambda t: vv.engine(t + emit_t0))(v)))
    if config.second_source is not None:
        pos = np.array([*config.second_source, 1.0])
        em = harmonic_engine(duration, rng, FS, f0=float(rng.uniform(90, 140)))
        sources.append((em, (lambda p: lambda t: np.broadcast_to(p, (np.size(t), 3)))(pos)))
    return sources


class _Network:
    """The nodes' clocks and time translation, and the packets delivered to the fusion node:
    audio by hop-by-hop translation to the gateway mote, the gateway's mote → PC map, then RBS;
    video by RBS; all to the fusion node's clock."""

    def __init__(self, layout: Layout, t_sim0: float, t_end: float, rng: np.random.Generator):
        self.rng = rng
        clocks = {k: NodeClock.random(rng) for k in layout.sensor_ids}
        clocks["gateway_mote"] = NodeClock.random(rng)
        clocks["gateway_pc"] = NodeClock.random(rng)
        clocks["fusion"] = NodeClock.random(rng)
        self.clocks = clocks
        self.relay = NodeClock.random(rng)
        pcs = {k: clocks[k] for k in [v[0] for v in layout.video] + ["gateway_pc", "fusion"]}
        self.rbs = RbsDomain(pcs, "fusion", rng)
        self.rbs.broadcast_until(t_end + 2.0, t_sim0 - 10.0)
        # gateway: mote clock -> PC clock from paired readings (serial link, 20 µs jitter)
        self.pair_t = np.linspace(t_sim0 - 10, t_end + 2, 16)
        self.gw_a, self.gw_b = fit_clock_map(
            clocks["gateway_mote"].local(self.pair_t) + rng.normal(0, GATEWAY_JITTER, 16),
            clocks["gateway_pc"].local(self.pair_t) + rng.normal(0, GATEWAY_JITTER, 16),
        )
        self.hop = HopTranslation()
        self.packets: list[Packet] = []
        self.residuals: list[float] = []
        self.bounds: list[tuple[float, float]] = []

    def _slope(self, to: str, frm: str) -> float:
        """d(clock ``to``)/d(clock ``frm``)."""
        return (1 + self.clocks[to].skew) / (1 + self.clocks[frm].skew)

    def _rbs_variances(self, node: str, local: float) -> tuple[float, float]:
        """CRLB (s², fusion clock) of RBS's map of ``local`` from ``node``'s clock: with the
        protocol's window of beacons, and with every beacon received before it."""
        used = self.rbs.beacons_for(node, local)
        beta, var = self._slope("fusion", node), self.rbs.jitter**2
        x = self.clocks[node].local(self.rbs.beacons)
        window = map_value_variance(x[used], beta, var, var, local)
        return window, map_value_variance(x[: used.stop], beta, var, var, local)

    def _stamp_bounds(self, sid: str, t_event: float, local_gw: float, hops: int) -> None:
        """The packet's timestamp CRLB (:mod:`.sync_bound`), both RBS variants, in true time."""
        to_true = 1.0 / (1 + self.clocks["fusion"].skew)
        if sid.startswith("A"):
            b_gw = self._slope("gateway_pc", "gateway_mote")
            x_gw = self.clocks["gateway_mote"].local(self.pair_t)
            gw = map_value_variance(x_gw, b_gw, GATEWAY_JITTER**2, GATEWAY_JITTER**2, local_gw)
            pc_local = self.gw_a + self.gw_b * local_gw
            early = [
                (hop_variance(hops, self.hop.jitter), b_gw),
                (gw, self._slope("fusion", "gateway_pc")),
            ]
            rbs = self._rbs_variances("gateway_pc", pc_local)
        else:
            early = []
            rbs = self._rbs_variances(sid, float(self.clocks[sid].local(t_event)))
        w, c = (chained_variance([*early, (r, to_true)]) for r in rbs)
        self.bounds.append((w, c))

    def deliver(
        self, sid: str, seq: int, t_event: float, values: NDArray[np.float64], hops: int
    ) -> None:
        """Stamp an event of node ``sid`` in the fusion node's time and queue its packet."""
        rng, clocks = self.rng, self.clocks
        if sid.startswith("A"):
            route = [clocks[sid]] + [self.relay] * (hops - 1) + [clocks["gateway_mote"]]
            stays = list(rng.uniform(0.005, 0.02, hops))
            delays = list(rng.uniform(0.004, 0.006, hops))
            local_gw, arrive = self.hop.translate(t_event, route, stays, delays, rng)
            pc_local = self.gw_a + self.gw_b * local_gw
            ref = self.rbs.to_reference("gateway_pc", pc_local)
            arrive += rng.uniform(0.01, 0.05)
            self._stamp_bounds(sid, t_event, local_gw, hops)
        else:
            ref = self.rbs.to_reference(sid, float(clocks[sid].local(t_event)))
            arrive = t_event + rng.uniform(0.01, 0.05)
            self._stamp_bounds(sid, t_event, 0.0, hops)
        stamp = float(clocks["fusion"].true_time(ref))
        self.residuals.append(stamp - t_event)
        self.packets.append(Packet(sid, seq, stamp, values, arrive))


def stamp_trial(
    layout: Layout, rng: np.random.Generator, duration: float = 5.0
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    """One fresh network (clocks, beacons, gateway pairs) stamping one event per sensor at a
    uniform time in ``[0.5, duration]`` s, routed as in a pass (audio over ``1 + i % 3`` hops):
    the residuals (s), their CRLB variances ``(n, 2)`` (:mod:`.sync_bound`) and which are audio.
    Trials are independent, unlike a pass's packets, which share their map fits."""
    net = _Network(layout, 0.0, duration, rng)
    for i, sid in enumerate(layout.sensor_ids):
        hops = 1 + i % 3 if sid.startswith("A") else 1
        net.deliver(sid, 0, float(rng.uniform(0.5, duration)), np.zeros(1), hops)
    audio = np.array([sid.startswith("A") for sid in layout.sensor_ids])
    return np.array(net.residuals), np.array(net.bounds), audio


def _audio_packets(
    layout: Layout,
    config: SceneConfig,
    sources: list[Source],
    emit_t0: float,
    t_sim0: float,
    t_end: float,
    net: _Network,
    rng: np.random.Generator,
) -> None:
    """Acoustic nodes: beam energies every 250 ms of the node's own clock."""
    array = MicrophoneArray.rectangle()
    noise_std = 0.1 / 10 ** (config.snr_db / 20)
    for n_idx, (sid, x, y, heading) in enumerate(layout.audio):
        mics = np.column_stack([array.world_positions((x, y), heading), np.full(4, MIC_HEIGHT)])
        bf = Beamformer(array, alpha=config.beam_alpha, filter_band=config.filter_band)
        n = bf.window + bf.preroll
        phase = rng.uniform(0, DT)
        ticks = np.arange(t_sim0 + phase, t_end + DT, DT)
        for seq, t in enumerate(ticks):
            times = t - (np.arange(n)[::-1]) / FS
            sig = noise_std * pink_noise((4, n), rng)
            for em, path in sources:
                sig += propagate(em, path, mics, times - emit_t0, FS)
            lam = bf.process(sig)
            if config.quantise_audio:
                lam = audio_on_the_wire(lam, bf.window)
            # the energy describes the window: stamp it at the window's centre ([C])
            net.deliver(sid, seq, float(t) - bf.window / (2 * FS), lam, hops=1 + n_idx % 3)


def _video_packets(
    layout: Layout,
    vehicles: list[VehiclePass],
    config: SceneConfig,
    t_sim0: float,
    t_end: float,
    net: _Network,
    rng: np.random.Generator,
) -> None:
    """Video nodes: column scores of rendered frames at 4 fps, with the optional false peak."""
    for c_idx, (sid, x, y, yaw) in enumerate(layout.video):
        true_yaw = yaw + config.camera_yaw_error[c_idx]
        cam = PinholeCamera.from_pose((x, y, CAMERA_HEIGHT), true_yaw, hfov=CAMERA_FOV)
        renderer = RoadRenderer(cam, rng, clutter=config.clutter)
        det = VideoDetector(cam.column_angles(), cam.hfov)
        for _ in range(25):
            det.learn_background(renderer.render([]))
        phase = rng.uniform(0, DT)
        for seq, t in enumerate(np.arange(t_sim0 + phase, t_end + DT, DT)):
            boxes = [v.box(t) for v in vehicles]
            lam, _ = det.process(renderer.render(boxes))
            fp = config.false_video_peak
            if fp is not None and fp[2] <= t <= fp[3]:
                ghost = np.arctan2(fp[1] - y, fp[0] - x) - yaw
                ghost = float(np.mod(ghost + np.pi, 2 * np.pi) - np.pi)
                if abs(ghost) < CAMERA_FOV / 2:
                    k = int(np.argmin(np.abs(VIDEO_ANGLES - ghost)))
                    lam = lam.copy()  # a blob as wide as a car at 15 m, 1.5 times as high
                    lam[max(0, k - 7) : k + 8] += max(lam.max(), 50.0) * 1.5
            net.deliver(sid, seq, float(t), lam, hops=1)


# ---------------------------------------------------------------------------------------------
# The eight SBE approaches (Kushwaha 2010, Ch. III) on one recording.

VARIANTS: dict[str, tuple[tuple[str, ...], str, str]] = {
    "AS": (("audio",), "sum", "centralized"),
    "VS": (("video",), "sum", "centralized"),
    "AVCS": (("audio", "video"), "sum", "centralized"),
    "AVHS": (("audio", "video"), "sum", "hybrid"),
    "AP": (("audio",), "product", "centralized"),
    "VP": (("video",), "product", "centralized"),
    "AVCP": (("audio", "video"), "product", "centralized"),
    "AVHP": (("audio", "video"), "product", "hybrid"),
}


@dataclass(frozen=True)
class SinglePass:
    """One simulated single-vehicle pass: the vehicle, the times ``t0``, ``t1`` at which it
    enters and leaves the field, the recording and the true centre of mass per tick ``(T, 2)``."""

    vehicle: VehiclePass
    t0: float
    t1: float
    rec: Recording
    truth: NDArray[np.float64]


def simulate_single_pass(
    layout: Layout,
    rng: np.random.Generator,
    scene: Callable[[float, float], SceneConfig] | None = None,
    tail: float = 0.0,
) -> SinglePass:
    """A :func:`random_pass` simulated from entering the field to ``tail`` s after leaving it.

    ``scene(t0, t1)`` gives the conditions from the field interval (default: ``SceneConfig()``).
    Draws from ``rng`` in order: the pass, then the recording."""
    vehicle = random_pass(rng, layout.grid)
    t0, t1 = vehicle.field_interval(layout.grid)
    config = SceneConfig() if scene is None else scene(t0, t1)
    vehicle = replace(vehicle, engine_offset=config.engine_offset)
    rec = simulate_recording(layout, [vehicle], t0, t1 + tail, config, rng)
    truth = np.array([tr[0] for tr in rec.truth()])
    return SinglePass(vehicle, t0, t1, rec, truth)


def all_likelihoods(layout: Layout, fin: FusionInput) -> list[SensorLikelihoods]:
    return [tick_likelihoods(layout, taken) for taken in fin.taken]


def track_start(fin: FusionInput, threshold: float) -> int:
    """First tick at which some audio node's max λ exceeds the threshold (Kushwaha 2010, Ch. III:
    "If the maximum of the audio detection functions exceeds a threshold, we initialize")."""
    for k, taken in enumerate(fin.taken):
        if any(sid.startswith("A") and p.values.max() > threshold for sid, p in taken.items()):
            return k
    return len(fin.taken)


def track_end(fin: FusionInput, threshold: float, start: int, quiet: int = 4) -> int:
    """Tick (exclusive) at which a track started at ``start`` ends: after ``quiet`` consecutive
    ticks at which no audio node's max λ exceeds the start threshold (spec 003 §2.5 step 6 [C]:
    4 ticks = 1 s; the dissertation does not describe termination). The spec's other rule, the
    posterior mean leaving the field, cannot fire on the grid (the mean of a density on the
    field's cells is inside the field). ``len(fin.taken)`` when the track never ends."""
    run = 0
    for k in range(start + 1, len(fin.taken)):
        loud = any(
            sid.startswith("A") and p.values.max() > threshold for sid, p in fin.taken[k].items()
        )
        run = 0 if loud else run + 1
        if run == quiet:
            return k + 1
    return len(fin.taken)


def run_sbe(
    layout: Layout,
    liks: list[SensorLikelihoods],
    variant: str,
    start: int = 0,
    sensors: tuple[str, ...] | None = None,
    fin: FusionInput | None = None,
    prior: NDArray[np.float64] | None = None,
    delta: float = 1.5,
    end_at_exit: bool = False,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Posterior means ``(T, 2)`` and det Σ ``(T,)`` of one SBE approach (NaN before ``start``).

    ``sensors`` restricts the fusion to a subset (needs ``fin`` to know which row is which).
    ``end_at_exit``: the track ends (NaN from the next tick on) when the posterior mean is about
    to leave the field, i.e. mean + the tracker's velocity lies outside it -- spec 003 §2.5
    step 6's "posterior mean leaves the field", read for a grid, whose mean always lies inside;
    checked from the 5th tick of the track on, once the velocity has settled."""
    modalities, fusion, arch = VARIANTS[variant]
    filt = sbe_filter(layout, fusion, arch, delta)
    means = np.full((len(liks), 2), np.nan)
    dets = np.full(len(liks), np.nan)
    belief = filt.initial()
    for k in range(start, len(liks)):
        lik = liks[k]
        if sensors is not None and fin is not None:
            lik = tick_likelihoods(layout.subset(*_split(sensors)), fin.taken[k])
        measurements = lik.measurements(k * DT, modalities)
        if k > start or prior is not None:
            # Kushwaha 2010: the prior is initialised from the audio detection at track start;
            # the first step then predicts (δ = 3 m) and updates. Without a prior the first
            # step updates the uniform density.
            belief = filt.step(filt.initial(prior) if k == start else belief, DT, measurements)
        else:
            belief = filt.update(belief, measurements)
        means[k] = belief.mean
        dets[k] = np.linalg.det(belief.cov)
        settled = k - start >= 4  # 1 s: the velocity estimate needs a few steps
        ahead = belief.mean + belief.velocity * DT
        if end_at_exit and settled and not layout.grid.contains(ahead):
            break
    return means, dets


def sbe_filter(layout: Layout, fusion: str, architecture: str, delta: float = 1.5) -> GridFilter:
    """The grid SBE filter over the layout's sensors (A*: audio, V*: video likelihood maps)."""
    sensors = map_sensors(
        layout.grid, layout.sensor_ids, lambda sid: "audio" if sid.startswith("A") else "video"
    )
    return GridFilter(
        layout.grid,
        sensors,
        fusion,  # type: ignore[arg-type]
        architecture,  # type: ignore[arg-type]
        DirectionalMotion(delta),
    )


def audio_prior(
    lik: SensorLikelihoods, taken: dict[str, Packet], threshold: float, layout: Layout
) -> NDArray[np.float64]:
    """Normalised product of the audio likelihoods of the nodes above the threshold (uniform if
    fewer than two; spec 003 §2.5 step 5)."""
    from ...filters import fuse_product

    audio = [sid for sid, *_ in layout.audio if sid in taken]
    rows = [i for i, m in enumerate(lik.modality) if m == "audio"]
    above = [r for r, sid in zip(rows, audio) if taken[sid].values.max() > threshold]
    if len(above) < 2:
        return layout.grid.uniform()
    return fuse_product(lik.values[above])


def _split(sensors: tuple[str, ...]) -> tuple[tuple[str, ...], tuple[str, ...]]:
    return tuple(s for s in sensors if s.startswith("A")), tuple(
        s for s in sensors if s.startswith("V")
    )


def detection_sensors(layout: Layout) -> dict[str, Any]:
    """Every node as a detection-function sensor model, for the grid-free particle back end."""
    from ...sensors import DetectionFunctionSensor

    beams = AngularSampling.beams(36)
    out: dict[str, Any] = {}
    for sid, x, y, h in layout.audio:
        out[sid] = DetectionFunctionSensor(sid, (x, y), h, sampling=beams)
    for sid, x, y, h in layout.video:
        out[sid] = DetectionFunctionSensor(sid, (x, y), h, fov=CAMERA_FOV)
    return out


def bearing_detections(
    layout: Layout, taken: dict[str, Packet], modalities: tuple[str, ...], time: float = 0.0
) -> list[Any]:
    """The same reports as :func:`tick_likelihoods` as measurements for :func:`detection_sensors`."""
    from ...core import Measurement
    from ...sensors import DetectionFunctionSensor

    out = []
    if "audio" in modalities:
        for sid, _, _, _ in layout.audio:
            if sid in taken:
                out.append(Measurement(time, sid, taken[sid].values))
    if "video" in modalities:
        for sid, _, _, _ in layout.video:
            if sid in taken:
                mix = fit_angle_mixture(taken[sid].values, VIDEO_ANGLES, min_mass=20.0)
                if not mix.empty:
                    value = DetectionFunctionSensor.mixture_value(
                        mix.weights, mix.means, mix.sigmas
                    )
                    out.append(Measurement(time, sid, value))
    return out


def run_particle_backend(
    layout: Layout,
    fin: FusionInput,
    variant: str,
    start: int,
    prior: NDArray[np.float64],
    rng: np.random.Generator,
    n_particles: int = 2000,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Posterior means ``(T, 2)`` and det Σ of the particle back end (product fusion)."""
    from ...filters import DetectionParticleFilter, position_estimate
    from ...motion import ConstantVelocity

    modalities = VARIANTS[variant][0]
    pf = DetectionParticleFilter(
        ConstantVelocity(ndim=2, q=4.0), detection_sensors(layout), n_particles
    )
    cells = rng.choice(layout.grid.size, n_particles, p=prior / prior.sum())
    jitter = rng.uniform(-0.5, 0.5, (n_particles, 2)) * layout.grid.cell
    belief = pf.initial_belief(layout.grid.centres[cells] + jitter, 8.0, rng)
    means = np.full((len(fin.taken), 2), np.nan)
    dets = np.full(len(fin.taken), np.nan)
    for k in range(start, len(fin.taken)):
        zs = bearing_detections(layout, fin.taken[k], modalities, k * DT)
        belief = pf.update(pf.predict(belief, DT, rng), zs, rng)
        m, c = position_estimate(belief)
        means[k] = m
        dets[k] = np.linalg.det(c)
    return means, dets
