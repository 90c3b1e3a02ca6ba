"""``echocal scene``: a 3D picture of the probe against the part."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from echocal.cli._common import console, parse_pose
from echocal.cli._setup_option import SETUP_HELP, SPECIMEN_HELP, resolve_setup


def register(app: typer.Typer) -> None:
    """Add ``echocal scene`` to ``app``."""

    @app.command("scene")
    def scene(
        pose: Annotated[
            list[str],
            typer.Option(
                "--pose",
                help="X,Y,Z[,AZIMUTH,COELEVATION]: lengths in mm unless a unit is given, angles "
                "in degrees. Repeat for several poses.",
            ),
        ],
        setup: Annotated[str, typer.Option(help=SETUP_HELP)] = "thesis",
        specimen: Annotated[str | None, typer.Option(help=SPECIMEN_HELP)] = None,
        rays: Annotated[int, typer.Option(min=1, help="Rays drawn per pose.")] = 60,
        out: Annotated[Path, typer.Option(help="Image file (.png or .svg).")] = Path(
            "echocal-out/scene.png"
        ),
    ) -> None:
        """Save a 3D view of specimen, transducer and a subsample of rays with their hits."""
        from echocal.cli._common import check_out_file
        from echocal.plots import figure_formats, save_figure
        from echocal.plots.scene import scene_figure

        check_out_file(out, suffix=None, example="scene.png")  # a directory, or a file as a folder

        formats = figure_formats(out)  # a format matplotlib cannot write: refused first
        virtual = resolve_setup(setup, specimen=specimen)
        poses = [parse_pose(p) for p in pose]
        for text, target in zip(pose, poses, strict=True):
            if problems := virtual.limits.violations(target):  # drawn, but say so
                console.print(
                    f"[yellow]warning:[/] --pose {text} is out of the setup's positioner "
                    f"limits ({'; '.join(problems)}); `echocal simulate` would refuse it",
                    highlight=False,
                    soft_wrap=True,
                )
        inside = virtual.specimen.containing([p.position for p in poses])
        for text, index in zip(pose, inside, strict=True):
            if index >= 0:
                shape = virtual.specimen[int(index)]
                console.print(
                    f"[yellow]warning:[/] --pose {text} is inside {shape.kind} {shape.name!r} "
                    f"of the specimen; `echocal simulate` would refuse it",
                    highlight=False,
                    soft_wrap=True,
                )
        fig = scene_figure(
            virtual.specimen,
            virtual.transducer,
            poses,
            n_rays=rays,
            reflection=virtual.reflection,
        )
        written = save_figure(fig, out, formats=formats, dpi=130)
        console.print(f"scene saved to [bold]{written[0]}[/]")
