"""Posterior Cramér–Rao lower bound (PCRB) for filtering, by the information recursion.

For ``x_{k+1} = f(x_k, dt_k) + w_k``, ``w_k ~ N(0, Q(dt_k))`` and sensors
``z_{s,k} = h_s(x_k) + v``, ``v ~ N(0, R_s)``, any estimator's mean-square error obeys
``E[(x_hat_k - x_k)(x_hat_k - x_k)^T] >= J_k^-1`` with the Fisher information ``J_k`` of the
recursion of Tichavský, Muravchik & Nehorai (1998, IEEE Trans. Signal Process. 46(5),
Proposition 1, additive-Gaussian case)::

    J_{k+1} = D22_k - D21_k (J_k + D11_k)^-1 D12_k
    D11_k = E[F_k^T Q_k^-1 F_k]            F_k = df/dx at x_k  (motion.jacobian(x_k, dt_k))
    D12_k = -E[F_k]^T Q_k^-1 = D21_k^T     Q_k = motion.noise_cov(dt_k)
    D22_k = Q_k^-1 + E[sum_s q_{s,k+1} H_s^T R_s^-1 H_s]     (sensor.fisher_information(x_{k+1}))
    J_0   = P_0^-1 + E[sum_s q_{s,0} H_s^T R_s^-1 H_s]

Expectations are Monte Carlo averages over true trajectories ``(R, T, d)``; with ``R = 1`` the
bound is evaluated along one known trajectory. ``q_{s,k}`` is the *information reduction
factor* of sensor ``s`` at step ``k``: the ``mask`` entry (1 = reported, 0 = no report, or any
number in [0, 1]) times, optionally, the sensor's detection probability at the true state.
Without clutter the reduction factor of a detection probability ``P_D`` is exactly ``P_D``
(Niu, Willett & Bar-Shalom 2001; Hernandez, Farina & Ristic 2006): the expected information is
``E[1_detected] H^T R^-1 H``.

On a linear-Gaussian model the recursion is the Kalman filter's information-form covariance
recursion, so ``J_k^-1`` equals the filter's posterior covariance.

**Covariance form (singular Q).** When the motion's Jacobian ``F_k`` is the same at every true
state the expectation is taken over (a linear motion model, or one trajectory with
``average=False``), ``D11 = F^T Q^-1 F`` and ``D12 = -F^T Q^-1``, and the matrix inversion lemma
turns Proposition 1 into::

    J_{k+1} = (Q_k + F_k J_k^-1 F_k^T)^-1 + E[sum_s q_{s,k+1} H_s^T R_s^-1 H_s]

(the PCRB for linear dynamics of Ristic, Arulampalam & Gordon 2004, Ch. 4; Bergman 2001), which
needs no ``Q^-1``: it holds for rank-deficient process noise (a Wiener-sequence acceleration, a
constant component), as the limit of the full-rank bound while ``Q + F J^-1 F^T`` stays
invertible, and on a linear-Gaussian model ``J_k^-1`` is the Kalman filter's covariance.
``form="auto"`` (default) takes the information form when ``Q`` is invertible and the
covariance form otherwise; a singular ``Q`` with Jacobians that differ between the averaged
trajectories (nonlinear motion) is a :class:`~fusetrack.core.ConfigError`.

Step convention: ``trajectories[:, k]`` is the true state at step ``k``; ``dt[k]`` is the interval
from step ``k`` to ``k + 1`` (irregular intervals are fine). ``prior_cov`` is the covariance of
``x_0`` *before* the measurements of step 0; mask out step 0 (``mask[..., 0, :] = False``) when
the filter does not update there.

Models are used only through the :class:`~fusetrack.core.MotionModel` and
:class:`~fusetrack.core.SensorModel` protocols (``jacobian``, ``noise_cov``,
``fisher_information``, ``detection_probability``), so any combination works.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Literal, TypedDict, Unpack

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import ellipe

from ..core import ConfigError, MotionModel, SensorModel, ShapeError, invalid

Array = NDArray[np.float64]
Sensors = Mapping[str, SensorModel] | Sequence[SensorModel]
Form = Literal["auto", "information", "covariance"]
FORMS = ("auto", "information", "covariance")


# --------------------------------------------------------------------------------------------
# input checks


def _sensor_list(sensors: Sensors) -> list[SensorModel]:
    if isinstance(sensors, Mapping):
        return list(sensors.values())
    return list(sensors)


def _trajectories(trajectories: ArrayLike, motion: MotionModel) -> tuple[Array, bool]:
    x = np.asarray(trajectories, dtype=float)
    single = x.ndim == 2
    if single:
        x = x[None]
    if x.ndim != 3 or x.shape[1] < 1:
        raise ShapeError(invalid("trajectories.shape", x.shape, "(R, T, d) or (T, d)"))
    d = x.shape[-1]
    mdim = getattr(motion, "dim", d)
    if mdim != d:
        raise ShapeError(invalid("trajectories.shape", x.shape, f"last axis = motion.dim = {mdim}"))
    if not np.all(np.isfinite(x)):
        raise ConfigError(invalid("trajectories", "non-finite values", "finite true states"))
    return x, single


def _steps(dt: float | ArrayLike, T: int) -> Array:
    a = np.asarray(dt, dtype=float)
    if a.ndim == 0:
        a = np.full(max(T - 1, 0), float(a))
    if a.shape != (max(T - 1, 0),):
        raise ShapeError(invalid("dt.shape", a.shape, f"a scalar or ({T - 1},) (one per step)"))
    bad = ~(np.isfinite(a) & (a > 0))
    if bad.any():
        i = int(np.argmax(bad))
        raise ConfigError(invalid(f"dt[{i}]", float(a[i]), "a finite interval > 0 (seconds)"))
    return a


def _prior_information(prior_cov: ArrayLike, d: int) -> Array:
    P = np.asarray(prior_cov, dtype=float)
    if P.shape != (d, d):
        raise ShapeError(invalid("prior_cov.shape", P.shape, f"({d}, {d})"))
    try:
        L = np.linalg.cholesky(P)
    except np.linalg.LinAlgError:
        raise ConfigError(
            invalid("prior_cov", "not positive definite", "a positive-definite covariance")
        ) from None
    Linv = np.linalg.solve(L, np.eye(d))
    return Linv.T @ Linv


def _weights(mask: ArrayLike | None, R: int, T: int, S: int) -> Array:
    """Information-reduction factors ``(R, T, S)`` from the mask (all ones when None)."""
    if mask is None:
        return np.ones((R, T, S))
    m = np.asarray(mask, dtype=float)
    if m.ndim == 2:
        m = m[None]
    try:
        m = np.broadcast_to(m, (R, T, S))
    except ValueError:
        valid = f"(T, S) = ({T}, {S}) or (R, T, S) = ({R}, {T}, {S})"
        raise ShapeError(invalid("mask.shape", np.shape(mask), valid)) from None
    if not np.all((m >= 0.0) & (m <= 1.0)):
        raise ConfigError(invalid("mask", "values outside [0, 1]", "booleans or factors in [0, 1]"))
    return m


def _noise(motion: MotionModel, dt: float, d: int) -> tuple[Array, Array | None]:
    """``Q(dt)`` and ``Q(dt)^-1``, or None in its place when ``Q(dt)`` is singular."""
    Q = np.asarray(motion.noise_cov(dt), dtype=float)
    if Q.shape != (d, d):
        raise ShapeError(invalid(f"motion.noise_cov({dt!r}).shape", Q.shape, f"({d}, {d})"))
    if not np.all(np.isfinite(Q)):
        raise ConfigError(invalid(f"motion.noise_cov(dt={dt!r})", "non-finite", "finite entries"))
    eig = np.linalg.eigvalsh(0.5 * (Q + Q.T))
    if eig[0] > d * np.finfo(float).eps * max(eig[-1], 0.0):
        return Q, np.linalg.inv(Q)
    return Q, None


def _singular_noise(Q: Array, dt: float, why: str) -> ConfigError:
    """The error for a singular ``Q(dt)`` the information form would need to invert."""
    eig = np.round(np.linalg.eigvalsh(0.5 * (Q + Q.T)), 15).tolist()
    return ConfigError(
        invalid(
            f"motion.noise_cov(dt={dt!r})",
            f"singular{why} (eigenvalues {eig})",
            "an invertible process-noise covariance: the PCRB of nonlinear motion needs Q^-1 "
            "(use a model with full-rank noise, e.g. ConstantVelocity(noise='continuous'), a "
            "linear motion model, whose covariance form needs no Q^-1, or deterministic_crlb "
            "for Q = 0)",
        )
    )


def _jacobian(motion: MotionModel, x: Array, dt: float) -> Array:
    R, d = x.shape
    F = np.asarray(motion.jacobian(x, dt), dtype=float)
    try:
        return np.broadcast_to(F, (R, d, d))
    except ValueError:
        valid = f"(R, {d}, {d}) or ({d}, {d})"
        raise ShapeError(invalid("motion.jacobian(x, dt).shape", F.shape, valid)) from None


def _given(name: str, value: ArrayLike | None, shape: tuple[int, ...], valid: str) -> Any:
    """A precomputed per-run array broadcast to ``shape`` and checked finite, or None."""
    if value is None:
        return None
    a = np.asarray(value, dtype=float)
    try:
        a = np.broadcast_to(a, shape)
    except ValueError:
        raise ShapeError(invalid(f"{name}.shape", a.shape, valid)) from None
    if not np.all(np.isfinite(a)):
        raise ConfigError(invalid(name, "non-finite values", "finite matrices"))
    return a


def _given_jacobians(jacobians: ArrayLike | None, R: int, T: int, d: int) -> Any:
    """The precomputed transition Jacobians ``(R, T - 1, d, d)`` (broadcast), or None."""
    n = max(T - 1, 0)
    valid = f"(T - 1, d, d) = ({n}, {d}, {d}) or (R, T - 1, d, d) with R = {R}"
    return _given("jacobians", jacobians, (R, n, d, d), valid)


def _given_information(information: ArrayLike | None, R: int, T: int, S: int, d: int) -> Any:
    """The precomputed per-sensor information ``(R, T, S, d, d)`` (broadcast), or None."""
    valid = f"(T, S, d, d) = ({T}, {S}, {d}, {d}) or (R, T, S, d, d) with R = {R}"
    return _given("information", information, (R, T, S, d, d), valid)


def _measurement_information(
    sensors: list[SensorModel],
    x: Array,
    w: Array,
    use_detection_probability: bool,
    given: Array | None = None,
) -> Array:
    """``sum_s q_s(x) H_s^T R_s^-1 H_s`` at states ``x`` ``(R, d)``, factors ``w`` ``(R, S)``;
    ``given`` ``(R, S, d, d)``: the sensors' information there, precomputed."""
    R, d = x.shape
    info = np.zeros((R, d, d))
    for s, sensor in enumerate(sensors):
        q = w[:, s]
        if use_detection_probability:
            q = q * np.broadcast_to(np.asarray(sensor.detection_probability(x), dtype=float), (R,))
        if not np.any(q > 0):
            continue  # no report: no information (and no need to evaluate the geometry)
        raw = sensor.fisher_information(x) if given is None else given[:, s]
        fi = np.broadcast_to(np.asarray(raw, dtype=float), (R, d, d))
        info += np.where((q > 0)[:, None, None], q[:, None, None] * fi, 0.0)
    return info


def _symmetrise(a: NDArray[np.floating[Any]]) -> Array:
    return np.asarray(0.5 * (a + np.swapaxes(a, -1, -2)), dtype=float)


class BoundOptions(TypedDict, total=False):
    """Keyword options every bound takes (see :func:`posterior_information`)."""

    mask: ArrayLike | None
    use_detection_probability: bool
    information: ArrayLike | None
    jacobians: ArrayLike | None


class PosteriorOptions(BoundOptions, total=False):
    """Keyword options of the posterior bound: :class:`BoundOptions`, ``average`` and
    ``form``."""

    average: bool
    form: Form


@dataclass(frozen=True)
class _Problem:
    """Checked inputs of a bound: true states ``x`` ``(R, T, d)``, ``steps`` ``(T - 1,)``,
    sensors, their factors ``weights`` ``(R, T, S)`` and the prior information ``P_0^-1``."""

    x: Array
    single: bool
    sensors: list[SensorModel]
    steps: Array
    weights: Array
    use_detection_probability: bool
    prior: Array
    given: Array | None = None
    transitions: Array | None = None

    def jacobian(self, motion: MotionModel, k: int) -> Array:
        """The transition Jacobian from step ``k`` to ``k + 1`` per trajectory: ``(R, d, d)``."""
        if self.transitions is not None:
            return np.asarray(self.transitions[:, k])
        return _jacobian(motion, self.x[:, k], float(self.steps[k]))

    def information(self, k: int) -> Array:
        """``sum_s q_{s,k} H_s^T R_s^-1 H_s`` at step ``k`` per trajectory: ``(R, d, d)``."""
        given = None if self.given is None else self.given[:, k]
        return _measurement_information(
            self.sensors, self.x[:, k], self.weights[:, k], self.use_detection_probability, given
        )


def _problem(
    motion: MotionModel,
    sensors: Sensors,
    trajectories: ArrayLike,
    dt: float | ArrayLike,
    prior_cov: ArrayLike,
    options: BoundOptions,
) -> _Problem:
    """Check the inputs shared by every bound (in the order the errors are reported)."""
    x, single = _trajectories(trajectories, motion)
    R, T, d = x.shape
    sl = _sensor_list(sensors)
    steps = _steps(dt, T)
    w = _weights(options.get("mask"), R, T, len(sl))
    use_pd = bool(options.get("use_detection_probability", False))
    prior = _prior_information(prior_cov, d)
    given = _given_information(options.get("information"), R, T, len(sl), d)
    transitions = _given_jacobians(options.get("jacobians"), R, T, d)
    return _Problem(x, single, sl, steps, w, use_pd, prior, given, transitions)


def _information_step(
    J: Array, F: Array, Qi: Array, info: Array, expect: Callable[[Array], Array]
) -> Array:
    """Tichavský et al. 1998, Prop. 1: ``J_{k+1} = D22 - D21 (J_k + D11)^-1 D12``."""
    D11 = expect(np.swapaxes(F, -1, -2) @ (Qi @ F))  # E[F^T Q^-1 F]
    D12 = -np.swapaxes(expect(F), -1, -2) @ Qi  # -E[F]^T Q^-1
    D22 = Qi + info
    Y = np.linalg.solve(J + D11, D12)
    return _symmetrise(D22 - np.swapaxes(D12, -1, -2) @ Y)


def _covariance_step(J: Array, F: Array, Q: Array, info: Array, dt: float) -> Array:
    """Prop. 1 for one Jacobian ``F``, by the matrix inversion lemma:
    ``J_{k+1} = (Q + F J_k^-1 F^T)^-1 + info`` (no ``Q^-1``)."""
    M = _symmetrise(Q + F @ np.linalg.solve(J, np.swapaxes(F, -1, -2)))
    try:
        L = np.linalg.cholesky(M)
    except np.linalg.LinAlgError:
        raise ConfigError(
            invalid(
                f"motion.noise_cov(dt={dt!r}) + F J^-1 F^T",
                "singular (a state component predicted exactly)",
                "a positive-definite predicted covariance (an invertible F or a larger Q)",
            )
        ) from None
    Linv = np.linalg.solve(L, np.broadcast_to(np.eye(M.shape[-1]), M.shape))
    return _symmetrise(np.swapaxes(Linv, -1, -2) @ Linv + info)


def _common_jacobian(F: Array) -> Array | None:
    """``F[0]`` when every trajectory's Jacobian is the same (linear motion), else None."""
    return F[:1] if bool(np.all(F == F[:1])) else None


# --------------------------------------------------------------------------------------------
# public


def posterior_information(
    motion: MotionModel,
    sensors: Sensors,
    trajectories: ArrayLike,
    dt: float | ArrayLike,
    prior_cov: ArrayLike,
    **options: Unpack[PosteriorOptions],
) -> Array:
    """Fisher information matrices ``J_k`` of the Tichavský et al. (1998) recursion.

    ``motion``: a :class:`~fusetrack.core.MotionModel`. ``sensors``: a sequence or a
    mapping of :class:`~fusetrack.core.SensorModel`; their order is the ``S`` axis of ``mask``.
    ``trajectories``: true states ``(R, T, d)`` (or ``(T, d)`` for one). ``dt``: a scalar or one
    interval per step ``(T - 1,)``. ``prior_cov``: ``P_0`` ``(d, d)``.

    ``mask`` ``(T, S)`` or ``(R, T, S)``: which sensor reported at which step (missing reports
    add no information), or any factors in [0, 1]. ``use_detection_probability=True`` multiplies
    every sensor's information by ``sensor.detection_probability(x_k)`` at the true state (its
    detection probability, field of view and range), the expected-information (information
    reduction factor) bound. Both may be used together. ``information`` ``(T, S, d, d)`` or
    ``(R, T, S, d, d)``: each sensor's ``H^T R^-1 H`` at the true states, precomputed (in one
    vectorised call over all steps, or once for several masks and priors), in place of calling
    ``sensor.fisher_information`` at every step. ``jacobians`` ``(T - 1, d, d)`` or
    ``(R, T - 1, d, d)``: the transition Jacobian ``F_k`` of each step at the true states,
    precomputed, in place of ``motion.jacobian`` (a motion whose model changes at known steps,
    e.g. manoeuvres on a schedule; ``motion`` then gives only ``noise_cov``).

    ``average=True`` (default) takes the expectations over the ``R`` trajectories and returns
    ``(T, d, d)``; ``average=False`` runs the recursion along every trajectory separately (each
    its own ``R = 1`` bound) and returns ``(R, T, d, d)``. Everything is vectorised over ``R``.

    ``form``: ``"information"`` (Prop. 1, needs ``Q^-1``: :class:`~fusetrack.core.ConfigError`
    naming ``dt`` when ``noise_cov(dt)`` is singular), ``"covariance"`` (the module docstring's
    covariance form, needs one Jacobian over the averaged trajectories) or ``"auto"`` (default:
    the information form when ``Q`` is invertible, else the covariance form).
    """
    form = options.get("form", "auto")
    if form not in FORMS:
        raise ConfigError(invalid("form", form, f"one of {FORMS}"))
    pb = _problem(motion, sensors, trajectories, dt, prior_cov, options)
    average = options.get("average", True)
    R, T, d = pb.x.shape

    def expect(a: Array) -> Array:  # E[.] over trajectories, or per trajectory
        return a.mean(axis=0, keepdims=True) if average else a

    J = np.empty((R if not average else 1, T, d, d))
    # Tichavský et al. 1998: J_0 = P_0^-1, plus what the sensors report at step 0
    J[:, 0] = pb.prior + expect(pb.information(0))
    noise: dict[float, tuple[Array, Array | None]] = {}
    for k in range(T - 1):  # loop over steps; every step is vectorised over the R trajectories
        h = float(pb.steps[k])
        if h not in noise:
            noise[h] = _noise(motion, h, d)
        Q, Qi = noise[h]
        F = pb.jacobian(motion, k)
        info = expect(pb.information(k + 1))
        if form == "information" or (form == "auto" and Qi is not None):
            if Qi is None:
                raise _singular_noise(Q, h, "")
            J[:, k + 1] = _information_step(J[:, k], F, Qi, info, expect)
            continue
        Fc = F if not average else _common_jacobian(F)
        if Fc is None and Qi is None:
            raise _singular_noise(Q, h, ", motion.jacobian differs between trajectories")
        if Fc is None:
            valid = "'auto' or 'information' for motion whose Jacobian differs between trajectories"
            raise ConfigError(invalid("form", form, valid))
        J[:, k + 1] = _covariance_step(J[:, k], Fc, Q, info, h)
    return J[0] if average else J


def posterior_crlb(
    motion: MotionModel,
    sensors: Sensors,
    trajectories: ArrayLike,
    dt: float | ArrayLike,
    prior_cov: ArrayLike,
    **options: Unpack[PosteriorOptions],
) -> Array:
    """The posterior Cramér–Rao bound ``J_k^-1``: ``(T, d, d)`` (or ``(R, T, d, d)``).

    Arguments as :func:`posterior_information`. Use :func:`position_rmse_bound`,
    :func:`velocity_rmse_bound` or :func:`axis_bounds` to compare with an RMSE.
    """
    J = posterior_information(motion, sensors, trajectories, dt, prior_cov, **options)
    return _symmetrise(np.linalg.inv(J))


def deterministic_crlb(
    motion: MotionModel,
    sensors: Sensors,
    trajectories: ArrayLike,
    dt: float | ArrayLike,
    prior_cov: ArrayLike,
    **options: Unpack[BoundOptions],
) -> Array:
    """CRLB for a target with no process noise (``Q = 0``), along each trajectory.

    The ``Q -> 0`` limit of the recursion for a deterministic state with invertible ``F``
    (Taylor 1979; Ristic, Arulampalam & Gordon 2004, Ch. 4)::

        J_{k+1} = F_k^-T J_k F_k^-1 + sum_s q_{s,k+1} H_s^T R_s^-1 H_s
        J_0     = P_0^-1 + sum_s q_{s,0} H_s^T R_s^-1 H_s

    Evaluated per trajectory (the state is a fixed parameter): returns ``J_k^-1`` as
    ``(R, T, d, d)``, or ``(T, d, d)`` for ``(T, d)`` input. Other arguments (``mask``,
    ``use_detection_probability``, ``information``, ``jacobians``) as
    :func:`posterior_information`.
    """
    pb = _problem(motion, sensors, trajectories, dt, prior_cov, options)
    R, T, d = pb.x.shape
    J = np.empty((R, T, d, d))
    J[:, 0] = pb.prior + pb.information(0)
    for k in range(T - 1):
        F = pb.jacobian(motion, k)
        FT = np.swapaxes(F, -1, -2)
        try:
            Y = np.linalg.solve(FT, J[:, k])  # F^-T J
            A = np.swapaxes(np.linalg.solve(FT, np.swapaxes(Y, -1, -2)), -1, -2)  # F^-T J F^-1
        except np.linalg.LinAlgError:
            raise ConfigError(
                invalid(
                    f"motion.jacobian(x, dt={float(pb.steps[k])!r})",
                    "singular",
                    "an invertible transition Jacobian (deterministic_crlb needs F^-1)",
                )
            ) from None
        J[:, k + 1] = _symmetrise(A + pb.information(k + 1))
    bounds = _symmetrise(np.linalg.inv(J))
    return bounds[0] if pb.single else bounds


def rmse_bound(bounds: ArrayLike, index: Sequence[int]) -> Array:
    """``sqrt(trace(B[index, index]))``: the lowest achievable joint RMSE of those components.

    ``bounds`` ``(..., d, d)`` (e.g. ``(T, d, d)`` from :func:`posterior_crlb`) -> ``(...)``.
    """
    B = np.asarray(bounds, dtype=float)
    idx = [int(i) for i in index]
    if not idx or any(not 0 <= i < B.shape[-1] for i in idx):
        valid = f"non-empty state indices below {B.shape[-1]}"
        raise ConfigError(invalid("index", tuple(index), valid))
    diag = np.diagonal(B, axis1=-2, axis2=-1)[..., idx]
    return np.sqrt(np.clip(diag.sum(axis=-1), 0.0, None))


def position_rmse_bound(bounds: ArrayLike, position_index: Sequence[int]) -> Array:
    """Position RMSE bound ``sqrt(trace of the position block)``, ``(..., d, d)`` -> ``(...)``."""
    return rmse_bound(bounds, position_index)


def velocity_rmse_bound(bounds: ArrayLike, velocity_index: Sequence[int]) -> Array:
    """Velocity RMSE bound ``sqrt(trace of the velocity block)``, ``(..., d, d)`` -> ``(...)``."""
    return rmse_bound(bounds, velocity_index)


def axis_bounds(bounds: ArrayLike, index: Sequence[int] | None = None) -> Array:
    """Per-component RMSE bounds ``sqrt(diag(B))``: ``(..., d, d)`` -> ``(..., k)``."""
    B = np.asarray(bounds, dtype=float)
    diag = np.diagonal(B, axis1=-2, axis2=-1)
    if index is not None:
        diag = diag[..., [int(i) for i in index]]
    return np.sqrt(np.clip(diag, 0.0, None))


_LOG_NODES = np.linspace(-60.0, 60.0, 1201)
"""Nodes in ``u = log s`` of :func:`expected_norm`'s integral for ``d != 2``: tails ~ exp(-30),
trapezoid error ~ exp(-2 pi^2 / 0.1)."""


def expected_norm(cov: ArrayLike) -> Array:
    """``E|e|`` for ``e ~ N(0, cov)``, ``cov`` ``(..., d, d)``.

    With a bound's position block as ``cov`` it is the mean-Euclidean-error bound of an
    estimator whose error is centred Gaussian with covariance at least the bound (Jensen: adding
    independent noise cannot lower an expected norm), the bound a paper's *mean* error is
    compared with (a mean-square bound bounds only the RMS error).

    ``d = 2``: ``sqrt(2 / pi) s_1 E(m)``, ``m = 1 - s_2^2 / s_1^2`` (the norm over a uniform
    angle of a Rayleigh radius; ``E`` the complete elliptic integral of the second kind). Other
    ``d``: the exact 1-D integral ``E sqrt(Q) = (1 / (2 sqrt(pi))) int_0^inf (1 - E exp(-s Q))
    s^(-3/2) ds`` with ``E exp(-s Q) = prod_i (1 + 2 s lam_i)^(-1/2)`` (``Q = |e|^2``, ``lam``
    the eigenvalues), in ``u = log s`` by the trapezoid rule (the integrand is analytic in a
    strip, so the rule converges geometrically)."""
    lam = np.clip(np.linalg.eigvalsh(np.asarray(cov, dtype=float)), 0.0, None)
    if lam.shape[-1] == 2:
        lo, hi = lam[..., 0], lam[..., 1]
        m = 1.0 - np.divide(lo, hi, out=np.ones_like(hi), where=hi > 0)
        return np.asarray(np.sqrt(2.0 / np.pi) * np.sqrt(hi) * ellipe(m))
    top = lam.max(axis=-1, keepdims=True)
    rel = np.divide(lam, top, out=np.zeros_like(lam), where=top > 0)
    s = np.exp(_LOG_NODES)
    log_mgf = -0.5 * np.sum(np.log1p(2.0 * s[:, None] * rel[..., None, :]), axis=-1)  # (..., n)
    f = -np.expm1(log_mgf) * np.exp(-0.5 * _LOG_NODES)  # 1 - E exp(-s Q) without cancellation
    integral = np.sum(f, axis=-1) * (_LOG_NODES[1] - _LOG_NODES[0])
    return np.asarray(np.sqrt(top[..., 0]) * integral / (2.0 * np.sqrt(np.pi)))


def gaussian_information(
    jacobian: ArrayLike, variance: ArrayLike, nuisance: ArrayLike | None = None
) -> Array:
    """Fisher information ``(..., p, p)`` of ``θ`` from ``y ~ N(μ(θ, η), σ² I)`` (``n`` values).

    ``jacobian`` ``(..., n, p)``: ``∂μ/∂θ``; ``variance`` ``(...)``: ``σ²``; ``nuisance``
    ``(..., n, q)``: ``∂μ/∂η`` of unknown nuisance parameters, whose information is taken out
    (the Schur complement of the joint information, Kay 1993, Vol. I, §3.9 and Eq. 3.13;
    ``G^T (I - Π_N) G / σ²`` with ``Π_N`` the projector onto the columns of ``N``)."""
    G = np.asarray(jacobian, dtype=float)
    if G.ndim < 2:
        raise ShapeError(invalid("jacobian.shape", G.shape, "(..., n, p)"))
    var = np.asarray(variance, dtype=float)
    if np.any(~(var > 0)):
        raise ConfigError(invalid("variance", variance, "variances > 0"))
    if nuisance is not None:
        N = np.asarray(nuisance, dtype=float)
        if N.shape[:-1] != G.shape[:-1]:
            raise ShapeError(invalid("nuisance.shape", N.shape, f"{G.shape[:-1]} + (q,)"))
        G = G - N @ (np.linalg.pinv(N) @ G)  # the part of G that no nuisance change explains
    return np.asarray(np.swapaxes(G, -1, -2) @ G / var[..., None, None])


def harmonic_frequency_crlb(
    amplitudes: ArrayLike, sigma: float, n_samples: int, fs: float = 1.0
) -> Array:
    """Standard-deviation bound (Hz) of a fundamental ``f0`` observed in channels
    ``y_c[n] = Σ_h A_ch cos(2π h f0 n / fs + φ_ch) + w_c[n]`` (``n_samples`` each, white noise of
    std ``sigma`` independent across channels, amplitudes and phases unknown).

    One real sinusoid: ``var(f) >= 12 / ((2π)² η N (N² - 1))`` in cycles per sample with
    ``η = A² / (2σ²)`` (Kay 1993, Vol. I, Eq. 3.41, asymptotic in ``N``). Harmonic ``h`` moves as ``h f0``, so it adds
    ``h²`` times its information, and independent channels add theirs (Christensen & Jakobsson
    2009, *Multi-Pitch Estimation*, Eq. 2.37)::

        var(f0) >= 24 σ² fs² / ((2π)² N (N² - 1) Σ_c Σ_h h² A_ch²)

    ``amplitudes`` ``(..., C, H)``: column ``h - 1`` is harmonic ``h``; returns ``(...)``."""
    a = np.asarray(amplitudes, dtype=float)
    if a.ndim < 2:
        raise ShapeError(invalid("amplitudes.shape", a.shape, "(..., C, H)"))
    if not (sigma > 0 and n_samples >= 2 and fs > 0):
        raise ConfigError(
            invalid("sigma, n_samples, fs", (sigma, n_samples, fs), "sigma > 0, N >= 2, fs > 0")
        )
    h = np.arange(1, a.shape[-1] + 1, dtype=float)
    n = float(n_samples)
    info = (2 * np.pi) ** 2 * n * (n * n - 1) * np.sum(h**2 * a**2, axis=(-2, -1))
    with np.errstate(divide="ignore"):
        return np.asarray(fs * np.sqrt(24.0 * sigma**2 / info))
