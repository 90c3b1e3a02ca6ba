"""The peer optimizers of the calibration benchmark (``bench_calibration.py``).

Each peer is a function ``peer(tr, x0, box, seed)`` that minimizes ``tr`` (a
:class:`_Tracker`: −metric through the benchmark's
:class:`~echocal.measurement.SourceObjective`, which counts the measurements and enforces
the budget) from ``x0`` [deg], the bounded ones inside ``box`` [deg] (2, 2), seeded by
``seed``.  Their settings, and why, are in ``bench_calibration.py``'s docstring (the report
quotes it).  Every peer's package is optional: :func:`available_peers` skips one that does
not import.

Not a package (no ``__init__.py``): ``bench_calibration.py`` imports it from its own
directory, as it does ``_common``.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from echocal.errors import BudgetExhaustedError
from echocal.measurement import SourceObjective

PEERS = (
    "scipy-nelder-mead",
    "py-bobyqa",
    "skopt-gp",
    "nevergrad-ngopt",
    "cma-es",
    "botorch-qlognei",
)
"""The peers of a default run, each run when it imports (``available_peers``)."""
GP_REFIT_EVERY = 5
"""The GP peer fits its hyperparameters by maximum likelihood (with restarts) at every this
many-th model update and keeps them in between (see ``bench_calibration.py``'s docstring)."""
GP_N_POINTS = 2000
"""Candidates sampled per step at which the GP peer evaluates its acquisition functions."""
CMA_SIGMA0 = 1.0
"""[deg] CMA-ES's initial step size σ₀ (as Nelder–Mead's simplex and BOBYQA's rhobeg)."""
BOTORCH_N_SOBOL = 10
"""The BoTorch peer's initial design: x0, then this many scrambled Sobol points in the box."""
BOTORCH_RESTARTS = 4
"""Gradient-based restarts of ``optimize_acqf`` per acquisition step."""
BOTORCH_RAW_SAMPLES = 128
"""Sobol points at which ``optimize_acqf`` evaluates the acquisition to pick the restarts."""
BOTORCH_MC_SAMPLES = 128
"""Quasi-Monte-Carlo posterior samples of qLogNEI."""
_PEER_MODULES = {
    "scipy-nelder-mead": "scipy.optimize",
    "py-bobyqa": "pybobyqa",
    "skopt-gp": "skopt",
    "nevergrad-ngopt": "nevergrad",
    "cma-es": "cma",
    "botorch-qlognei": "botorch",
}
INSTALL_HINT = {
    "botorch-qlognei": "pip install botorch (with a CPU-only torch: bench_calibration's docstring)"
}
"""How to install a peer that is not in echocal's ``bench`` extra."""


class _Stop(Exception):
    """Raised inside a peer's objective when the budget is spent."""


class _Tracker:
    """−metric for a minimizing peer, through the SourceObjective; keeps best-so-far."""

    def __init__(self, objective: SourceObjective) -> None:
        self.objective = objective
        self.best_x: np.ndarray | None = None
        self.best_f = np.inf
        self.history: list[np.ndarray] = []  # estimate after each measurement
        # a peer with its own recommendation sets this list: its estimate after each measurement
        self.history_override: list[np.ndarray] | None = None

    @property
    def budget(self) -> int:
        """Measurements the peer may make: the objective's budget."""
        assert self.objective.budget is not None
        return self.objective.budget

    def __call__(self, x: Any) -> float:
        x = np.asarray(x, dtype=float).reshape(2)
        try:
            value = float(self.objective(x[None, :])[0])
        except BudgetExhaustedError:
            raise _Stop from None
        f = -value if np.isfinite(value) else np.inf
        if f < self.best_f or self.best_x is None:
            self.best_f, self.best_x = f, x.copy()
        self.history.append(self.best_x.copy())
        return f


def _box(x0: np.ndarray, half: float, bounds: np.ndarray) -> np.ndarray:
    """[deg] (2, 2): the box x0 ± ``half`` clipped to ``bounds``, where the bounded peers
    search."""
    return np.stack(
        [np.maximum(x0 - half, bounds[:, 0]), np.minimum(x0 + half, bounds[:, 1])], axis=1
    )


def _peer_nelder_mead(tr: _Tracker, x0: np.ndarray, box: np.ndarray, seed: int) -> None:
    from scipy.optimize import minimize

    simplex = x0 + np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    minimize(
        tr,
        x0,
        method="Nelder-Mead",
        bounds=tr.objective.bounds,
        options={"initial_simplex": simplex, "maxfev": tr.budget, "xatol": 1e-4, "fatol": 0.0},
    )


def _peer_bobyqa(tr: _Tracker, x0: np.ndarray, box: np.ndarray, seed: int) -> None:
    import pybobyqa

    np.random.seed(seed % 2**32)  # noqa: NPY002 - Py-BOBYQA draws from the global stream
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        pybobyqa.solve(
            tr,
            x0,
            bounds=(box[:, 0], box[:, 1]),
            maxfun=tr.budget,
            rhobeg=1.0,
            rhoend=1e-3,
            objfun_has_noise=True,
            seek_global_minimum=False,
            scaling_within_bounds=False,
        )


def _peer_skopt(tr: _Tracker, x0: np.ndarray, box: np.ndarray, seed: int) -> None:
    """gp_minimize(noise="gaussian", x0=[x0], n_initial_points=10, acq_optimizer="sampling")
    as an ask/tell loop whose GP refits its hyperparameters every GP_REFIT_EVERY-th update."""
    from sklearn.base import clone
    from sklearn.utils import check_random_state
    from skopt import Optimizer
    from skopt.learning.gaussian_process.kernels import WhiteKernel
    from skopt.utils import cook_estimator, normalize_dimensions

    rng = check_random_state(seed % 2**31)  # the stream gp_minimize draws from
    space = normalize_dimensions([tuple(box[0]), tuple(box[1])])
    gp = cook_estimator(
        "GP", space=space, noise="gaussian", random_state=rng.randint(0, np.iinfo(np.int32).max)
    )
    n_initial = 1 + 10  # x0, then 10 random points
    opt = Optimizer(
        space,
        clone(gp),
        n_initial_points=n_initial,
        acq_func="gp_hedge",
        acq_optimizer="sampling",
        acq_optimizer_kwargs={"n_points": GP_N_POINTS},
        random_state=rng,
    )
    x = list(x0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for i in range(tr.budget):
            y = tr(x)
            if i == tr.budget - 1:
                return  # no model needed after the last measurement
            update = i + 1 - n_initial  # this tell's model update (< 0: none yet)
            if update > 0 and update % GP_REFIT_EVERY:
                # hold the last fitted hyperparameters; skopt zeroes the fitted white-noise
                # term for prediction and keeps its level in noise_, so put it back
                last = opt.models[-1]
                kernel = last.kernel_.k1 + WhiteKernel(noise_level=max(last.noise_, 1e-5))
                opt.base_estimator_ = clone(gp).set_params(kernel=kernel, optimizer=None)
            else:
                opt.base_estimator_ = clone(gp)  # maximum likelihood, 2 restarts
            opt.tell(x, y)
            x = opt.ask()


def _peer_nevergrad(tr: _Tracker, x0: np.ndarray, box: np.ndarray, seed: int) -> None:
    import nevergrad as ng

    param = ng.p.Array(init=x0).set_bounds(box[:, 0], box[:, 1]).set_mutation(sigma=1.0)
    param.random_state = np.random.RandomState(seed % 2**32)
    param.function.deterministic = False  # noisy: NGOpt picks a noise-robust optimizer
    opt = ng.optimizers.NGOpt(parametrization=param, budget=tr.budget, num_workers=1)
    recommended: list[np.ndarray] = []  # nevergrad's own recommendation after each tell
    tr.history_override = recommended
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for _ in range(tr.budget):
            cand = opt.ask()
            try:
                f = tr(cand.value)
            except _Stop:
                return
            opt.tell(cand, f)
            recommended.append(np.asarray(opt.provide_recommendation().value, float))


def _peer_cma(tr: _Tracker, x0: np.ndarray, box: np.ndarray, seed: int) -> None:
    """pycma's CMA-ES (default population, 6 in 2-D) from x0 with σ₀ = :data:`CMA_SIGMA0`
    inside ``box``; the estimate is the distribution's mean (``xfavorite``, pycma's
    recommendation on a noisy function) after each completed generation, x0 before."""
    import cma

    opts = {
        "bounds": [list(box[:, 0]), list(box[:, 1])],
        "seed": seed % (2**32 - 1) + 1,  # pycma draws a random seed for 0
        "maxfevals": tr.budget,
        "verbose": -9,
    }
    recommended: list[np.ndarray] = []
    tr.history_override = recommended
    estimate = np.asarray(x0, dtype=float)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        es = cma.CMAEvolutionStrategy(list(x0), CMA_SIGMA0, opts)
        while not es.stop():
            xs = es.ask()
            fs = []
            for x in xs:
                f = tr(x)  # _Stop when the budget is spent
                fs.append(f if np.isfinite(f) else 0.0)  # no value: no echo (-metric <= 0)
                recommended.append(estimate.copy())
            es.tell(xs, fs)
            estimate = np.asarray(es.result.xfavorite, dtype=float)
            recommended[-1] = estimate.copy()  # the generation's mean, once it is told


def _peer_botorch(tr: _Tracker, x0: np.ndarray, box: np.ndarray, seed: int) -> None:
    """Noisy-EI Bayesian optimization with BoTorch, maximizing the metric: a SingleTaskGP
    (inferred homoskedastic noise, inputs normalized to the box, outcomes standardized)
    refitted after every measurement, qLogNoisyExpectedImprovement; the estimate is the
    measured point of highest posterior mean."""
    import torch
    from botorch.acquisition.logei import qLogNoisyExpectedImprovement
    from botorch.exceptions.errors import ModelFittingError
    from botorch.fit import fit_gpytorch_mll
    from botorch.models import SingleTaskGP
    from botorch.models.transforms import Normalize, Standardize
    from botorch.optim import optimize_acqf
    from botorch.sampling import SobolQMCNormalSampler
    from botorch.utils.sampling import draw_sobol_samples, manual_seed
    from gpytorch.mlls import ExactMarginalLogLikelihood

    torch.set_num_threads(1)  # one core per benchmark worker
    dtype = torch.float64  # BoTorch's advice: GP fits in single precision are fragile
    bounds = torch.as_tensor(box.T, dtype=dtype)  # (2, d): lower row, upper row
    design = [
        torch.as_tensor(x0, dtype=dtype),
        *draw_sobol_samples(bounds, n=BOTORCH_N_SOBOL, q=1, seed=seed).squeeze(1),
    ]
    xs: list[Any] = []  # the measured points with a finite metric (tensors (d,))
    ys: list[float] = []  # their metric values, maximized (the tracker returns −metric)
    recommended: list[np.ndarray] = []  # the estimate after each measurement
    tr.history_override = recommended
    model = None
    with manual_seed(seed), warnings.catch_warnings():
        warnings.simplefilter("ignore")  # BoTorch's input-scaling and numerical warnings
        x = design[0]
        for i in range(tr.budget):
            f = tr(x.numpy())
            if np.isfinite(f):
                xs.append(x)
                ys.append(-f)
            previous, model = model, None
            if len(xs) >= 2:
                train_x = torch.stack(xs)
                model = SingleTaskGP(
                    train_x,
                    torch.tensor(ys, dtype=dtype).unsqueeze(-1),
                    input_transform=Normalize(d=train_x.shape[-1], bounds=bounds),
                    outcome_transform=Standardize(m=1),
                )
                if previous is not None:  # warm start: the last fit's hyperparameters
                    for part in ("likelihood", "mean_module", "covar_module"):
                        getattr(model, part).load_state_dict(getattr(previous, part).state_dict())
                try:
                    fit_gpytorch_mll(ExactMarginalLogLikelihood(model.likelihood, model))
                except ModelFittingError:
                    model.eval()  # every attempt failed: the starting hyperparameters
                with torch.no_grad():
                    best = int(model.posterior(train_x).mean.squeeze(-1).argmax())
                recommended.append(xs[best].numpy().copy())
            else:  # nothing to model: the one point measured, or x0
                recommended.append((xs[0] if xs else design[0]).numpy().copy())
            if i + 1 == tr.budget:
                return
            if i + 1 < len(design) or model is None:
                x = design[(i + 1) % len(design)]  # (again while nothing finite to model)
                continue
            acqf = qLogNoisyExpectedImprovement(
                model,
                X_baseline=train_x,
                sampler=SobolQMCNormalSampler(sample_shape=torch.Size([BOTORCH_MC_SAMPLES])),
                prune_baseline=True,
            )
            candidate, _ = optimize_acqf(
                acqf,
                bounds=bounds,
                q=1,
                num_restarts=BOTORCH_RESTARTS,
                raw_samples=BOTORCH_RAW_SAMPLES,
            )
            x = candidate.detach().squeeze(0)


_PEER_FUNCS: dict[str, Callable[..., None]] = {
    "scipy-nelder-mead": _peer_nelder_mead,
    "py-bobyqa": _peer_bobyqa,
    "skopt-gp": _peer_skopt,
    "nevergrad-ngopt": _peer_nevergrad,
    "cma-es": _peer_cma,
    "botorch-qlognei": _peer_botorch,
}


def available_peers(names: list[str]) -> tuple[list[str], dict[str, str]]:
    """The peers that import, and a reason for each skipped one."""
    ok, skipped = [], {}
    for name in names:
        try:
            __import__(_PEER_MODULES[name])
            ok.append(name)
        except Exception as exc:  # a broken install is a skip, not a crash
            skipped[name] = f"{type(exc).__name__}: {exc}"
    return ok, skipped
