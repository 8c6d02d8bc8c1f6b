"""Which HOMFLY-PT ties of the tables does each further invariant break?

Usage::

    .venv/bin/python scripts/homfly_ties.py [MAX_CROSSINGS] [--json OUT.json]

For every set of knots through MAX_CROSSINGS (default 12) that share a HOMFLY-PT polynomial in
topoly's table (what :func:`stiffknots.knots.identify.identify` answers as 'a|b'), tries in
turn the invariants :func:`stiffknots.knots.identify.identify_name` uses, on KnotInfo's own
diagrams: the hyperbolic volume (KnotInfo's column; torus and composite knots have none), knot
Floer homology (mirror-insensitive ranks) and the isometry class of the complement (SnapPy,
Gordon–Luecke). Prints each tie with the invariant that breaks it, or 'remains'.
"""

from __future__ import annotations

import json
import sys
import time
from collections import Counter

from stiffknots.knots import exterior as ex
from stiffknots.knots.catalogue import get_knot
from stiffknots.knots.identify import _topoly, crossing_number_of_name, identify_code


def ties(max_crossings: int) -> list[list[str]]:
    _, _, _, polvalues = _topoly()
    groups = set()
    for code in polvalues["HOMFLYPT"]:
        names = identify_code(code, max_crossings=max_crossings).split("|")
        names = [n for n in names if crossing_number_of_name(n) <= max_crossings]
        if len(names) > 1:
            groups.add(tuple(names))
    return sorted((list(g) for g in groups),
                  key=lambda g: (crossing_number_of_name(g[0]), g))


def _vol(name: str):
    return None if "#" in name else ex.knotinfo_volume(get_knot(name))


def _ranks(name: str):
    h = ex._catalogue_diagram(name).hfk()
    r = dict(h["ranks"])
    return min(sorted(r.items()), sorted(ex._mirror_ranks(r).items()))


def split_by(group: list[str]) -> str:
    """The first invariant that tells every member of ``group`` apart, or what is left."""
    vols = [_vol(n) for n in group]
    if all(not ex.volumes_match(a, b) for i, a in enumerate(vols) for b in vols[i + 1:]):
        return "volume"
    prime = [n for n in group if "#" not in n]
    ranks = [repr(_ranks(n)) for n in prime]
    rest = []  # classes still tied after volume and knot Floer homology
    classes: dict = {}
    for n, v in zip(group, vols, strict=True):
        key = ("#" if "#" in n else round(v, 6) if v is not None else None,
               repr(_ranks(n)) if "#" not in n else "")
        classes.setdefault(key, []).append(n)
    rest = [c for c in classes.values() if len(c) > 1]
    if not rest:
        return "volume+HFK" if len(set(ranks)) > 1 else "volume"
    left = []
    for c in rest:
        hyper = [n for n in c if "#" not in n and _vol(n) is not None]
        if len(hyper) != len(c):
            left.append(c)
            continue
        res = [ex.isometry_orientations(ex._catalogue_diagram(a), b)
               for i, a in enumerate(c) for b in c[i + 1:]]
        iso = any(r is None or len(r) > 0 for r in res)  # None: SnapPy undecided
        if iso:
            left.append(c)
    if not left:
        return "volume+HFK+isometry"
    return "remains: " + "; ".join("|".join(c) for c in left)


def main(argv: list[str]) -> None:
    max_c = int(argv[0]) if argv and argv[0].isdigit() else 12
    out = argv[argv.index("--json") + 1] if "--json" in argv else None
    t0 = time.time()
    rows = []
    for g in ties(max_c):
        how = split_by(g)
        rows.append({"tie": "|".join(g), "broken_by": how})
        print(f"{'|'.join(g):40s} {how}", flush=True)
    counts = Counter(r["broken_by"].split(":")[0] for r in rows)
    print(f"{len(rows)} ties through {max_c} crossings: {dict(counts)} "
          f"({time.time() - t0:.0f} s)")
    if out:
        with open(out, "w") as fh:
            json.dump({"max_crossings": max_c, "ties": rows}, fh, indent=1)


if __name__ == "__main__":
    main(sys.argv[1:])
