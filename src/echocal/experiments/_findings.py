"""The thesis's qualitative findings as measurable criteria (private).

Each check reads the per-configuration medians of :func:`~._runs.summarize_configs`
and returns a :class:`Finding`: the claim, the criterion, whether our runs
agree, and one sentence of evidence with the numbers.

Speed is judged by the *convergence key* (median iterations until the estimate
reaches and keeps 90 % of the optimal pseudo-energy; ties — typically "never" —
broken by the median final angular error), oscillation by the median number of
reversals of the error trend larger than 0.2°.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import pandas as pd

__all__ = ["Finding"]


@dataclass(frozen=True)
class Finding:
    """One qualitative thesis claim tested on our runs.

    claim : the thesis's statement; criterion : how we measure it;
    agrees : whether our runs agree; evidence : one sentence with the numbers;
    group : the sub-study (e.g. "thesis gains") it was tested on;
    why : where our runs do not agree, the reason in plain words, read from the same
        numbers ("" when they agree or no reason can be read from them).
    """

    claim: str
    criterion: str
    agrees: bool
    evidence: str
    group: str = ""
    why: str = ""

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready dict."""
        return asdict(self)


def fmt_iter(value: float) -> str:
    """A median iteration/measurement count; inf → 'never'."""
    return "never" if not math.isfinite(value) else f"{value:g}"


def _key(row: pd.Series) -> tuple[float, float]:
    return (float(row["iterations_to_90pct"]), float(row["final_error_deg"]))


def _describe(row: pd.Series) -> str:
    k = row["iterations_to_90pct"]
    reached = f"90 % after {k:g} it." if math.isfinite(k) else "90 % never reached"
    return f"{row['label']}: {reached}, final error {row['final_error_deg']:.2f}°"


SPEED = (
    "median iterations to reach and keep 90 % of the optimal pseudo-energy (ties, e.g. "
    "'never', broken by the median final angular error)"
)


def faster_with_order(
    summary: pd.DataFrame, *, claim: str, group: str, increasing: bool
) -> Finding:
    """Speed improves monotonically along the rows (``increasing``: later rows faster)."""
    rows = [r for _, r in summary.iterrows()]
    keys = [_key(r) for r in rows]
    if not increasing:
        keys = keys[::-1]
    monotone = all(a >= b for a, b in itertools.pairwise(keys))
    strict = keys[-1] < keys[0]
    direction = "larger" if increasing else "smaller"
    return Finding(
        claim=claim,
        criterion=f"{SPEED}: no slower for each {direction} value, and strictly faster at the "
        "extreme than at the other end",
        agrees=bool(monotone and strict),
        evidence="; ".join(_describe(r) for r in rows) + ".",
        group=group,
    )


def faster_but_oscillates(summary: pd.DataFrame, *, claim: str, group: str) -> Finding:
    """Largest value (last row) faster AND more oscillatory than the smallest (first row)."""
    lo, hi = summary.iloc[0], summary.iloc[-1]
    faster = _key(hi) < _key(lo)
    oscillates = hi["oscillations"] > lo["oscillations"] and hi["oscillations"] > 0
    return Finding(
        claim=claim,
        criterion=f"{SPEED} lower at the largest value than at the smallest, AND median "
        "oscillations (error-trend reversals > 0.2°) higher and non-zero at the largest value",
        agrees=bool(faster and oscillates),
        evidence=(
            f"{_describe(lo)}, {lo['oscillations']:g} oscillations; "
            f"{_describe(hi)}, {hi['oscillations']:g} oscillations "
            f"(faster: {'yes' if faster else 'no'}, oscillates more: "
            f"{'yes' if oscillates else 'no'})."
        ),
        group=group,
    )


def less_oscillation(
    summary: pd.DataFrame, *, claim: str, group: str, high: tuple[str, ...]
) -> Finding:
    """Summed median oscillations at the high momentum values: Nesterov < momentum."""
    sub = summary[summary["value"].isin(high)]
    mom = sub[sub["method"] == "momentum"]["oscillations"].sum()
    nes = sub[sub["method"] == "nesterov"]["oscillations"].sum()
    detail = ", ".join(
        f"{r['method']} η={r['value']}: {r['oscillations']:g} osc., "
        f"final {r['final_error_deg']:.2f}°"
        for _, r in sub.iterrows()
    )
    return Finding(
        claim=claim,
        criterion="sum over momentum η ∈ {"
        + ", ".join(high)
        + "} of the median oscillations (error-trend reversals > 0.2°): Nesterov < momentum",
        agrees=bool(nes < mom),
        evidence=f"Nesterov {nes:g} vs momentum {mom:g} ({detail}).",
        group=group,
    )


def stable_but_less_accurate(summary: pd.DataFrame, *, claim: str, group: str) -> Finding:
    """Rows ordered by decreasing SNR: no median divergence, lowest SNR less accurate."""
    stable = bool((summary["diverged_fraction"] <= 0.5).all())
    hi, lo = summary.iloc[0], summary.iloc[-1]
    less = lo["final_error_deg"] > hi["final_error_deg"]
    detail = "; ".join(
        f"{r['snr_db']:g} dB: final {r['final_error_deg']:.2f}° "
        f"(IQR {r['final_error_iqr_deg']:.2f}°), "
        f"diverged {100 * r['diverged_fraction']:.0f} %"
        for _, r in summary.iterrows()
    )
    return Finding(
        claim=claim,
        criterion="stable: at every SNR at most half the runs end farther from the optimum than "
        "they started; less accurate: median final error at the lowest SNR > at the highest",
        agrees=bool(stable and less),
        evidence=f"{detail} (stable: {'yes' if stable else 'no'}, less accurate: "
        f"{'yes' if less else 'no'}).",
        group=group,
    )


def diverges_far(summary: pd.DataFrame, *, claim: str, group: str, near_max: float) -> Finding:
    """Initial guesses within ``near_max`` [deg] converge; all farther ones do not."""
    is_near = summary["initial_error_deg"] <= near_max + 1e-6  # x0 (0, 0) is 6° ± 1e-12 away
    near, far = summary[is_near], summary[~is_near]
    near_ok = bool((near["converged_fraction"] >= 0.5).all())
    far_fail = bool((far["converged_fraction"] < 0.5).all()) and len(far) > 0
    detail = "; ".join(
        f"x0 {r['initial_error_deg']:.0f}° away → final {r['final_error_deg']:.2f}° "
        f"(converged {100 * r['converged_fraction']:.0f} %, diverged "
        f"{100 * r['diverged_fraction']:.0f} %)"
        for _, r in summary.iterrows()
    )
    return Finding(
        claim=claim,
        criterion=f"initial guesses ≤ {near_max:g}° from the optimum converge (≥ half the seeds "
        f"reach 90 % of the optimal pseudo-energy) and every guess farther away does not",
        agrees=bool(near_ok and far_fail),
        evidence=f"{detail}.",
        group=group,
    )


def fewest_measurements(
    summary: pd.DataFrame, *, claim: str, group: str, method: str, gains: str = "these gains"
) -> Finding:
    """``method`` has the fewest median measurements to 90 % among the thesis methods.

    gains : how the group's gains are named in the explanation (e.g. "the thesis's gains").
    """
    thesis = summary[~summary["beyond_thesis"]]
    best = thesis["measurements_to_90pct"].min()
    own = float(thesis[thesis["method"] == method]["measurements_to_90pct"].iloc[0])
    ok = math.isfinite(own) and own <= best
    detail = ", ".join(
        f"{r['label']} {fmt_iter(r['measurements_to_90pct'])}" for _, r in thesis.iterrows()
    )
    return Finding(
        claim=claim,
        criterion="median measurements until the estimate reaches and keeps 90 % of the optimal "
        f"pseudo-energy: {method} lowest among the six thesis methods (and finite)",
        agrees=bool(ok),
        evidence=f"measurements to 90 %: {detail}.",
        group=group,
        why="" if ok else _why_not_fewest(summary, method, gains),
    )


def _why_not_fewest(summary: pd.DataFrame, method: str, gains: str) -> str:
    """Plain words: why ``method`` is not the cheapest to 90 % (read from ``summary``'s rows)."""
    thesis = summary[~summary["beyond_thesis"]]
    reached = thesis[np.isfinite(thesis["measurements_to_90pct"].astype(float))]
    if reached.empty:
        return _why_stalled(thesis, gains) + _beyond(summary[summary["beyond_thesis"]])
    own = thesis[thesis["method"] == method].iloc[0]
    fastest = reached.loc[reached["measurements_to_90pct"].astype(float).idxmin()]
    if not math.isfinite(own["measurements_to_90pct"]):
        return (
            f"With {gains}, {own['label']} never reached 90 % of the optimal echo energy (median "
            f"final error {own['final_error_deg']:.1f}°), while {fastest['label']} did after "
            f"{fastest['measurements_to_90pct']:g} measurements."
        )
    ratio = own["iterations_to_90pct"] / fastest["iterations_to_90pct"]
    cause = (
        f"{own['label']} spends fewer measurements per iteration than a finite-difference "
        "gradient (2 instead of 4: in two angles it can save at most half), but it estimates "
        "the gradient along only one random direction per iteration, so its steps are less "
        "direct: it"
        if method == "spsa"
        else own["label"]
    )
    return (
        f"{cause} needed {own['iterations_to_90pct']:g} iterations "
        f"({own['measurements_to_90pct']:g} measurements) to reach 90 % of the optimal echo "
        f"energy, {ratio:.1f}× the "
        f"{fastest['iterations_to_90pct']:g} iterations ({fastest['measurements_to_90pct']:g} "
        f"measurements) of {fastest['label']}."
    )


def _why_stalled(rows: pd.DataFrame, gains: str) -> str:
    """Plain words for 'no configuration reached 90 %': how little the estimates moved."""
    start = float(rows["initial_error_deg"].median())
    ends = rows["final_error_deg"].astype(float)
    near, far = rows.loc[ends.idxmin()], rows.loc[ends.idxmax()]
    budget = float(rows["n_measurements"].max())
    return (
        f"None of the {len(rows)} thesis methods reached 90 % of the optimal echo energy, so "
        f"none can be called the fastest: with {gains} the estimates move too little per "
        f"iteration on this setup. Starting "
        f"{start:.1f}° from the optimum, the median runs ended between "
        f"{near['final_error_deg']:.1f}° ({near['label']}) and {far['final_error_deg']:.1f}° "
        f"({far['label']}) from it, after up to {budget:g} measurements."
    )


def _beyond(rows: pd.DataFrame) -> str:
    """' On the same runs, X reached 90 % after N measurements.' for the best such row."""
    m = rows["measurements_to_90pct"].astype(float) if len(rows) else pd.Series(dtype=float)
    if not np.isfinite(m).any():
        return ""
    best = rows.loc[m.idxmin()]
    return (
        f" On the same setup and starts, {best['label']} reached it after "
        f"{best['measurements_to_90pct']:g} measurements."
    )


def reaches_truth(summary: pd.DataFrame, *, claim: str, group: str, tol: float) -> Finding:
    """The last row (largest value) ends within ``tol`` [deg] of the optimum (median)."""
    row = summary.iloc[-1]
    return Finding(
        claim=claim,
        criterion=f"median final angular error of the largest value < {tol:g}°",
        agrees=bool(row["final_error_deg"] < tol),
        evidence=f"{row['label']}: median final error {row['final_error_deg']:.2f}° "
        f"(measurements to {tol:g}°: {fmt_iter(row['measurements_to_0.5deg'])}).",
        group=group,
    )
