"""What the plots of ``echocal calibrate`` cost against the calibration they show.

Run from the repository root::

    python benchmarks/bench_plots.py            # immersion-5mhz from x0 = 12,8 (a far start)
    python benchmarks/bench_plots.py --repeats 3 --json out.json
    python benchmarks/bench_plots.py --parameterization azimuth-coelevation  # two-panel maps

In one process, after an untimed warm-up run (numba's kernels, the detector and
lobe-profile caches on disk, in a fresh cache folder), each repeat runs the same seeded
``echocal calibrate --setup SETUP --x0 X0`` twice through the CLI: with ``--no-plots``
and with the default plots (convergence, the path over its cost map, the final
A-scan).  Reported: the CPU time of each (``time.process_time``: this process's threads,
the wave model's pool included; the median over the repeats), their ratio, the CPU time
spent writing the figures (``save_figure``: laying out, drawing and encoding the PNGs;
median per plotted run), and the wave-model A-scans the path plot's cost map simulated
(its ``map`` line).  BLAS is pinned
to one thread (``OPENBLAS_NUM_THREADS=1`` etc., unless set already), as a calibration
runs.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before numpy is imported

import argparse  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import machine_info  # noqa: E402


def _calibrate(args: list[str]) -> float:
    """[s] CPU time of one ``echocal calibrate`` call in this process."""
    from echocal.cli import app

    t0 = time.process_time()
    code = app(args=["calibrate", *args], standalone_mode=False)
    spent = time.process_time() - t0
    if code not in (None, 0):
        raise SystemExit(f"calibrate {' '.join(args)} exited with {code}")
    return spent


def _record_maps(into: list[dict[str, Any]]) -> None:
    """Keep what every path plot's map computed (``PathMap.to_dict``) in ``into``."""
    from echocal.plots import path_map

    inner = path_map.path_cost_map

    def recorded(*args: Any, **kwargs: Any) -> path_map.PathMap:
        drawn = inner(*args, **kwargs)
        into.append(drawn.to_dict())
        return drawn

    path_map.path_cost_map = recorded  # type: ignore[assignment]  # the CLI imports it per call


def _record_saves(into: list[float]) -> None:
    """Add the CPU time of every ``save_figure`` call to ``into`` (the CLI imports it per
    call, from :mod:`echocal.plots`)."""
    import echocal.plots

    inner = echocal.plots.save_figure

    def timed(*args: Any, **kwargs: Any) -> list[Path]:
        t0 = time.process_time()
        try:
            return inner(*args, **kwargs)
        finally:
            into.append(time.process_time() - t0)

    echocal.plots.save_figure = timed  # type: ignore[assignment]


def run(setup: str, x0: str, repeats: int, work: Path, param: str = "tilt") -> dict[str, Any]:
    """Time ``repeats`` pairs of runs (without plots, with plots) after a warm-up."""
    maps: list[dict[str, Any]] = []
    saves: list[float] = []
    _record_maps(maps)
    _record_saves(saves)
    common = ["--setup", setup, "--x0", x0, "--parameterization", param, "--json", "--overwrite"]
    _calibrate([*common, "--out", str(work / "warm"), "--no-plots"])
    bare, plotted, saving = [], [], []
    for _ in range(repeats):
        bare.append(_calibrate([*common, "--out", str(work / "bare"), "--no-plots"]))
        saves.clear()
        plotted.append(_calibrate([*common, "--out", str(work / "plots")]))
        saving.append(sum(saves))
    result = json.loads((work / "plots" / "result.json").read_text(encoding="utf-8"))
    without, with_plots = statistics.median(bare), statistics.median(plotted)
    return {
        "setup": setup,
        "x0": x0,
        "parameterization": param,
        "repeats": repeats,
        "cpu_s_without_plots": without,
        "cpu_s_with_plots": with_plots,
        "ratio": with_plots / without,
        "cpu_s_saving_figures": statistics.median(saving),
        "cpu_s_all": {"without_plots": bare, "with_plots": plotted},
        "measurements": result.get("n_measurements"),
        "map": maps[-1] if maps else None,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--setup", default="immersion-5mhz")
    parser.add_argument("--x0", default="12,8")
    parser.add_argument("--parameterization", default="tilt")
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--json", type=Path, default=None, help="write every number here")
    opts = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="echocal-bench-plots-") as tmp:
        os.environ["ECHOCAL_CACHE_DIR"] = str(Path(tmp) / "cache")
        result = run(opts.setup, opts.x0, max(1, opts.repeats), Path(tmp), opts.parameterization)
    result["machine"] = machine_info(["numpy", "numba", "matplotlib"])
    print(
        f"HEADLINE calibrate --setup {opts.setup} --x0 {opts.x0} "
        f"--parameterization {opts.parameterization}: "
        f"{result['cpu_s_without_plots']:.2f} CPU-s without plots, "
        f"{result['cpu_s_with_plots']:.2f} CPU-s with plots: "
        f"ratio {result['ratio']:.2f} (median of {result['repeats']}); "
        f"writing the figures {result['cpu_s_saving_figures']:.2f} CPU-s"
    )
    print(f"map: {json.dumps(result['map'])}")
    if opts.json is not None:
        opts.json.write_text(json.dumps(result, indent=2) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
