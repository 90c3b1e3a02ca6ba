"""A rich progress bar with elapsed time and ETA on stderr, or nothing (private)."""

from __future__ import annotations

from typing import Any, Self


class ProgressBar:
    """Context manager: ``label ━━━ done/total [unit] elapsed ETA remaining`` on stderr.

    Parameters
    ----------
    label : the first column (rich markup; ``{task.description}`` shows ``description``).
    total, completed : units of work in all and already done (a resumed run).
    enabled : False makes every method a no-op (no bar, no rich import).
    description : the task's description (see ``label``).
    unit : text after the ``done/total`` counter (None: no column).
    """

    def __init__(
        self,
        label: str,
        *,
        total: int,
        completed: int = 0,
        enabled: bool = True,
        description: str = "",
        unit: str | None = None,
    ) -> None:
        self.label, self.total, self.completed = label, total, completed
        self.enabled, self.description, self.unit = enabled, description, unit
        self._bar: Any = None
        self._task: Any = None

    def __enter__(self) -> Self:
        if not self.enabled:
            return self
        from rich.console import Console
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )

        counter = [MofNCompleteColumn()] + ([TextColumn(self.unit)] if self.unit else [])
        self._bar = Progress(
            TextColumn(self.label),
            BarColumn(),
            *counter,
            TimeElapsedColumn(),
            TextColumn("ETA"),
            TimeRemainingColumn(),
            console=Console(stderr=True),
        )
        self._bar.start()
        self._task = self._bar.add_task(
            self.description, total=self.total, completed=self.completed
        )
        return self

    def advance(self) -> None:
        """One more unit of work done."""
        if self._bar is not None:
            self._bar.advance(self._task)

    def describe(self, description: str) -> None:
        """Replace the task's description (shown where ``label`` has ``{task.description}``)."""
        if self._bar is not None:
            self._bar.update(self._task, description=description)

    def __exit__(self, *exc: object) -> None:
        if self._bar is not None:
            self._bar.stop()
