"""The log posterior of a fit: priors + a Gaussian likelihood around the forward model.

    log p(theta | y) = sum_j log prior_j(theta_j)
                       - 1/2 sum_i [ (y_i - m_i(theta))^2 / (s sigma_i)^2 + 2 log(s sigma_i) + log 2 pi ]

with s the noise scale (fixed at 1 unless given a prior). Deterministic and smooth in
theta (the forward model has no Monte Carlo in it); vectorised over parameter sets, which
is how emcee calls it (``vectorize=True``). The forward model is the smooth C++ one or the
full model through the adding-doubling solver (``[model] kind``, bsdflab.fit.full_forward).
"""
from __future__ import annotations

import abc
import copy

import numpy as np

from bsdflab.fit.config import FitConfig
from bsdflab.fit.data import Dataset
from bsdflab.fit.full_forward import forward_model
from bsdflab.fit.parameters import ALL_NAMES

_LOG_2PI = float(np.log(2.0 * np.pi))


class GaussianPosterior(abc.ABC):
    """Priors + the Gaussian likelihood above, vectorised over parameter sets. A subclass
    sets ``free``, ``config`` (its ``priors``), ``dataset``, ``_base`` (every parameter's
    fixed value, NaN where free), ``_free_cols``, ``_noise_col`` and ``evaluations``, and
    gives the model's values for full parameter rows (``_model_values``)."""

    # the row columns with_data compares (a specular-only posterior has no angle_out/phi)
    ROW_KEYS = ("geometry", "angle_deg", "angle_out_deg", "phi_deg", "wavelength_nm")

    @property
    def ndim(self) -> int:
        return len(self.free)

    def with_data(self, dataset: Dataset) -> GaussianPosterior:
        """The same posterior (priors, forward model: an emulator is shared) for other values
        at the same rows (simulation-based calibration, repeated measurements)."""
        same = len(dataset) == len(self.dataset) and all(
            np.array_equal(getattr(dataset, k), getattr(self.dataset, k), equal_nan=True)
            for k in self.ROW_KEYS)
        if not same:
            raise ValueError("with_data needs a dataset with the same rows (geometry, angles, wavelengths)")
        new = copy.copy(self)
        new.dataset, new.evaluations = dataset, 0
        return new

    def sample_prior(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """n draws (n, ndim) from the priors."""
        return np.column_stack([self.config.priors[name].dist.rvs(size=n, random_state=rng)
                                for name in self.free])

    def full(self, x) -> np.ndarray:
        """All parameters (P, all names) from free values (P, ndim)."""
        x = np.atleast_2d(np.asarray(x, float))
        out = np.repeat(self._base[None, :], len(x), axis=0)
        out[:, self._free_cols] = x
        return out

    @abc.abstractmethod
    def _model_values(self, full: np.ndarray) -> np.ndarray:
        """The forward model's values (P, rows) for full parameter rows (P, all names)."""

    def predict(self, x) -> np.ndarray:
        """Model values (P, rows) for free values (P, ndim)."""
        return self._model_values(self.full(x))

    def log_prior(self, x) -> np.ndarray:
        x = np.atleast_2d(np.asarray(x, float))
        lp = np.zeros(len(x))
        for j, name in enumerate(self.free):
            lp += self.config.priors[name].logpdf(x[:, j])
        return lp

    def pointwise_log_likelihood(self, x) -> np.ndarray:
        """log likelihood of every row, (P, rows) (PSIS-LOO needs it per observation)."""
        full = self.full(x)
        m = self._model_values(full)
        self.evaluations += len(full)
        s = full[:, self._noise_col:self._noise_col + 1] * self.dataset.sigma[None, :]
        r = (self.dataset.reflectance[None, :] - m) / s
        return -0.5 * (r * r + 2.0 * np.log(s) + _LOG_2PI)

    def log_likelihood(self, x) -> np.ndarray:
        ll = np.sum(self.pointwise_log_likelihood(x), axis=1)
        return np.where(np.isfinite(ll), ll, -np.inf)

    def __call__(self, x) -> np.ndarray:
        """log posterior of free values (P, ndim) -> (P,); -inf outside the support."""
        x = np.atleast_2d(np.asarray(x, float))
        lp = self.log_prior(x)
        out = np.full(len(x), -np.inf)
        ok = np.isfinite(lp)
        if np.any(ok):
            out[ok] = lp[ok] + self.log_likelihood(x[ok])
        return out


class LogPosterior(GaussianPosterior):
    def __init__(self, dataset: Dataset, config: FitConfig):
        self.dataset, self.config = dataset, config
        self.free = config.free
        # parameters the model does not use stay NaN
        base = np.array([config.fixed.get(n, np.nan) for n in ALL_NAMES])
        solver_free = [n for n in self.free if n != "noise_scale"]
        if config.model.kind == "full" and config.model.emulator_nodes and solver_free:
            from bsdflab.fit.emulator import EmulatedForward, prior_box

            boxes = {n: prior_box(n, config.priors[n]) for n in solver_free}
            self.model = EmulatedForward(dataset, config.model, base, boxes, config.model.emulator_checks,
                                         config.sampler.seed)
        else:
            self.model = forward_model(dataset, config.model)
        self._base = base
        self._free_cols = np.array([ALL_NAMES.index(n) for n in self.free])
        self._noise_col = ALL_NAMES.index("noise_scale")
        self.evaluations = 0

    def _model_values(self, full: np.ndarray) -> np.ndarray:
        return self.model.evaluate(full)

