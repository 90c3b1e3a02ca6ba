"""The wave model's cost on a layered part against the single plate (issue 46).

Run from the repository root::

    python benchmarks/bench_layered.py            # 20 repeats per case
    python benchmarks/bench_layered.py --quick    # 3 repeats

Measured in one process, CPU time per noiseless A-scan (the whole echo train), as ratios
against the single plate:

1. ``single``: the built-in ``immersion-layered``'s probe, pulse and window over one
   aluminium plate 80 mm thick, its back wall and two multiples (3 echoes);
2. ``layered``: ``immersion-layered`` itself without its holes: acrylic 30 mm on aluminium
   50 mm, order 2 (7 paths, 6 distinct diffraction computations);
3. ``layered order 3``: the same at order 3 (20 paths);
4. ``layered + holes``: ``immersion-layered`` with its two flat-bottom holes (their echoes
   and their shadows on every deeper wall path);
5. ``layered exact``: case 2 with ``exact_stack = true``: the whole stack's exact A-scan
   (:mod:`echocal.wave.stack`) besides its 7 paths;

each at normal incidence and at 2° of tilt.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import re  # noqa: E402
import statistics  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from importlib import resources  # noqa: E402
from pathlib import Path  # noqa: E402

from _common import fmt_time, machine_info  # noqa: E402

from echocal import Pose, load_setup  # noqa: E402


def _text() -> str:
    return (resources.files("echocal") / "data" / "setups" / "immersion-layered.toml").read_text()


def _variants(folder: Path) -> dict[str, Path]:
    """The setup files of the four cases (module doc)."""
    base = _text()
    no_holes = re.sub(r"\[\[specimen\.flaws\]\].*?(?=\n\[transducer\])", "", base, flags=re.S)
    single = re.sub(r"\[\[specimen\.layers\]\].*?(?=\n\[transducer\])", "", no_holes, flags=re.S)
    single = single.replace(
        "back_wall_echoes = 2",
        'material = "aluminium"\nthickness = "80 mm"\nback_wall_echoes = 3',
    )
    texts = {
        "single": single,
        "layered": no_holes,
        "layered order 3": no_holes.replace("back_wall_echoes = 2", "back_wall_echoes = 3"),
        "layered + holes": base,
        "layered exact": no_holes.replace(
            "back_wall_echoes = 2", "back_wall_echoes = 2\nexact_stack = true"
        ),
    }
    out = {}
    for name, text in texts.items():
        path = folder / f"{name.replace(' ', '-').replace('+', 'and')}.toml"
        path.write_text(text)
        out[name] = path
    return out


def _cpu(fn, repeats: int) -> float:
    """Median CPU seconds of ``fn()`` after one untimed call."""
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.process_time()
        fn()
        times.append(time.process_time() - t0)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="3 repeats per case")
    args = parser.parse_args()
    repeats = 3 if args.quick else 20
    print(machine_info())
    with tempfile.TemporaryDirectory() as folder:
        setups = {name: load_setup(path) for name, path in _variants(Path(folder)).items()}
        for tilt in (0.0, 2.0):
            pose = Pose.from_tilt(0.0, 0.0, 0.05, tilt, 0.0)
            cost = {
                name: _cpu(lambda s=setup, p=pose: s.simulate([p], noise=False), repeats)
                for name, setup in setups.items()
            }
            print(f"\ntilt {tilt:g}°: CPU time per A-scan (median of {repeats})")
            for name, seconds in cost.items():
                labels = len(setups[name].interior_echoes.labels)
                ratio = seconds / cost["single"]
                print(f"  {name:18s} {labels:3d} echoes  {fmt_time(seconds):>10s}  ×{ratio:.2f}")


if __name__ == "__main__":
    main()
