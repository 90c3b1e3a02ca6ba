"""The thesis's calibration studies (Tables 1–7) as data: each table's run configurations,
the checks of its qualitative findings and its notes.  :mod:`echocal.experiments.scenarios`
runs them (its ``table-1`` … ``table-7`` scenarios) and writes their results."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import pandas as pd

from echocal.experiments import _findings as fnd
from echocal.experiments._findings import Finding
from echocal.experiments._runs import (
    Bench,
    RunConfig,
)

__all__ = [
    "FULL_SEEDS",
    "PARAMETERIZATION",
    "QUICK_SEEDS",
    "RESCALED_MU",
    "TABLE1_STEP_SIZES",
    "THESIS_MU",
    "Study",
    "table_1",
    "table_2",
    "table_3",
    "table_4",
    "table_5",
    "table_6",
    "table_7",
    "thesis_bench",
]

PARAMETERIZATION = "azimuth-coelevation"
"""The thesis's parameterization: every table scenario runs in it."""

THESIS_MU = 0.05
"""The thesis's step size μ (Tables 2, 3, 5, 6, 7) on energy normalized to a peak of ~1."""

TABLE1_STEP_SIZES = (0.05, 0.5, 2.0, 5.0, 20.0)
"""Step sizes μ of ``table-1``: the thesis's 0.05 and multiples ×10, ×40, ×100, ×400.

The thesis does not list its step sizes.  On our setup (energy normalized to ~1,
angles in degrees, main lobe ±8° at half energy) the gradient is ~0.1 per degree
near x0, so μ = 0.05 moves the estimate ~0.005° per iteration: it crawls.  The
multiples span crawling to the largest step that stays stable; μ ≳ 50 jumps out
of the main lobe (measured: final errors of 14–39°)."""

RESCALED_MU = 5.0
"""μ of the "rescaled" groups of tables 2 and 3: 100 × the thesis's 0.05, the largest
``table-1`` value that never diverged in our runs (see :data:`TABLE1_STEP_SIZES`)."""

FULL_SEEDS = 7
QUICK_SEEDS = 2


# ------------------------------------------------------------------ table scenarios
@dataclass(frozen=True)
class Study:
    """The configurations of a table scenario, its checks per group and its notes."""

    configs: list[RunConfig]
    checks: dict[str, list[Callable[[pd.DataFrame, str], Finding]]]
    notes: list[str]


def thesis_bench(seed: int) -> Bench:
    from echocal.setups import load_setup

    setup = load_setup("thesis", seed=seed)
    return Bench(setup, setup.reference_position, PARAMETERIZATION)


def _fmt(v: float) -> str:
    return f"{v:g}"


def table_1(bench: Bench, quick: bool) -> Study:
    group = "step sizes"
    configs = [
        RunConfig(
            group=group,
            label=f"μ = {_fmt(mu)}",
            method="gradient",
            parameter="mu",
            value=mu,
            preset="thesis-table-1",
            options={"mu": mu},
        )
        for mu in TABLE1_STEP_SIZES
    ]
    return Study(
        configs,
        {
            group: [
                lambda s, g: fnd.faster_with_order(
                    s, claim="larger step sizes converge faster", group=g, increasing=True
                ),
                lambda s, g: fnd.reaches_truth(
                    s,
                    claim="with the largest step size the estimate reaches the true solution "
                    "within the 30 iterations",
                    group=g,
                    tol=0.5,
                ),
            ]
        },
        [
            "Step sizes: the thesis's μ = 0.05 and ×10, ×40, ×100, ×400 (the thesis does not "
            "list its values). μ = 0.05 crawls on our energy/degree scale; μ ≳ 50 leaves the "
            "main lobe. See TABLE1_STEP_SIZES.",
            "In (azimuth, co-elevation) the azimuth gradient vanishes at the pole x0 = (0, 0) "
            "and stays small near the optimum (co-elevation 6°), so the azimuth converges slowly.",
        ],
    )


def _momentum_groups() -> list[tuple[str, float]]:
    return [(f"thesis μ = {_fmt(THESIS_MU)}", THESIS_MU), (f"μ = {_fmt(RESCALED_MU)}", RESCALED_MU)]


_ETAS = (0.65, 0.7, 0.8, 0.85)
_MU_NOTE = (
    f"Two groups: the thesis's μ = {_fmt(THESIS_MU)} (Table 2), which crawls on our scale, and "
    f"μ = {_fmt(RESCALED_MU)} (RESCALED_MU, the largest stable table-1 step), where the "
    "momentum dynamics show within 30 iterations."
)


def table_2(bench: Bench, quick: bool) -> Study:
    configs, checks = [], {}
    for group, mu in _momentum_groups():
        for eta in _ETAS:
            configs.append(
                RunConfig(
                    group=group,
                    label=f"momentum {_fmt(eta)}",
                    method="momentum",
                    parameter="momentum",
                    value=eta,
                    preset="thesis-table-2",
                    options={"mu": mu, "momentum": eta},
                )
            )
        checks[group] = [
            lambda s, g: fnd.faster_but_oscillates(
                s, claim="larger momentum converges faster but oscillates", group=g
            )
        ]
    return Study(configs, checks, [_MU_NOTE])


def table_3(bench: Bench, quick: bool) -> Study:
    configs, checks = [], {}
    for group, mu in _momentum_groups():
        for method in ("momentum", "nesterov"):
            for eta in _ETAS:
                configs.append(
                    RunConfig(
                        group=group,
                        label=f"{method} {_fmt(eta)}",
                        method=method,
                        parameter="momentum",
                        value=eta,
                        # each method's own preset (both normalize the energy)
                        preset="thesis-table-3" if method == "nesterov" else "thesis-table-2",
                        options={"mu": mu, "momentum": eta},
                    )
                )
        checks[group] = [
            lambda s, g: fnd.less_oscillation(
                s,
                claim="Nesterov oscillates less than momentum at high momentum",
                group=g,
                high=("0.8", "0.85"),
            )
        ]
    return Study(configs, checks, [_MU_NOTE, "Momentum runs repeated here as the reference."])


def table_4(bench: Bench, quick: bool) -> Study:
    snrs = (30.0, 10.0) if quick else (30.0, 20.0, 10.0, 0.0)
    groups = [
        ("thesis gains (ε = 0.1, c′ = 1)", {}),
        ("Spall-calibrated ε", {"eps": None}),
    ]
    configs, checks = [], {}
    for group, extra in groups:
        for snr in snrs:
            configs.append(
                RunConfig(
                    group=group,
                    label=f"SNR {_fmt(snr)} dB",
                    method="spsa",
                    parameter="snr_db",
                    value=snr,
                    preset="thesis-table-4",
                    options=extra,
                    snr_db=snr,
                )
            )
        checks[group] = [
            lambda s, g: fnd.stable_but_less_accurate(
                s, claim="SPSA stays stable at lower SNR but is less accurate", group=g
            )
        ]
    return Study(
        configs,
        checks,
        [
            "The receiver's noise σ is fixed by the SNR of the reference echo (docs/physics.md).",
            "Second group: ε calibrated by Spall's rule (first step ≈ 0.5°), other gains as "
            "Table 4.",
        ],
    )


_NEWTON_DISTANCES = (2.0, 4.0, 12.0, 20.0, 30.0)
_NEAR_MAX = 6.0


def table_5(bench: Bench, quick: bool) -> Study:
    truth = bench.truth()
    starts = [((0.0, 0.0), "x0 = (0, 0) (thesis)")]
    for d in _NEWTON_DISTANCES:
        # along the meridian through the optimum: the angular distance is exactly d
        starts.append(((float(truth[0]), float(truth[1] + d)), f"{_fmt(d)}° from optimum"))
    configs, checks = [], {}
    for group, mu in ((f"thesis μ = {_fmt(THESIS_MU)}", THESIS_MU), ("full step μ = 1", 1.0)):
        for x0, label in starts:
            configs.append(
                RunConfig(
                    group=group,
                    label=label,
                    method="newton",
                    parameter="x0",
                    value=f"({x0[0]:.1f}, {x0[1]:.1f})",
                    preset="thesis-table-5",
                    options={"mu": mu},
                    x0=x0,
                )
            )
        checks[group] = [
            lambda s, g: fnd.diverges_far(
                s, claim="Newton diverges from far initial guesses", group=g, near_max=_NEAR_MAX
            )
        ]
    return Study(
        configs,
        checks,
        [
            f"Initial guesses: the thesis's (0, 0) (6° from the optimum (−15°, −6°) ≡ (165°, 6°)) "
            f"and points {', '.join(_fmt(d) for d in _NEWTON_DISTANCES)}° away along the "
            f"optimum's meridian; 'near' means ≤ {_fmt(_NEAR_MAX)}°.",
            "Our Newton is damped (Levenberg shift where H is not negative definite) and rejects "
            "downhill steps (docs/physics.md, the thesis's errata), so it stalls rather than "
            "run away.",
        ],
    )


def table_6(bench: Bench, quick: bool) -> Study:
    configs, checks = [], {}
    for group, mu in ((f"thesis μ = {_fmt(THESIS_MU)}", THESIS_MU), ("μ = 1", 1.0)):
        for lam in (0.1, 0.5, 0.8):
            configs.append(
                RunConfig(
                    group=group,
                    label=f"λ = {_fmt(lam)}",
                    method="quasi-newton",
                    parameter="lam",
                    value=lam,
                    preset="thesis-table-6",
                    options={"mu": mu, "lam": lam},
                )
            )
        checks[group] = [
            lambda s, g: fnd.faster_with_order(
                s, claim="smaller scaling factors converge faster", group=g, increasing=False
            )
        ]
    return Study(
        configs,
        checks,
        [
            "B₀ = λ I approximates the Hessian of −f; the first step is μ ĝ / λ (capped at 2°).",
            "Second group: μ = 1 (echocal's default full quasi-Newton step).",
        ],
    )


_THESIS_METHODS = ("gradient", "momentum", "nesterov", "spsa", "newton", "quasi-newton")


def table_7(bench: Bench, quick: bool) -> Study:
    configs, checks = [], {}
    thesis_group = "thesis presets (Table 7)"
    for method in _THESIS_METHODS:
        configs.append(
            RunConfig(
                group=thesis_group,
                label=method,
                method=method,
                parameter="method",
                value=method,
                preset="thesis-table-7",
            )
        )
    for method in ("model-based", "auto"):
        configs.append(
            RunConfig(
                group=thesis_group,
                label=f"{method} (beyond the thesis)",
                method=method,
                parameter="method",
                value=method,
                beyond_thesis=True,
            )
        )
    auto_group = "echocal automatic gains"
    for method in _THESIS_METHODS:
        configs.append(
            RunConfig(
                group=auto_group,
                label=f"{method} (auto gains)",
                method=method,
                parameter="method",
                value=method,
            )
        )

    def spsa_fewest(gains: str) -> Callable[[pd.DataFrame, str], Finding]:
        return lambda s, g: fnd.fewest_measurements(
            s,
            claim="SPSA needs the fewest measurements among the thesis methods",
            group=g,
            method="spsa",
            gains=gains,
        )

    checks[thesis_group] = [spsa_fewest("the thesis's gains")]
    checks[auto_group] = [spsa_fewest("automatic gains")]
    return Study(
        configs,
        checks,
        [
            "Thesis presets: μ = 0.05, momentum 0.7, λ = 0.9, SPSA ε = 0.1, c′ = 1, A = 5 on "
            "energy normalized to ~1 (calibrate/presets.py).",
            "'model-based' and 'auto' are echocal's own methods — beyond the thesis.",
            "Second group: the six thesis methods with echocal's automatic gain calibration "
            "(no preset): first step ≈ 0.5° whatever the energy unit.",
            "Measurements per iteration: 4 for the FD gradient methods and quasi-Newton, 2 for "
            "SPSA, 9 for Newton.",
        ],
    )
