"""Can topoly's chiral HOMFLY-PT names (+8_8 / -8_8) be matched with KnotInfo's chirality?

Usage::

    .venv/bin/python scripts/chirality_conventions.py [MAX_CROSSINGS]   # default 10

For every chiral prime knot through MAX_CROSSINGS: the closure of KnotInfo's braid word
(:func:`stiffknots.knots.starts.start_chain`) is identified by
:func:`stiffknots.knots.identify.identify_details`, whose chirality is measured against
KnotInfo's own diagram (``pd_notation``) through the complement (SnapPy) or τ; the script then
reads the sign topoly's table gives the polygon's polynomial, and counts how often topoly's
'+' is KnotInfo's knot. It also reports knots whose braid word (as embedded) is the mirror of
their PD diagram.
"""

from __future__ import annotations

import sys
import time

from stiffknots.errors import EmbeddingError
from stiffknots.knots.catalogue import catalogue
from stiffknots.knots.embedding import minimal_beads
from stiffknots.knots.identify import _topoly, homfly_code, identify_details, normalize_name
from stiffknots.knots.starts import start_chain


def topoly_sign(code: str, name: str) -> str | None:
    _, _, _, polvalues = _topoly()
    for c in polvalues["HOMFLYPT"].get(code, "").split("|"):
        if "#" not in c and normalize_name(c) == name:
            return c[0] if c[0] in "+-" else None
    return None


def main(argv):
    max_c = int(argv[0]) if argv else 10
    t0 = time.time()
    same = opposite = amph = undecided = 0
    mirrored_words = []
    disagree = []
    unsure = []
    for k in catalogue(max_c):
        if k.crossing_number < 3:
            continue
        try:
            x = start_chain(k, "braid", 150)
        except EmbeddingError:
            x = start_chain(k, "braid", minimal_beads(k.braid_word, k.braid_strands))
        r = identify_details(x)
        if r.name != k.name:
            print(f"{k.name}: identified as {r.name} {r.candidates}")
            continue
        if r.chirality is None:
            amph += "amphi" in r.chirality_by
            if "amphi" not in r.chirality_by:
                undecided += 1
                unsure.append(f"{k.name} (stiffknots: {r.chirality_by})")
            continue
        if r.chirality == "-":
            mirrored_words.append(k.name)
        ts = topoly_sign(homfly_code(x), k.name)
        if ts is None:
            undecided += 1
            unsure.append(f"{k.name} (topoly's name has no sign)")
        elif ts == r.chirality:
            same += 1
        else:
            opposite += 1
            disagree.append(k.name)
    print(f"through {max_c} crossings: topoly's sign = KnotInfo's chirality for {same} knots, "
          f"the opposite for {opposite}; amphichiral {amph}; undecided {undecided} "
          f"({time.time() - t0:.0f} s)")
    print("topoly's sign opposite to KnotInfo:", " ".join(disagree))
    print("undecided:", "; ".join(unsure))
    print("braid word (as embedded) is the mirror of KnotInfo's PD:", " ".join(mirrored_words))


if __name__ == "__main__":
    main(sys.argv[1:])
