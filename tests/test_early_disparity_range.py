"""The disparity range estimate's search down the pyramid: a level's window wider than the level is cut at
its margins, never where the coarser level found matches (tests/test_disparity_range.py holds the rest)."""

from vmcl.datasets import load_stereo
from vmcl.early.disparity_range import estimate_range


def test_a_wide_margin_keeps_the_range_the_images_show(datasets_root, machine):
    """tsukuba's disparities run 5..14. With margin 100 the half-size level's window (-198..208) is wider
    than that level (192 pixels): its top was cut to the level's width above the bottom, -191..0, which lost
    every true disparity (the range came out -383..0); the cut now falls on the margins, and the range
    holds 5..14 and finds what margin 1 finds."""
    pair = load_stereo("tsukuba", datasets_root)
    wide = estimate_range(pair.left, pair.right, margin=100, machine=machine)
    narrow = estimate_range(pair.left, pair.right, machine=machine)
    assert wide.decided and wide.d_min <= 5 and wide.d_max >= 14, wide
    assert wide.found == narrow.found, (wide, narrow)
