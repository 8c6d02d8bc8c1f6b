"""How the tables print a segment distance (``stiffknots.report.text``)."""

from stiffknots.report.text import TOUCHING_BELOW, segment_distance_text, touching_note


def test_a_touching_crossing_is_not_printed_as_zero():
    assert segment_distance_text(0.4567) == "0.457"
    assert segment_distance_text(TOUCHING_BELOW) == "0.001"
    assert segment_distance_text(1.00000000007e-4) == "1.0e-04"  # the polish's strand gap
    assert segment_distance_text(0.0) == "0.0e+00"
    assert segment_distance_text(None) == "—"
    assert "1e-04" in touching_note()
