"""Particle filters: bootstrap (SIR), auxiliary (Pitt & Shephard 1999) and regularised (Musso,
Oudjane & Le Gland 2001), on one skeleton.

A particle set is a :class:`~fusetrack.core.Particles` with states ``(..., N, d)`` and
log-weights ``(..., N)``; leading axes are independent runs (Monte Carlo replications or
targets) that the filter advances all at once. One step is

``predict(particles, dt, rng)``
    resample the runs whose effective sample size fell below ``ess_threshold * N`` (the
    regularised filter then jitters the copies), and draw every particle's next state from the
    motion model, ``x_k ~ p(x_k | x_{k-1})``;
``update(particles, measurements, rng)``
    for each measurement in turn, ``log w_i += log p(z | x_i)``; normalise by log-sum-exp.

Estimates: :meth:`ParticleFilter.estimate` (weighted mean and covariance, a Gaussian) and
:meth:`ParticleFilter.mean` (mean only, one pass). The particle sets a filter returns carry their
normalised weights in ``info``, so neither recomputes an ``exp``; the log-likelihoods of all the
measurements of an update are summed and normalised once (the degeneracy rules below still hold
per measurement: a cheap bound vouches for each, and the exact one-at-a-time update runs when it
cannot).

:meth:`ParticleFilter.update_with_likelihood` also returns the log-likelihood increment
``log p(z_k | z_1:k-1)`` per run, the log normaliser of the same pass (so the filters are
:class:`~fusetrack.core.LikelihoodFilter` s: parameter estimation, model comparison).

Resampling sits at the start of ``predict`` rather than the end of ``update`` so that the
estimate after an update (:meth:`ParticleFilter.estimate`) is taken from the weighted particles,
which has lower variance than taking it after resampling; the sequence of particle sets is the
usual SIR one. ``resample="every_update"`` is the other policy, the sequential importance
sampling loop of Zhai 2007 (Sec. 2.1-2.2): the update weights, resamples every run at once,
optionally moves the particles by MCMC and estimates from the resampled set, and
:meth:`ParticleFilter.step` draws from a pluggable proposal ``q(x_t | x_{t-1}, z_t)`` with the
measurements in view (:mod:`~fusetrack.filters.proposals`; the class docstring lists the
parts). :class:`~fusetrack.filters.ProposalParticleFilter` and
:class:`~fusetrack.filters.MultipleModelParticleFilter` are that configuration; both policies
share the likelihoods, the weight normalisation, the degeneracy policy, the resampling schemes
and the draws from the motion model.

Measurements. Any subset of the filter's sensors may report at a step; several measurements
are applied in sequence. A value ``(m,)`` applies to every run, ``(R, m)`` (or any leading shape
that broadcasts to the batch) gives each run its own. Rows with NaN or infinite entries are
skipped and counted in ``stats.skipped_measurements``; a measurement from an unknown sensor raises
:class:`~fusetrack.core.UnknownSensorError`. A measurement's own ``covariance`` replaces the
sensor's noise: the likelihood is then Gaussian in ``sensor.residual(z, sensor.predict(x))``.

Degenerate weights. A measurement is *degenerate* for a run when its log predictive density
under the particles, ``log sum_i w_i p(z | x_i)``, is not finite or is below
``min_log_evidence`` (default ``log`` of the smallest normal double, about -708: every particle's
likelihood would underflow to 0 in double precision, as happens when the measurement falls far
outside the particle cloud). The filter never returns NaN: it adds one to
``stats.degenerate_steps`` (once per ``update`` call), warns once per filter with
:class:`~fusetrack.core.DegenerateWeightsWarning` and applies ``degenerate``:

``"keep"`` (default)
    keep the weights the run had before this measurement, i.e. ignore the measurement;
``"inflate"``
    temper the likelihood, ``log w_i + beta * log p(z | x_i)`` with ``beta = temper_factor^k``
    for ``k = 1, 2, ...`` (for a Gaussian likelihood this inflates its covariance by
    ``1 / beta``) until the tempered evidence is finite and above ``min_log_evidence``; a run
    where no ``beta > 1e-300`` succeeds (every likelihood ``-inf``) falls back to ``"keep"``.

Randomness. Every draw comes from ``rng``. Pass one :class:`numpy.random.Generator` to draw for
the whole batch at once (fastest), or a sequence of generators, one per run (flattened C order
over the batch axes), to make run ``r`` of a batch bit-identical to a separate single run driven
by ``rng[r]``: the filter then calls the motion model, the sensors and the resampler run by
run (pass the same sequence to ``update``, which the auxiliary filter draws in, and which then
also evaluates the likelihoods run by run). With one generator a batch is statistically, not
bitwise, equivalent to separate runs. The process noise of a linear-Gaussian motion model
(``fused_transition``) is drawn as ``motion.sample`` draws it below
:data:`~fusetrack.filters.fused.SPLIT_MIN` particles per generator; from there the particles are
cut into :data:`~fusetrack.filters.fused.NOISE_STREAMS` fixed parts whose normals come from as
many child generators of that generator (``Generator.spawn``, once; the filter keeps them, and a
reference to their parent, for its lifetime), so that both cores can draw. The split depends on
the number of particles only, never on the threads: a seed gives the same particles everywhere.
With ``engine="numba"`` the generators enter the Numba loops as handles
(:mod:`~fusetrack.filters.rng_handles`; the same numbers as NumPy's), and a batch with one
generator per run and fewer than ``SPLIT_MIN`` particles per run draws, resamples and propagates
all its runs in one threaded loop over the runs (:mod:`~fusetrack.filters.run_streams`), each
run from its own generator in the order a separate run draws. ``engine="numba"`` uses the kernels of
:mod:`fusetrack.filters.kernels`, ``engine="numpy"`` their NumPy references (same draws; results
agree to rounding, about 1e-15). Both use the resampling schemes of
:mod:`fusetrack.core.resampling`.

Counters (``filter.stats``, a :class:`~fusetrack.filters.stats.FilterStats`):
``skipped_measurements`` (one per skipped row), ``degenerate_steps`` (one per ``update`` that
recovered, however many runs) and ``resample_count`` (one per step that resampled any run).

>>> import numpy as np
>>> from fusetrack.core import Gaussian, Measurement
>>> from fusetrack.motion import ConstantVelocity
>>> from fusetrack.sensors import PositionFix
>>> gps = PositionFix("gps", cov=[[1.0]], position_index=(0,))
>>> pf = BootstrapFilter(ConstantVelocity(ndim=1, q=0.1), [gps], n_particles=2000)
>>> rng = np.random.default_rng(0)
>>> p = pf.initialize(Gaussian(np.zeros(2), np.eye(2)), rng)
>>> p = pf.update(pf.predict(p, 1.0, rng), [Measurement(1.0, "gps", [0.5])])
>>> pf.estimate(p).mean.shape
(2,)
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from itertools import repeat
from typing import Any, ClassVar, Literal, NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

from ..core import (
    ConfigError,
    Gaussian,
    Measurement,
    MeasurementError,
    MotionModel,
    Particles,
    Resampler,
    SensorModel,
    ShapeError,
    check_positive,
    check_probability,
    get_resampler,
    invalid,
    resampling,
)
from . import fused, fused_update, kernels, rng_handles, run_streams
from .proposals import (
    LogLikelihood,
    Move,
    PriorProposal,
    Proposal,
    ProposalContext,
    SISBelief,
    SISStats,
    aligned_values,
    check_generator,
    log_transition,
)
from .stats import FilterStats, as_sensor_map, validate_measurement

Array = NDArray[np.float64]
Rng = np.random.Generator | Sequence[np.random.Generator]

LOG_TINY = math.log(np.finfo(float).tiny)
"""``log`` of the smallest normal double (about -708.4): the default ``min_log_evidence``."""

_LOG_2PI = math.log(2.0 * math.pi)
_CACHE = "_pf_weights"  # Particles.info key: the normalised weights of those log-weights
_MEAN = "_pf_mean"  # Particles.info key: the weighted mean of those log-weights (fused update)
_PARENTS = "_apf_parents"  # Particles.info key: (parent states, dt) for the auxiliary filter
_MAX_TEMPER = 1e-300
_THREADED_DRAW_MIN = 1 << 15  # normals per step from which per-run draws use a few threads

__all__ = [
    "LOG_TINY",
    "AuxiliaryParticleFilter",
    "BootstrapFilter",
    "ParticleFilter",
    "RegularizedParticleFilter",
]


class _Weights(NamedTuple):
    """Normalised log-weights, weights and ESS of a batch, as rows ``(R, N)`` / ``(R,)``."""

    lw: Array
    w: Array
    ess: Array


class _Checked(NamedTuple):
    """A usable measurement: its sensor, value rows ``(R, m)``, covariance rows or None, and
    which runs may use it ``(R,)``."""

    sensor: SensorModel
    z: Array | _RawValue
    cov: Array | None
    usable: NDArray[np.bool_]


class _RawValue(NamedTuple):
    """A likelihood-only sensor's report, passed to its ``log_likelihood`` as given."""

    value: Any


class _Engine(NamedTuple):
    add: Callable[..., tuple[Array, Array]]
    normalize: Callable[..., tuple[Array, Array, Array, Array]]
    update: Callable[[Array, Array], tuple[Array, Array, Array, Array]]
    mean: Callable[[Array, Array], Array]
    mean_cov: Callable[[Array, Array], tuple[Array, Array]]


_ENGINES = {
    "numba": _Engine(
        kernels.add_log_likelihood,
        kernels.normalize_log_weights,
        kernels.log_weight_update,
        kernels.weighted_mean,
        kernels.weighted_mean_cov,
    ),
    "numpy": _Engine(
        kernels.add_log_likelihood_reference,
        kernels.normalize_log_weights_reference,
        kernels.log_weight_update_reference,
        kernels.weighted_mean_reference,
        kernels.weighted_mean_cov_reference,
    ),
}


def _sqrt_factor(cov: Array) -> Array:
    """``D`` with ``D D^T = cov`` (each ``(..., d, d)``): Cholesky, or ``V sqrt(L)`` if singular."""
    try:
        return np.asarray(np.linalg.cholesky(cov), dtype=np.float64)
    except np.linalg.LinAlgError:
        s, v = np.linalg.eigh(0.5 * (cov + np.swapaxes(cov, -1, -2)))
        return np.asarray(v * np.sqrt(np.clip(s, 0.0, None))[..., None, :], dtype=np.float64)


def _gather(states: Array, idx: NDArray[np.intp]) -> Array:
    """``states[r, idx[r]]`` for rows ``(K, N, d)`` and ancestors ``(K, N)`` (one flat take)."""
    k, n, d = states.shape
    if k == 1:
        return states[0].take(idx[0], axis=0)[None]
    flat = idx + (np.arange(k) * n)[:, None]
    return states.reshape(k * n, d).take(flat.ravel(), axis=0).reshape(k, idx.shape[1], d)


class ParticleFilter:
    """The shared skeleton of the particle filters (see the module docstring).

    Parameters
    ----------
    motion:
        A motion model (``sample``, ``mean``; :class:`~fusetrack.core.MotionModel`).
    sensors:
        A mapping ``sensor_id -> model`` or a sequence of sensor models (keyed by ``sensor_id``).
    n_particles:
        Particles per run, ``N``.
    resampler:
        ``"systematic"`` (default), ``"stratified"``, ``"residual"``, ``"multinomial"`` or a
        callable ``(weights (K, N), rng) -> ancestors (K, N)``.
    ess_threshold:
        Fraction of ``N``: a run is resampled when its ESS ``< ess_threshold * N``
        (1.0: every step with a non-uniform weighting; 0: never).
    engine:
        ``"numba"`` (kernels) or ``"numpy"`` (their references).
    degenerate:
        Recovery policy for a degenerate measurement, ``"keep"`` or ``"inflate"``.
    temper_factor:
        ``"inflate"`` multiplies the tempering exponent by this factor in ``(0, 1)`` per try.
    min_log_evidence:
        Log predictive density below which a measurement counts as degenerate (default:
        :data:`LOG_TINY`; ``-inf`` with ``resample="every_update"``).
    resample:
        ``"ess"`` (default): resample at the next ``predict`` when the ESS is low (above);
        ``"every_update"``: resample every update right after weighting, which is what a
        proposal's weight assumes (the SIS loop, see :ref:`below <every-update>`;
        ``ess_threshold`` is then unused); the filter carries a
        :class:`~fusetrack.filters.SISBelief`.
    proposal:
        ``q(x_t | x_{t-1}, z_t)`` (:class:`~fusetrack.filters.proposals.Proposal`) drawn from by
        :meth:`step` with the step's measurements in view; ``"every_update"`` only (default
        there: :class:`~fusetrack.filters.PriorProposal`, the transition prior).
    move:
        An MCMC kernel applied after resampling (:mod:`~fusetrack.filters.mcmc_moves`);
        ``"every_update"`` only.
    estimate:
        ``"weighted"`` (default): the weighted mean of the weighted particles; ``"resampled"``
        (``"every_update"`` only): the mean of the resampled (and moved) particles.
    transition:
        ``"paired"`` or ``"marginal"``: the transition density in a proposal's weight
        (:func:`~fusetrack.filters.proposals.log_transition`).

    .. _every-update:

    With ``resample="every_update"`` one update (Zhai 2007, Sec. 2.1-2.2) weights the drawn
    particles (Eq. 13: ``log p(z_t | x) + log p(x | x_{t-1}) - log q(x)``, the previous weights
    being equal), normalises, resamples every run with ``resampler``, moves, estimates and feeds
    the estimate back to the proposal. The weight of a step is one increment: a run is degenerate
    when it has no finite weight (with the default ``min_log_evidence=-inf``), and the policy
    ``degenerate`` applies to the whole increment. Every draw goes through the models' own
    ``sample`` (never the fused linear path) from one :class:`numpy.random.Generator`.
    """

    _resamples_every_update: ClassVar[bool] = True  # False: a filter with its own selection

    def __init__(
        self,
        motion: MotionModel,
        sensors: Mapping[str, SensorModel] | Sequence[SensorModel] | SensorModel,
        n_particles: int = 1000,
        resampler: str | Resampler = "systematic",
        ess_threshold: float = 1.0,
        engine: str = "numba",
        *,
        degenerate: str = "keep",
        temper_factor: float = 0.5,
        min_log_evidence: float | None = None,
        resample: Literal["ess", "every_update"] = "ess",
        proposal: Proposal | None = None,
        move: Move | None = None,
        estimate: Literal["weighted", "resampled"] = "weighted",
        transition: Literal["paired", "marginal"] = "paired",
    ) -> None:
        every = self._check_policy(resample, proposal, move, estimate, transition)
        if min_log_evidence is None:
            min_log_evidence = -math.inf if every else LOG_TINY
        if (
            isinstance(n_particles, bool)
            or not isinstance(n_particles, int | np.integer)
            or n_particles < 1
        ):
            raise ConfigError(invalid("n_particles", n_particles, "an integer >= 1"))
        if engine not in _ENGINES:
            raise ConfigError(invalid("engine", engine, f"one of {sorted(_ENGINES)}"))
        if degenerate not in ("keep", "inflate"):
            raise ConfigError(invalid("degenerate", degenerate, "'keep' or 'inflate'"))
        tf = check_positive("temper_factor", temper_factor)
        if not tf < 1.0:
            raise ConfigError(invalid("temper_factor", temper_factor, "a number in (0, 1)"))
        try:
            mle = float(min_log_evidence)
        except (TypeError, ValueError):
            raise ConfigError(invalid("min_log_evidence", min_log_evidence, "a number")) from None
        if math.isnan(mle):
            raise ConfigError(invalid("min_log_evidence", min_log_evidence, "a number"))
        self.motion = motion
        self.sensors: dict[str, SensorModel] = as_sensor_map(sensors)
        self._by_id = self.sensors  # the sensors by id (a subclass may expose them otherwise)
        self.resample_policy = resample
        self.proposal: Proposal | None = (proposal or PriorProposal()) if every else None
        self.move = move
        self.estimate_policy = estimate
        self.transition = transition
        self._side_ids: tuple[str, ...] = tuple(getattr(self.proposal, "side_inputs", ()))
        self.n_particles = int(n_particles)
        self.resampler = resampler
        self._resample: Resampler = get_resampler(resampler)
        self.ess_threshold = check_probability("ess_threshold", ess_threshold)
        self.engine = engine
        self._k = _ENGINES[engine]
        self.degenerate = degenerate
        self.temper_factor = tf
        self.min_log_evidence = mle
        self.stats: FilterStats = SISStats() if every else FilterStats()
        self._fused_dt: tuple[float, tuple[Array, Array] | None] | None = None
        self._fused_ll: dict[int, tuple[SensorModel, tuple[int, Array] | None]] = {}
        self._streams: dict[int, tuple[np.random.Generator, tuple[Any, ...], Any]] = {}
        self._fused_sets: dict[tuple[int, ...], tuple[tuple[Any, ...], Any]] = {}
        self._everyone: dict[int, NDArray[np.bool_]] = {}  # read-only all-True "usable" rows
        self._runs: rng_handles.RunStreams | None = None  # handles of the last per-run gens
        self._one: rng_handles.RunStreams | None = None  # handle of the last single generator

    def _check_policy(
        self, resample: str, proposal: Any, move: Any, estimate: str, transition: str
    ) -> bool:
        """Validate the resampling policy and its parts; whether it is ``"every_update"``."""
        if resample not in ("ess", "every_update"):
            raise ConfigError(invalid("resample", resample, "'ess' or 'every_update'"))
        every = resample == "every_update"
        if every and not self._resamples_every_update:
            raise ConfigError(invalid("resample", resample, f"'ess' for {type(self).__name__}"))
        for name, value, default in (
            ("proposal", proposal, None),
            ("move", move, None),
            ("estimate", estimate, "weighted"),
            ("transition", transition, "paired"),
        ):
            given = value is not None if default is None else value != default
            if given and not every:
                raise ConfigError(invalid(name, value, f"{default!r} with resample='ess'"))
        if estimate not in ("weighted", "resampled"):
            raise ConfigError(invalid("estimate", estimate, "'weighted' or 'resampled'"))
        if transition not in ("paired", "marginal"):
            raise ConfigError(invalid("transition", transition, "'paired' or 'marginal'"))
        return every

    def __repr__(self) -> str:
        return (
            f"{type(self).__name__}(motion={self.motion!r}, sensors={sorted(self.sensors)}, "
            f"n_particles={self.n_particles}, resampler={self.resampler!r}, "
            f"ess_threshold={self.ess_threshold}, engine={self.engine!r})"
        )

    # ------------------------------------------------------------------------------------------
    # public interface

    def initialize(self, prior: Gaussian, rng: Rng, batch_shape: tuple[int, ...] = ()) -> Particles:
        """``N`` equally weighted draws from ``prior`` per run: states ``(*batch, N, d)``.

        The batch is ``batch_shape`` broadcast with the prior's own leading axes.
        """
        mean = np.asarray(prior.mean, dtype=float)
        d = mean.shape[-1]
        dim = getattr(self.motion, "dim", d)
        if d != dim:
            raise ShapeError(
                invalid("prior.mean.shape", mean.shape, f"(..., {dim}) for the motion model")
            )
        try:
            batch = np.broadcast_shapes(mean.shape[:-1], tuple(int(b) for b in batch_shape))
        except ValueError:
            raise ShapeError(
                invalid(
                    "batch_shape",
                    batch_shape,
                    f"a shape that broadcasts with the prior's {mean.shape[:-1]}",
                )
            ) from None
        gens = self._generators(rng, batch)
        n = self.n_particles
        L = _sqrt_factor(np.broadcast_to(np.asarray(prior.cov, dtype=float), (*batch, d, d)))
        mean = np.broadcast_to(mean, (*batch, d))
        if isinstance(gens, np.random.Generator):
            x = gens.standard_normal((*batch, n, d)) @ np.swapaxes(L, -1, -2)
            x += mean[..., None, :]
        else:
            L2, m2 = L.reshape(-1, d, d), mean.reshape(-1, d)
            x = np.empty((len(gens), n, d))
            for r, g in enumerate(gens):
                x[r] = g.standard_normal((n, d)) @ L2[r].T
                x[r] += m2[r]
            x = x.reshape((*batch, n, d))
        W = self._uniform(int(np.prod(batch, dtype=np.int64)), n)
        if self.proposal is None:
            return self._particles(x, W)
        assert isinstance(gens, np.random.Generator)  # _generators: one with a proposal
        pstate = self.proposal.initialize(prior, x, gens)
        return self._sis_belief(x, W, np.broadcast_to(mean, (*batch, d)).copy(), pstate)

    def predict(self, particles: Particles, dt: float, rng: Rng | None = None) -> Particles:
        """Resample runs with low ESS, then draw ``x_k ~ p(x_k | x_{k-1})`` for each particle
        (``resample="every_update"``: the draw only, its parents kept for :meth:`update`)."""
        if self.proposal is not None:
            return self._predict_parents(particles, dt, rng)
        gens = self._generators(rng, particles.batch_shape)
        W = self._weights(particles)
        n, d = particles.states.shape[-2:]
        if not isinstance(gens, np.random.Generator):
            fast = self._predict_runs(particles, W, dt, gens)
            if fast is not None:
                return fast
        if (
            type(self)._regularize is ParticleFilter._regularize
            and self._fused_motion(dt) is not None
            and np.all(W.ess < self.ess_threshold * n)
        ):  # fused: gather the resampled parents inside the propagation loop (no copy)
            self.stats.resample_count += 1
            rows = np.arange(W.ess.size)
            anc = self._ancestors(W.w, rows, gens)
            s2 = particles.states.reshape(-1, n, d)
            new = self._sample_motion(s2, dt, gens, ancestors=anc)
            return self._particles(new.reshape(particles.states.shape), self._uniform(rows.size, n))
        states, W = self._maybe_resample(particles.states, W, gens)
        return self._particles(self._sample_motion(states, dt, gens), W)

    def _predict_runs(
        self, particles: Particles, W: _Weights, dt: float, gens: list[np.random.Generator]
    ) -> Particles | None:
        """:meth:`predict` of a batch with one generator per run in one threaded Numba loop
        over the runs (:func:`fusetrack.filters.run_streams.linear_gaussian_runs`: each run's
        resampling uniform, ancestors, normals and propagation, from its own generator, in the
        order a separate run draws them). None when it does not apply (engine "numpy", a motion
        model without ``fused_transition``, a regularised filter, child noise streams from
        :data:`~fusetrack.filters.fused.SPLIT_MIN` particles per run, one generator given for
        several runs)."""
        n, d = particles.states.shape[-2:]
        fg = self._fused_motion(dt)
        if (
            self.engine != "numba"
            or fg is None
            or n >= fused.SPLIT_MIN
            or type(self)._regularize is not ParticleFilter._regularize
        ):
            return None
        runs = self._runs
        if runs is None or not runs.matches(gens):
            runs = self._runs = rng_handles.RunStreams(gens)
        if not runs.distinct:  # one generator for several runs: NumPy's path, which locks it
            return None
        need = W.ess < self.ess_threshold * n
        anc = None
        if not need.any():
            mode = np.full(need.size, run_streams.KEEP, dtype=np.int64)
        elif self._resample is resampling.systematic:  # drawn and merged inside the loop
            mode = np.where(need, run_streams.SYSTEMATIC, run_streams.KEEP)
        else:  # another scheme draws its uniforms first, as a separate run does
            mode = np.where(need, run_streams.GATHER, run_streams.KEEP)
            rows = np.flatnonzero(need)
            anc = np.zeros(W.w.shape, dtype=np.intp)
            anc[rows] = self._ancestors(W.w, rows, gens)
        s2 = particles.states.reshape(-1, n, d)
        new = run_streams.linear_gaussian_runs(runs, s2, fg[0], fg[1], mode, W.w, anc)
        if need.any():
            self.stats.resample_count += 1
        return self._particles(new.reshape(particles.states.shape), self._resampled(W, need))

    def update(
        self,
        particles: Particles,
        measurements: Sequence[Measurement] | Measurement,
        rng: Rng | None = None,
    ) -> Particles:
        """Weight by each usable measurement in turn (``log w += log p(z | x)``, normalised)."""
        return self.update_with_likelihood(particles, measurements, rng)[0]

    def update_with_likelihood(
        self,
        particles: Particles,
        measurements: Sequence[Measurement] | Measurement,
        rng: Rng | None = None,
    ) -> tuple[Particles, Array]:
        """:meth:`update` and the log-likelihood increment ``log p(z_k | z_1:k-1)`` ``(...)``
        per run, from the same pass: ``logsumexp_i(log w_i + sum_m log p(z_m | x_i))`` with the
        prior weights ``w`` normalised (the particle estimate of the predictive density,
        Doucet & Johansen 2009, Eq. 47). Measurements are chained: the sum over ``m`` of each
        one's ``log sum_i w_i^(m-1) p(z_m | x_i)``. A measurement that a run skips adds 0; one
        recovered by the degeneracy policy adds its (untempered) evidence estimate, very
        negative or ``-inf``: the particles could not explain it."""
        if self.proposal is not None:
            return self._update_and_resample(particles, measurements, rng)
        batch = particles.batch_shape
        checked = self._check_measurements(measurements, batch)
        if not checked:
            return particles, np.zeros(batch)
        W = self._weights(particles)
        fast = self._reweight_fused(particles.states, W, checked)
        if fast is not None:  # weights and their mean in one pass (see mean())
            W2, mean, lse = fast
            return self._particles(particles.states, W2, mean=mean), lse.reshape(batch)
        W, degenerate, lse = self._reweight(particles.states, W, checked, rng, fused=False)
        self._note_degenerate(degenerate)
        return self._particles(particles.states, W), lse.reshape(batch)

    def estimate(self, particles: Particles) -> Gaussian:
        """Weighted mean ``(..., d)`` and covariance ``(..., d, d)`` of the particles."""
        W = self._weights(particles)
        s = particles.states
        n, d = s.shape[-2:]
        mean, cov = self._k.mean_cov(s.reshape(-1, n, d), W.w)
        lead = particles.batch_shape
        return Gaussian(mean.reshape((*lead, d)), cov.reshape((*lead, d, d)))

    def mean(self, particles: Particles) -> Array:
        """Weighted mean ``(..., d)`` only (one pass; cheaper than :meth:`estimate`); a
        :class:`~.proposals.SISBelief`'s own estimate (e.g. of the resampled particles)."""
        if isinstance(particles, SISBelief) and particles.estimate.size:
            return np.array(particles.estimate)
        cached = particles.info.get(_MEAN)
        if cached is not None and cached[0] is particles.log_weights:
            return np.array(cached[1].reshape((*particles.batch_shape, particles.dim)))
        W = self._weights(particles)
        s = particles.states
        n, d = s.shape[-2:]
        return self._k.mean(s.reshape(-1, n, d), W.w).reshape((*particles.batch_shape, d))

    def weights(self, particles: Particles) -> Array:
        """Normalised weights ``(..., N)`` (cached: no ``exp`` when they came from this filter)."""
        return self._weights(particles).w.reshape(particles.log_weights.shape)

    def effective_sample_size(self, particles: Particles) -> Array:
        """``1 / sum_i w_i^2`` per run, ``(...)``."""
        return self._weights(particles).ess.reshape(particles.batch_shape)

    # ------------------------------------------------------------------------------------------
    # resample="every_update": the proposal-driven loop (Zhai 2007, Sec. 2.1-2.2)

    def step(
        self,
        particles: Particles,
        dt: float,
        measurements: Sequence[Measurement] | Measurement,
        rng: Rng | None = None,
    ) -> Particles:
        """One step. ``resample="ess"``: :meth:`predict` (when ``dt > 0``) then :meth:`update`
        (when there are measurements), as :func:`~fusetrack.core.filter_step` does.
        ``"every_update"``: draw ``x_t ~ q(x_t | x_{t-1}, z_t)`` from the proposal with the
        measurements in view, weight (Zhai 2007, Eq. 13), resample, move, estimate, feed back."""
        return self.step_with_likelihood(particles, dt, measurements, rng)[0]

    def step_with_likelihood(
        self,
        particles: Particles,
        dt: float,
        measurements: Sequence[Measurement] | Measurement,
        rng: Rng | None = None,
    ) -> tuple[Particles, Array]:
        """:meth:`step` and ``log p(z_t | z_1:t-1)`` per run ``(...)``: the update's increment,
        or, with a proposal, the log mean of the incremental weights (0 where nothing reported)."""
        if self.proposal is None:
            if dt > 0:
                particles = self.predict(particles, dt, rng)
            if not measurements:
                return particles, np.zeros(particles.batch_shape)
            return self.update_with_likelihood(particles, measurements, rng)
        check_positive("dt", dt)
        gen = check_generator(rng)  # type: ignore[arg-type]
        zs, side, checked = self._step_inputs(measurements, particles.batch_shape)
        ctx = self.context(side)
        prev = particles.states
        x, log_q, pstate = self.proposal.draw(
            getattr(particles, "proposal", None), prev, zs, dt, gen, ctx
        )
        ll = self._summed_loglik(x, checked)
        if log_q is None:
            log_w = ll
        elif getattr(self.proposal, "returns_log_ratio", False):
            # the proposal returned log(p(x_t | z_{1:t-1}) / q(x_t)) (exact marginal weight)
            log_w = (ll if checked else 0.0) + log_q
        else:
            log_w = ll + self.log_transition(x, prev, dt) - log_q
        return self._weigh_and_resample(x, prev, log_w, bool(checked), zs, pstate, dt, gen, ctx)

    def context(self, side: Mapping[str, Array] | None = None) -> ProposalContext:
        """What proposals and moves see of this filter (:class:`~.proposals.ProposalContext`)."""
        assert isinstance(self.stats, SISStats)  # every filter with a proposal keeps SISStats
        return ProposalContext(self.motion, list(self._by_id.values()), self.stats, side or {})

    def log_transition(self, x: Array, prev: Array, dt: float) -> Array:
        """The transition term of a proposal's weight (:func:`~.proposals.log_transition`)."""
        return log_transition(self.motion, x, prev, dt, self.transition)

    def _predict_parents(self, particles: Particles, dt: float, rng: Rng | None) -> SISBelief:
        """``x_t ~ p(x_t | x_{t-1})`` for every particle through ``motion.sample`` (or the
        proposal's ``prior_draw``, e.g. regimes first); the parents wait for :meth:`update`."""
        check_positive("dt", dt)
        gen = check_generator(rng)  # type: ignore[arg-type]
        pstate = getattr(particles, "proposal", None)
        prior_draw = getattr(self.proposal, "prior_draw", None)
        if prior_draw is None:
            x = self._sample_motion(particles.states, dt, gen)
        else:
            x, pstate = prior_draw(pstate, particles.states, dt, gen)
        n = x.shape[-2]
        W = self._uniform(int(np.prod(x.shape[:-2], dtype=np.int64)), n)
        return self._sis_belief(x, W, x.mean(axis=-2), pstate, particles.states, dt)

    def _update_and_resample(
        self,
        particles: Particles,
        measurements: Sequence[Measurement] | Measurement,
        rng: Rng | None,
    ) -> tuple[Particles, Array]:
        """:meth:`update` with ``resample="every_update"``: weight the predicted particles by
        ``p(z_t | x_t)``, resample, move, estimate, feed back (nothing when nothing reported)."""
        batch = particles.batch_shape
        zs, side, checked = self._step_inputs(measurements, batch)
        if not checked:
            return particles, np.zeros(batch)
        gen = check_generator(rng)  # type: ignore[arg-type]
        sis = particles if isinstance(particles, SISBelief) else None
        parents = sis.parents if sis is not None and sis.parents is not None else particles.states
        x = particles.states
        return self._weigh_and_resample(
            x,
            parents,
            self._summed_loglik(x, checked),
            True,
            zs,
            getattr(particles, "proposal", None),
            sis.dt if sis is not None else 0.0,
            gen,
            self.context(side),
        )

    def _step_inputs(
        self, measurements: Sequence[Measurement] | Measurement, batch: tuple[int, ...]
    ) -> tuple[list[Array | None], dict[str, Array], list[_Checked]]:
        """The step's values aligned with the sensors (for proposals; at most one report per
        sensor), its side inputs, and its checked sensor reports in the sensors' order (so the
        log-likelihoods are summed in one order whatever the order of the reports)."""
        ms = [measurements] if isinstance(measurements, Measurement) else list(measurements)
        for m in ms:
            if not isinstance(m, Measurement):
                raise MeasurementError(
                    invalid("measurements", m, "a sequence of fusetrack Measurement")
                )
        zs, side = aligned_values(list(self._by_id.values()), ms, self._side_ids)
        order = {sid: k for k, sid in enumerate(self._by_id)}
        ours = sorted((m for m in ms if m.sensor_id in order), key=lambda m: order[m.sensor_id])
        return zs, side, self._check_measurements(ours, batch)

    def _summed_loglik(self, x: Array, checked: list[_Checked]) -> Array:
        """``sum_k log p(z_k | x_i)`` ``(..., N)`` over the checked reports (0 without any)."""
        total = np.zeros(x.shape[:-1])
        for ll in self._measurement_logliks(x, checked, None):
            total = total + ll.reshape(x.shape[:-1])
        return total

    def _weigh_and_resample(
        self,
        x: Array,
        prev: Array,
        log_w: Array,
        reported: bool,
        zs: list[Array | None],
        pstate: Any,
        dt: float,
        gen: np.random.Generator,
        ctx: ProposalContext,
    ) -> tuple[SISBelief, Array]:
        """Normalise the step's log-weights ``(..., N)`` (one increment: the previous weights
        are equal) with the degeneracy policy, resample every run, reindex the proposal's
        per-particle state, move (when a sensor ``reported``), estimate, feed back. Returns the
        belief and the log mean of the incremental weights (0 when nothing ``reported``)."""
        n, d = x.shape[-2:]
        batch = x.shape[:-2]
        rows = int(np.prod(batch, dtype=np.int64))
        # equal prior weights kept unnormalised (log 0): the log-weights are normalised as given
        W0 = _Weights(np.zeros((rows, n)), np.full((rows, n), 1.0 / n), np.full(rows, float(n)))
        lw = np.reshape(log_w, (rows, n))
        W, degenerate, lse = self._apply_logliks(W0, [np.ones(rows, dtype=bool)], [lw])
        self._note_degenerate(degenerate)
        increment = lse.reshape(batch) - math.log(n) if reported else np.zeros(batch)
        weighted = None
        if self.estimate_policy == "weighted":
            weighted = self._k.mean(x.reshape(rows, n, d), W.w).reshape((*batch, d))
        self.stats.resample_count += 1
        idx = self._ancestors(W.w, np.arange(rows), gen)
        x_res = _gather(x.reshape(rows, n, d), idx).reshape(x.shape)
        reindex = getattr(self.proposal, "reindex", None)
        if reindex is not None:  # per-particle parts of the proposal state (regimes)
            pstate = reindex(pstate, idx.reshape((*batch, n)))
        if self.move is not None and reported:
            parents = _gather(prev.reshape(rows, n, d), idx).reshape(x.shape)
            loglik = LogLikelihood(ctx.sensors, zs)
            x_res = self.move(x_res, parents, loglik, dt, gen, ctx)
        est = x_res.mean(axis=-2) if weighted is None else weighted
        assert self.proposal is not None
        pstate = self.proposal.feedback(pstate, x_res, est, ctx)
        return self._sis_belief(x_res, self._uniform(rows, n), est, pstate), increment

    def _sis_belief(
        self,
        states: Array,
        W: _Weights,
        estimate: Array,
        pstate: Any,
        parents: Array | None = None,
        dt: float = 0.0,
    ) -> SISBelief:
        """A :class:`~.proposals.SISBelief` with its weights cached."""
        lw = W.lw.reshape(states.shape[:-1])
        return SISBelief(states, lw, {_CACHE: (lw, W)}, estimate, pstate, parents, dt)

    # ------------------------------------------------------------------------------------------
    # weights and their cache

    def _particles(
        self, states: Array, W: _Weights, mean: Array | None = None, **info: Any
    ) -> Particles:  # mean: keyword only in practice (info keys never clash with it)
        """Particles with their normalised weights (and, when given, their weighted mean rows
        ``(R, d)``) cached in ``info`` for these log-weights."""
        lw = W.lw.reshape(states.shape[:-1])
        if mean is not None:
            info[_MEAN] = (lw, mean)
        return Particles(states, lw, {_CACHE: (lw, W), **info})

    def _weights(self, particles: Particles) -> _Weights:
        """Normalised rows of ``particles``' weights, from the cache when it matches."""
        cached = particles.info.get(_CACHE)
        if cached is not None and cached[0] is particles.log_weights:
            W: _Weights = cached[1]
            return W
        n = particles.n
        lw, w, lse, ess = self._k.normalize(particles.log_weights.reshape(-1, n))
        bad = ~np.isfinite(lse)
        if bad.any():
            raise ConfigError(
                invalid(
                    "particles.log_weights",
                    "a run whose weights are all zero (or +inf)",
                    "at least one finite log-weight per run",
                )
            )
        return _Weights(lw, w, ess)

    @staticmethod
    def _uniform(rows: int, n: int) -> _Weights:
        return _Weights(
            np.full((rows, n), -math.log(n)), np.full((rows, n), 1.0 / n), np.full(rows, float(n))
        )

    # ------------------------------------------------------------------------------------------
    # randomness: one generator for the batch, or one per run

    def _generators(
        self, rng: Rng | None, batch: tuple[int, ...]
    ) -> np.random.Generator | list[np.random.Generator]:
        if isinstance(rng, np.random.Generator):
            return rng
        if self.proposal is not None:  # proposals and moves draw from one generator
            return check_generator(rng)  # type: ignore[arg-type]
        runs = int(np.prod(batch, dtype=np.int64))
        valid = f"a numpy.random.Generator or a sequence of {runs} of them (one per run)"
        if rng is None or isinstance(rng, str | bytes) or not isinstance(rng, Sequence):
            raise ConfigError(invalid("rng", rng, valid))
        gens = list(rng)
        if len(gens) != runs or not all(map(isinstance, gens, repeat(np.random.Generator))):
            raise ConfigError(invalid("rng", f"a sequence of {len(gens)} items", valid))
        return gens

    def _fused_motion(self, dt: float) -> tuple[Array, Array] | None:
        """``(F, G)`` of a linear-Gaussian motion model at ``dt`` (its ``fused_transition``),
        else None. Both engines use it: "numba" runs the fused loop, "numpy" its reference."""
        cached = self._fused_dt
        if cached is not None and cached[0] == dt:
            return cached[1]
        offer = getattr(self.motion, "fused_transition", None)
        # with a proposal every draw is the models' own (the SIS loop's exact draws)
        fg = offer(dt) if callable(offer) and self.proposal is None else None
        self._fused_dt = (dt, fg)
        return fg

    def _noise_streams(self, gen: np.random.Generator, particles: int) -> tuple[Any, ...]:
        """The generators that draw the process noise of ``particles`` particles for ``gen``:
        ``(gen,)`` below :data:`~fusetrack.filters.fused.SPLIT_MIN`, else ``gen``'s
        :data:`~fusetrack.filters.fused.NOISE_STREAMS` children, spawned once per generator
        and kept (so that they continue their streams from step to step). The split is fixed:
        the draws do not depend on the number of threads."""
        if particles < fused.SPLIT_MIN:
            return (gen,)
        hit = self._streams.get(id(gen))
        if hit is not None and hit[0] is gen:  # the entry holds gen: its id cannot be reused
            return hit[1]
        try:
            kids = tuple(gen.spawn(fused.NOISE_STREAMS))
        except (TypeError, ValueError):  # a bit generator without a SeedSequence
            seed = np.random.SeedSequence(gen.integers(0, 2**63, size=4).tolist())
            kids = tuple(np.random.default_rng(s) for s in seed.spawn(fused.NOISE_STREAMS))
        self._streams[id(gen)] = (gen, kids, rng_handles.RunStreams(kids))
        return kids

    def _sample_motion(
        self,
        states: Array,
        dt: float,
        gens: np.random.Generator | list[np.random.Generator],
        rows: NDArray[np.intp] | None = None,
        ancestors: NDArray[np.intp] | None = None,
    ) -> Array:
        """A draw of the next state of every particle; with per-run generators, row ``j`` of
        ``states`` belongs to run ``rows[j]`` (default: row ``j`` is run ``j``).

        ``ancestors`` ``(R, N)`` (linear-Gaussian models only) propagates
        ``states[r, ancestors[r]]``: the gather of resampling done inside the loop. A
        linear-Gaussian model (``fused_transition``) draws ``F x + G eps`` with ``eps`` from
        :meth:`_noise_streams` (what ``motion.sample`` draws when there is one stream); other
        models are called as they are.
        """
        fg = self._fused_motion(dt)
        if fg is not None:
            return self._linear_step(states, fg, gens, rows, ancestors)
        if isinstance(gens, np.random.Generator):
            return np.asarray(self.motion.sample(states, dt, gens), dtype=float)
        n, d = states.shape[-2:]
        s2 = states.reshape(-1, n, d)
        runs = range(s2.shape[0]) if rows is None else rows
        out = np.empty_like(s2)
        for j, r in enumerate(runs):
            out[j] = self.motion.sample(s2[j], dt, gens[r])
        return out.reshape(states.shape)

    def _linear_step(
        self,
        states: Array,
        fg: tuple[Array, Array],
        gens: np.random.Generator | list[np.random.Generator],
        rows: NDArray[np.intp] | None,
        ancestors: NDArray[np.intp] | None,
    ) -> Array:
        """``F x_a + G eps`` for a linear-Gaussian model (see :meth:`_sample_motion`)."""
        F, G = fg
        n, d = states.shape[-2:]
        s2 = states.reshape(-1, n, d)
        numba_engine = self.engine == "numba"
        shape = s2.shape if ancestors is None else (s2.shape[0], ancestors.shape[1], d)
        if isinstance(gens, np.random.Generator):
            streams = self._noise_streams(gens, shape[0] * shape[1])
            if numba_engine and len(streams) > 1:  # drawn inside the loop, one thread per stream
                handles = self._streams[id(gens)][2]  # the children's, made once
                out = fused.linear_gaussian_draw(s2, F, G, handles, ancestors)
            elif numba_engine:  # one stream, drawn inside the serial loop through its handle
                one = self._one
                if one is None or one.gens[0] is not gens:  # the last generator only: no hoard
                    one = self._one = rng_handles.RunStreams((gens,))
                out = fused.linear_gaussian_draw(s2, F, G, one, ancestors)
            else:
                src = s2 if ancestors is None else _gather(s2, ancestors)
                out = src @ F.T + fused.standard_normals(streams, shape) @ G.T
        else:
            runs = range(s2.shape[0]) if rows is None else rows
            if shape[1] >= fused.SPLIT_MIN:  # each run's own streams, one run at a time
                out = np.empty(shape)
                for j, r in enumerate(runs):
                    a = None if ancestors is None else ancestors[j : j + 1]
                    out[j] = self._linear_step(s2[j : j + 1], fg, gens[r], None, a)[0]
            else:
                eps = np.empty(shape)
                _fill_normals([gens[r] for r in runs], eps)
                if numba_engine:
                    out = fused.linear_gaussian_step(s2, F, G, eps, ancestors)
                else:
                    src = s2 if ancestors is None else _gather(s2, ancestors)
                    out = src @ F.T + eps @ G.T
        return out if ancestors is not None else out.reshape(states.shape)

    def _motion_mean(self, states: Array, dt: float, per_run: bool) -> Array:
        if not per_run:
            return np.asarray(self.motion.mean(states, dt), dtype=float)
        n, d = states.shape[-2:]
        s2 = states.reshape(-1, n, d)
        return np.stack([np.asarray(self.motion.mean(s, dt), dtype=float) for s in s2]).reshape(
            states.shape
        )

    def _ancestors(
        self,
        w: Array,
        rows: NDArray[np.intp],
        gens: np.random.Generator | list[np.random.Generator],
    ) -> NDArray[np.intp]:
        """Ancestor indices ``(len(rows), N)`` for the given rows of the weights ``(R, N)``."""
        if isinstance(gens, np.random.Generator):
            sub = w if rows.size == w.shape[0] else w[rows]
            return np.asarray(self._resample(sub, gens), dtype=np.intp)
        if self._resample is resampling.systematic:  # one merge for all runs, same draws
            u0 = np.array([gens[r].random() for r in rows])
            return resampling.systematic_from_uniforms(w[rows], u0)
        return np.stack([np.asarray(self._resample(w[r], gens[r]), dtype=np.intp) for r in rows])

    # ------------------------------------------------------------------------------------------
    # resampling (the regularised filter adds its jitter in _regularize)

    def _maybe_resample(
        self, states: Array, W: _Weights, gens: np.random.Generator | list[np.random.Generator]
    ) -> tuple[Array, _Weights]:
        n, d = states.shape[-2:]
        need = W.ess < self.ess_threshold * n
        if not need.any():
            return states, W
        self.stats.resample_count += 1
        rows = np.flatnonzero(need)
        s2 = states.reshape(-1, n, d)
        new = _gather(s2[rows] if rows.size < s2.shape[0] else s2, self._ancestors(W.w, rows, gens))
        new = self._regularize(s2, W.w, new, rows, gens)
        if rows.size == s2.shape[0]:
            return new.reshape(states.shape), self._uniform(rows.size, n)
        out = s2.copy()
        out[rows] = new
        return out.reshape(states.shape), self._resampled(W, need)

    def _resampled(self, W: _Weights, need: NDArray[np.bool_]) -> _Weights:
        """``W`` with the rows ``need`` (resampled runs) made uniform."""
        if not need.any():
            return W
        rows, n = W.lw.shape
        if need.all():
            return self._uniform(rows, n)
        lw, w, ess = W.lw.copy(), W.w.copy(), W.ess.copy()
        lw[need], w[need], ess[need] = -math.log(n), 1.0 / n, float(n)
        return _Weights(lw, w, ess)

    def _regularize(
        self,
        states: Array,
        w: Array,
        resampled: Array,
        rows: NDArray[np.intp],
        gens: np.random.Generator | list[np.random.Generator],
    ) -> Array:
        """Hook after resampling ``rows`` of ``states`` ``(R, N, d)`` (weights ``w``) into
        ``resampled`` ``(len(rows), N, d)``; the bootstrap filter returns the copies as they are."""
        return resampled

    # ------------------------------------------------------------------------------------------
    # measurements

    def _check_measurements(
        self, measurements: Sequence[Measurement] | Measurement, batch: tuple[int, ...]
    ) -> list[_Checked]:
        """Validate every measurement; keep those with a usable run, as rows ``(R, ...)``."""
        ms = [measurements] if isinstance(measurements, Measurement) else list(measurements)
        runs = math.prod(batch)
        out: list[_Checked] = []
        for m in ms:
            if not isinstance(m, Measurement):
                raise MeasurementError(
                    invalid("measurements", m, "a sequence of fusetrack Measurement")
                )
            raw = self._check_raw_report(m, runs)
            if raw is not None:
                out.append(raw)
                continue
            quick = self._check_one_report(m, runs)
            if quick is not None:
                out.append(quick)
                continue
            v = validate_measurement(m, self._by_id, self.stats)
            lead = v.value.shape[:-1]
            if not _broadcasts(lead, batch) or np.broadcast_shapes(lead, batch) != batch:
                raise MeasurementError(
                    invalid(
                        f"value.shape (sensor {m.sensor_id!r}, time={m.time})",
                        v.value.shape,
                        f"(m,) or batch axes {batch} followed by m (the particles' runs)",
                    )
                )
            usable = np.broadcast_to(v.usable, batch).reshape(runs)
            if not usable.any():
                continue
            mdim = v.value.shape[-1]
            z = np.broadcast_to(v.value, (*batch, mdim)).reshape(runs, mdim)
            cov = None
            if v.covariance is not None:
                clead = v.covariance.shape[:-2]
                if not _broadcasts(clead, batch) or np.broadcast_shapes(clead, batch) != batch:
                    raise MeasurementError(
                        invalid(
                            f"covariance.shape (sensor {m.sensor_id!r}, time={m.time})",
                            v.covariance.shape,
                            f"(m, m) or batch axes {batch} followed by (m, m)",
                        )
                    )
                cov = np.broadcast_to(v.covariance, (*batch, mdim, mdim)).reshape(runs, mdim, mdim)
            if not usable.all():  # fill unusable rows with a usable one: no NaN reaches the models
                first = int(np.argmax(usable))
                z = np.where(usable[:, None], z, z[first])
                if cov is not None:
                    cov = np.where(usable[:, None, None], cov, cov[first])
            out.append(_Checked(v.sensor, z, cov, usable))
        return out

    def _check_raw_report(self, m: Measurement, runs: int) -> _Checked | None:
        """A report for a likelihood-only sensor (one without ``dim``: only ``sensor_id`` and
        ``log_likelihood(value, x)``, e.g. a detection function whose value has no fixed size):
        its value goes to the sensor as given, the same for every run. None for other sensors."""
        sensor = self._by_id.get(m.sensor_id)
        if sensor is None or hasattr(sensor, "dim"):
            return None
        usable = np.ones(runs, dtype=bool)
        return _Checked(sensor, _RawValue(m.value), None, usable)

    def _check_one_report(self, m: Measurement, runs: int) -> _Checked | None:
        """The common case of :meth:`_check_measurements` without its array checks: a known
        sensor, one finite value ``(m,)`` for every run, no covariance. None otherwise (the
        caller then validates in full, raising or counting as it must)."""
        sensor = self._by_id.get(m.sensor_id)
        z = m.value
        if (
            sensor is None
            or m.covariance is not None
            or z.ndim != 1
            or z.shape[0] != sensor.dim
            or not all(math.isfinite(v) for v in z.tolist())
        ):
            return None
        usable = self._everyone.get(runs)
        if usable is None:
            usable = self._everyone[runs] = np.ones(runs, dtype=bool)
            usable.flags.writeable = False
        rows = z.reshape(1, -1) if runs == 1 else np.broadcast_to(z, (runs, z.shape[0]))
        return _Checked(sensor, rows, None, usable)

    def _loglik(self, c: _Checked, states: Array, per_run: bool) -> Array:
        """``log p(z | x_i)`` for every particle, as a writable array of rows ``(R, N)``."""
        n, d = states.shape[-2:]
        s2 = states.reshape(-1, n, d)
        rows = s2.shape[0]
        z, cov = c.z, c.cov
        if isinstance(z, _RawValue):  # a likelihood-only sensor: one value for every run
            ll = np.asarray(c.sensor.log_likelihood(z.value, states), dtype=float)
            return np.array(np.broadcast_to(ll, states.shape[:-1]).reshape(rows, n))
        if per_run:  # the very calls a single run makes, one run at a time
            out = np.empty((rows, n))
            for r in range(rows):
                out[r] = _sensor_loglik(
                    c.sensor, z[r][None, :], None if cov is None else cov[r], s2[r]
                )
            return out
        if rows == 1 or (np.all(z == z[0]) and (cov is None or np.all(cov == cov[0]))):
            ll = _sensor_loglik(c.sensor, z[0][None, :], None if cov is None else cov[0], states)
        else:  # each run its own value: insert the particle axis, z[:, None, :]
            ll = _sensor_loglik(c.sensor, z[:, None, :], cov, s2)
        if ll.size != rows * n:
            return np.array(np.broadcast_to(ll, states.shape[:-1]).reshape(rows, n))
        ll = ll.reshape(rows, n)
        return ll if ll.flags.writeable else ll.copy()

    def _reweight(
        self,
        states: Array,
        W: _Weights,
        checked: list[_Checked],
        rng: Rng | None,
        subtract: list[Array] | None = None,
        fused: bool = True,
    ) -> tuple[_Weights, bool, Array]:
        """Apply the measurements in sequence; ``subtract[k]`` (auxiliary filter) is removed from
        measurement ``k``'s log-likelihood. Returns the new weights, whether any recovered and
        the log normaliser per run ``(R,)`` (the log-likelihood increment, see
        :meth:`update_with_likelihood`).

        Fast path: the log-likelihoods are summed into one buffer and normalised once (one
        ``exp`` per particle however many measurements). Measurement ``k`` cannot be degenerate
        when ``max_i A_k,i - U_{k-1} >= min_log_evidence``, where ``A_k`` is the running sum and
        ``U_{k-1}`` an upper bound of ``logsumexp(A_{k-1})`` (0 for the normalised prior, then
        ``max A + log N``), because the evidence ``logsumexp(A_k) - logsumexp(A_{k-1})`` is at
        least that. If the bound cannot vouch for every measurement of every run, the exact
        sequential update (:meth:`_reweight_exact`) runs instead.
        """
        if subtract is None and fused:
            fast = self._reweight_fused(states, W, checked)
            if fast is not None:
                return fast[0], False, fast[2]
        lls = self._measurement_logliks(states, checked, rng, subtract)
        return self._apply_logliks(W, [c.usable for c in checked], lls)

    def _measurement_logliks(
        self,
        states: Array,
        checked: list[_Checked],
        rng: Rng | None,
        subtract: list[Array] | None = None,
    ) -> list[Array]:
        """``log p(z_k | x_i)`` rows ``(R, N)`` per measurement (minus ``subtract[k]``), 0 in
        the runs that skip it."""
        per_run = rng is not None and not isinstance(rng, np.random.Generator)
        lls = []
        for k, c in enumerate(checked):
            ll = self._loglik(c, states, per_run)
            if subtract is not None:
                with np.errstate(invalid="ignore"):
                    ll = ll - subtract[k]
            if not c.usable.all():
                ll[~c.usable] = 0.0  # a skipped row leaves that run's weights alone
            lls.append(ll)
        return lls

    def _apply_logliks(
        self, W: _Weights, usable: list[NDArray[np.bool_]], lls: list[Array]
    ) -> tuple[_Weights, bool, Array]:
        """Add the log-likelihood rows ``lls`` to ``W`` in sequence and normalise once (the fast
        path of :meth:`_reweight`, which documents the bound), or one at a time
        (:meth:`_reweight_exact`) when the bound cannot vouch for every increment."""
        log_n = math.log(W.lw.shape[-1])
        bound = np.zeros(W.lw.shape[0])
        acc: Array | None = None
        rowmax = bound
        for use, ll in zip(usable, lls):
            acc, rowmax = self._k.add(W.lw if acc is None else acc, ll, out=acc)
            with np.errstate(invalid="ignore"):
                safe = np.isfinite(rowmax) & (rowmax - bound >= self.min_log_evidence)
            if not np.all(safe | ~use):
                return self._reweight_exact(W, usable, lls)
            bound = np.where(use, rowmax + log_n, bound)
        lw, w, lse, ess = self._k.normalize(acc, rowmax, overwrite=True)
        return _Weights(lw, w, ess), False, lse

    def _fused_sensor(self, sensor: SensorModel) -> tuple[int, Array] | None:
        """``(kind, params)`` of the sensor's fused form (engine "numba"), else None."""
        if self.engine != "numba":
            return None
        hit = self._fused_ll.get(id(sensor))
        if hit is not None and hit[0] is sensor:
            return hit[1]
        offer = getattr(sensor, "fused_likelihood", None)
        spec = offer() if callable(offer) else None
        entry = None if spec is None else (fused.KINDS[spec[0]], fused.sensor_params(*spec))
        self._fused_ll[id(sensor)] = (sensor, entry)
        return entry

    def _reweight_fused(
        self, states: Array, W: _Weights, checked: list[_Checked]
    ) -> tuple[_Weights, Array, Array] | None:
        """:meth:`_reweight` in one pass over the particles when every sensor has a fused form
        and no measurement carries its own covariance; None otherwise, or when the degeneracy
        bound cannot vouch for a measurement (the caller then takes the generic path)."""
        key = tuple(id(c.sensor) for c in checked)
        hit = self._fused_sets.get(key)
        if hit is None or any(c.sensor is not s for c, s in zip(checked, hit[0])):
            specs = [self._fused_sensor(c.sensor) for c in checked]
            if any(spec is None for spec in specs):
                hit = (tuple(c.sensor for c in checked), None)
            else:
                kinds = np.array([sp[0] for sp in specs], dtype=np.int64)  # type: ignore[index]
                hit = (tuple(c.sensor for c in checked), (kinds, np.stack([sp[1] for sp in specs])))  # type: ignore[index]
            self._fused_sets[key] = hit
        if hit[1] is None or any(c.cov is not None for c in checked):
            return None
        kinds, params = hit[1]
        rows = W.lw.shape[0]
        n, d = states.shape[-2:]
        s3 = states.reshape(-1, n, d)
        z = np.zeros((rows, len(checked), 3))
        for k, c in enumerate(checked):
            assert isinstance(c.z, np.ndarray)  # a likelihood-only sensor has no fused form
            z[:, k, : c.z.shape[-1]] = c.z
        usable = np.stack([c.usable for c in checked], axis=1)
        lw, w, lse, ess, mean, maxima = fused_update.log_weight_update_rows(
            s3, W.lw, kinds, params, z, usable
        )
        if not self._bound_holds(maxima, usable, n):
            return None
        return _Weights(lw, w, ess), mean, lse

    def _bound_holds(self, maxima: Array, usable: NDArray[np.bool_], n: int) -> bool:
        """The degeneracy bound of :meth:`_reweight` for every measurement ``k`` and run:
        ``maxima[:, k] - U_{k-1} >= min_log_evidence`` (``U_{-1} = 0``, then
        ``U_k = maxima[:, k] + log N`` where measurement ``k`` is usable)."""
        log_n = math.log(n)
        mle = self.min_log_evidence
        if maxima.shape[0] == 1:  # one run: plain floats
            top = 0.0
            for mk, use in zip(maxima[0].tolist(), usable[0].tolist()):
                if use:
                    if not (math.isfinite(mk) and mk - top >= mle):
                        return False
                    top = mk + log_n
            return True
        bound = np.zeros(maxima.shape[0])
        for k in range(maxima.shape[1]):
            rowmax = maxima[:, k]
            with np.errstate(invalid="ignore"):
                safe = np.isfinite(rowmax) & (rowmax - bound >= mle)
            if not np.all(safe | ~usable[:, k]):
                return False
            bound = np.where(usable[:, k], rowmax + log_n, bound)
        return True

    def _reweight_exact(
        self, W: _Weights, usable: list[NDArray[np.bool_]], lls: list[Array]
    ) -> tuple[_Weights, bool, Array]:
        """One measurement at a time, each normalised and checked for degeneracy; the summed
        (untempered) log evidences ``(R,)`` as the third value."""
        degenerate = False
        total = np.zeros(W.lw.shape[0])
        for use, ll in zip(usable, lls):
            lw, w, lse, ess = self._k.update(W.lw, ll)
            total += np.where(use, lse, 0.0)
            ok = np.isfinite(lse) & (lse >= self.min_log_evidence)
            bad = use & ~ok
            keep = ~use
            if bad.any():
                degenerate = True
                keep = keep | bad
                if self.degenerate == "inflate":
                    keep &= ~self._temper(W, ll, bad, lw, w, ess)
            if keep.any():
                lw[keep], w[keep], ess[keep] = W.lw[keep], W.w[keep], W.ess[keep]
            W = _Weights(lw, w, ess)
        return W, degenerate, total

    def _temper(
        self, W: _Weights, ll: Array, bad: NDArray[np.bool_], lw: Array, w: Array, ess: Array
    ) -> NDArray[np.bool_]:
        """Policy ``"inflate"``: temper ``ll`` on the ``bad`` rows, writing recovered rows into
        ``lw, w, ess``; returns the mask of recovered rows."""
        recovered = np.zeros_like(bad)
        rows = np.flatnonzero(bad)
        lw0, ll0 = W.lw[rows], ll[rows]
        # Tempering cannot help a run whose likelihoods are all -inf, or one with +inf.
        finite = np.any(np.isfinite(ll0) & np.isfinite(lw0), axis=-1)
        hope = finite & ~np.any(ll0 == np.inf, axis=-1)
        rows, lw0, ll0 = rows[hope], lw0[hope], ll0[hope]
        beta = 1.0
        while rows.size and beta > _MAX_TEMPER:
            beta *= self.temper_factor
            with np.errstate(invalid="ignore"):
                t_lw, t_w, t_lse, t_ess = self._k.update(lw0, beta * ll0)
            ok = np.isfinite(t_lse) & (t_lse >= self.min_log_evidence)
            if ok.any():
                done = rows[ok]
                lw[done], w[done], ess[done] = t_lw[ok], t_w[ok], t_ess[ok]
                recovered[done] = True
                rows, lw0, ll0 = rows[~ok], lw0[~ok], ll0[~ok]
        return recovered

    def _note_degenerate(self, degenerate: bool) -> None:
        if degenerate:
            self.stats.note_degenerate(
                type(self).__name__,
                "for a measurement: log evidence not finite or below min_log_evidence="
                f"{self.min_log_evidence:.1f}; recovered with degenerate={self.degenerate!r}",
                stacklevel=4,
            )


def _sensor_loglik(sensor: SensorModel, z: Array, cov: Array | None, x: Array) -> Array:
    """``sensor.log_likelihood(z, x)``, or, with a measurement covariance ``(m, m)`` or
    ``(R, m, m)``, the Gaussian log density of ``sensor.residual(z, sensor.predict(x))``."""
    if cov is None:
        return np.asarray(sensor.log_likelihood(z, x), dtype=float)
    r = sensor.residual(z, sensor.predict(x))  # (..., N, m)
    try:
        L = np.linalg.cholesky(cov)
    except np.linalg.LinAlgError:
        raise MeasurementError(
            invalid(
                f"covariance (sensor {sensor.sensor_id!r})",
                cov.tolist(),
                "a positive definite matrix",
            )
        ) from None
    u = r @ np.swapaxes(np.linalg.inv(L), -1, -2)  # L^-1 r for each particle
    logdet = 2.0 * np.log(np.diagonal(L, axis1=-2, axis2=-1)).sum(-1)
    maha = np.einsum("...i,...i->...", u, u)
    return np.asarray(
        -0.5 * (maha + np.asarray(logdet)[..., None] + r.shape[-1] * _LOG_2PI), dtype=float
    )


def _take_rows(values: Array, rows: NDArray[np.intp], idx: NDArray[np.intp]) -> Array:
    """``values`` ``(R, N)`` with ``values[rows[j]]`` replaced by ``values[rows[j], idx[j]]``."""
    if rows.size == values.shape[0]:
        return np.take_along_axis(values, idx, axis=-1)
    out = values.copy()
    out[rows] = np.take_along_axis(values[rows], idx, axis=-1)
    return out


_POOL: ThreadPoolExecutor | None = None


def _fill_normals(gens: list[np.random.Generator], eps: Array) -> None:
    """``eps[j] = gens[j].standard_normal(eps[j].shape)`` for every run ``j``, the runs split
    over a few threads (each generator fills its own rows, so the numbers do not depend on the
    threads; NumPy releases the GIL while it draws)."""
    global _POOL
    fused.passive_threads()  # get_num_threads starts Numba's threading layer
    threads = min(numba.get_num_threads(), len(gens))
    if threads < 2 or eps.size < _THREADED_DRAW_MIN:
        for j, g in enumerate(gens):
            g.standard_normal(out=eps[j])
        return
    if _POOL is None:
        _POOL = ThreadPoolExecutor(max_workers=max(1, (os.cpu_count() or 2) - 1))

    def fill(lo: int, hi: int) -> None:
        for j in range(lo, hi):
            gens[j].standard_normal(out=eps[j])

    bounds = fused.split_bounds(len(gens), threads)
    jobs = [_POOL.submit(fill, lo, hi) for lo, hi in bounds[1:]]
    fill(*bounds[0])
    for job in jobs:
        job.result()


def _broadcasts(a: tuple[int, ...], b: tuple[int, ...]) -> bool:
    try:
        np.broadcast_shapes(a, b)
    except ValueError:
        return False
    return True


class BootstrapFilter(ParticleFilter):
    """The bootstrap (SIR) particle filter: the motion model is the proposal and the
    likelihood the weight (Gordon, Salmond & Smith 1993). Everything is the shared skeleton,
    :class:`ParticleFilter`; see the module docstring for the step, the measurement rules, the
    degeneracy policy and the randomness contract."""


class RegularizedParticleFilter(ParticleFilter):
    """Post-regularised particle filter (Musso, Oudjane & Le Gland 2001).

    After resampling a run, every copy is moved by a draw from the Gaussian kernel,
    ``x_i <- x_i + h D eps_i``, ``eps_i ~ N(0, I)``, where ``D D^T = S`` is the Cholesky factor of
    the weighted covariance ``S`` of the particles before resampling and ``h`` is the optimal
    bandwidth for a Gaussian kernel and a Gaussian density (Musso et al. 2001:
    ``h_opt = A N^(-1/(d+4))``, ``A = (4 / (d + 2))^(1/(d+4))``), i.e.
    ``h_opt = (4 / (N (d + 2)))^(1 / (d + 4))``, times ``bandwidth_scale``. The jitter restores diversity lost to resampling (sample impoverishment
    with little process noise) at the price of a slightly wider posterior. A singular ``S`` uses
    its symmetric square root instead of Cholesky. Everything else is :class:`ParticleFilter`.
    """

    _resamples_every_update = False  # the jitter belongs to its predict-time resampling

    def __init__(self, *args: Any, bandwidth_scale: float = 1.0, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.bandwidth_scale = check_positive("bandwidth_scale", bandwidth_scale, allow_zero=True)

    def bandwidth(self, n: int, d: int) -> float:
        """``bandwidth_scale * (4 / (N (d + 2)))^(1 / (d + 4))``."""
        # Musso, Oudjane & Le Gland 2001, h_opt for the Gaussian kernel
        return self.bandwidth_scale * (4.0 / (n * (d + 2))) ** (1.0 / (d + 4))

    def _regularize(
        self,
        states: Array,
        w: Array,
        resampled: Array,
        rows: NDArray[np.intp],
        gens: np.random.Generator | list[np.random.Generator],
    ) -> Array:
        k, n, d = resampled.shape
        h = self.bandwidth(n, d)
        if h == 0.0:
            return resampled
        sub_s = states if rows.size == states.shape[0] else states[rows]
        sub_w = w if rows.size == w.shape[0] else w[rows]
        _, cov = self._k.mean_cov(sub_s, sub_w)
        D = _sqrt_factor(cov) * h  # (K, d, d)
        if isinstance(gens, np.random.Generator):
            eps = gens.standard_normal((k, n, d))
            resampled += eps @ np.swapaxes(D, -1, -2) if k > 1 else eps[0] @ D[0].T
        else:
            for j, r in enumerate(rows):
                resampled[j] += gens[r].standard_normal((n, d)) @ D[j].T
        return resampled


class AuxiliaryParticleFilter(ParticleFilter):
    """Auxiliary particle filter (Pitt & Shephard 1999), as a predict/update pair.

    ``predict`` draws every particle's child as the bootstrap filter does (so the predicted set is
    a valid prior when no measurement follows) and remembers the parents and ``dt``; it does not
    resample. ``update`` with usable measurements then:

    1. first stage: ``lambda_i ∝ w_i p(z | mu_i)`` with ``mu_i = motion.mean(x_{k-1}^i, dt)``
       (the likelihood of all of the step's measurements at the predicted mean;
       Pitt & Shephard 1999, the auxiliary weights with ``mu = E[x_k | x_{k-1}]``);
    2. resamples ancestors ``a_j ~ lambda`` (in the runs whose first-stage ESS is below
       ``ess_threshold * N``) and draws fresh children ``x_k^j ~ p(. | x_{k-1}^{a_j})`` — this
       second propagation replaces the one ``predict`` made;
    3. second stage: ``w_j ∝ p(z | x_k^j) / p(z | mu_{a_j})``, one measurement at a time with the
       degeneracy rules of :class:`ParticleFilter`.

    A run not resampled keeps its predicted children and ends with ``w_i p(z | x_k^i)``, the
    bootstrap weight. ``update`` without a preceding ``predict`` (or with no usable
    measurement) is the bootstrap update. If the first stage is degenerate for a run (every
    ``p(z | mu_i)`` vanishes), that run selects by its previous weights.
    """

    _resamples_every_update = False  # its update is its own two-stage selection

    def predict(self, particles: Particles, dt: float, rng: Rng | None = None) -> Particles:
        """Draw every child (no resampling) and remember the parents for :meth:`update`."""
        gens = self._generators(rng, particles.batch_shape)
        W = self._weights(particles)
        children = self._sample_motion(particles.states, dt, gens)
        return self._particles(children, W, None, **{_PARENTS: (particles.states, dt)})

    def update_with_likelihood(
        self,
        particles: Particles,
        measurements: Sequence[Measurement] | Measurement,
        rng: Rng | None = None,
    ) -> tuple[Particles, Array]:
        """First-stage selection at the predicted means, fresh children, second-stage weights;
        the log-likelihood increment is the product of the two stages' normalisers,
        ``log sum_i w_i p(z | mu_i) + log sum_j lambda_j p(z | x_j) / p(z | mu_{a_j})``
        (Pitt & Shephard 1999; per run, ``(...)``)."""
        batch = particles.batch_shape
        checked = self._check_measurements(measurements, batch)
        stash = particles.info.get(_PARENTS)
        if not checked:
            return particles, np.zeros(batch)
        W = self._weights(particles)
        if stash is None:
            W2, degenerate, lse = self._reweight(particles.states, W, checked, rng)
            self._note_degenerate(degenerate)
            return self._particles(particles.states, W2), lse.reshape(batch)
        parents, dt = stash
        per_run = rng is not None and not isinstance(rng, np.random.Generator)
        n, d = parents.shape[-2:]
        # 1. first stage at mu_i = f(x_{k-1}^i) (Pitt & Shephard 1999, first-stage weights)
        mu = self._motion_mean(parents, dt, per_run)
        lmu = []
        for c in checked:
            l_k = self._loglik(c, mu, per_run)
            l_k[~c.usable] = 0.0
            lmu.append(l_k)
        total = lmu[0] if len(lmu) == 1 else lmu[0] + lmu[1]
        for l_k in lmu[2:]:
            total += l_k
        lam_lw, lam_w, lse, lam_ess = self._k.update(W.lw, total)
        bad = ~(np.isfinite(lse) & (lse >= self.min_log_evidence))
        degenerate = bool(bad.any())
        if degenerate:  # select by the previous weights; nothing to correct in stage two
            lam_lw[bad], lam_w[bad], lam_ess[bad] = W.lw[bad], W.w[bad], W.ess[bad]
            for l_k in lmu:
                l_k[bad] = 0.0
            lse = np.where(bad, 0.0, lse)
        lam = _Weights(lam_lw, lam_w, lam_ess)
        # 2. resample ancestors by lambda and draw fresh children
        need = lam.ess < self.ess_threshold * n
        children = particles.states
        if need.any():
            gens = self._generators(rng, particles.batch_shape)
            self.stats.resample_count += 1
            rows = np.flatnonzero(need)
            everyone = rows.size == need.size
            p2 = parents.reshape(-1, n, d)
            a = self._ancestors(lam.w, rows, gens)
            fresh = self._sample_motion(_gather(p2 if everyone else p2[rows], a), dt, gens, rows)
            lmu = [_take_rows(l_k, rows, a) for l_k in lmu]
            if everyone:
                children = fresh.reshape(parents.shape)
                lam = self._uniform(rows.size, n)
            else:  # runs not resampled keep their predicted children and first-stage weights
                c2 = particles.states.reshape(-1, n, d).copy()
                c2[rows] = fresh
                children = c2.reshape(parents.shape)
                lw, w, ess = lam.lw.copy(), lam.w.copy(), lam.ess.copy()
                lw[rows], w[rows], ess[rows] = -math.log(n), 1.0 / n, float(n)
                lam = _Weights(lw, w, ess)
        # 3. second stage: p(z | x_k^j) / p(z | mu_{a_j})
        W2, degenerate2, lse2 = self._reweight(children, lam, checked, rng, subtract=lmu)
        self._note_degenerate(degenerate or degenerate2)
        return self._particles(children, W2), (lse + lse2).reshape(batch)
