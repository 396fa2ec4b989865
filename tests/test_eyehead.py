"""The vergence of the (simulated) eye-head selects or interpolates the stereo warp table."""

import numpy as np
from test_early_registration import dot_image, grid_dots, inner_pixels, transform

from hardware.head import Head
from vmcl.early.registration import TableStore
from vmcl.eyehead import calibrate_vergences, table_for_fixation


def test_vergence_selects_and_interpolates_tables(machine):
    left = grid_dots(np.random.default_rng(4))

    def pattern_seen_by(head):
        # The right view's dots move with the vergence the head reports, as a real pair's would.
        def capture():
            vergence = head.vergence()
            shift = (50 * np.tan(np.deg2rad(vergence) / 2), 1.0)
            return dot_image(left), dot_image(transform(left, shift=shift, angle_deg=0.05 * vergence))
        return capture

    with Head("sim://") as head:
        head.home()
        store = TableStore()
        angles = calibrate_vergences(head, store, pattern_seen_by(head), distances=[4.0, 1.0], baseline=0.3,
                                     max_shift=10, machine=machine)
        assert angles[0] < angles[1] and [t.vergence for t in store.tables] == sorted(angles)
        head.fixate(4.0, baseline=0.3)
        assert table_for_fixation(head, store) is store.tables[0]
        head.fixate(2.0, baseline=0.3)
        between = table_for_fixation(head, store)
        direct = TableStore()
        calibrate_vergences(head, direct, pattern_seen_by(head), distances=[2.0], baseline=0.3, max_shift=10,
                            machine=machine)
    assert angles[0] < between.vergence < angles[1]
    _, inside = inner_pixels(left)
    assert np.abs(between.source - direct.tables[0].source)[inside].max() < 0.25


def test_a_bad_distance_anywhere_in_the_list_leaves_the_store_and_the_eyes_untouched():
    """Every distance (and the baseline) is checked before the first table goes into the store."""
    import math

    import pytest

    def capture():
        raise AssertionError("nothing may be captured before every distance is checked")

    with Head("sim://") as head:
        head.home()
        store = TableStore()
        before = head.vergence()
        for distances, baseline, name in (([0.7, math.nan], 0.3, r"distances\[1\]"), ([0.7, -1.0], 0.3, r"distances\[1\]"),
                                          ([0.7], 0.0, "baseline")):
            with pytest.raises(ValueError, match=name):
                calibrate_vergences(head, store, capture, distances=distances, baseline=baseline, max_shift=10)
        assert not store.tables and head.vergence() == before
