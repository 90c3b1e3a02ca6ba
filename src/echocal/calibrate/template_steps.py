"""The lobe's template in ``model-based``'s steps: from the lobe's tail to its fitted peak,
then flanks around it until the log-quadratic takes over (a mixin of
:class:`~echocal.calibrate.model_based.ModelBased`).

A diffraction lobe's tail is not Gaussian (the 5 MHz probe's falls to 0.035 of the peak 0.9°
out and then only slowly), so a log-quadratic fitted to it sees a lobe twice as broad.  The
template (:mod:`echocal.calibrate.lobe_template`, the simulated probe's pseudo-energy versus
misalignment) is fitted to every measurement after each tell: the peak and its energy (for
the simulator the peak's energy is known to 25 %, which breaks the tail's trade between a
strong far peak and a weak near one).  While no measurement lies on the main lobe's top the
next point is the fitted peak; once one does, the flanks around it are measured and the
recommendation is the fitted peak; once :data:`_QUADRATIC_TOP` measurements lie on the top
and the quadratic's maximum agrees with the template's, the quadratic takes over for good
(:meth:`TemplateSteps._hand_over`).

The top is the main lobe only
(:meth:`~echocal.calibrate.lobe_template.LobeTemplate.on_top`), and a fitted peak is kept
unless the data clearly prefer another (``fit_template``'s ``previous``): over a ball the
12.7 mm probe's lobe has a near-field ring at about 0.8 of its peak 1.6° out, which is above
half the peak and which a centre across the ring fits almost as well.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from echocal.calibrate._fd import FloatArray
from echocal.calibrate.lobe_template import (
    LobeTemplate,
    TemplateFit,
    fit_template,
    seek_point,
    tail_reach,
)
from echocal.calibrate.local_model import REFUTE, QuadraticModel

__all__ = ["TemplateSteps"]

_SEEK_MAX = 8
"""Seek measurements (:func:`~echocal.calibrate.lobe_template.seek_point`) at most, after a
warm start the template does not fit yet, before the usual steps take over."""

_TEMPLATE_MISFIT = 25.0
"""A template fit whose χ² per degree of freedom (against the measurement noise) exceeds
this refutes the template for the run: the log-quadratic alone, as without one (a lobe
that is not the probe's; fits of the probe's own stay at 1–4)."""
_QUADRATIC_TOP = 6
"""Measurements on the lobe's top before the log-quadratic (6 parameters) takes over from
the template there."""

_AGREE = 0.25
"""[× the lobe's width] the log-quadratic's maximum and the template's peak agree within
this distance before the quadratic takes over."""


class TemplateSteps:
    """The template's steps, for a local method that keeps its measurements in ``_x``
    [deg] (n, 2) and ``_y`` (n,), its incumbent in ``_incumbent``, its fitted
    log-quadratic in ``_model``, its value scale in ``_scale``, its fitting space in
    ``space``, its normalization in ``normalize`` and its largest step in ``max_radius``
    [deg], and provides ``_floor()``, ``_sigmas(values)``, ``clip(points)``,
    ``_times_measured(point)`` and ``_supported_max()``."""

    x0: FloatArray
    _x: FloatArray
    _y: FloatArray
    _incumbent: FloatArray
    _model: QuadraticModel | None
    _scale: float
    space: str
    normalize: str
    max_radius: float

    if TYPE_CHECKING:  # provided by the method

        def _floor(self) -> float: ...

        def _sigmas(self, values: FloatArray) -> FloatArray | None: ...

        def clip(self, points: ArrayLike) -> FloatArray: ...

        def _times_measured(self, point: FloatArray) -> int: ...

        def _supported_max(self) -> FloatArray | None: ...

    def _init_template_steps(self, lobe_template: Callable[[], LobeTemplate | None] | None) -> None:
        """No template asked for yet, no fit: ``lobe_template`` (called once, when first
        needed) gives the probe's lobe or None."""
        self.lobe_template = lobe_template
        self._template: LobeTemplate | None = None
        self._template_asked = False
        self._tfit: TemplateFit | None = None
        self._n_top = 0  # measurements on the fitted template's top
        self._quadratic_on_top = False  # the log-quadratic has taken over from the template
        self._seeks_left = 0  # seek measurements still allowed (:meth:`_start_seek`)

    def _fit_template(self) -> None:
        """Fit the probe's lobe template to every measurement
        (:func:`~echocal.calibrate.lobe_template.fit_template`, peaks within
        ``max_radius`` of the incumbent): ``_tfit`` is the fit when its peak is a
        significant echo (``REFUTE`` standard errors), else None; ``_n_top`` counts the
        measurements on the lobe's main top (:meth:`LobeTemplate.on_top`: above half its
        peak, not on a ring around it); the previous fit's peak is kept unless the data
        clearly prefer another (``fit_template``'s ``previous``).  Log space only, with a
        live noise model; the prior on the peak's energy only when the values keep the
        objective's units (``normalize="none"``)."""
        previous = None if self._tfit is None else self._tfit.centre  # kept on ties
        self._tfit, self._n_top = None, 0
        if self._quadratic_on_top or self.space != "log" or not len(self._x):
            return
        if not self._template_asked:
            self._template_asked = True
            self._template = None if self.lobe_template is None else self.lobe_template()
        template = self._template
        if template is None:
            return
        y = self._y - self._floor()
        sig = self._sigmas(np.maximum(y, 0.0))
        if sig is None:
            return
        known = template.peak is not None and self.normalize == "none"
        peak = template.peak / self._scale if known and template.peak is not None else None
        fit = fit_template(
            template, self._x, y, sig, self._incumbent, self.max_radius, peak, previous
        )
        if fit is None or fit.measured < REFUTE * fit.energy_sigma:  # the data's own evidence
            return
        if len(y) >= 7 and fit.chi2 > _TEMPLATE_MISFIT * (len(y) - 3):
            self._template = None  # refuted: this lobe is not the probe's, for the whole run
            return
        self._tfit = fit  # only an accepted fit's peak is kept next time: not one of noise
        self._n_top = int(np.count_nonzero(template.on_top(self._x - fit.centre)))

    def _seek_template(self) -> LobeTemplate | None:
        """The template when a seek can use it — the peak's metric known in the objective's
        units (> 0), the values not normalized, the model in log space, the noise known —
        else None."""
        template = self._template
        if template is None or not (template.peak or 0.0) > 0.0 or self.normalize != "none":
            return None
        if self.space != "log" or self._sigmas(np.zeros(1)) is None:
            return None
        return template

    def _start_seek(self) -> bool:
        """For a warm start the template does not fit yet (typically a detection in the
        lobe's tail; also a false alarm handed on): seek the peak (:meth:`_seek_step`, up
        to :data:`_SEEK_MAX` measurements) instead of measuring a design around x0 — True —
        when :meth:`_seek_template` gives the template; else False."""
        if self._seek_template() is None:
            return False
        self._seeks_left = _SEEK_MAX
        return True

    def _seek_step(self) -> FloatArray | None:
        """While seeking and no template fit is accepted: the point [deg] (2,) where the
        candidate peaks' predicted echoes disagree most
        (:func:`~echocal.calibrate.lobe_template.seek_point`, candidates out to where the
        lobe's tail is still 3 σ above the noise, at least ``max_radius`` from x0); else
        None, and the seek is over for the run — also when that point, as the positioner
        reaches it, was measured already (clipped onto a limit, or a NaN there: it would
        teach nothing new)."""
        template = self._seek_template()
        if self._tfit is not None or template is None or template.peak is None:
            self._seeks_left = 0
            return None
        if self._seeks_left <= 0:
            return None
        y = self._y - self._floor()
        sig, noise = self._sigmas(np.maximum(y, 0.0)), self._sigmas(np.zeros(1))
        if sig is None or noise is None:
            return None
        peak = template.peak / self._scale
        reach = max(self.max_radius, tail_reach(template, peak, float(noise[0])))
        point = seek_point(template, self._x, y, sig, float(noise[0]), peak, self.x0, reach)
        if point is None or self._times_measured(point):
            self._seeks_left = 0
            return None
        self._seeks_left -= 1
        return self.clip(point)

    def _template_step(self) -> FloatArray | None:
        """While no measurement lies on the lobe's top: the fitted template's peak [deg]
        (2,) unless measured already; else None (the log-quadratic's steps)."""
        if self._tfit is None or self._n_top:
            return None
        target = self.clip(self._tfit.centre)
        return None if self._times_measured(target) else target

    def _template_top(self) -> FloatArray | None:
        """The fitted template's peak [deg] (2,), clipped to the bounds, once a measurement
        lies on the lobe's top and until the log-quadratic takes over
        (:meth:`_hand_over`); else None."""
        if self._tfit is None or not self._n_top:
            return None
        return self.clip(self._tfit.centre)

    def _hand_over(self) -> None:
        """Once :data:`_QUADRATIC_TOP` measurements lie on the lobe's top (the
        log-quadratic's 6 parameters need them there) and the quadratic's maximum agrees
        with the template's peak (:data:`_AGREE`), the quadratic takes over for good: the
        template is not fitted again.  The maximum need not be supported by a measurement
        near it: over a broad lobe the flank points lie a lobe's width out."""
        if self._tfit is None or self._template is None or self._n_top < _QUADRATIC_TOP:
            return
        xs = self._supported_max()
        m = self._model
        if xs is None and m is not None and m.concave:
            xs = m.argmax()  # flank points only (a broad lobe): none near the maximum yet
        centre = self.clip(self._tfit.centre)
        if xs is not None and np.hypot(*(xs - centre)) <= _AGREE * self._template.width:
            self._quadratic_on_top = True
            self._tfit, self._n_top = None, 0
