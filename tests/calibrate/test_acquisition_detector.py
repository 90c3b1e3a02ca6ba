"""Acquisition with a detection channel: significances instead of values, and confirmation."""

from __future__ import annotations

import numpy as np

from echocal.calibrate import Acquisition, FunctionObjective, calibrate


class _Scripted:
    """A detector returning scripted significances for the next tells."""

    def __init__(self) -> None:
        self.next: np.ndarray | None = None

    def __call__(self) -> np.ndarray | None:
        return self.next


def test_the_detector_decides_not_the_values():
    det = _Scripted()
    acq = Acquisition(np.zeros(2), spacing=1.0, noise_sigma=1.0, noise_floor=0.0, detector=det)
    pts = acq.ask()
    det.next = np.full(len(pts), 3.5)  # x0's neighbourhood: 3.5·7/√7 = 9.3 > 3 + 2: sure
    acq.tell(np.zeros(len(pts)))  # the values alone (all at the floor) would find nothing
    assert acq.local is not None and acq.found_at == 7
    np.testing.assert_allclose(acq.scores()[0], 3.5 * np.sqrt(7), rtol=1e-12)


def test_without_significances_the_values_are_tested():
    det = _Scripted()  # returns None: e.g. an analytic objective
    acq = Acquisition(np.zeros(2), spacing=1.0, noise_sigma=1.0, noise_floor=0.0, detector=det)
    pts = acq.ask()
    acq.tell(np.full(len(pts), 3.5))
    assert acq.local is not None


def _marginal_start() -> tuple[Acquisition, _Scripted]:
    det = _Scripted()
    acq = Acquisition(np.zeros(2), spacing=1.0, detector=det)
    pts = acq.ask()
    det.next = np.full(len(pts), 1.3)  # x0's neighbourhood: 1.3·√7 = 3.44 in (3, 6.5): marginal
    acq.tell(np.zeros(len(pts)))
    assert acq.local is None
    return acq, det


def test_a_marginal_detection_is_remeasured_and_a_noise_outlier_rejected():
    acq, det = _marginal_start()
    again = acq.ask()
    np.testing.assert_allclose(again, [[0.0, 0.0]])  # the best point, x0, once more
    det.next = np.array([-1.0])  # noise: (9.1 − 1)/√8 = 2.86 < 3
    acq.tell(np.zeros(1))
    assert acq.local is None
    nxt = acq.ask()
    assert np.hypot(*nxt[0]) > 1.5  # the search goes on with ring 2


def test_a_confirmed_detection_hands_over():
    acq, det = _marginal_start()
    acq.ask()
    det.next = np.array([2.0])  # (9.1 + 2)/√8 = 3.92 > 3
    acq.tell(np.zeros(1))
    assert acq.local is not None and acq.found_at == 8


class _WithSignificance(FunctionObjective):
    """An analytic objective that also reports scripted significances per call."""

    def __init__(self, script: list[np.ndarray], **kw) -> None:
        super().__init__(lambda p: np.zeros(len(p)), **kw)
        self.script = list(script)

    def _significance(self) -> np.ndarray:
        return self.script.pop(0)


def test_repeats_combine_significances_by_stouffer():
    a, b = np.array([1.0, 4.0, np.nan]), np.array([3.0, np.nan, np.nan])
    obj = _WithSignificance([a, b], repeats=2)
    obj(np.zeros((3, 2)))
    # (1 + 3)/√2; one finite repeat: itself; none: NaN
    np.testing.assert_allclose(obj.detections(), [4.0 / np.sqrt(2.0), 4.0, np.nan])
    assert FunctionObjective(lambda p: np.zeros(len(p))).detections() is None


def test_the_driver_wires_the_objective_detector_into_auto():
    # neither the significances nor the values ever show an echo
    obj = _WithSignificance([np.zeros(7), np.array([0.0]), *[np.zeros(1)] * 50])
    res = calibrate(obj, "auto", x0=(0.0, 0.0), budget=20, max_radius=2.0, rng=0, settle=None)
    assert res.options["detector"] == "objective"  # supplied by the objective, named
    assert res.status == 4  # nothing significant: the lattice to 2° searched in vain
    assert res.n_measurements == 19 and res.acquisition_measurements is None


def test_a_failed_confirmation_is_not_a_confirmation():
    acq, det = _marginal_start()
    acq.ask()
    det.next = np.array([np.nan])
    acq.tell(np.array([np.nan]))  # the repeat returned NaN: no evidence either way
    assert acq.local is None
    assert np.hypot(*acq.ask()[0]) > 1.5  # the search goes on with ring 2


def test_a_nan_significance_does_not_blind_the_search():
    det = _Scripted()
    acq = Acquisition(np.zeros(2), spacing=1.0, detector=det, confirm=False)
    pts = acq.ask()
    det.next = np.array([np.nan, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])  # value finite, g unknown
    acq.tell(np.zeros(len(pts)))
    assert np.all(np.isfinite(acq.scores()))
    pts = acq.ask()
    det.next = np.full(len(pts), 50.0)  # then a strong echo
    acq.tell(np.zeros(len(pts)))
    assert acq.local is not None


def test_acquisition_measurements_count_repeats():
    def peak(p):
        return 10.0 * np.exp(-np.sum((np.atleast_2d(p) - [2.0, 0.0]) ** 2, axis=1) / 0.5)

    counts = {}
    for repeats in (1, 3):
        obj = FunctionObjective(peak, noise_sigma=0.01, noise_floor=0.0, rng=0, repeats=repeats)
        res = calibrate(obj, "auto", x0=(0.0, 0.0), max_iter=2, rng=0)
        counts[repeats] = res.acquisition_measurements
    # the same points are searched; each costs `repeats` measurements
    assert counts[3] == 3 * counts[1] and counts[1] >= 7
