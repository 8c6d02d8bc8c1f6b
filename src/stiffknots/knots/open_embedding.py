"""Open knots with straight ends along z (paper §VIII), built from a closed embedding.

Construction
------------
A closed chain of the knot (:func:`stiffknots.knots.embedding.embed_braid`) is cut at one
bond (a, a+1). The chain is rotated so that this bond points along +z, and the bond is chosen
so that, seen from above, its two beads are the extreme point of the chain in some horizontal
direction e (strictly beyond every other bead). From bead a+1 a straight arm of unit bonds
leaves along e and turns down; from bead a an arm leaves along e and turns up; both vertical
runs lie on one vertical line, which becomes the z axis. Because the arms and the line lie in
the half-space beyond every other bead, the open chain closed far out along ±z is isotopic
to the closed chain with the bond restored: the knot type is unchanged (and it is verified
anyway, with :func:`stiffknots.knots.identify.verify_knot` on the closure along z).

The end segments are clamped on the z axis as the open-chain kernel requires
(:func:`stiffknots.engine.state.check_open_clamping`). The excess length is
L_e = (N − 1) − Δz = N_k + 2h − 2 for a closed chain of N_k beads and arms of h bonds, since
the vertical runs add no excess.
"""

from __future__ import annotations

import numpy as np

from stiffknots.knots.embedding import D_MIN, EmbeddingError, embed_braid
from stiffknots.measures import min_bead_distance


def _rotation_to_z(t: np.ndarray) -> np.ndarray:
    """A rotation matrix taking the unit vector t to +z."""
    z = np.array([0.0, 0.0, 1.0])
    v = np.cross(t, z)
    s = np.linalg.norm(v)
    c = float(t @ z)
    if s < 1e-12:
        return np.eye(3) if c > 0 else np.diag([1.0, -1.0, -1.0])
    k = v / s
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + s * kx + (1 - c) * kx @ kx


def _best_cut(x: np.ndarray, n_dirs: int = 90) -> list[tuple[float, int, np.ndarray, np.ndarray]]:
    """Candidate cuts (clearance, a, rotation, e), best first; clearance > 0 only."""
    n = len(x)
    angles = np.linspace(0, 2 * np.pi, n_dirs, endpoint=False)
    dirs = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    out = []
    idx = np.arange(n)
    for a in range(n):
        b = (a + 1) % n
        rot = _rotation_to_z(x[a] - x[b])
        y = x @ rot.T
        others = (idx != a) & (idx != b)
        p = y[a, :2]
        proj = (y[others, :2] - p) @ dirs.T  # (n-2, n_dirs): ≤ 0 means behind the cut
        clearance = -proj.max(axis=0)
        k = int(np.argmax(clearance))
        if clearance[k] > 0:
            out.append((float(clearance[k]), a, rot, dirs[k]))
    out.sort(key=lambda t: -t[0])
    return out


def open_from_closed(x: np.ndarray, arm: int = 1, tail: int = 3, cut: int = 0) -> np.ndarray:
    """Open a closed unit-bond chain into a chain with its ends clamped on the z axis.

    Parameters
    ----------
    x : ndarray
        (N_k, 3) closed chain with unit bonds.
    arm : int
        Bonds of each horizontal arm (h ≥ 1).
    tail : int
        How far (in bond lengths) the vertical runs reach beyond the chain's z extent, at
        least. The free beads live between the clamped ends, so the slab must hold the
        relaxed knot: each run also reaches at least L_e/π (the diameter of a circle of the
        excess length, the open trefoil's loop) beyond the chain's z extent.
    cut : int
        Which candidate cut to use (0 = the one with the largest clearance).

    Returns
    -------
    ndarray
        (N, 3) open chain, bead 0 at the bottom of the z axis, bead N−1 at the top.
    """
    x = np.asarray(x, dtype=float)
    if arm < 1 or tail < 2:
        raise ValueError(f"need arm ≥ 1 and tail ≥ 2, got arm={arm}, tail={tail}")
    cands = _best_cut(x)
    if cut >= len(cands):
        raise EmbeddingError("no bond of the chain is an extreme point in any direction")
    _, a, rot, e2 = cands[cut]
    n = len(x)
    y = x @ rot.T
    e = np.array([e2[0], e2[1], 0.0])
    b = (a + 1) % n
    top, bot = y[a], y[b]  # bond points up: y[a] = y[b] + ez
    zmin, zmax = y[:, 2].min(), y[:, 2].max()
    corner_lo = bot + arm * e
    corner_hi = top + arm * e
    excess = n + 2 * arm - 2
    reach = max(tail, int(np.ceil(excess / np.pi)) + 2)
    n_down = int(np.ceil(corner_lo[2] - zmin)) + reach
    n_up = int(np.ceil(zmax - corner_hi[2])) + reach
    # bottom tail (upwards), lower arm (inwards), the knot from b round to a, upper arm, top tail
    lower_line = [corner_lo - k * np.array([0, 0, 1.0]) for k in range(n_down, 0, -1)]
    lower_arm = [bot + k * e for k in range(arm, 0, -1)]
    knot = [y[(b + k) % n] for k in range(n)]  # b, b+1, …, a
    upper_arm = [top + k * e for k in range(1, arm + 1)]
    upper_line = [corner_hi + k * np.array([0, 0, 1.0]) for k in range(1, n_up + 1)]
    pts = np.array(lower_line + lower_arm + knot + upper_arm + upper_line)
    pts[:, 0] -= corner_lo[0]
    pts[:, 1] -= corner_lo[1]
    pts[:, 2] -= pts[0, 2]
    return pts


def embed_open(word, n_strands: int | None = None, n_knot_beads: int = 60, *, arm: int = 1,
               tail: int = 3, d_min: float = D_MIN, expected: str | None = None,
               seed: int | None = None) -> np.ndarray:
    """An open chain of a knot with straight ends clamped on the z axis (paper §VIII).

    Parameters
    ----------
    word
        Braid word of the knot (as for :func:`~stiffknots.knots.embedding.embed_braid`).
    n_strands : int or None
        Number of strands of the braid.
    n_knot_beads : int
        Beads N_k of the closed chain that is cut open; the excess length of the
        result is L_e = N_k + 2·arm − 2.
    arm, tail : int
        See :func:`open_from_closed`.
    d_min : float
        Bead exclusion distance the result satisfies.
    expected : str or None
        If given, the knot type the closure along z must have (verified with topoly);
        candidate cuts are tried until one verifies.
    seed : int or None
        Passed to the closed embedding (a random rotation / bead numbering).

    Returns
    -------
    ndarray
        (N, 3) open chain; bonds are unit, beads 0, 1, N−2, N−1 on the z axis.
    """
    from stiffknots.knots.identify import close_open_chain_along_z, verify_knot

    x = embed_braid(word, n_strands, n_beads=int(n_knot_beads), d_min=d_min, seed=seed)
    last_error = "no cut tried"
    for cut in range(8):
        try:
            pts = open_from_closed(x, arm=arm, tail=tail, cut=cut)
        except EmbeddingError as exc:
            last_error = str(exc)
            break
        if d_min - min_bead_distance(pts, False, 2) > 1e-12:
            last_error = f"cut {cut} violates the bead exclusion"
            continue
        if expected is not None:
            ok, found = verify_knot(close_open_chain_along_z(pts), expected, closed=True)
            if not ok:
                last_error = f"cut {cut} identified as {found}, expected {expected}"
                continue
        return pts
    raise EmbeddingError(f"could not open the chain with straight ends along z: {last_error}")


def pad_open_chain(coords: np.ndarray, n_beads: int) -> np.ndarray:
    """Lengthen both straight ends of an open chain along the z axis to ``n_beads`` beads.

    The added beads continue the clamped end segments (unit bonds on the axis), so the closure
    along z, the excess length and the energy are unchanged; bead 0 is put at z = 0.
    """
    x = np.asarray(coords, dtype=float)
    extra = int(n_beads) - len(x)
    if extra < 0:
        raise ValueError(f"the starting chain has {len(x)} beads, more than n_beads={n_beads}; "
                         "raise n_beads or lower the starting excess length")
    lo, hi = extra // 2, extra - extra // 2
    below = np.zeros((lo, 3))
    below[:, 2] = x[0, 2] - np.arange(lo, 0, -1)
    above = np.zeros((hi, 3))
    above[:, 2] = x[-1, 2] + np.arange(1, hi + 1)
    out = np.vstack([below, x, above])
    out[:, 2] -= out[0, 2]
    out[[0, 1, -2, -1], :2] = 0.0
    return out
