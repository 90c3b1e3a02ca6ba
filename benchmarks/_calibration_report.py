"""The calibration benchmark's report: per-method tables, winners, the best method per
cell, the Markdown page and the figure, from a run's data (:mod:`bench_calibration`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from _calibration_cases import BUDGET, CASES, FRONT_FIRST, OURS, STARTS
from _common import markdown_table
from _peers import PEERS

from echocal.plots import save_figure
from echocal.plots._style import MARKERS


def _fmt_n(v: float) -> str:
    return f">{BUDGET}" if not np.isfinite(v) else f"{v:g}"


def _bench_cells(s: dict[str, Any]) -> list[str]:
    """The bench-time columns of a method's row: median to 0.1° (inf: most runs never got
    there) and over the whole budget [s]."""
    return [f"{s['median_bench_to_0.1']:.1f}", f"{s['median_bench_time']:.1f}"]


def case_table(summary: dict[str, dict[str, Any]]) -> str:
    header = [
        "method",
        "runs",
        "ok 0.05°",
        "ok 0.1°",
        "n to 0.05° med / p90",
        "n to 0.1° med / p90",
        "≤0.1° at 20 / 40 / 80",
        "median error [°] at 20 / 40 / 80",
    ]
    timed = all("median_bench_to_0.1" in s for s in summary.values())
    if timed:  # a bench: what the runs cost in bench time
        header += ["bench time to 0.1° med [s]", "bench time at 80 med [s]"]
    order = sorted(summary, key=lambda m: (summary[m]["median_n_0.1"], -summary[m]["success_0.1"]))
    rows = []
    for m in order:
        s = summary[m]
        rows.append(
            [
                m,
                s["runs"],
                f"{100 * s['success_0.05']:.0f} %",
                f"{100 * s['success_0.1']:.0f} %",
                f"{_fmt_n(s['median_n_0.05'])} / {_fmt_n(s['p90_n_0.05'])}",
                f"{_fmt_n(s['median_n_0.1'])} / {_fmt_n(s['p90_n_0.1'])}",
                " / ".join(f"{100 * s[f'within_0.1_at_{b}']:.0f} %" for b in (20, 40, 80)),
                " / ".join(f"{s[f'median_error_at_{b}']:.3g}" for b in (20, 40, 80)),
            ]
            + (_bench_cells(s) if timed else [])
        )
    return markdown_table(header, rows)


def winner(summary: dict[str, dict[str, Any]], peers: list[str]) -> dict[str, Any]:
    """The method with the fewest median measurements to 0.1° (ties: higher success), and
    its margin over the best peer."""

    def key(m: str) -> tuple[float, float, float]:
        s = summary[m]
        return (s["median_n_0.1"], -s["success_0.1"], s["p90_n_0.1"])

    best = min(summary, key=key)
    present = [p for p in peers if p in summary]
    out = {"method": best, "median_n_0.1": summary[best]["median_n_0.1"]}
    if present:
        bp = min(present, key=key)
        out.update(best_peer=bp, best_peer_median_n_0_1=summary[bp]["median_n_0.1"])
    return out


def plot_ecdf(per_case: dict[str, dict[str, dict[str, Any]]], path: Path) -> None:
    """Fraction of runs within 0.1° (and staying there) vs measurements, per method."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(per_case), figsize=(6.5 * len(per_case), 4.6), squeeze=False)
    n = np.arange(BUDGET + 1)
    for ax, (case, summary) in zip(axes[0], per_case.items(), strict=True):
        for i, (m, s) in enumerate(sorted(summary.items())):
            reach = np.array([np.inf if v is None else v for v in s["n_to_0.1"]])
            frac = (reach[None, :] <= n[:, None]).mean(axis=1)
            # every series its own colour, line style and marker, for colour-blind readers
            # too: 20 colours (tab20, dark shades first), 4 styles and 8 markers cycling (no
            # two of 32 series share a style and a marker); markers staggered along x
            ax.step(
                n,
                100 * frac,
                where="post",
                color=plt.get_cmap("tab20")((2 * i) % 20 + (2 * i) // 20),
                ls=("-", "--", ":", "-.")[i % 4],
                marker=MARKERS[i % len(MARKERS)],
                ms=4.5,
                mfc="none",
                markevery=(i % 10, 10),
                lw=2.2 if m == "auto" else 1.3,
                label=f"{m} (peer)" if m in PEERS else m,
            )
        ax.set_title(f"{case}: all cells pooled")
        ax.set_xlabel("measurements")
        ax.set_ylabel("runs within 0.1° (and staying) [%]")
        ax.set_xlim(0, BUDGET)
        ax.set_ylim(0, 100)
        ax.grid(alpha=0.3)
    axes[0][-1].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    save_figure(fig, path, formats=("png",), dpi=110)
    plt.close(fig)


def _best_cell_entry(cell: dict[str, dict[str, Any]], among: list[str]) -> str:
    """'method: success %, median n' of the best of ``among`` in ``cell`` (most runs within
    0.1° at the budget, then the fewest median measurements to it), or 'none: 0 %'."""
    present = [m for m in among if m in cell]
    if not present:
        return "–"
    best = min(present, key=lambda m: (-cell[m]["success_0.1"], cell[m]["median_n_0.1"]))
    s = cell[best]
    if s["success_0.1"] == 0.0:
        return "none: 0 %"
    return f"{best}: {100 * s['success_0.1']:.0f} %, {_fmt_n(s['median_n_0.1'])}"


def best_per_cell_table(per_cell: dict[str, dict[str, dict[str, Any]]]) -> str:
    """A Markdown table, one row per cell: the best of echocal's methods (and ``auto``'s
    figures when another is best) against the best peer."""
    rows = []
    for key, cell in per_cell.items():
        case, start, snr = key.split("|")
        ours = _best_cell_entry(cell, [*OURS, FRONT_FIRST])
        if "auto" in cell and not ours.startswith(("auto:", "none")):
            ours += f" (auto: {_best_cell_entry(cell, ['auto']).split(': ', 1)[1]})"
        band = STARTS[start]
        rows.append(
            [
                f"{case}, start {band[0]:g}–{band[1]:g}°, {snr} dB",
                ours,
                _best_cell_entry(cell, list(PEERS)),
            ]
        )
    return markdown_table(["cell", "best of echocal", "best peer"], rows)


def _winner_sentence(w: dict[str, Any]) -> str:
    text = f"fewest measurements to 0.1 deg (median): {w['method']} ({_fmt_n(w['median_n_0.1'])})"
    if "best_peer" in w:
        bp = w["best_peer_median_n_0_1"]
        text += f"; best peer {w['best_peer']} ({_fmt_n(bp)})"
        if np.isfinite(bp) and w["median_n_0.1"] > 0:
            text += f": {bp / w['median_n_0.1']:.1f}x fewer"
        elif not np.isfinite(bp):
            text += f": the best peer's median run is not within 0.1 deg after {BUDGET}"
    return text


def report_markdown(data: dict[str, Any], png_name: str, method: str) -> str:
    """The Markdown report of a run's ``data`` (what ``bench_calibration`` writes as JSON):
    how it was made, the ``method`` text (the benchmark's docstring on its cases and
    metrics), winners, the best method per cell, auto's targets, the plot ``png_name`` and
    the tables."""
    command = data.get("command", "python benchmarks/bench_calibration.py (options not recorded)")
    commit = data["machine"].get("echocal_git") or "(commit not recorded)"
    skipped, winners, auto_targets = data["skipped_peers"], data["winners"], data["auto_targets"]
    per_case, per_cell = data["cases"], data["cells"]
    md = [
        "# Calibration benchmark",
        "",
        f"Generated by `{command}` at echocal {commit} "
        f"(mode `{data['mode']}`: {data['runs_per_cell']} seeded runs per cell and method; "
        f"budget {data['budget']} measurements; {data['elapsed_s'] / 60:.1f} min on "
        f"{data.get('workers', '?')} worker(s)).",
        *(
            f"Then `{u['command']}` at echocal {u['echocal_git']} ran "
            f"{', '.join(f'`{m}`' for m in u['methods'])} again on the same cells and seeds "
            f"({u['elapsed_s'] / 60:.1f} min); the tables hold those runs for "
            f"{'that method' if len(u['methods']) == 1 else 'those methods'}."
            for u in data.get("updates", [])
        ),
        "",
        "## Method",
        "",
        method.rstrip(),
        "",
    ]
    if skipped:
        md += ["Skipped peers: " + "; ".join(f"{k} ({v})" for k, v in skipped.items()), ""]
    md += ["## Results", ""]
    for c, w in winners.items():
        md.append(f"* **{c}** ({CASES[c]['lobe']} lobe, all cells pooled): {_winner_sentence(w)}.")
    md += [
        "",
        "Per cell, the method of echocal with the most runs within 0.1° at the budget (ties: "
        "the fewer median measurements until it stays within 0.1°) against the best peer:",
        "",
        best_per_cell_table(per_cell),
        "",
    ]
    if auto_targets:
        md += ["Targets for `auto` (issue 19's on the wave model, issue 5's on the ray model):", ""]
        md += [
            markdown_table(
                ["target", "runs meeting it", "goal", "met"],
                [
                    [k, f"{100 * v['got']:.0f} %", f"≥ {100 * v['goal']:.0f} %", v["met"]]
                    for k, v in auto_targets.items()
                ],
            ),
            "",
        ]
    md += [
        f"![fraction of runs within 0.1° vs measurements]({png_name})",
        "",
        "Columns: *ok* = estimate within the tolerance at the budget; *n to* = measurements "
        "after which the estimate stays within the tolerance (median / 90th percentile; "
        f"`>{BUDGET}` = not within the budget); *≤0.1° at* = fraction within 0.1° after "
        "20 / 40 / 80 measurements; median error after 20 / 40 / 80.",
        "",
    ]
    for c, summary in per_case.items():
        md += [f"## {c} — {CASES[c]['lobe']} lobe, all cells pooled", "", case_table(summary), ""]
        for key, cell in per_cell.items():
            cc, s, snr = key.split("|")
            if cc == c:
                md += [f"### {c}, start {s} ({STARTS[s][0]:g}–{STARTS[s][1]:g}°), {snr} dB", ""]
                md += [case_table(cell), ""]
    return "\n".join(md) + "\n"
