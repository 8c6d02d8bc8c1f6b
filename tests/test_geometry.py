import numpy as np

from stiffknots.geometry import segment_distance


def _brute(p0, p1, q0, q1, n=401):
    s = np.linspace(0, 1, n)
    P = p0 + s[:, None] * (p1 - p0)
    Q = q0 + s[:, None] * (q1 - q0)
    return np.min(np.linalg.norm(P[:, None, :] - Q[None, :, :], axis=2))


def test_segment_distance_matches_sampling():
    rng = np.random.default_rng(1)
    for _ in range(200):
        p0, p1, q0, q1 = rng.normal(size=(4, 3))
        d = segment_distance(p0, p1, q0, q1)
        b = _brute(p0, p1, q0, q1)
        assert d <= b + 1e-12
        assert b - d < 0.02  # sampling resolution


def test_segment_distance_special_cases():
    z = np.zeros(3)
    x = np.array([1.0, 0, 0])
    # crossing at right angles at their midpoints, offset by h
    for h in (0.0, 0.1, 0.7):
        d = segment_distance([-0.5, 0, 0], [0.5, 0, 0], [0, -0.5, h], [0, 0.5, h])
        assert abs(d - h) < 1e-14
    # parallel, overlapping
    assert abs(segment_distance(z, x, [0.5, 1.0, 0], [1.5, 1.0, 0]) - 1.0) < 1e-14
    # collinear, disjoint
    assert abs(segment_distance(z, x, [3.0, 0, 0], [4.0, 0, 0]) - 2.0) < 1e-14
    # degenerate segment (a point)
    assert abs(segment_distance(z, x, [0.5, 2.0, 0], [0.5, 2.0, 0]) - 2.0) < 1e-14
