"""Shared test configuration: derandomized hypothesis, headless matplotlib."""

from __future__ import annotations

import os

import matplotlib
from hypothesis import settings

matplotlib.use("Agg")
os.environ.setdefault("MPLBACKEND", "Agg")

settings.register_profile("echocal", derandomize=True, max_examples=60, deadline=None)
settings.load_profile("echocal")
