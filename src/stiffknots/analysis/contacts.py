"""Contact maps of a chain: which non-adjacent beads touch (paper §V and §VII).

In the thin limit ``w → 0`` of §V the strands of a knot gather into *line-braids* (several
strands running together along a curve) joined at *multiple points* and *point-braids*
(Fig. 4 c, d and Fig. 5). At finite width these accumulations show up as
*contacts*: pairs of beads that are far apart along the chain but close in space. This module
finds them; :mod:`stiffknots.analysis.structure` turns them into line-braids, point-braids and
the structure graph.

Contact rule
------------
Beads ``i`` and ``j`` are in contact when

* their index separation along the chain is at least ``min_sep`` (cyclic for a closed chain,
  ``min(|i-j|, N-|i-j|)``; plain ``|i-j|`` for an open chain), and
* their distance is at most ``cutoff = factor × d``.

``d`` is the exclusion distance of the chain: the beads of the §VII Monte Carlo chain may not
come closer than ``d = 1/√2`` (bond length 1). The paper notes that this bead rule makes an
excluded-volume tube of non-constant width ``w`` between ``1`` and ``√2`` (§VII), so two strands
lying against each other have their beads ``d`` to ``√2 = 2d`` apart: the default
``factor = 2`` (``cutoff = √2`` for the bead rule) counts exactly the strands that touch within
the widest tube. For a chain made with a tube rule of diameter ``w`` (strands touch at ``≈ w``)
pass ``d = w`` and a smaller factor such as 1.25, or an explicit ``cutoff``.

Default ``min_sep = 5``: beads closer than 5 bonds along the chain are never counted. On an arc
of curvature radius ``R ≥ 1.5`` bonds (every annealed stiff knot: their radius of curvature is
several bonds) the chord between beads 5 bonds apart exceeds 2.9 > √2, so such pairs are never
contacts anyway, while a strand that comes back to touch itself needs a loop of at least
``π × cutoff ≈ 4.4`` bonds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from stiffknots.chain import as_coords as chain_coords

__all__ = [
    "DEFAULT_D",
    "DEFAULT_CONTACT_FACTOR",
    "DEFAULT_MIN_SEP",
    "ContactMap",
    "as_coords",
    "contact_cutoff",
    "contact_map",
    "index_separation",
]

#: Exclusion distance of the §VII bead chain (beads no closer than ``1/√2``, unit bonds).
DEFAULT_D = 1.0 / math.sqrt(2.0)
#: Default contact distance in units of ``d``: ``2d = √2`` is the widest tube of the bead rule.
DEFAULT_CONTACT_FACTOR = 2.0
#: Default minimum index separation of a contact (beads closer along the chain are ignored).
DEFAULT_MIN_SEP = 5


def as_coords(coords: Any, closed: bool = True, *, name: str = "coords") -> np.ndarray:
    """Validate chain coordinates and return them as a C-contiguous float64 ``(N, 3)`` array.

    Parameters
    ----------
    coords : array_like, shape (N, 3)
        Bead positions (a :class:`stiffknots.chain.Chain` is accepted too).
    closed : bool
        Closed chain (needs ``N >= 4``) or open chain (``N >= 3``).
    name : str
        Name used in error messages.

    Raises
    ------
    ValueError
        Not numbers, wrong shape, non-finite values, too few beads.
    """
    arr = chain_coords(coords, name)
    nmin = 4 if closed else 3
    if arr.shape[0] < nmin:
        kind = "closed" if closed else "open"
        raise ValueError(f"a {kind} chain needs at least {nmin} beads for analysis, "
                         f"got {arr.shape[0]}")
    return arr


def _check_positive(value: Any, name: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a positive number, got {value!r}") from None
    if not math.isfinite(v) or v <= 0.0:
        raise ValueError(f"{name} must be a positive finite number, got {value!r}")
    return v


def contact_cutoff(d: float = DEFAULT_D, factor: float = DEFAULT_CONTACT_FACTOR,
                   cutoff: float | None = None) -> float:
    """The contact distance: ``cutoff`` if given, else ``factor × d``.

    Raises
    ------
    ValueError
        ``d``, ``factor`` or ``cutoff`` not a positive finite number.
    """
    if cutoff is not None:
        return _check_positive(cutoff, "cutoff")
    return _check_positive(d, "d") * _check_positive(factor, "factor")


def _check_min_sep(min_sep: Any, n: int, closed: bool) -> int:
    if isinstance(min_sep, bool) or int(min_sep) != min_sep or int(min_sep) < 2:
        raise ValueError(f"min_sep must be an integer >= 2 (beads at index separation 1 are "
                         f"bonded), got {min_sep!r}")
    min_sep = int(min_sep)
    top = n // 2 if closed else n - 1
    if min_sep > top:
        kind = "closed" if closed else "open"
        raise ValueError(f"min_sep = {min_sep} leaves no possible contact on a {kind} chain of "
                         f"{n} beads (the largest index separation is {top})")
    return min_sep


def index_separation(i: Any, j: Any, n: int, closed: bool = True) -> np.ndarray:
    """Index separation of beads ``i`` and ``j`` along the chain (cyclic when ``closed``)."""
    s = np.abs(np.asarray(i) - np.asarray(j))
    return np.minimum(s, n - s) if closed else s


@dataclass(frozen=True, eq=False)
class ContactMap:
    """The contacts of a chain (pairs ``i < j``) and the rule that made them.

    Attributes
    ----------
    n : int
        Number of beads.
    closed : bool
        Closed (cyclic index separation) or open chain.
    cutoff : float
        Contact distance (bond units).
    min_sep : int
        Minimum index separation of a contact.
    i, j : ndarray of int
        The contact pairs, ``i < j``, sorted by ``(i, j)``; shape ``(K,)``.
    dist : ndarray of float
        Their distances; shape ``(K,)``.
    """

    n: int
    closed: bool
    cutoff: float
    min_sep: int
    i: np.ndarray
    j: np.ndarray
    dist: np.ndarray

    @property
    def n_contacts(self) -> int:
        """Number of contact pairs."""
        return int(self.i.shape[0])

    def matrix(self) -> np.ndarray:
        """Dense symmetric boolean contact matrix, shape ``(N, N)``."""
        m = np.zeros((self.n, self.n), dtype=bool)
        m[self.i, self.j] = True
        m[self.j, self.i] = True
        return m

    def in_contact(self) -> np.ndarray:
        """Boolean mask ``(N,)``: the beads with at least one contact."""
        mask = np.zeros(self.n, dtype=bool)
        mask[self.i] = True
        mask[self.j] = True
        return mask

    def directed(self) -> tuple[np.ndarray, np.ndarray]:
        """Both directions of every contact, sorted by (source, target): ``(src, dst)``."""
        src = np.concatenate([self.i, self.j])
        dst = np.concatenate([self.j, self.i])
        order = np.lexsort((dst, src))
        return src[order], dst[order]

    def partners(self, s: int) -> np.ndarray:
        """Sorted indices of the beads in contact with bead ``s``."""
        if not 0 <= int(s) < self.n:
            raise ValueError(f"bead index must be in [0, {self.n - 1}], got {s}")
        return np.sort(np.concatenate([self.j[self.i == s], self.i[self.j == s]]))

    def to_dict(self) -> dict:
        """Plain-data summary (pairs as lists)."""
        return {
            "n": self.n,
            "closed": self.closed,
            "cutoff": self.cutoff,
            "min_sep": self.min_sep,
            "n_contacts": self.n_contacts,
            "pairs": np.column_stack([self.i, self.j]).tolist(),
            "dist": self.dist.tolist(),
        }


def contact_map(coords: Any, closed: bool = True, *, d: float = DEFAULT_D,
                factor: float = DEFAULT_CONTACT_FACTOR, cutoff: float | None = None,
                min_sep: int = DEFAULT_MIN_SEP) -> ContactMap:
    """Contact map of a chain: non-adjacent beads closer than ``cutoff`` (§V, §VII).

    Parameters
    ----------
    coords : array_like, shape (N, 3)
        Bead positions.
    closed : bool, default True
        Closed chain (index separation cyclic) or open chain.
    d : float, default ``1/√2``
        Exclusion distance of the chain (the §VII bead rule).
    factor : float, default 2
        Contact distance in units of ``d`` (``2d = √2``, the widest tube of the bead rule,
        see the module docstring).
    cutoff : float, optional
        Explicit contact distance; overrides ``factor × d``.
    min_sep : int, default 5
        Minimum index separation (``>= 2``) of a contact.

    Returns
    -------
    ContactMap

    Notes
    -----
    Uses a k-d tree (``scipy.spatial.cKDTree.query_pairs``): ``O(N log N + K)`` for ``K``
    close pairs, a few milliseconds for thousands of beads.
    """
    x = as_coords(coords, closed)
    n = x.shape[0]
    rc = contact_cutoff(d, factor, cutoff)
    ms = _check_min_sep(min_sep, n, closed)
    pairs = cKDTree(x).query_pairs(rc, output_type="ndarray")
    if pairs.size == 0:
        empty_i = np.zeros(0, dtype=np.int64)
        return ContactMap(n, bool(closed), rc, ms, empty_i, empty_i.copy(), np.zeros(0))
    a = np.minimum(pairs[:, 0], pairs[:, 1]).astype(np.int64)
    b = np.maximum(pairs[:, 0], pairs[:, 1]).astype(np.int64)
    keep = index_separation(a, b, n, closed) >= ms
    a, b = a[keep], b[keep]
    order = np.lexsort((b, a))
    a, b = a[order], b[order]
    dist = np.linalg.norm(x[a] - x[b], axis=1)
    return ContactMap(n, bool(closed), rc, ms, a, b, dist)
