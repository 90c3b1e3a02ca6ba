"""Calibration: find the orientation [deg] of maximum echo from few, noisy measurements.

Ask/tell optimizers behind one registry (:func:`method_names`), a counted and bounded
:class:`Objective`, the :func:`calibrate` driver and a plain-data
:class:`CalibrationResult`.  Thesis Part II methods (``gradient``, ``momentum``,
``nesterov``, ``spsa``, ``newton``, ``quasi-newton``) with the errata of the thesis fixed
(docs/physics.md, "The thesis's errata"), plus ``model-based``, ``grid``, ``acquisition``
and ``auto``.
"""

from echocal.calibrate.acquisition import Acquisition
from echocal.calibrate.auto import Auto
from echocal.calibrate.base import Optimizer
from echocal.calibrate.driver import CalibrationState, build_optimizer, calibrate
from echocal.calibrate.gradient import GradientAscent, Momentum, Nesterov
from echocal.calibrate.grid import GridSearch
from echocal.calibrate.model_based import ModelBased
from echocal.calibrate.newton import Newton
from echocal.calibrate.objective import FunctionObjective, MeasurementLog, Objective
from echocal.calibrate.presets import Preset, method_options, preset_names, presets
from echocal.calibrate.quasi_newton import QuasiNewton
from echocal.calibrate.registry import get_method, method_names, register_method
from echocal.calibrate.result import STATUS_MESSAGES, CalibrationResult
from echocal.calibrate.spsa import SPSA

__all__ = [
    "SPSA",
    "STATUS_MESSAGES",
    "Acquisition",
    "Auto",
    "CalibrationResult",
    "CalibrationState",
    "FunctionObjective",
    "GradientAscent",
    "GridSearch",
    "MeasurementLog",
    "ModelBased",
    "Momentum",
    "Nesterov",
    "Newton",
    "Objective",
    "Optimizer",
    "Preset",
    "QuasiNewton",
    "build_optimizer",
    "calibrate",
    "get_method",
    "method_names",
    "method_options",
    "preset_names",
    "presets",
    "register_method",
]
