"""3-D tracking with a network of smart cameras (Kushwaha 2010, Ch. V, Algorithms 2-3, Eqs. 70-103).

Every tracker is a :class:`~fusetrack.core.Filter` over a :class:`SmartCameraBelief`: the
velocity filter's Gaussian over position and velocity, the target's orientation (scalar-last
quaternion), what the last update sent over the network, and (baseline P) its per-camera 2-D
particle sets. Each camera's frame arrives as ``Measurement(time, camera_id, FeatureImage)``;
its likelihood is the camera's appearance sensor model
(:class:`~fusetrack.sensors.appearance_camera.AppearanceCamera`). The trackers differ in how the
cameras' evidence is fused and what they send per step:

* ``T0`` (Alg. 2) -- synchronised 3-D particles ``x_i ~ N(x0 + v0, S)`` drawn alike on every
  camera; each camera sends its weights ``rho_n(x_i)`` (8 B each); the base multiplies them
  (Eq. 70) and takes the MMSE estimate (Eq. 82). Cost ``80 + 8 M N`` bytes.
* ``T1`` -- each camera compresses its weighted particles' kernel density (Eq. 85) to a Gaussian
  mixture (Eq. 86) and sends it (10 doubles per component); the base multiplies the mixtures
  and takes the mode (Eq. 87).
* ``T2`` -- T1 with in-network aggregation: along the routing tree each node multiplies its own
  mixture with its children's (Eq. 88) and reduces the product to ``K`` components (Eqs. 89-93).
* ``T3`` (Alg. 3) -- image-plane particles around the predicted pixel; each camera lifts its
  2-D mixture to 3-D Gaussians elongated along the viewing rays (the paper announces but does not
  give this step; spec A-V-3) and aggregates them in-network like T2.
* ``T4`` -- cameras send 2-D mixtures; the base finds the MAP of
  ``N(x | x0, S0) prod_i sum_j a_ij N(pi_i(x) | u_ij, S_ij)`` (Eq. 99) numerically; the one-step
  closed form of Eq. 103 is returned beside it (``belief.extra["eq103"]``).
* ``P`` -- the baseline: an independent colour particle filter per camera (Perez et al.) and the
  least-squares intersection of the rays through the 2-D estimates.

The paper weighs a particle by ``rho`` itself; ``rho`` of a wrong region is rarely far below
that of the right one, so all trackers here use ``rho^gamma`` (``sharpness`` gamma, 1 = the
paper). A camera takes part in a step when the target's predicted ellipse is usable in its image
(:meth:`EllipsoidCamera.participates`) and its frame arrived; otherwise it contributes the factor
1 and sends nothing. ``predict`` is the constant-velocity Kalman prediction (``x0 + v0`` with
``dt = 1`` per frame, Alg. 2); ``update`` fuses the frames into a position estimate, updates the
velocity filter with it (the paper's N-scan smoother; at the newest step a fixed-lag smoother's
estimate is the filtered one), and then the orientation from the viewpoint similarities
(Eqs. 77-78).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import minimize

from ..core import (
    ConfigError,
    Gaussian,
    GaussianMixture,
    Measurement,
    MeasurementError,
    Particles,
    invalid,
)
from ..motion import ConstantVelocity
from ..sensors import (
    RHO_FLOOR,
    AppearanceCamera,
    AppearanceModel,
    EllipsoidCamera,
    FeatureImage,
    PositionFix,
    axis_angle_quaternion,
    colour_log_likelihood,
    intersect_rays,
    quaternion_multiply,
    quaternion_to_rotation,
    reference_histogram,
    rotation_to_quaternion,
)
from .gaussian_mixtures import (
    fit_kde_mixture,
    floor_covariances,
    mixture_mode,
    mixture_product,
    prune_mixture,
    reduce_mixture,
)
from .kalman import KalmanFilter
from .weighting import draw_ancestors, particle_weights

Array = NDArray[np.float64]

STATE_BYTES = 80  # |chi| = 24 (position) + 24 (velocity) + 32 (quaternion), Sec. "T0" [L2341]
WEIGHT_BYTES = 8
GMM3_BYTES = 80  # weight + 3 mean + 6 covariance doubles
GMM2_BYTES = 48  # weight + 2 mean + 3 covariance doubles
PIXEL_BYTES = 16  # the baseline's 2-D estimate


def routing_tree(positions: Array, base: Array) -> list[int]:
    """Parent of each camera (``-1`` = the base station): Prim's minimum spanning tree grown
    from the base (the paper's trees, Figs 40c/50c, are not given numerically; spec A-V-1)."""
    n = len(positions)
    nodes = np.vstack([base[None], positions])
    parent = [-1] * n
    in_tree = np.zeros(n + 1, bool)
    in_tree[0] = True
    best = np.linalg.norm(nodes - nodes[0], axis=1)
    link = np.zeros(n + 1, int)
    for _ in range(n):
        cand = np.where(in_tree, np.inf, best)
        j = int(np.argmin(cand))
        in_tree[j] = True
        parent[j - 1] = int(link[j]) - 1
        d = np.linalg.norm(nodes - nodes[j], axis=1)
        closer = (~in_tree) & (d < best)
        best[closer] = d[closer]
        link[closer] = j
    return parent


def hops(parent: Sequence[int], n: int) -> int:
    """Links a message from camera ``n`` crosses to reach the base station."""
    k, p = 1, parent[n]
    while p >= 0:
        k, p = k + 1, parent[p]
    return k


def children_first(parent: Sequence[int]) -> list[int]:
    """Nodes ordered so that every node comes after all of its descendants."""
    depth = []
    for n in range(len(parent)):
        d, p = 0, parent[n]
        while p >= 0:
            d, p = d + 1, parent[p]
        depth.append(d)
    return sorted(range(len(parent)), key=lambda n: -depth[n])


@dataclass(frozen=True)
class CameraNetwork:
    """The cameras' appearance sensor models (one per camera, in network order) and the routing
    tree (``parent[n]``, ``-1`` = the base station)."""

    sensors: tuple[AppearanceCamera, ...]
    parent: tuple[int, ...]

    @classmethod
    def build(
        cls,
        cameras: Sequence[EllipsoidCamera],
        model: AppearanceModel,
        semi_axes: Sequence[float],
        base: Sequence[float],
    ) -> CameraNetwork:
        axes = (float(semi_axes[0]), float(semi_axes[1]), float(semi_axes[2]))
        ids = [c.sensor_id for c in cameras]
        if len(set(ids)) != len(ids):
            raise ConfigError(invalid("cameras[].sensor_id", ids, "distinct camera ids"))
        pos = np.array([c.centre for c in cameras])
        parent = routing_tree(pos, np.asarray(base, float))
        return cls(tuple(AppearanceCamera(c, model, axes) for c in cameras), tuple(parent))

    @property
    def cameras(self) -> tuple[EllipsoidCamera, ...]:
        return tuple(s.camera for s in self.sensors)

    @property
    def semi_axes(self) -> tuple[float, float, float]:
        return self.sensors[0].semi_axes

    def usable(self, x: Array, q: Array) -> list[int]:
        """Cameras whose image holds a usable ellipse of the target at ``x``."""
        return [n for n, s in enumerate(self.sensors) if s.participates(x, q)]

    def frames(self, measurements: Sequence[Measurement]) -> dict[int, FeatureImage]:
        """Each camera's frame by camera index; measurements of other sensors are left out."""
        index = {s.sensor_id: n for n, s in enumerate(self.sensors)}
        out: dict[int, FeatureImage] = {}
        for m in measurements:
            n = index.get(m.sensor_id)
            if n is None:
                continue
            if not isinstance(m.value, FeatureImage):
                raise MeasurementError(
                    invalid(f"value of camera {m.sensor_id!r}", type(m.value), "a FeatureImage")
                )
            out[n] = m.value
        return out

    def measurements(self, time: float, frames: Sequence[FeatureImage]) -> list[Measurement]:
        """One measurement per camera from frames in network order."""
        return [Measurement(time, s.sensor_id, f) for s, f in zip(self.sensors, frames)]


def camera_view(
    sensor: AppearanceCamera, frame: FeatureImage, x: Array, q: Array, sharpness: float
) -> tuple[Array, Array, float]:
    """A camera's evidence on the orientation (Eq. 77): the similarity-weighted mean viewpoint
    ``e_avg`` (body frame, towards the camera), the world direction from the target to the
    camera, and the weight ``max_j rho_j``. The viewpoints are weighted by ``rho_j^gamma`` like
    the particles (``gamma = 1`` is the paper's ``rho_j``)."""
    rho = sensor.view_similarities(frame, x, q)
    w = np.maximum(rho, RHO_FLOOR) ** sharpness
    e_avg = w @ sensor.model.viewpoints / max(w.sum(), 1e-300)
    e_avg /= max(np.linalg.norm(e_avg), 1e-12)
    centre = sensor.camera.centre
    to_cam = (centre - x) / np.linalg.norm(centre - x)
    return e_avg, to_cam, float(rho.max())


def minimal_rotation_quaternion(e_avg: Array, to_cam: Array) -> Array:
    """One camera's orientation (Eqs. 77-78): the smallest rotation taking the camera's axis in
    the body frame, ``-e_avg``, to the camera-to-target direction ``-to_cam`` (spec A-V-7)."""
    a, b = -e_avg, -to_cam
    axis = np.cross(a, b)
    angle = float(np.arccos(np.clip(np.dot(a, b), -1.0, 1.0)))
    return axis_angle_quaternion(axis, angle)


def wahba_rotation(body: Array, world: Array, weights: Array) -> Array:
    """Rotation ``R`` minimising ``sum_n w_n |R b_n - d_n|^2`` (Kabsch/SVD) for two or more
    non-parallel pairs; the full rotation, roll included."""
    H = np.einsum("n,ni,nj->ij", weights, world, body)
    U, _, Vt = np.linalg.svd(H)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
    return U @ D @ Vt


def fuse_orientation(
    views: Sequence[tuple[Array, Array, float]],
    prior: Array,
    alpha: float,
    method: Literal["paper", "wahba"] = "wahba",
) -> Array:
    """Network orientation from the cameras' views, blended with the prior:
    ``theta = alpha theta_all + (1 - alpha) theta_prior`` renormalised (spec Sec. 2.9).

    ``paper``: ``theta_all = sum w_n theta_n / |.|`` over the per-camera minimal rotations (Eq.
    78; each sets the unobservable roll arbitrarily, so their average is poor). ``wahba``: the
    rotation that best maps every camera's ``e_avg`` onto its target-to-camera direction at once
    (the same evidence, fused as one least-squares problem); with one camera, the minimal
    correction of the prior."""
    if not views:
        return prior
    if method == "paper":
        acc = np.zeros(4)
        for e_avg, to_cam, wn in views:
            qn = minimal_rotation_quaternion(e_avg, to_cam)
            acc += wn * (qn if np.dot(qn, prior) >= 0 else -qn)
        if np.linalg.norm(acc) < 1e-12:
            return prior
        q_all = acc / np.linalg.norm(acc)
    else:
        body = np.array([v[0] for v in views])
        world = np.array([v[1] for v in views])
        w = np.array([v[2] for v in views])
        if len(views) >= 2 and np.linalg.matrix_rank(world, tol=1e-3) >= 2:
            q_all = rotation_to_quaternion(wahba_rotation(body, world, w))
        else:
            R0 = quaternion_to_rotation(prior)
            fix = minimal_rotation_quaternion(-(R0 @ body[0]), -world[0])  # R0 b -> d
            q_all = quaternion_multiply(fix, prior)
    q_all = q_all if np.dot(q_all, prior) >= 0 else -q_all
    q = alpha * q_all + (1 - alpha) * prior
    return q / np.linalg.norm(q)


@dataclass(frozen=True)
class TrackerSettings:
    """The constants the paper leaves open (spec Sec. 7.2, [C])."""

    n_particles: int = 1000  # T0/T1/T2
    n_particles_2d: int = 200  # T3/T4/P
    sigma: float = 0.15  # proposal std (m), room scale
    sigma_px: float = 6.0  # image-plane proposal std (px)
    sharpness: float = 20.0  # gamma in rho^gamma (1 = the paper)
    m_max: int = 5
    k_reduce: int = 4
    orientation_alpha: float = 0.3
    kf_q: float = 0.01  # CV process noise PSD (m^2/step^3)
    kf_r: float = 0.1  # std of a position estimate (m) in the velocity filter
    depth_fraction: float = 0.5  # T3: depth std = fraction x predicted depth
    base_components: int = 64  # T1: components kept at the base after each product
    estimate_orientation: bool = True
    orientation_fusion: Literal["paper", "wahba"] = "wahba"


@dataclass(frozen=True)
class Communication:
    """What the cameras sent in one update: the payload they originate (the paper's accounting,
    one hop each), the same payload counted on every link it crosses on the routing tree, and the
    number of cameras whose evidence was fused."""

    bytes_sent: int = 0
    link_bytes: int = 0
    cameras_used: int = 0


@dataclass(frozen=True, eq=False)
class PixelTrack:
    """One camera's 2-D colour particle filter (baseline P): its fixed ellipse ``shape``
    ``(2, 2)`` and its equally weighted pixel particles."""

    shape: Array
    particles: Particles


@dataclass(frozen=True, eq=False)
class SmartCameraBelief:
    """Everything a smart-camera tracker carries from one step to the next.

    ``kinematics``: the velocity filter's ``N([position, velocity], P)``; ``quaternion``: the
    target's orientation; ``sent``: the last update's communication; ``particles``: the last
    update's weighted 3-D particles (T0-T2, for inspection); ``extra``: other estimates of the
    last update (T4: ``"eq103"``); ``references`` and ``pixel_tracks``: baseline P's reference
    histograms and running 2-D trackers, by camera index. ``mean``/``cov`` are the position's.
    """

    kinematics: Gaussian
    quaternion: Array
    sent: Communication = Communication()
    particles: Particles | None = None
    extra: Mapping[str, Array] = field(default_factory=dict)
    references: Mapping[int, Array] = field(default_factory=dict)
    pixel_tracks: Mapping[int, PixelTrack] = field(default_factory=dict)

    @property
    def position(self) -> Array:
        return self.kinematics.mean[:3]

    @property
    def velocity(self) -> Array:
        return self.kinematics.mean[3:]

    @property
    def mean(self) -> Array:
        return self.position

    @property
    def cov(self) -> Array:
        return self.kinematics.cov[:3, :3]


@dataclass(frozen=True, eq=False)
class Fusion:
    """What one update's fusion produced: the position estimate (None: nothing to fuse), the
    cameras whose frames inform the orientation, the communication and the extras."""

    estimate: Array | None
    orientation_cameras: Sequence[int]
    sent: Communication
    particles: Particles | None = None
    extra: Mapping[str, Array] = field(default_factory=dict)
    pixel_tracks: Mapping[int, PixelTrack] | None = None  # P: the 2-D trackers after the step


def _require_rng(rng: np.random.Generator | None) -> np.random.Generator:
    if rng is None:
        raise ConfigError(invalid("rng", rng, "a numpy.random.Generator (the update draws)"))
    return rng


class SmartCameraTracker:
    """The part every tracker shares: the velocity filter's prediction, the update's skeleton
    (fuse the frames, update the velocity filter, then the orientation) and the configuration.
    A subclass supplies :meth:`fuse`."""

    name = "tracker"

    def __init__(self, net: CameraNetwork, settings: TrackerSettings = TrackerSettings()) -> None:
        self.net = net
        self.s = settings
        self.kf = KalmanFilter(
            ConstantVelocity(ndim=3, q=settings.kf_q),
            [PositionFix("estimate", cov=settings.kf_r**2 * np.eye(3), position_index=(0, 1, 2))],
        )

    def initial_belief(
        self,
        position: Array,
        velocity: Array,
        quaternion: Array,
        frames: Sequence[Measurement] = (),
    ) -> SmartCameraBelief:
        """The manual initialisation: state known to 5 cm and 5 cm/step; ``frames`` (the first
        frame of each camera) is read by trackers that take a reference from it (P)."""
        kin = Gaussian(np.concatenate([position, velocity]), np.diag([0.05**2] * 3 + [0.05**2] * 3))
        q = np.asarray(quaternion, float) / np.linalg.norm(quaternion)
        return SmartCameraBelief(kin, q)

    def predict(
        self, belief: SmartCameraBelief, dt: float, rng: np.random.Generator | None = None
    ) -> SmartCameraBelief:
        """Constant-velocity prediction of the velocity filter (``x0 + v0`` for ``dt = 1``)."""
        return replace(belief, kinematics=self.kf.predict(belief.kinematics, dt))

    def update(
        self,
        belief: SmartCameraBelief,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> SmartCameraBelief:
        """Fuse the cameras' frames at the predicted position, then update the velocity filter
        with the estimate and the orientation from the frames (Eqs. 77-78)."""
        frames = self.net.frames(measurements)
        fused = self.fuse(belief, frames, _require_rng(rng))
        kin = belief.kinematics
        est = fused.estimate
        if est is not None and np.all(np.isfinite(est)):
            time = max((m.time for m in measurements), default=0.0)
            kin = self.kf.update(kin, [Measurement(time, "estimate", est)])
        q = belief.quaternion
        if self.s.estimate_orientation and fused.orientation_cameras:
            x = kin.mean[:3]
            views = [
                camera_view(self.net.sensors[n], frames[n], x, q, self.s.sharpness)
                for n in fused.orientation_cameras
            ]
            q = fuse_orientation(views, q, self.s.orientation_alpha, self.s.orientation_fusion)
        return replace(
            belief,
            kinematics=kin,
            quaternion=q,
            sent=fused.sent,
            particles=fused.particles,
            extra=fused.extra,
            pixel_tracks=belief.pixel_tracks if fused.pixel_tracks is None else fused.pixel_tracks,
        )

    def fuse(
        self,
        belief: SmartCameraBelief,
        frames: Mapping[int, FeatureImage],
        rng: np.random.Generator,
    ) -> Fusion:
        """The cameras' evidence fused into a position estimate at the predicted ``belief``."""
        raise NotImplementedError

    def participating(
        self, belief: SmartCameraBelief, frames: Mapping[int, FeatureImage]
    ) -> list[int]:
        """Cameras that see the predicted target and sent a frame, in network order."""
        return [n for n in self.net.usable(belief.position, belief.quaternion) if n in frames]


class _ModalTracker(SmartCameraTracker):
    """A tracker family whose variants (the paper's T0..T4) differ by ``mode`` only."""

    modes: tuple[str, ...] = ()

    def __init__(
        self, mode: str, net: CameraNetwork, settings: TrackerSettings = TrackerSettings()
    ) -> None:
        if mode not in self.modes:
            raise ConfigError(invalid("mode", mode, f"one of {list(self.modes)}"))
        super().__init__(net, settings)
        self.name = self.mode = mode


def _mixture_bytes(
    parent: Sequence[int], mixtures: Mapping[int, GaussianMixture], size: int
) -> Communication:
    """Every camera's mixture sent straight to the base (T1, T4)."""
    sent = sum(size * len(g.weights) for g in mixtures.values())
    links = sum(size * len(g.weights) * hops(parent, n) for n, g in mixtures.items())
    return Communication(STATE_BYTES + sent, STATE_BYTES + links, len(mixtures))


class Particle3DTracker(_ModalTracker):
    """T0, T1 and T2: synchronised 3-D particles, fused as weights, mixtures, or in-network."""

    modes = ("T0", "T1", "T2")

    def fuse(
        self,
        belief: SmartCameraBelief,
        frames: Mapping[int, FeatureImage],
        rng: np.random.Generator,
    ) -> Fusion:
        s = self.s
        x0, q = belief.position, belief.quaternion
        used = self.participating(belief, frames)
        states = x0 + s.sigma * rng.standard_normal((s.n_particles, 3))
        logw = {
            n: s.sharpness * self.net.sensors[n].log_likelihood(frames[n], states, q) for n in used
        }
        parent = self.net.parent
        if not used:
            return Fusion(None, used, Communication(STATE_BYTES, STATE_BYTES, 0))
        total = np.asarray(sum(logw.values()), dtype=np.float64)
        particles = Particles(states, total)
        if self.mode == "T0":
            w = particle_weights(total).weights
            nbytes = STATE_BYTES + WEIGHT_BYTES * s.n_particles * len(used)
            links = STATE_BYTES + sum(WEIGHT_BYTES * s.n_particles * hops(parent, n) for n in used)
            sent = Communication(nbytes, links, len(used))
            # MMSE (Eq. 82) is the estimate; MLE (Eq. 83) and MAP (Eq. 84, the prior N(x0, Σ0)
            # being the proposal the particles were drawn from) ride along as extras
            log_prior = -0.5 * np.sum((states - x0) ** 2, axis=1) / s.sigma**2
            extra = {"MLE": states[np.argmax(total)], "MAP": states[np.argmax(total + log_prior)]}
            return Fusion(w @ states, used, sent, particles, extra=extra)
        mixtures = {}
        for n in used:
            w = np.exp(logw[n] - logw[n].max())
            mixtures[n], _ = fit_kde_mixture(states, w, rng, m_max=s.m_max)
        if self.mode == "T1":
            fused = _product_all(list(mixtures.values()), s.base_components)
            sent = _mixture_bytes(parent, mixtures, GMM3_BYTES)
        else:
            fused, nbytes = _aggregate(parent, mixtures, s.k_reduce, rng)
            sent = Communication(STATE_BYTES + nbytes, STATE_BYTES + nbytes, len(used))
        return Fusion(mixture_mode(fused), used, sent, particles)


def _product_all(mixtures: Sequence[GaussianMixture], keep: int) -> GaussianMixture:
    out = mixtures[0]
    for g in mixtures[1:]:
        out = prune_mixture(mixture_product(out, g), keep)
    return out


def _aggregate(
    parent: Sequence[int],
    own: dict[int, GaussianMixture],
    k: int,
    rng: np.random.Generator,
) -> tuple[GaussianMixture, int]:
    """In-network product and reduction along the routing tree (T2/T3, Eqs. 88-93).

    Each node multiplies its own mixture (if it has one) with what its children sent, reduces
    the product to ``k`` components and sends it to its parent; the base multiplies what reaches
    it. Returns the base's mixture and the bytes sent on all links."""
    inbox: dict[int, list[GaussianMixture]] = {n: [] for n in range(-1, len(parent))}
    sent = 0
    for n in children_first(parent):
        parts = ([own[n]] if n in own else []) + inbox[n]
        if not parts:
            continue
        msg = reduce_mixture(_product_all(parts, k * k * 4), k, rng)
        sent += GMM3_BYTES * len(msg.weights) if msg.dim == 3 else GMM2_BYTES * len(msg.weights)
        inbox[parent[n]].append(msg)
    return _product_all(inbox[-1], k * k * 4), sent


class ImagePlaneTracker(_ModalTracker):
    """T3 (lift to 3-D, in-network) and T4 (2-D mixtures to the base, MAP)."""

    modes = ("T3", "T4")

    def _camera_mixture(
        self, n: int, frame: FeatureImage, x0: Array, q: Array, rng: np.random.Generator
    ) -> GaussianMixture:
        """2-D particles around the predicted pixel, weighed by ``rho^gamma`` in the predicted
        ellipse moved to each particle (Alg. 3, Eqs. 94-98), compressed to a 2-D mixture."""
        s = self.s
        sensor = self.net.sensors[n]
        yc, _ = sensor.predicted_region(x0, q)
        pts = yc + s.sigma_px * rng.standard_normal((s.n_particles_2d, 2))
        lw = s.sharpness * sensor.log_likelihood_pixels(frame, pts, x0, q)
        gm, _ = fit_kde_mixture(pts, np.exp(lw - lw.max()), rng, m_max=s.m_max)
        return gm

    def _lift(self, n: int, gm: GaussianMixture, x0: Array) -> GaussianMixture:
        """3-D Gaussians along the rays through the 2-D components at the predicted depth
        ``z``: lateral covariance ``(z/f)^2 J S J^T``, depth std ``depth_fraction * z`` (A-V-3)."""
        cam = self.net.cameras[n]
        z = float(cam.depth(x0))
        K, R = cam.camera.K, cam.camera.R
        f = K[0, 0]
        a = (
            np.column_stack(
                [
                    (gm.means[:, 0] - K[0, 2]) / f,
                    (gm.means[:, 1] - K[1, 2]) / K[1, 1],
                    np.ones(len(gm.weights)),
                ]
            )
            @ R
        )  # ray direction at unit depth, world frame
        means = cam.centre + z * a
        J = (z / f) * R.T[:, :2]  # d X / d (u, v)
        lateral = np.einsum("ia,kab,jb->kij", J, gm.covs, J)
        depth = (self.s.depth_fraction * z) ** 2 * a[:, :, None] * a[:, None, :]
        return GaussianMixture(gm.weights, means, floor_covariances(lateral + depth, 1e-6))

    def fuse(
        self,
        belief: SmartCameraBelief,
        frames: Mapping[int, FeatureImage],
        rng: np.random.Generator,
    ) -> Fusion:
        x0, q = belief.position, belief.quaternion
        used = self.participating(belief, frames)
        mixtures = {n: self._camera_mixture(n, frames[n], x0, q, rng) for n in used}
        if not used:
            return Fusion(None, used, Communication(STATE_BYTES, STATE_BYTES, 0))
        if self.mode == "T3":
            lifted = {n: self._lift(n, g, x0) for n, g in mixtures.items()}
            fused, nbytes = _aggregate(self.net.parent, lifted, self.s.k_reduce, rng)
            sent = Communication(STATE_BYTES + nbytes, STATE_BYTES + nbytes, len(used))
            return Fusion(mixture_mode(fused), used, sent)
        cams = [self.net.cameras[n] for n in used]
        gms = [mixtures[n] for n in used]
        prior_cov = self.s.sigma**2 * np.eye(3)
        sent = _mixture_bytes(self.net.parent, mixtures, GMM2_BYTES)
        eq103 = closed_form_map(cams, gms, x0, prior_cov)
        return Fusion(map_estimate(cams, gms, x0, prior_cov), used, sent, extra={"eq103": eq103})


def _neg_log_posterior(
    x: Array,
    cams: Sequence[EllipsoidCamera],
    terms: Sequence[tuple[Array, Array, Array]],
    x0: Array,
    prec0: Array,
) -> tuple[float, Array]:
    """``-log`` of Eq. 99 and its gradient; ``terms`` per camera: means, inverse covariances and
    log(weight / sqrt(det 2 pi S)) of its 2-D mixture."""
    r = x - x0
    val = 0.5 * r @ prec0 @ r
    grad = prec0 @ r
    for cam, (means, inv, logc) in zip(cams, terms):
        P = cam.P
        h = P @ np.append(x, 1.0)
        y = h[:2] / h[2]
        J = (P[:2, :3] - np.outer(y, P[2, :3])) / h[2]  # d y / d x
        diff = y - means
        sd = np.einsum("kij,kj->ki", inv, diff)
        logn = logc - 0.5 * np.einsum("ki,ki->k", diff, sd)
        top = logn.max()
        resp = np.exp(logn - top)
        total = resp.sum()
        val -= float(top + np.log(total))
        grad += J.T @ (resp @ sd) / total
    return float(val), grad


def map_estimate(
    cams: Sequence[EllipsoidCamera], gms: Sequence[GaussianMixture], x0: Array, prior_cov: Array
) -> Array:
    """Numerical MAP of Eq. 99 (L-BFGS on ``-log p`` with its gradient) started at ``x0`` and at
    the ray intersection of each camera's heaviest component (spec A-V-9)."""
    prec0 = np.linalg.inv(prior_cov)
    terms = [
        (
            gm.means,
            np.linalg.inv(gm.covs),
            np.log(gm.weights) - 0.5 * np.linalg.slogdet(2 * np.pi * gm.covs)[1],
        )
        for gm in gms
    ]
    starts = [x0]
    if len(cams) >= 2:
        heads = [gm.means[int(np.argmax(gm.weights))] for gm in gms]
        rays = np.array([c.ray(h) for c, h in zip(cams, heads)])
        starts.append(intersect_rays(np.array([c.centre for c in cams]), rays))
    best, best_val = x0, np.inf
    for s0 in starts:
        res = minimize(
            _neg_log_posterior, s0, args=(cams, terms, x0, prec0), jac=True, method="L-BFGS-B"
        )
        if np.isfinite(res.fun) and res.fun < best_val:
            best, best_val = res.x, res.fun
    return np.asarray(best, float)


def closed_form_map(
    cams: Sequence[EllipsoidCamera], gms: Sequence[GaussianMixture], x0: Array, prior_cov: Array
) -> Array:
    """The one-step closed form of Eq. 103 in homogeneous coordinates, evaluated at ``x0``:
    ``x = [S0^-1 + sum_i R_i / p_i(x0)]^-1 S0^-1 x0`` with
    ``R_i = sum_j beta_ij (I - p3 x0^T / p3^T x0) Q_ij^T S_ij^-1 Q_ij``.

    The paper prints ``R_ij = Q^T S^-1 Q (I - x p3^T / p3^T x)``; that product annihilates ``x0``
    (``(I - x0 p3^T / p3^T x0) x0 = 0``), so Eq. 103 as printed always returns ``x0``. The
    projector belongs on the left (it is the transposed Jacobian of the perspective division),
    which is what is used here. ``S0`` is padded to 4x4 with a tiny variance on the scale."""
    xh = np.append(x0, 1.0)
    S0 = np.zeros((4, 4))
    S0[:3, :3] = prior_cov
    S0[3, 3] = 1e-9
    P0 = np.linalg.inv(S0)
    A = P0.copy()
    for cam, gm in zip(cams, gms):
        P = cam.P
        p3 = P[2]
        depth = float(p3 @ xh)
        y = (P @ xh)[:2] / depth
        proj = np.eye(4) - np.outer(p3, xh) / depth
        inv = np.linalg.inv(gm.covs)
        diff = y - gm.means
        logb = np.log(gm.weights) - 0.5 * np.einsum("ki,kij,kj->k", diff, inv, diff)
        logb -= 0.5 * np.log(np.linalg.det(2 * np.pi * gm.covs))
        beta = np.exp(logb - logb.max())  # common factor cancels in R_i / p_i
        Ri = np.zeros((4, 4))
        for j in range(len(gm.weights)):
            Q = (P[:2] - np.outer(gm.means[j], p3)) / depth
            Ri += beta[j] * proj @ Q.T @ inv[j] @ Q
        A += Ri / beta.sum()
    xh_new = np.linalg.solve(A, P0 @ xh)
    return xh_new[:3] / xh_new[3]


class RayIntersectionTracker(SmartCameraTracker):
    """Baseline P: a colour particle filter per camera (Perez et al.: fixed ellipse, random-walk
    pixels, likelihood ``exp(-20 (1 - rho))``) and least-squares ray intersection in 3-D."""

    name = "P"

    def initial_belief(
        self,
        position: Array,
        velocity: Array,
        quaternion: Array,
        frames: Sequence[Measurement] = (),
    ) -> SmartCameraBelief:
        """Manual initialisation at the first frames: each camera that sees the target takes its
        reference histogram from its frame and starts a 2-D tracker there."""
        belief = super().initial_belief(position, velocity, quaternion)
        first = self.net.frames(frames)
        refs: dict[int, Array] = {}
        tracks: dict[int, PixelTrack] = {}
        for n in self.net.usable(belief.position, belief.quaternion):
            if n not in first:
                continue
            yc, B = self.net.sensors[n].predicted_region(belief.position, belief.quaternion)
            refs[n] = reference_histogram(first[n], yc, B)
            tracks[n] = self._start(yc, B)
        return replace(belief, references=refs, pixel_tracks=tracks)

    def _start(self, yc: Array, B: Array) -> PixelTrack:
        return PixelTrack(B, Particles.uniform(np.repeat(yc[None], self.s.n_particles_2d, axis=0)))

    def fuse(
        self,
        belief: SmartCameraBelief,
        frames: Mapping[int, FeatureImage],
        rng: np.random.Generator,
    ) -> Fusion:
        """Each camera's colour particle filter (random walk, weigh, estimate, resample); a
        tracker whose estimate leaves the image has lost the target and stops."""
        estimates: dict[int, Array] = {}
        tracks: dict[int, PixelTrack] = {}
        for n, track in belief.pixel_tracks.items():
            if n not in frames:
                tracks[n] = track
                continue
            cam = self.net.cameras[n]
            pixels = track.particles.states
            pts = pixels + self.s.sigma_px * rng.standard_normal(pixels.shape)
            lw = colour_log_likelihood(frames[n], pts, track.shape, belief.references[n])
            pw = particle_weights(lw)
            est = pw.weights @ pts
            wd, ht = cam.size
            if not (0 <= est[0] < wd and 0 <= est[1] < ht):
                continue  # the 2-D tracker lost the target
            estimates[n] = est
            tracks[n] = PixelTrack(track.shape, Particles.uniform(pts[draw_ancestors(pw, rng)]))
        estimate: Array | None = None
        if len(estimates) >= 2:
            cams = [self.net.cameras[n] for n in estimates]
            rays = np.array([c.ray(estimates[n]) for c, n in zip(cams, estimates)])
            estimate = intersect_rays(np.array([c.centre for c in cams]), rays)
        nbytes = PIXEL_BYTES * len(estimates)
        links = sum(PIXEL_BYTES * hops(self.net.parent, n) for n in estimates)
        sent = Communication(nbytes, links, len(estimates))
        return Fusion(estimate, (), sent, pixel_tracks=tracks)

    def update(
        self,
        belief: SmartCameraBelief,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> SmartCameraBelief:
        """The shared update, then a 2-D tracker starts in every camera the target has entered
        (reference: the camera's earlier one, else the mean of the others')."""
        out = super().update(belief, measurements, rng)
        refs = dict(out.references)
        tracks = dict(out.pixel_tracks)
        for n in self.net.usable(out.position, out.quaternion):
            if n in tracks:
                continue
            if n not in refs:
                if not refs:
                    continue
                refs[n] = np.mean(list(refs.values()), axis=0)
            yc, B = self.net.sensors[n].predicted_region(out.position, out.quaternion)
            tracks[n] = self._start(yc, B)
        return replace(out, references=refs, pixel_tracks=tracks)
