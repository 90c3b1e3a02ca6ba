"""The analytic signal, on scipy.fft (private to the signal layer).

Kept apart from scipy.signal on purpose: importing scipy.signal pulls in scipy.stats
(~0.7 s), which every ``echocal`` command would pay at start-up.
"""

from __future__ import annotations

import numpy as np
import scipy.fft
from numpy.typing import ArrayLike, NDArray

__all__ = ["analytic_signal"]


def analytic_signal(x: ArrayLike) -> NDArray[np.complex128]:
    """Analytic signal x + i·H{x} along the last axis (the same as scipy.signal.hilbert).

    Kept here, on scipy.fft, so that importing echocal does not import scipy.signal
    (which pulls in scipy.stats: ~0.7 s).
    """
    x = np.asarray(x, dtype=np.float64)
    n = x.shape[-1]
    spectrum = scipy.fft.fft(x, axis=-1)
    weights = np.zeros(n)
    weights[0] = 1.0
    if n % 2 == 0:
        weights[n // 2] = 1.0
        weights[1 : n // 2] = 2.0
    else:
        weights[1 : (n + 1) // 2] = 2.0
    return scipy.fft.ifft(spectrum * weights, axis=-1)
