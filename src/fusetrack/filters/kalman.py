r"""Gaussian filters: the Kalman filter, the extended Kalman filter and the unscented Kalman filter.

All three keep the belief as one Gaussian ``N(x, P)`` and run the same two steps.

**Predict** through the motion model ``x_k = f(x_{k-1}, dt) + w``, ``w ~ N(0, Q(dt))``::

    x^- = E[f(x)],   P^- = Cov[f(x)] + Q(dt)

**Update** with a measurement ``z = h(x) + v``, ``v ~ N(0, R)``::

    z^  = E[h(x)]                    predicted measurement
    S   = Cov[h(x)] + R              innovation covariance   (P_zz + R)
    C   = Cov[x, h(x)]               state-measurement cross covariance (P_xz)
    K   = C S^-1                     gain
    x^+ = x^- + K (z - z^)           (z - z^ through sensor.residual: angles wrapped)
    P^+ = P^- - K S K^T

The filters differ only in how they compute the moments ``E[f(x)]``, ``Cov[f(x)]``, ``E[h(x)]``,
``Cov[h(x)]`` and ``Cov[x, h(x)]`` of a Gaussian pushed through ``f`` and ``h``:

* :class:`KalmanFilter` — ``f`` and ``h`` are linear (``f(x) = F x``, ``h(x) = H x + c``); the
  moments are exact: ``F x``, ``F P F^T``, ``H x + c``, ``H P H^T``, ``P H^T`` (Kalman 1960).
* :class:`ExtendedKalmanFilter` — the same formulas with ``F`` and ``H`` the Jacobians of ``f``
  and ``h`` at the current mean (a first-order Taylor expansion).
* :class:`UnscentedKalmanFilter` — ``2d + 1`` sigma points that match the mean and covariance
  are pushed through ``f`` and ``h`` and the moments are weighted sums over them (the scaled
  unscented transform of Wan & van der Merwe 2000). Angular measurement components are averaged
  on the circle.

(Two more filters could be written in a few lines each: a subclass returning other moments,
e.g. cubature points or a second-order expansion, gets everything else from the base.)

:class:`GaussianFilter` holds the shared skeleton; a subclass only says how to propagate moments
(:meth:`GaussianFilter.propagate_motion` and :meth:`GaussianFilter.propagate_sensor`).

The covariance update uses the Joseph form ``P^+ = (I - K H) P^- (I - K H)^T + K R K^T``
(Bucy & Joseph 1968) — for the UKF with its statistical linearisation ``H`` and the
linearisation error added to ``R`` — which stays symmetric positive semi-definite in floating
point even for a badly conditioned problem. Every returned covariance is symmetrised,
``(P + P^T) / 2``.

**Batches.** A belief may carry leading batch axes — ``mean`` ``(R, d)``, ``cov`` ``(R, d, d)``
for ``R`` independent Monte Carlo runs or targets — and measurement values may be ``(R, m)``
(one report per run). Every step is a handful of batched NumPy linear-algebra calls; there is no
Python loop over ``R``.

**Measurements.** Several measurements at one time are applied one after the other (for
independent noises and linear models this equals one stacked update). With ``joint=True`` the
measurements of one :meth:`~GaussianFilter.update` call are fused as *one* stacked measurement
(:class:`~fusetrack.sensors.StackedSensor`: ``z = [z_1; ...; z_n]``, ``H`` the stacked
Jacobians, ``R = blkdiag(R_i)``): one gain for all of them, linearised once at the prior mean
(the joint EKF) instead of after each reading; identical for linear models, and for ``n``
bearings a few array operations instead of ``n`` updates (the fusion node's default).
A call in which some measurement is unusable in some batch rows, or whose batch axes do not
broadcast, falls back to the sequential updates. The measurement covariance is
``Measurement.covariance`` when given, else ``sensor.noise_cov(x^-)``. A value with NaN or
infinite entries is skipped (the belief is unchanged in that run) and counted in
``filter.stats.skipped_measurements``; an unknown ``sensor_id`` raises
:class:`~fusetrack.core.UnknownSensorError`.

Example (needs the motion and sensor models)::

    >>> import numpy as np
    >>> from fusetrack.core import Gaussian, Measurement
    >>> from fusetrack.motion import ConstantVelocity
    >>> from fusetrack.sensors import PositionFix
    >>> kf = KalmanFilter(ConstantVelocity(q=0.1), [PositionFix("tag", cov=0.25 * np.eye(2))])
    >>> belief = Gaussian(np.zeros(4), np.eye(4))
    >>> belief = kf.predict(belief, dt=1.0)
    >>> belief = kf.update(belief, [Measurement(1.0, "tag", [0.9, -0.2])])
    >>> belief.mean.round(3)
    array([ 0.801, -0.178,  0.414, -0.092])
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, NamedTuple, Protocol, cast

import numpy as np
from numpy.typing import NDArray

from ..core import (
    ConfigError,
    Gaussian,
    Measurement,
    MotionModel,
    SensorModel,
    ShapeError,
    check_positive,
    circular_mean,
    invalid,
)
from ..sensors import StackedSensor
from .kalman_kernels import joseph_update
from .stats import FilterStats, ValidatedMeasurement, as_sensor_map, validate_measurement

Array = NDArray[np.float64]
Sensors = Mapping[str, SensorModel] | Sequence[SensorModel]

_LOG_2PI = float(np.log(2.0 * np.pi))


def _t(a: NDArray[Any]) -> NDArray[Any]:
    """Transpose the last two axes (batched ``A^T``)."""
    return np.swapaxes(a, -1, -2)


def _sym(c: NDArray[Any]) -> NDArray[Any]:
    """``(C + C^T) / 2``: exactly symmetric in floating point."""
    return 0.5 * (c + _t(c))


def _mv(a: NDArray[Any], x: NDArray[Any]) -> NDArray[Any]:
    """Batched matrix-vector product ``A x`` for ``A`` ``(..., p, q)`` and ``x`` ``(..., q)``."""
    return (a @ x[..., None])[..., 0]


def _solve_small(s: Array, b: Array) -> Array:
    """``S^-1 B`` for a batch of ``(..., m, m)`` systems: closed form for ``m <= 2`` (NumPy's
    batched ``solve`` costs about 1 us per 2x2 system, the closed form a few ns), else
    :func:`numpy.linalg.solve`. Raises :class:`numpy.linalg.LinAlgError` for a singular ``S``."""
    m = s.shape[-1]
    if m == 1:
        d = s[..., 0, 0]
        if not np.all(np.isfinite(d) & (d != 0.0)):
            raise np.linalg.LinAlgError("singular matrix")
        return np.asarray(b / s, dtype=np.float64)
    if m == 2:
        a, c, e, f = s[..., 0, 0], s[..., 0, 1], s[..., 1, 0], s[..., 1, 1]
        det = a * f - c * e
        if not np.all(np.isfinite(det) & (det != 0.0)):
            raise np.linalg.LinAlgError("singular matrix")
        b0, b1 = b[..., 0, :], b[..., 1, :]
        inv_det = (1.0 / det)[..., None]
        return np.stack(
            [
                (f[..., None] * b0 - c[..., None] * b1) * inv_det,
                (a[..., None] * b1 - e[..., None] * b0) * inv_det,
            ],
            axis=-2,
        )
    return np.asarray(np.linalg.solve(s, b), dtype=np.float64)


def _constant(f: Array) -> Array:
    """``f`` ``(..., d, d)`` as one ``(d, d)`` matrix when it is a broadcast of one (a linear
    model's Jacobian), else unchanged."""
    if f.ndim > 2 and all(st == 0 for st in f.strides[:-2]):
        return np.asarray(f[(0,) * (f.ndim - 2)])
    return f


def _congruence(f: Array, cov: Array) -> Array:
    """``F P F^T`` for ``P`` ``(..., d, d)``; a single ``F`` ``(d, d)`` uses two flat GEMMs
    (a batched matmul of 4x4 matrices costs as much as a GEMM of all of them together)."""
    if f.ndim != 2 or cov.ndim < 3:
        return np.asarray(f @ cov @ _t(f))
    d = cov.shape[-1]
    pft = (np.ascontiguousarray(cov).reshape(-1, d) @ f.T).reshape(cov.shape)  # P F^T
    return np.asarray(
        _t((np.ascontiguousarray(_t(pft)).reshape(-1, d) @ f.T).reshape(cov.shape))
    )  # F (P F^T) = ((P F^T)^T F^T)^T


def _broadcast(mean: Array, cov: Array) -> tuple[Array, Array]:
    """Give ``mean`` and ``cov`` the same leading (batch) axes."""
    d = mean.shape[-1]
    try:
        batch = np.broadcast_shapes(mean.shape[:-1], cov.shape[:-2])
    except ValueError:
        raise ShapeError(
            invalid("(mean.shape, cov.shape)", (mean.shape, cov.shape), "matching batch axes")
        ) from None
    if mean.shape[:-1] != batch:
        mean = np.broadcast_to(mean, (*batch, d)).copy()
    if cov.shape[:-2] != batch:
        cov = np.broadcast_to(cov, (*batch, d, d)).copy()
    return mean, cov


class _LinearMotion(Protocol):
    def transition_matrix(self, dt: float) -> Array: ...


class SensorMoments(NamedTuple):
    """Moments of ``z = h(x)`` for ``x ~ N(mean, cov)``, measurement noise excluded.

    ``z_pred`` ``(..., m)``; ``pzz`` = ``Cov[h(x)]`` ``(..., m, m)``; ``pxz`` = ``Cov[x, h(x)]``
    ``(..., d, m)``. ``jacobian`` is a linearisation ``H`` ``(..., m, d)`` with
    ``H cov = pxz^T`` and ``lin_error`` = ``pzz - H cov H^T`` (None for 0): then the covariance
    update uses the Joseph form ``(I - K H) P (I - K H)^T + K (R + lin_error) K^T``, which
    equals ``P - K S K^T`` and stays positive semi-definite in floating point. With
    ``jacobian=None`` the update is ``P - K S K^T``.
    """

    z_pred: Array
    pzz: Array
    pxz: Array
    jacobian: Array | None
    lin_error: Array | None = None


class GaussianFilter:
    """Shared predict/update skeleton of the Gaussian (Kalman-family) filters.

    Subclasses implement :meth:`propagate_motion` and :meth:`propagate_sensor`; everything else —
    measurement checks, sequential updates, the gain, the Joseph-form or ``K S K^T`` covariance
    update, NaN masking, batching, symmetrisation — lives here.

    Parameters
    ----------
    motion:
        a :class:`~fusetrack.core.MotionModel` (``mean``, ``jacobian``, ``noise_cov``, ``dim``).
    sensors:
        a mapping ``sensor_id -> SensorModel`` or a sequence of sensor models (keyed by their
        ``sensor_id``).

    Attributes
    ----------
    stats:
        a :class:`~fusetrack.filters.FilterStats` counting skipped measurements and degenerate
        steps (singular innovation covariance, covariance that lost positive definiteness).
    """

    def __init__(self, motion: MotionModel, sensors: Sensors, *, joint: bool = False) -> None:
        self.motion = motion
        self.sensors = as_sensor_map(sensors)
        self.stats = FilterStats()
        self.joint = bool(joint)
        self._stacks: dict[tuple[str, ...], Any] = {}  # joint updates: stacked sensors by ids

    def __repr__(self) -> str:
        return f"{type(self).__name__}(motion={self.motion!r}, sensors={sorted(self.sensors)})"

    # -- what a subclass provides ---------------------------------------------------------------

    def propagate_motion(self, mean: Array, cov: Array, dt: float) -> tuple[Array, Array]:
        """``(E[f(x)], Cov[f(x)])`` for ``x ~ N(mean, cov)``; the process noise is added later."""
        raise NotImplementedError

    def propagate_sensor(self, sensor: SensorModel, mean: Array, cov: Array) -> SensorMoments:
        """Moments of ``h(x)`` for ``x ~ N(mean, cov)``; the measurement noise is added later."""
        raise NotImplementedError

    # -- the shared skeleton --------------------------------------------------------------------

    def predict(
        self, belief: Gaussian, dt: float, rng: np.random.Generator | None = None
    ) -> Gaussian:
        """Prior at ``t + dt``: ``x^- = E[f(x)]``, ``P^- = Cov[f(x)] + Q(dt)``.

        ``rng`` is accepted for the common filter interface and ignored (the step is
        deterministic). ``dt`` must be finite and ``>= 0``.
        """
        dt = check_positive("dt", dt, allow_zero=True)
        mean, cov = _broadcast(belief.mean, belief.cov)
        mean, cov = self.propagate_motion(mean, cov, dt)
        q = np.asarray(self.motion.noise_cov(dt), dtype=float)
        mean, cov = _broadcast(mean, _sym(cov + q))
        return Gaussian(mean, cov)

    def update(
        self,
        belief: Gaussian,
        measurements: Sequence[Measurement] | Measurement,
        rng: np.random.Generator | None = None,
    ) -> Gaussian:
        """Posterior after the measurements, applied one after the other.

        ``measurements`` may be any subset of the filter's sensors (or empty: the belief is
        returned unchanged). ``rng`` is accepted for the common filter interface and ignored.
        """
        return self._update(belief, measurements, want_loglik=False)[0]

    def update_with_likelihood(
        self,
        belief: Gaussian,
        measurements: Sequence[Measurement] | Measurement,
        rng: np.random.Generator | None = None,
    ) -> tuple[Gaussian, Array]:
        """Like :meth:`update`, and also ``log p(z_1..z_k | past)`` ``(...)`` per batch entry.

        Each usable measurement adds its predictive log density
        ``log N(z - z^; 0, S) = -(y^T S^-1 y + log det S + m log 2 pi) / 2``, evaluated with the
        belief just before it (so the sum is the joint predictive density). Multiple-model
        filters (IMM) weigh their models with it. Skipped rows add 0.
        """
        return self._update(belief, measurements, want_loglik=True)

    def _update(
        self,
        belief: Gaussian,
        measurements: Sequence[Measurement] | Measurement,
        want_loglik: bool,
    ) -> tuple[Gaussian, Array]:
        if isinstance(measurements, Measurement):
            measurements = [measurements]
        mean, cov = _broadcast(belief.mean, belief.cov)
        loglik: Array = np.zeros(mean.shape[:-1])
        if self.joint and len(measurements) > 1:
            plain = _stacked_plain(measurements, self.sensors, self._stacks)
            if plain is not None:  # many plain readings of one time: checked as one array
                mean, cov, ll = self._update_one(mean, cov, plain, want_loglik)
                loglik = np.broadcast_to(loglik + ll, mean.shape[:-1]).copy()
                return Gaussian(mean, cov), loglik
        validated = [
            (meas, validate_measurement(meas, self.sensors, self.stats)) for meas in measurements
        ]
        validated = [(m, c) for m, c in validated if c.usable.any()]
        if self.joint and len(validated) > 1 and all(c.usable.all() for _, c in validated):
            try:
                validated = [
                    (validated[0][0], _stacked([c for _, c in validated], mean, self._stacks))
                ]
            except ValueError:  # batch axes that do not broadcast: raised below, per measurement
                pass
        for meas, checked in validated:
            try:
                np.broadcast_shapes(checked.value.shape[:-1], mean.shape[:-1])
            except ValueError:
                raise ShapeError(
                    invalid(
                        f"value.shape (sensor {meas.sensor_id!r}, time={meas.time})",
                        checked.value.shape,
                        f"batch axes that broadcast with the belief's {mean.shape[:-1]}",
                    )
                ) from None
            mean, cov, ll = self._update_one(mean, cov, checked, want_loglik)
            if want_loglik:
                loglik = loglik + ll
        if want_loglik:
            loglik = np.broadcast_to(loglik, mean.shape[:-1]).copy()
        return Gaussian(mean, cov), loglik

    def _update_one(
        self, mean: Array, cov: Array, checked: ValidatedMeasurement, want_loglik: bool
    ) -> tuple[Array, Array, Array]:
        sensor, usable = checked.sensor, checked.usable
        fast = self._kernel_update(mean, cov, checked, want_loglik)
        if fast is None and not want_loglik:
            fast = self._many_readings_update(mean, cov, checked)
        if fast is not None:
            return fast
        mom = self.propagate_sensor(sensor, mean, cov)
        if checked.covariance is not None:
            r = checked.covariance
        else:
            r = np.asarray(sensor.noise_cov(mean), dtype=float)
        partial = not bool(usable.all())
        z = checked.value
        if partial:  # unusable rows: any finite value, the result is discarded below
            z = np.where(usable[..., None], z, mom.z_pred)
            r = np.where(usable[..., None, None], r, np.eye(r.shape[-1]))
        s = _sym(mom.pzz + r)
        y = np.asarray(sensor.residual(z, mom.z_pred), dtype=float)
        kt = None
        if mom.jacobian is not None and mom.lin_error is None and r.shape[-1] > mean.shape[-1]:
            kt = _gain_many_readings(cov, mom.jacobian, r)
        if kt is None:
            # K = P_xz S^-1, computed as (S^-1 P_xz^T)^T with S symmetric
            try:
                kt = _solve_small(s, _t(mom.pxz))
            except np.linalg.LinAlgError:
                self.stats.degenerate_steps += 1
                kt = np.linalg.pinv(s, hermitian=True) @ _t(mom.pxz)
        k = _t(kt)
        new_mean = mean + _mv(k, y)
        h = mom.jacobian
        if h is not None:
            # Joseph form (Bucy & Joseph 1968; Bar-Shalom et al. 2001, Eq. 5.2.3-18), with the
            # linearisation error added to R for the UKF (see UnscentedKalmanFilter)
            ikh = np.eye(mean.shape[-1]) - k @ h
            r_eff = r if mom.lin_error is None else r + mom.lin_error
            new_cov = ikh @ cov @ _t(ikh) + k @ r_eff @ kt
        else:
            new_cov = cov - k @ s @ kt
        new_cov = _sym(new_cov)
        ll: Array = np.zeros(())
        if want_loglik:
            try:
                sy = np.linalg.solve(s, y[..., None])[..., 0]
            except np.linalg.LinAlgError:
                sy = _mv(np.linalg.pinv(s, hermitian=True), y)
            maha = np.sum(y * sy, axis=-1)
            logdet = np.linalg.slogdet(s)[1]
            ll = -0.5 * (maha + logdet + y.shape[-1] * _LOG_2PI)
            if partial:
                ll = np.where(usable, ll, 0.0)
        if partial:
            new_mean = np.where(usable[..., None], new_mean, mean)
            new_cov = np.where(usable[..., None, None], new_cov, cov)
        new_mean, new_cov = _broadcast(new_mean, new_cov)
        return new_mean, new_cov, ll

    def _kernel_update(
        self, mean: Array, cov: Array, checked: ValidatedMeasurement, want_loglik: bool
    ) -> tuple[Array, Array, Array] | None:
        """The update of a batch of at least :data:`KERNEL_MIN_BATCH` beliefs by the Numba
        Joseph kernel (:mod:`.kalman_kernels`; the same equations, one belief at a time) when
        the moments are the linearised ones (:class:`KalmanFilter`, :class:`ExtendedKalmanFilter`)
        and every row is usable; None otherwise (the NumPy path below runs)."""
        if (
            type(self).propagate_sensor is not KalmanFilter.propagate_sensor
            or mean.ndim != 2
            or cov.ndim != 3
            or mean.shape[0] < KERNEL_MIN_BATCH
            or not checked.usable.all()
        ):
            return None
        n, d = mean.shape
        sensor = checked.sensor
        h = _constant(np.asarray(sensor.jacobian(mean), dtype=float))
        z_pred = np.asarray(sensor.predict(mean), dtype=float)
        m = z_pred.shape[-1]
        r = checked.covariance
        r = _constant(np.asarray(sensor.noise_cov(mean) if r is None else r, dtype=float))
        if m > d or h.shape[-2:] != (m, d) or r.shape[-2:] != (m, m):
            return None
        h3 = h[None] if h.ndim == 2 else h
        r3 = r[None] if r.ndim == 2 else r
        if h3.shape[0] not in (1, n) or r3.shape[0] not in (1, n) or h3.ndim != 3 or r3.ndim != 3:
            return None
        y = np.asarray(sensor.residual(checked.value, z_pred), dtype=float)
        if y.shape != (n, m):
            y = np.broadcast_to(y, (n, m))
        out = joseph_update(mean, cov, h3, r3, y, want_loglik)
        if out is None:
            return None
        new_mean, new_cov, ll = out
        return new_mean, new_cov, (ll if want_loglik else np.zeros(()))

    def _many_readings_update(
        self, mean: Array, cov: Array, checked: ValidatedMeasurement
    ) -> tuple[Array, Array, Array] | None:
        """The linearised update for more readings than states (``m > d``: a stacked update of
        many sensors) with a diagonal ``R``, in ``O(d^2 m)``: no ``m x m`` matrix is formed
        (``S``, ``H P H^T`` and ``R`` were 8 MB each at m = 1000, ~150 ms a tick). The gain is
        :func:`_gain_many_readings`' ``K = (I + P H^T R^-1 H)^-1 P H^T R^-1``, the covariance the
        same Joseph form as below with ``K R K^T = (K diag(r)) K^T``; the numbers equal the
        general path's to rounding. None (the general path runs) for other filters' moments, an
        unusable row, a non-diagonal ``R`` or ``m <= d``."""
        if type(self).propagate_sensor is not KalmanFilter.propagate_sensor:
            return None
        sensor, d = checked.sensor, mean.shape[-1]
        m = int(getattr(sensor, "dim", 0))
        if m <= d or not checked.usable.all():
            return None
        r_diag = _noise_diagonal(sensor, checked, mean)
        if r_diag is None:
            return None
        h = np.asarray(sensor.jacobian(mean), dtype=float)
        z_pred = np.asarray(sensor.predict(mean), dtype=float)
        if h.shape[-2:] != (m, d) or z_pred.shape[-1] != m:
            return None
        p_ht_rinv = cov @ (_t(h) / r_diag[..., None, :])  # P H^T R^-1, (..., d, m)
        try:
            k = np.linalg.solve(np.eye(d) + p_ht_rinv @ h, p_ht_rinv)  # K, (..., d, m)
        except np.linalg.LinAlgError:
            return None
        y = np.asarray(sensor.residual(checked.value, z_pred), dtype=float)
        ikh = np.eye(d) - k @ h
        new_cov = _sym(ikh @ cov @ _t(ikh) + (k * r_diag[..., None, :]) @ _t(k))
        new_mean, new_cov = _broadcast(mean + _mv(k, y), new_cov)
        return new_mean, new_cov, np.zeros(())


def _noise_diagonal(
    sensor: SensorModel, checked: ValidatedMeasurement, mean: Array
) -> Array | None:
    """The variances ``(..., m)`` of a diagonal measurement noise (the measurement's own
    covariance, else the sensor's; a :class:`StackedSensor` gives its diagonal without the
    ``m x m`` matrix), or None when it is not diagonal with positive entries."""
    if checked.covariance is None and isinstance(sensor, StackedSensor):
        diag = sensor.noise_diagonal(mean)
    else:
        r = checked.covariance
        r = np.asarray(sensor.noise_cov(mean) if r is None else r, dtype=float)
        diag = np.diagonal(r, axis1=-2, axis2=-1)
        if np.count_nonzero(r) != np.count_nonzero(diag):
            return None
    if diag is None or not np.all(diag > 0):
        return None
    return np.asarray(diag, dtype=float)


KERNEL_MIN_BATCH = 16
"""Batches of at least this many beliefs take the Numba update kernel (below it the NumPy
path's call overhead is smaller than a kernel call's; both give the same result to rounding)."""


def _gain_many_readings(cov: Array, h: Array, r: Array) -> Array | None:
    """``K^T`` for more readings than states (``m > d``) and a diagonal ``R``, without the
    ``m x m`` solve: ``K = P H^T S^-1 = (I + P H^T R^-1 H)^-1 P H^T R^-1``, since
    ``(I + P H^T R^-1 H) P H^T = P H^T R^-1 (R + H P H^T)`` (a ``d x d`` solve; the Woodbury
    identity without ``P^-1``). None when ``R`` is not diagonal or the solve fails."""
    r_diag = np.diagonal(r, axis1=-2, axis2=-1)
    if np.any(r != r_diag[..., :, None] * np.eye(r.shape[-1])) or not np.all(r_diag > 0):
        return None
    ht_rinv = _t(h) / r_diag[..., None, :]  # H^T R^-1, (..., d, m)
    p_ht_rinv = cov @ ht_rinv
    try:
        k = np.linalg.solve(np.eye(cov.shape[-1]) + p_ht_rinv @ h, p_ht_rinv)
    except np.linalg.LinAlgError:
        return None
    return _t(k)


def _stacked_plain(
    measurements: Sequence[Measurement],
    sensors: Mapping[str, SensorModel],
    cache: dict[tuple[str, ...], Any],
) -> ValidatedMeasurement | None:
    """:func:`_stacked` of measurements that are all plain — one time, a finite ``(m_i,)``
    float value of the sensor's size, no covariance of their own, known sensors — checked
    with one concatenation instead of one :func:`validate_measurement` each (1000 readings:
    ~25 ms a tick); None for anything else (the general path then checks and reports it)."""
    try:
        parts = [sensors[m.sensor_id] for m in measurements]
    except KeyError:
        return None
    t0 = measurements[0].time
    for m, p in zip(measurements, parts):
        v = m.value
        if (
            m.time != t0
            or m.covariance is not None
            or type(v) is not np.ndarray
            or v.ndim != 1
            or v.shape[0] != getattr(p, "value_size", p.dim)
            or v.shape[0] != p.dim
        ):
            return None
    value = np.concatenate([m.value for m in measurements]).astype(float, copy=False)
    if not np.isfinite(value).all():
        return None
    ids = tuple(m.sensor_id for m in measurements)
    sensor = cache.get(ids)
    if sensor is None:
        if len(cache) > 1024:
            cache.clear()
        sensor = cache[ids] = StackedSensor("+".join(ids), parts)
    return ValidatedMeasurement(sensor, value, None, np.ones((), dtype=bool))


def _stacked(
    parts: Sequence[ValidatedMeasurement], mean: Array, cache: dict[tuple[str, ...], Any]
) -> ValidatedMeasurement:
    """Several usable measurements of one time as one: values concatenated, the sensors
    stacked (one :class:`StackedSensor` per combination of sensors, kept in ``cache``), the
    covariance block-diagonal (a measurement's own covariance where it has one)."""
    ids = tuple(str(c.sensor.sensor_id) for c in parts)
    sensor = cache.get(ids)
    if sensor is None:
        if len(cache) > 1024:  # bounded: the combinations seen last are the likely ones
            cache.clear()
        sensor = cache[ids] = StackedSensor("+".join(ids), [c.sensor for c in parts])
    shapes = {c.value.shape[:-1] for c in parts}
    if len(shapes) == 1:
        batch = shapes.pop()
        value = np.concatenate([c.value for c in parts], axis=-1)
    else:
        batch = np.broadcast_shapes(*shapes)
        value = np.concatenate(
            [np.broadcast_to(c.value, (*batch, c.value.shape[-1])) for c in parts], axis=-1
        )
    cov = None
    if any(c.covariance is not None for c in parts):
        blocks = [
            np.asarray(c.sensor.noise_cov(mean) if c.covariance is None else c.covariance, float)
            for c in parts
        ]
        cov_batch = np.broadcast_shapes(*(b.shape[:-2] for b in blocks))
        cov = np.zeros((*cov_batch, sensor.dim, sensor.dim))
        i = 0
        for b in blocks:
            m = b.shape[-1]
            cov[..., i : i + m, i : i + m] = b
            i += m
    return ValidatedMeasurement(sensor, value, cov, np.ones(batch, dtype=bool))


class KalmanFilter(GaussianFilter):
    r"""The Kalman filter (Kalman 1960) for linear-Gaussian models.

    Assumes ``x_k = F(dt) x_{k-1} + w`` with ``w ~ N(0, Q(dt))`` (the motion model must provide
    ``transition_matrix(dt)``) and sensors ``z = H x + c + v``, ``v ~ N(0, R)``. For a linear
    sensor ``H = sensor.jacobian(x)`` anywhere and ``H x + c = sensor.predict(x)``, so the filter
    uses those; given a nonlinear sensor it would linearise at the prior mean, i.e. behave as
    the :class:`ExtendedKalmanFilter` — use that class to say so.

    Predict::

        x^- = F x,           P^- = F P F^T + Q

    Update (Joseph form)::

        S = H P^- H^T + R,   K = P^- H^T S^-1
        x^+ = x^- + K (z - H x^- - c)
        P^+ = (I - K H) P^- (I - K H)^T + K R K^T

    With a Gaussian prior this is the exact posterior: the same numbers as conditioning the joint
    Gaussian of all states and measurements (see ``tests/filters/test_kalman_exact.py``).

    Example::

        >>> import numpy as np
        >>> from fusetrack.core import Gaussian, Measurement
        >>> from fusetrack.motion import ConstantVelocity
        >>> from fusetrack.sensors import PositionFix
        >>> kf = KalmanFilter(ConstantVelocity(q=0.1), [PositionFix("tag", cov=0.25 * np.eye(2))])
        >>> prior = Gaussian(np.zeros(4), np.eye(4))
        >>> post = kf.update(kf.predict(prior, 1.0), [Measurement(1.0, "tag", [0.9, -0.2])])
        >>> np.allclose(post.cov, post.cov.T)
        True
    """

    def __init__(self, motion: MotionModel, sensors: Sensors, *, joint: bool = False) -> None:
        if not callable(getattr(motion, "transition_matrix", None)):
            raise ConfigError(
                invalid(
                    "motion",
                    motion,
                    "a linear motion model with transition_matrix(dt) "
                    "(use ExtendedKalmanFilter or UnscentedKalmanFilter for nonlinear motion)",
                )
            )
        super().__init__(motion, sensors, joint=joint)

    def propagate_motion(self, mean: Array, cov: Array, dt: float) -> tuple[Array, Array]:
        f = np.asarray(cast(_LinearMotion, self.motion).transition_matrix(dt), dtype=np.float64)
        return _mv(f, mean), _congruence(f, cov)

    def propagate_sensor(self, sensor: SensorModel, mean: Array, cov: Array) -> SensorMoments:
        h = np.asarray(sensor.jacobian(mean), dtype=float)
        z_pred = np.asarray(sensor.predict(mean), dtype=float)
        pxz = cov @ _t(h)
        return SensorMoments(z_pred, h @ pxz, pxz, h)


class ExtendedKalmanFilter(KalmanFilter):
    r"""The extended Kalman filter: the Kalman filter on models linearised at the current mean.

    Assumes ``x_k = f(x_{k-1}, dt) + w`` and ``z = h(x) + v`` with differentiable ``f`` and
    ``h`` and additive Gaussian noises. With ``F = df/dx`` at the posterior mean and
    ``H = dh/dx`` at the prior mean::

        x^- = f(x, dt),      P^- = F P F^T + Q
        S = H P^- H^T + R,   K = P^- H^T S^-1
        x^+ = x^- + K r(z, h(x^-))          r = sensor.residual (angles wrapped)
        P^+ = (I - K H) P^- (I - K H)^T + K R K^T

    It is exact for linear models (then it equals :class:`KalmanFilter`) and good when ``f`` and
    ``h`` are nearly linear over the spread of the belief; for a bearing-only sensor close to the
    target prefer :class:`UnscentedKalmanFilter` or a particle filter.

    Example::

        >>> import numpy as np
        >>> from fusetrack.core import Gaussian, Measurement
        >>> from fusetrack.motion import ConstantVelocity
        >>> from fusetrack.sensors import RangeBearing
        >>> radar = RangeBearing("radar", position=[0.0, 0.0], sigma_range=0.5, sigma_bearing=0.01)
        >>> ekf = ExtendedKalmanFilter(ConstantVelocity(q=0.1), [radar])
        >>> prior = Gaussian(np.array([10.0, 0.0, 0.0, 1.0]), np.eye(4))
        >>> post = ekf.update(ekf.predict(prior, 1.0), [Measurement(1.0, "radar", [10.1, 0.1])])
        >>> post.mean.shape
        (4,)
    """

    def __init__(self, motion: MotionModel, sensors: Sensors, *, joint: bool = False) -> None:
        GaussianFilter.__init__(self, motion, sensors, joint=joint)

    def propagate_motion(self, mean: Array, cov: Array, dt: float) -> tuple[Array, Array]:
        f = _constant(np.asarray(self.motion.jacobian(mean, dt), dtype=float))
        return np.asarray(self.motion.mean(mean, dt), dtype=float), _congruence(f, cov)


class UnscentedKalmanFilter(GaussianFilter):
    r"""The unscented Kalman filter with the scaled unscented transform (Wan & van der Merwe 2000).

    Assumes ``x_k = f(x_{k-1}, dt) + w`` and ``z = h(x) + v`` with additive Gaussian noises; ``f``
    and ``h`` need not be differentiable. For a state of dimension ``n`` with
    ``lambda = alpha^2 (n + kappa) - n`` the ``2n + 1`` sigma points and weights are::

        X_0 = x,   X_i = x + sqrt(n + lambda) L_i,   X_{n+i} = x - sqrt(n + lambda) L_i
        Wm_0 = lambda / (n + lambda),   Wc_0 = Wm_0 + 1 - alpha^2 + beta
        Wm_i = Wc_i = 1 / (2 (n + lambda))                       (i = 1..2n)

    with ``L_i`` the columns of the Cholesky factor ``L L^T = P``. The moments are::

        x^- = sum Wm_i f(X_i),       P^- = sum Wc_i (f(X_i) - x^-)(f(X_i) - x^-)^T + Q
        z^  = sum Wm_i h(X_i)        (circular mean atan2(sum Wm sin, sum Wm cos) for the
                                      sensor's angular components)
        P_zz = sum Wc_i r(h(X_i), z^) r(h(X_i), z^)^T,   P_xz = sum Wc_i (X_i - x^-) r(h(X_i), z^)^T

    with ``r = sensor.residual`` (angles wrapped), then ``S = P_zz + R``, ``K = P_xz S^-1``,
    ``x^+ = x^- + K r(z, z^)``, ``P^+ = P^- - K S K^T``. Sigma points are drawn afresh from the
    current belief for every predict and every measurement, so several measurements at one time
    are applied correctly in sequence.

    ``P^- - K S K^T`` subtracts two nearly equal matrices when a measurement is much more
    precise than the prior, and can lose positive definiteness. The filter therefore computes
    the same matrix in Joseph form: with the statistical linearisation ``H = P_xz^T P^-1``
    (obtained from the sigma points as ``G^T L^-1``, no inverse of ``P``) and the part of
    ``P_zz`` no linear map explains, ``E = P_zz - H P H^T = sum Wc_i e_i e_i^T`` with
    ``e_i = r(h(X_i), z^) - H (X_i - x^-)``::

        P^+ = (I - K H) P^- (I - K H)^T + K (R + E) K^T      (= P^- - K S K^T exactly)

    For a linear sensor ``E = 0`` and this is the Kalman filter's own update.

    Parameters
    ----------
    alpha, beta, kappa:
        spread of the sigma points, prior-knowledge weight (2 is optimal for Gaussians) and
        secondary scaling. ``kappa=None`` means ``3 - n`` (Julier's choice, giving
        ``n + lambda = 3 alpha^2``). ``alpha^2 (n + kappa)`` must be positive. With
        ``alpha = 1`` all covariance weights are positive and ``P`` stays positive
        semi-definite; a small ``alpha`` (the paper suggests 1e-3) makes ``Wc_0`` very negative.
        These match FilterPy's ``MerweScaledSigmaPoints(n, alpha, beta, kappa)``.

    Example::

        >>> import numpy as np
        >>> from fusetrack.core import Gaussian, Measurement
        >>> from fusetrack.motion import ConstantVelocity
        >>> from fusetrack.sensors import Bearing
        >>> mics = [Bearing("mic0", position=[0, 0], sigma=0.02),
        ...         Bearing("mic1", position=[10, 0], sigma=0.02)]
        >>> ukf = UnscentedKalmanFilter(ConstantVelocity(q=0.1), mics)
        >>> prior = Gaussian(np.array([5.0, 5.0, 0.0, 0.0]), np.eye(4))
        >>> post = ukf.update(ukf.predict(prior, 0.5),
        ...                   [Measurement(0.5, "mic0", [0.8]), Measurement(0.5, "mic1", [2.3])])
        >>> post.mean.shape
        (4,)
    """

    def __init__(
        self,
        motion: MotionModel,
        sensors: Sensors,
        alpha: float = 1.0,
        beta: float = 2.0,
        kappa: float | None = None,
        *,
        joint: bool = False,
    ) -> None:
        super().__init__(motion, sensors, joint=joint)
        n = int(motion.dim)
        self.alpha = check_positive("alpha", alpha)
        self.beta = float(beta)
        self.kappa = float(3 - n if kappa is None else kappa)
        scale = self.alpha**2 * (n + self.kappa)  # n + lambda
        if not scale > 0:
            raise ConfigError(
                invalid("kappa", kappa, f"a number > {-n} (the state dimension is {n})")
            )
        lam = scale - n
        # Wan & van der Merwe 2000, Eq. 15
        wm = np.full(2 * n + 1, 0.5 / scale)
        wc = wm.copy()
        wm[0] = lam / scale
        wc[0] = lam / scale + 1.0 - self.alpha**2 + self.beta
        self.n = n
        self.scale = scale
        self.wm: Array = wm
        self.wc: Array = wc

    def sigma_points(self, mean: Array, cov: Array) -> Array:
        """The ``2n + 1`` sigma points of ``N(mean, cov)``: ``(..., 2n + 1, n)``.

        Order: the mean, then ``mean + sqrt(n + lambda) L_i`` for ``i = 1..n``, then
        ``mean - sqrt(n + lambda) L_i`` (FilterPy's order).
        """
        return self._sigma_points(mean, cov)[0]

    def _sigma_points(self, mean: Array, cov: Array) -> tuple[Array, NDArray[Any]]:
        """Sigma points and the square root ``A`` (``A A^T = cov``) they were built from."""
        if mean.shape[-1] != self.n:
            raise ShapeError(
                invalid("mean.shape", mean.shape, f"(..., {self.n}) to match the motion model")
            )
        a = self._sqrt(cov)
        root = _t(a) * np.sqrt(self.scale)  # row i = column i of the square root
        centre = mean[..., None, :]
        return np.concatenate([centre, centre + root, centre - root], axis=-2), a

    def _sqrt(self, cov: Array) -> NDArray[Any]:
        """A square root ``A A^T = cov``: Cholesky, or eigen-decomposition with clipped
        eigenvalues when ``cov`` is not numerically positive definite (counted as degenerate)."""
        try:
            return np.linalg.cholesky(cov)
        except np.linalg.LinAlgError:
            self.stats.degenerate_steps += 1
            w, v = np.linalg.eigh(_sym(cov))
            floor = 1e-12 * np.maximum(np.abs(w).max(axis=-1, keepdims=True), 1e-300)
            return v * np.sqrt(np.maximum(w, floor))[..., None, :]

    def _weighted_cov(self, a: Array, b: Array) -> Array:
        """``sum_i Wc_i a_i b_i^T`` for ``a`` ``(..., 2n+1, p)``, ``b`` ``(..., 2n+1, q)``."""
        return _t(a * self.wc[:, None]) @ b

    def propagate_motion(self, mean: Array, cov: Array, dt: float) -> tuple[Array, Array]:
        xf = np.asarray(self.motion.mean(self.sigma_points(mean, cov), dt), dtype=float)
        m = np.einsum("k,...kd->...d", self.wm, xf)
        dx = xf - m[..., None, :]
        return m, self._weighted_cov(dx, dx)

    def propagate_sensor(self, sensor: SensorModel, mean: Array, cov: Array) -> SensorMoments:
        x, a = self._sigma_points(mean, cov)
        zs = np.asarray(sensor.predict(x), dtype=float)
        z_pred = np.einsum("k,...km->...m", self.wm, zs)
        ang = np.asarray(getattr(sensor, "angular", ()), dtype=bool)
        if ang.any():
            z_pred[..., ang] = circular_mean(zs[..., ang], self.wm[:, None], axis=-2)
        dz = np.asarray(sensor.residual(zs, z_pred[..., None, :]), dtype=float)
        dx = x - mean[..., None, :]
        pzz = self._weighted_cov(dz, dz)
        pxz = self._weighted_cov(dx, dz)
        # Statistical linearisation H = P_xz^T P^-1. With dX_i = +-sqrt(n+lambda) A_i,
        # P_xz = A G where row i of G is Wc_i sqrt(n+lambda) (dZ_i - dZ_{n+i}), so H = G^T A^-1.
        n = self.n
        g = (dz[..., 1 : n + 1, :] - dz[..., n + 1 :, :]) * (self.wc[1] * np.sqrt(self.scale))
        try:
            h = _t(np.linalg.solve(_t(a), g))
        except np.linalg.LinAlgError:  # cannot happen after _sqrt's eigenvalue floor
            return SensorMoments(z_pred, pzz, pxz, None)
        # pzz - H P H^T = sum Wc_i e_i e_i^T with e_i = dZ_i - H dX_i: the part of Cov[h(x)] no
        # linear map explains, summed without cancellation
        e = dz - dx @ _t(h)
        return SensorMoments(z_pred, pzz, pxz, h, _sym(self._weighted_cov(e, e)))
