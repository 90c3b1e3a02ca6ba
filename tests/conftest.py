"""Shared test configuration: derandomized hypothesis, headless matplotlib."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import matplotlib
from hypothesis import settings

sys.path.insert(0, str(Path(__file__).parent))  # tests/cli_helpers.py, from any folder
matplotlib.use("Agg")
os.environ.setdefault("MPLBACKEND", "Agg")

settings.register_profile("echocal", derandomize=True, max_examples=60, deadline=None)
settings.load_profile("echocal")
