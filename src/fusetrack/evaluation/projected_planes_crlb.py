"""Cramér-Rao bounds for Projected Planes Selection and for the direct 3-D filter (Lee 2009, Sec. 2.3).

Deterministic state (no process noise), known model: the information recursion
``J_n = F^-T J_{n-1} F^-1 + H_n^T R_n^-1 H_n`` (Lee 2009, Eq. 2.30) with ``H`` the Jacobian of the
measurement at the true state (Eqs. 2.36-2.38 for the planes; for 3-D the correct form of the
garbled Eq. 2.41) and ``R`` the projected variance of the plane (scalar) or ``diag(s^2, s^2)``.

Two departures from the text, both needed for a finite bound:

* The text starts from ``J_0 = 0``. A static bearing sensor cannot observe scale when the motion
  is linear in the state (constant velocity, or the text's state-dependent linear form of the
  constant-acceleration model), so the true state is then a null vector of every ``J_n`` and no
  bound exists; we start from the prior information ``J_0 = P_0^-1`` (``sigma_pos``,
  ``sigma_vel`` per axis), the same for every plane and for 3-D, matching "the initial state is
  given". (With a known nonzero acceleration and the true, affine transition, scale is in fact
  weakly observable and the bound stays finite even with a vanishing prior; the tests show both.)
* ``F`` is the Jacobian of the true (deterministic) transition. For the additive
  constant-acceleration map that is the constant-velocity matrix; the text instead uses its
  state-dependent linear form ``[[1, A T^2/(2V) + T], [0, A T/V + 1]]`` (Eq. 2.15), available as
  ``transition="printed"`` (constant-acceleration models without a turn only).

For PPS the bound of each plane is given "always on" (its measurement every step) and
"switched" (measurement information only while the plane is selected; the information still
propagates), Lee 2009 Figs. 2-10 ... 2-13.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from ..core import ConfigError, ShapeError, invalid
from ..motion import AccelTurn
from ..sensors import (
    PLANE_AXES,
    PLANES,
    DoaSensor3D,
    direction_angles,
    projected_angles,
    projected_variance,
)

Array = np.ndarray

TRANSITIONS = ("jacobian", "printed")


def _numerical_jacobian(model: AccelTurn, x: Array, dt: float, eps: float = 1e-6) -> Array:
    d = x.shape[-1]
    out = np.empty((d, d))
    for j in range(d):
        h = eps * max(1.0, abs(x[j]))
        xp, xm = x.copy(), x.copy()
        xp[j] += h
        xm[j] -= h
        out[:, j] = (model.mean(xp, dt) - model.mean(xm, dt)) / (2 * h)
    return out


def _printed_transition(model: AccelTurn, v_prev: Array, dt: float) -> Array:
    """Lee 2009, Eq. 2.15 state-dependent form, in ``[pos(n), vel(n)]`` layout."""
    if model.turn_axes is not None and model.turn_alpha != 0.0:
        raise ConfigError(invalid("transition", "printed", "'jacobian' for a turning model"))
    n = model.ndim
    F = np.eye(2 * n)
    acc = np.asarray(model.accel if len(model.accel) else np.zeros(n), float)
    for a in range(n):
        v = v_prev[a]
        ratio = acc[a] / v if abs(v) > 1e-12 else 0.0
        F[a, n + a] = ratio * dt * dt / 2 + dt
        F[n + a, n + a] = ratio * dt + 1
    return F


def _transition(model: AccelTurn, x_prev: Array, dt: float, transition: str) -> Array:
    if transition == "jacobian":
        return _numerical_jacobian(model, x_prev, dt)
    if transition == "printed":
        return _printed_transition(model, x_prev[model.ndim :], dt)
    raise ConfigError(invalid("transition", transition, f"one of {TRANSITIONS}"))


def _prior_information(ndim: int, sigma_pos: float, sigma_vel: float) -> Array:
    return np.diag(1.0 / np.array([sigma_pos**2] * ndim + [sigma_vel**2] * ndim))


def plane_information_rows(truth: Array, sensor: DoaSensor3D, plane: str) -> tuple[Array, Array]:
    """Jacobians ``H`` ``(T, 4)`` of the plane bearing (state ``[p_a, p_b, v_a, v_b]``) and ``R`` ``(T,)``.

    Lee 2009, Eqs. 2.36-2.38 (with the sensor offset and polarity).
    """
    a, b = PLANE_AXES[plane]
    local = sensor.local(truth[:, :3])
    la, lb = local[:, a], local[:, b]
    r2 = la * la + lb * lb
    H = np.zeros((len(truth), 4))
    H[:, 0] = -lb / r2 * sensor.polarity[a]
    H[:, 1] = la / r2 * sensor.polarity[b]
    theta = np.arctan2(local[:, 1], local[:, 0])
    phi = np.arctan2(np.hypot(local[:, 0], local[:, 1]), local[:, 2])
    R = projected_variance(theta, phi, sensor.sigma**2)[:, PLANES.index(plane)]
    return H, R


def plane_crlb(
    truth: Array,
    sensor: DoaSensor3D,
    plane: str,
    model: AccelTurn,
    dt: float,
    *,
    selected: Array | None = None,
    sigma_pos: float = 0.1,
    sigma_vel: float = 0.1,
    transition: str = "jacobian",
) -> Array:
    """Bound standard deviations ``(T, 4)`` of ``[p_a, p_b, v_a, v_b]`` of one plane filter.

    ``truth`` ``(T, 6)`` is the true 3-D trajectory; ``model`` the 3-D truth model (restricted to
    the plane here); ``selected`` ``(T,)`` booleans: add the measurement only at those steps.
    """
    truth = np.asarray(truth, dtype=float)
    if truth.ndim != 2 or truth.shape[1] != 6:
        raise ShapeError(invalid("truth.shape", truth.shape, "(T, 6)"))
    axes = PLANE_AXES[plane]
    idx = [axes[0], axes[1], axes[0] + 3, axes[1] + 3]
    sub = model.restrict(axes)
    H, R = plane_information_rows(truth, sensor, plane)
    use = np.ones(len(truth), bool) if selected is None else np.asarray(selected, bool)
    J = _prior_information(2, sigma_pos, sigma_vel)
    out = np.empty((len(truth), 4))
    for n in range(len(truth)):
        if n > 0:
            F = _transition(sub, truth[n - 1, idx], dt, transition)
            Fi = np.linalg.inv(F)
            J = Fi.T @ J @ Fi
        if use[n]:
            J = J + np.outer(H[n], H[n]) / R[n]
        out[n] = np.sqrt(np.diag(np.linalg.inv(J)))
    return out


def direct3d_crlb(
    truth: Array,
    sensor: DoaSensor3D | Sequence[DoaSensor3D],
    model: AccelTurn,
    dt: float,
    *,
    sigma_pos: float = 0.1,
    sigma_vel: float = 0.1,
    transition: str = "jacobian",
) -> Array:
    """Bound standard deviations ``(T, 6)`` of the direct 3-D filter (Lee 2009, Eqs. 2.39-2.41, corrected).

    ``sensor`` may be several sensors: their (independent) angle pairs add their information
    every step, ``J += sum_k H_k^T R_k^-1 H_k`` -- the bound of a 3-D filter using all of them.
    """
    truth = np.asarray(truth, dtype=float)
    if truth.ndim != 2 or truth.shape[1] != 6:
        raise ShapeError(invalid("truth.shape", truth.shape, "(T, 6)"))
    sensors = [sensor] if isinstance(sensor, DoaSensor3D) else list(sensor)
    if not sensors:
        raise ConfigError(
            invalid("sensor", sensor, "a DoaSensor3D or a non-empty sequence of them")
        )
    info = np.zeros((len(truth), 6, 6))
    for s in sensors:
        local = s.local(truth[:, :3])
        x, y, z = local[:, 0], local[:, 1], local[:, 2]
        r2 = x * x + y * y
        r = np.sqrt(r2)
        rho2 = r2 + z * z
        H = np.zeros((len(truth), 2, 6))
        H[:, 0, 0], H[:, 0, 1] = -y / r2, x / r2
        H[:, 1, 0], H[:, 1, 1], H[:, 1, 2] = x * z / (rho2 * r), y * z / (rho2 * r), -r / rho2
        H[:, :, :3] *= s.polarity
        info += np.einsum("tmi,tmj->tij", H, H) / s.sigma**2
    J = _prior_information(3, sigma_pos, sigma_vel)
    out = np.empty((len(truth), 6))
    for n in range(len(truth)):
        if n > 0:
            Fi = np.linalg.inv(_transition(model, truth[n - 1], dt, transition))
            J = Fi.T @ J @ Fi
        J = J + info[n]
        out[n] = np.sqrt(np.diag(np.linalg.inv(J)))
    return out


def axis_bounds_from_planes(plane_bounds: dict[str, Array]) -> dict[str, dict[str, Array]]:
    """Per coordinate (x, y, z): the position bound of every plane that has it, ``{axis: {plane: (T,)}}``."""
    out: dict[str, dict[str, Array]] = {c: {} for c in "xyz"}
    for plane, b in plane_bounds.items():
        a, c = PLANE_AXES[plane]
        out["xyz"[a]][plane] = b[:, 0]
        out["xyz"[c]][plane] = b[:, 1]
    return out


def fused_bound(a: Array, b: Array) -> Array:
    """``1 / sqrt(1/a^2 + 1/b^2)``: two independent estimates of a shared coordinate combined."""
    return 1.0 / np.sqrt(1.0 / np.square(a) + 1.0 / np.square(b))


def _angle_jacobian(fn: Callable[[Array], Array], x: Array, eps: float = 1e-6) -> Array:
    """Central differences of ``fn: (n,) -> (m,)`` angles, differences wrapped to ``(-pi, pi]``."""
    cols = []
    for j in range(len(x)):
        h = np.zeros(len(x))
        h[j] = eps * max(1.0, abs(x[j]))
        d = np.asarray(fn(x + h)) - np.asarray(fn(x - h))
        cols.append((np.mod(d + np.pi, 2 * np.pi) - np.pi) / (2 * h[j]))
    return np.stack(cols, axis=-1)


def angle_pair_information(
    position: Array, sensor: DoaSensor3D, planes: tuple[str, str]
) -> dict[str, Array]:
    """Fisher information ``(3, 3)`` about a (local-frame) position carried by one angle pair.

    Lee 2009's PPS bearings are functions of the same measured ``(theta, phi)``: with
    ``G = d(theta_p1, theta_p2)/d(theta, phi)`` and ``H = d(theta, phi)/dp``, the planes' noise
    is ``G R G^T`` (correlated), so their joint information ``H^T G^T (G R G^T)^-1 G H`` equals
    the 3-D pair's ``H^T R^-1 H`` when ``G`` is invertible, and any one plane carries less
    (data-processing inequality). Summing the planes as if independent (each with its own
    marginal variance, as a per-plane bound fused on the shared axis does) can exceed the 3-D
    information: the bound it gives is not a bound for PPS. Keys ``"3-D"``, ``"pair"`` (joint,
    correlated), ``"independent"`` (the planes' sum) and each plane's name.
    """
    local = sensor.local(np.asarray(position, float))
    R = sensor.sigma**2 * np.eye(2)
    H = _angle_jacobian(lambda p: np.array(direction_angles(p)), local)  # (2, 3)
    tp = np.array(direction_angles(local))
    idx = [PLANES.index(p) for p in planes]
    G = _angle_jacobian(lambda a: projected_angles(a[0], a[1])[idx], tp)  # (2, 2)
    Hp, Rp = G @ H, G @ R @ G.T
    out = {"3-D": H.T @ np.linalg.solve(R, H), "pair": Hp.T @ np.linalg.solve(Rp, Hp)}
    singles = {p: np.outer(Hp[i], Hp[i]) / Rp[i, i] for i, p in enumerate(planes)}
    out["independent"] = sum(singles.values(), np.zeros((3, 3)))
    return out | singles
