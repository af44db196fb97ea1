"""3-D tracking with a network of smart cameras (Kushwaha 2010, Ch. V, Algorithms 2-3, Eqs. 70-103).

Every tracker follows one ellipsoidal target (position, velocity, scalar-last orientation
quaternion) from per-frame colour/texture bins of each camera, and counts the bytes its cameras
send per step:

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
  closed form of Eq. 103 is returned beside it.
* ``P`` -- the baseline: an independent colour particle filter per camera (Perez et al.) and the
  least-squares intersection of the rays through the 2-D estimates.

The paper weighs a particle by ``rho`` itself; ``rho`` of a wrong region is rarely far below
that of the right one, so all trackers here use ``rho^gamma`` (``sharpness`` gamma, 1 = the
paper). A camera takes part in a step when the target's predicted ellipse is usable in its image
(:meth:`EllipsoidCamera.participates`); otherwise it contributes the factor 1 and sends nothing.
After each estimate a constant-velocity Kalman filter gives the position and velocity that
predict the next step (the paper's N-scan smoother; at the newest step a fixed-lag smoother's
estimate is the filtered one), and the orientation is updated from the viewpoint similarities
(Eqs. 77-78).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import minimize
from scipy.special import logsumexp

from ..core.beliefs import Gaussian, GaussianMixture
from ..core.errors import ConfigError, invalid
from ..core.measurement import Measurement
from ..core.resampling import systematic
from ..motion import ConstantVelocity
from ..perception.appearance import (
    N_HS,
    AppearanceModel,
    FeatureImage,
    bhattacharyya,
    region_histograms,
)
from ..sensors import PositionFix
from ..sensors.ellipsoid_camera import (
    EllipsoidCamera,
    axis_angle_quaternion,
    intersect_rays,
    quaternion_multiply,
    quaternion_to_rotation,
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

Array = NDArray[np.float64]

STATE_BYTES = 80  # |chi| = 24 (position) + 24 (velocity) + 32 (quaternion), Sec. "T0" [L2341]
WEIGHT_BYTES = 8
GMM3_BYTES = 80  # weight + 3 mean + 6 covariance doubles
GMM2_BYTES = 48  # weight + 2 mean + 3 covariance doubles
PIXEL_BYTES = 16  # the baseline's 2-D estimate
RHO_FLOOR = 1e-3


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
    """The cameras, the target's appearance model and shape, and the routing tree."""

    cameras: tuple[EllipsoidCamera, ...]
    model: AppearanceModel
    semi_axes: tuple[float, float, float]
    parent: tuple[int, ...]

    @classmethod
    def build(
        cls,
        cameras: Sequence[EllipsoidCamera],
        model: AppearanceModel,
        semi_axes: Sequence[float],
        base: Sequence[float],
    ) -> CameraNetwork:
        pos = np.array([c.centre for c in cameras])
        parent = routing_tree(pos, np.asarray(base, float))
        return cls(tuple(cameras), model, tuple(semi_axes), tuple(parent))  # type: ignore[arg-type]

    def usable(self, x: Array, q: Array) -> list[int]:
        """Cameras whose image holds a usable ellipse of the target at ``x``."""
        out = []
        for n, cam in enumerate(self.cameras):
            yc, B = cam.ellipse(x, q, self.semi_axes)
            if bool(cam.participates(yc, B)):
                out.append(n)
        return out

    def log_similarity(
        self, n: int, features: FeatureImage, x: Array, q: Array, sharpness: float
    ) -> Array:
        """``gamma log rho_n(x_i)`` for 3-D candidates ``x`` ``(M, 3)`` (Eqs. 71, 74-76, 81)."""
        cam = self.cameras[n]
        yc, B = cam.ellipse(x, q, self.semi_axes)
        view = self.model.view_index(cam.centre, x, quaternion_to_rotation(q))
        rho = self.model.similarity(features, yc, B, view)
        return sharpness * np.log(np.maximum(rho, RHO_FLOOR))

    def camera_view(
        self, n: int, features: FeatureImage, x: Array, q: Array, sharpness: float
    ) -> tuple[Array, Array, float]:
        """Camera ``n``'s evidence on the orientation (Eq. 77): the similarity-weighted mean
        viewpoint ``e_avg`` (body frame, towards the camera), the world direction from the target
        to the camera, and the weight ``max_j rho_j``. The viewpoints are weighted by
        ``rho_j^gamma`` like the particles (``gamma = 1`` is the paper's ``rho_j``)."""
        cam = self.cameras[n]
        yc, B = cam.ellipse(x, q, self.semi_axes)
        rho = self.model.all_views(features, yc, B)
        w = np.maximum(rho, RHO_FLOOR) ** sharpness
        e_avg = w @ self.model.viewpoints / max(w.sum(), 1e-300)
        e_avg /= max(np.linalg.norm(e_avg), 1e-12)
        to_cam = (cam.centre - x) / np.linalg.norm(cam.centre - x)
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


@dataclass
class StepReport:
    """What a tracker produced at one step."""

    position: Array
    quaternion: Array
    bytes_sent: int  # payload the cameras originate (the paper's accounting, one hop each)
    link_bytes: int  # the same payload counted on every link it crosses on the routing tree
    cameras_used: int
    extra: dict[str, Array] = field(default_factory=dict)


class _Tracker:
    """Shared skeleton: prediction, the velocity filter and the orientation update."""

    name = "tracker"

    def __init__(
        self,
        net: CameraNetwork,
        position: Array,
        velocity: Array,
        quaternion: Array,
        settings: TrackerSettings = TrackerSettings(),
    ) -> None:
        self.net = net
        self.s = settings
        self.q = np.asarray(quaternion, float) / np.linalg.norm(quaternion)
        self.kf = KalmanFilter(
            ConstantVelocity(ndim=3, q=settings.kf_q),
            [PositionFix("estimate", cov=settings.kf_r**2 * np.eye(3), position_index=(0, 1, 2))],
        )
        self.belief = Gaussian(
            np.concatenate([position, velocity]),
            np.diag([0.05**2] * 3 + [0.05**2] * 3),
        )
        self.t = 0

    @property
    def position(self) -> Array:
        return self.belief.mean[:3]

    @property
    def velocity(self) -> Array:
        return self.belief.mean[3:]

    def predicted(self) -> Array:
        return self.position + self.velocity  # x0 + v0 (dt absorbed, Alg. 2)

    def _finish(
        self, estimate: Array | None, frames: Sequence[FeatureImage], used: Sequence[int]
    ) -> Array:
        """Velocity filter on the new estimate, then the orientation update; returns the position."""
        self.t += 1
        prior = self.kf.predict(self.belief, 1.0)
        if estimate is not None and np.all(np.isfinite(estimate)):
            prior = self.kf.update(prior, [Measurement(float(self.t), "estimate", estimate)])
        self.belief = prior
        if self.s.estimate_orientation and used:
            x = self.position
            views = [self.net.camera_view(n, frames[n], x, self.q, self.s.sharpness) for n in used]
            self.q = fuse_orientation(
                views, self.q, self.s.orientation_alpha, self.s.orientation_fusion
            )
        return self.position.copy()

    def step(self, frames: Sequence[FeatureImage], rng: np.random.Generator) -> StepReport:
        raise NotImplementedError


class _ModalTracker(_Tracker):
    """A tracker family whose variants (the paper's T0..T4) differ by ``mode`` only."""

    modes: tuple[str, ...] = ()

    def __init__(
        self,
        mode: str,
        net: CameraNetwork,
        position: Array,
        velocity: Array,
        quaternion: Array,
        settings: TrackerSettings = TrackerSettings(),
    ) -> None:
        if mode not in self.modes:
            raise ConfigError(invalid("mode", mode, f"one of {list(self.modes)}"))
        super().__init__(net, position, velocity, quaternion, settings)
        self.name = self.mode = mode


class Particle3DTracker(_ModalTracker):
    """T0, T1 and T2: synchronised 3-D particles, fused as weights, mixtures, or in-network."""

    modes = ("T0", "T1", "T2")

    def step(self, frames: Sequence[FeatureImage], rng: np.random.Generator) -> StepReport:
        s = self.s
        x0 = self.predicted()
        used = self.net.usable(x0, self.q)
        particles = x0 + s.sigma * rng.standard_normal((s.n_particles, 3))
        logw = {
            n: self.net.log_similarity(n, frames[n], particles, self.q, s.sharpness) for n in used
        }
        nbytes = links = STATE_BYTES
        parent = self.net.parent
        estimate: Array | None = None
        if not used:
            estimate = None
        elif self.mode == "T0":
            total = sum(logw.values())
            w = np.exp(total - logsumexp(total))
            estimate = w @ particles  # MMSE, Eq. 82
            nbytes += WEIGHT_BYTES * s.n_particles * len(used)
            links += sum(WEIGHT_BYTES * s.n_particles * hops(parent, n) for n in used)
        else:
            mixtures = {}
            for n in used:
                w = np.exp(logw[n] - logw[n].max())
                mixtures[n], _ = fit_kde_mixture(particles, w, rng, m_max=s.m_max)
            if self.mode == "T1":
                nbytes += sum(GMM3_BYTES * len(g.weights) for g in mixtures.values())
                links += sum(
                    GMM3_BYTES * len(g.weights) * hops(parent, n) for n, g in mixtures.items()
                )
                fused = _product_all(list(mixtures.values()), s.base_components)
            else:
                fused, sent = _aggregate(parent, mixtures, s.k_reduce, rng)
                nbytes += sent
                links += sent
            estimate = mixture_mode(fused)
        pos = self._finish(estimate, frames, used)
        return StepReport(pos, self.q.copy(), nbytes, links, len(used))


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
        self, n: int, frame: FeatureImage, x0: Array, rng: np.random.Generator
    ) -> GaussianMixture:
        """2-D particles around the predicted pixel, weighed by ``rho^gamma`` in the predicted
        ellipse moved to each particle (Alg. 3, Eqs. 94-98), compressed to a 2-D mixture."""
        s = self.s
        cam = self.net.cameras[n]
        yc, B = cam.ellipse(x0, self.q, self.net.semi_axes)
        pts = yc + s.sigma_px * rng.standard_normal((s.n_particles_2d, 2))
        view = self.net.model.view_index(cam.centre, x0, quaternion_to_rotation(self.q))
        rho = self.net.model.similarity(frame, pts, np.broadcast_to(B, (len(pts), 2, 2)), view)
        lw = s.sharpness * np.log(np.maximum(rho, RHO_FLOOR))
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

    def step(self, frames: Sequence[FeatureImage], rng: np.random.Generator) -> StepReport:
        x0 = self.predicted()
        used = self.net.usable(x0, self.q)
        mixtures = {n: self._camera_mixture(n, frames[n], x0, rng) for n in used}
        nbytes = links = STATE_BYTES
        estimate: Array | None = None
        extra: dict[str, Array] = {}
        if used and self.mode == "T3":
            lifted = {n: self._lift(n, g, x0) for n, g in mixtures.items()}
            fused, sent = _aggregate(self.net.parent, lifted, self.s.k_reduce, rng)
            nbytes += sent
            links += sent
            estimate = mixture_mode(fused)
        elif used:
            nbytes += sum(GMM2_BYTES * len(g.weights) for g in mixtures.values())
            links += sum(
                GMM2_BYTES * len(g.weights) * hops(self.net.parent, n) for n, g in mixtures.items()
            )
            cams = [self.net.cameras[n] for n in used]
            gms = [mixtures[n] for n in used]
            prior_cov = self.s.sigma**2 * np.eye(3)
            estimate = map_estimate(cams, gms, x0, prior_cov)
            extra["eq103"] = closed_form_map(cams, gms, x0, prior_cov)
        pos = self._finish(estimate, frames, used)
        return StepReport(pos, self.q.copy(), nbytes, links, len(used), extra)


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


class RayIntersectionTracker(_Tracker):
    """Baseline P: a colour particle filter per camera (Perez et al.: fixed ellipse, random-walk
    pixels, likelihood ``exp(-20 (1 - rho))``) and least-squares ray intersection in 3-D."""

    name = "P"

    def __init__(
        self,
        net: CameraNetwork,
        position: Array,
        velocity: Array,
        quaternion: Array,
        first_frames: Sequence[FeatureImage],
        settings: TrackerSettings = TrackerSettings(),
        rng: np.random.Generator | None = None,
    ) -> None:
        super().__init__(net, position, velocity, quaternion, settings)
        self.shape: dict[int, Array] = {}
        self.reference: dict[int, Array] = {}
        self.pixels: dict[int, Array] = {}
        for n in net.usable(position, self.q):  # manual initialisation at the first frame
            self._start(n, first_frames[n], position, reference_from_frame=True)

    def _start(self, n: int, frame: FeatureImage, x: Array, reference_from_frame: bool) -> None:
        cam = self.net.cameras[n]
        yc, B = cam.ellipse(x, self.q, self.net.semi_axes)
        self.shape[n] = B
        if reference_from_frame or n not in self.reference:
            if reference_from_frame:
                self.reference[n] = region_histograms(frame.hs, yc, B, N_HS)[0]
            elif self.reference:
                self.reference[n] = np.mean(list(self.reference.values()), axis=0)
            else:
                return
        self.pixels[n] = np.repeat(yc[None], self.s.n_particles_2d, axis=0)

    def step(self, frames: Sequence[FeatureImage], rng: np.random.Generator) -> StepReport:
        s = self.s
        estimates: dict[int, Array] = {}
        for n in list(self.pixels):
            cam = self.net.cameras[n]
            pts = self.pixels[n] + s.sigma_px * rng.standard_normal(self.pixels[n].shape)
            B = np.broadcast_to(self.shape[n], (len(pts), 2, 2))
            p = region_histograms(frames[n].hs, pts, B, N_HS)
            lw = -20.0 * (1.0 - bhattacharyya(p, self.reference[n]))
            w = np.exp(lw - logsumexp(lw))
            est = w @ pts
            wd, ht = cam.size
            if not (0 <= est[0] < wd and 0 <= est[1] < ht):
                del self.pixels[n]  # the 2-D tracker lost the target
                continue
            estimates[n] = est
            self.pixels[n] = pts[systematic(w, rng)]
        estimate: Array | None = None
        if len(estimates) >= 2:
            cams = [self.net.cameras[n] for n in estimates]
            rays = np.array([c.ray(estimates[n]) for c, n in zip(cams, estimates)])
            estimate = intersect_rays(np.array([c.centre for c in cams]), rays)
        used = list(estimates)
        nbytes = PIXEL_BYTES * len(estimates)
        links = sum(PIXEL_BYTES * hops(self.net.parent, n) for n in estimates)
        pos = self._finish(estimate, frames, [])
        for n in self.net.usable(pos, self.q):  # cameras the target enters start a 2-D tracker
            if n not in self.pixels:
                self._start(n, frames[n], pos, reference_from_frame=False)
        return StepReport(pos, self.q.copy(), nbytes, links, len(used))
