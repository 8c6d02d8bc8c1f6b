"""Checks of the public parameters, done once at the boundary of every problem.

Each check raises :class:`~stiffknots.errors.InvalidParameter` naming the parameter, the
value given and what is allowed; the command line re-words it with the option's name. The
limits are the documented limits of the package (docs/getting-started.md).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from typing import Any

from stiffknots.errors import InvalidParameter, ParameterConflict
from stiffknots.width import BEAD_D, EXCLUSIONS, MAX_W_OVER_L, Width

#: the documented limits
MIN_BEADS = 8
MAX_BEADS = 20_000
MIN_MOVES = 1_000
MAX_MOVES = 10**12
#: the most replicas of one run (a documented limit)
MAX_REPLICAS = 1_000
MAX_SEED = 2**63 - 1
MIN_EXCESS_LENGTH = 8
MAX_EXCESS_LENGTH = 10_000
MAX_ROUNDS = 100


def integer(name: str, value: Any, lo: int | None = None, hi: int | None = None) -> int:
    """``value`` as an int in [lo, hi]; floats with an integer value are accepted."""
    ok = isinstance(value, numbers.Integral) and not isinstance(value, bool)
    if (not ok and not isinstance(value, bool) and isinstance(value, numbers.Real)
            and math.isfinite(value) and value == int(value)):
        ok, value = True, int(value)
    if not ok or (lo is not None and value < lo) or (hi is not None and value > hi):
        raise InvalidParameter(name, value, _describe("an integer", lo, hi))
    return int(value)


def number(name: str, value: Any, lo: float | None = None, hi: float | None = None, *,
           lo_open: bool = False, hi_open: bool = False) -> float:
    """``value`` as a finite float in the interval (open or closed at each end)."""
    ok = isinstance(value, numbers.Real) and not isinstance(value, bool)
    if ok:
        value = float(value)
        ok = math.isfinite(value)
    if ok and lo is not None:
        ok = value > lo if lo_open else value >= lo
    if ok and hi is not None:
        ok = value < hi if hi_open else value <= hi
    if not ok:
        raise InvalidParameter(name, value, _describe("a finite number", lo, hi, lo_open, hi_open,
                                                       "g"))
    return float(value)


def choice(name: str, value: Any, allowed: Sequence[str]) -> str:
    """``value`` as a str if it is one of ``allowed``."""
    if value not in allowed:
        raise InvalidParameter(name, value, "one of " + ", ".join(map(str, allowed)))
    return str(value)


def beads(value: Any, name: str = "beads") -> int:
    """``value`` as a number of beads in ``[MIN_BEADS, MAX_BEADS]``."""
    return integer(name, value, MIN_BEADS, MAX_BEADS)


def moves(value: Any, name: str = "moves") -> int:
    """``value`` as a number of moves in ``[MIN_MOVES, MAX_MOVES]``."""
    return integer(name, value, MIN_MOVES, MAX_MOVES)


def replicas(value: Any, name: str = "replicas") -> int:
    """``value`` as a number of replicas in [1, :data:`MAX_REPLICAS`]."""
    return integer(name, value, 1, MAX_REPLICAS)


def seed(value: Any, name: str = "seed") -> int:
    """``value`` as a seed in ``[0, MAX_SEED]``."""
    return integer(name, value, 0, MAX_SEED)


def _describe(what: str, lo, hi, lo_open: bool = False, hi_open: bool = False,
              spec: str = ",") -> str:
    """'an integer in [8, 20,000]', 'a number > 0', ... in words."""
    if lo is not None and hi is not None:
        return (f"{what} in {'(' if lo_open else '['}{lo:{spec}}, {hi:{spec}}"
                f"{')' if hi_open else ']'}")
    if lo is not None:
        return f"{what} {'>' if lo_open else '≥'} {lo:{spec}}"
    if hi is not None:
        return f"{what} {'<' if hi_open else '≤'} {hi:{spec}}"
    return what


def checkpoints(jobs) -> None:
    """Before any work: every checkpoint that a resumed job will read must be a readable
    checkpoint of this very run.

    Raises
    ------
    CheckpointError
        For an empty, truncated or junk file, a folder in its place, or a checkpoint written by
        another run (other settings, seed, replica, starting chain or version) — the error the
        worker would raise later, raised now.
    """
    from stiffknots.engine.checkpoints import check_resumable, load_checkpoint, run_meta

    for job in jobs:
        path = job.checkpoint
        if not job.resume or path is None or not (path.exists() or path.is_symlink()):
            continue  # nothing to resume: the job starts afresh
        kind = "tempering" if job.settings.schedule.kind == "tempering" else "anneal"
        _, meta = load_checkpoint(path)
        check_resumable(meta, run_meta(kind, job.settings, job.seed, job.replica, job.coords),
                        path)


#: default relative discretisation error of the N rule (:func:`beads_for_width`)
DISCRETISATION_REL_ERROR = 1e-3
#: what the tube model needs when a problem has no default diameter (``relax``)
_TUBE_NEEDS = "a number in (0, 1/8] with the tube model (its diameter, w = (w/L)·L)"


def width_model(exclusion: str | None = None, *, w: float | None = None,
                w_over_L: float | None = None) -> str:  # noqa: N803
    """The exclusion model that a problem's width parameters ask for, cross-checked before
    its N is known (:func:`width` gives the rules).

    Raises
    ------
    InvalidParameter
        An unknown exclusion model, a w/L outside (0, 1/8].
    ParameterConflict
        ``w`` with ``w_over_L``, or ``w`` with the bead rule.
    """
    if w is not None and w_over_L is not None:
        raise ParameterConflict("{} and {} both set the tube's diameter; give one", "w",
                                "w_over_L")
    if w_over_L is not None:
        number("w_over_L", w_over_L, 0, MAX_W_OVER_L, lo_open=True)
        return "tube"
    exclusion = choice("exclusion", "bead" if exclusion is None else exclusion, EXCLUSIONS)
    if exclusion == "bead" and w is not None:
        raise ParameterConflict("{} applies to {} tube only (the bead rule's distance is "
                                "d = 1/√2); add {} tube or drop {}", "w", "exclusion",
                                "exclusion", "w")
    return exclusion


def width(beads_: int, exclusion: str | None = None, *, w: float | None = None,
          w_over_L: float | None = None, closed: bool = True,  # noqa: N803
          default_w: float | None = BEAD_D) -> Width:
    """The width of a problem from its parameters, cross-checked once.

    ``w_over_L`` sets the tube model (w = (w/L)·L, L = N closed, N − 1 open); ``w`` is the
    tube's diameter in bond lengths and applies to the tube only; the two set one diameter
    and are never given together. A tube with neither has the diameter ``default_w`` (None:
    the problem needs one, e.g. ``relax``). The bead rule has the paper's d = 1/√2 (§VII).

    Raises
    ------
    InvalidParameter
        An unknown exclusion model, a width outside its range (:class:`~stiffknots.width.Width`).
    ParameterConflict
        ``w`` with ``w_over_L``, or ``w`` with the bead rule.
    """
    n = beads(beads_)
    model = width_model(exclusion, w=w, w_over_L=w_over_L)
    if w_over_L is not None:
        return Width.tube(n, w_over_L=w_over_L, closed=closed)
    if model == "tube":
        if w is None and default_w is None:
            raise InvalidParameter("w_over_L", None, _TUBE_NEEDS)
        return Width.tube(n, w=default_w if w is None else w, closed=closed)
    return Width.bead(n, closed=closed)


def w_over_L(value: Any, n_beads: int, name: str = "w_over_L") -> float:  # noqa: N802
    """A tube width ``w/L`` for a closed chain of ``n_beads`` unit bonds (``L = N``): a number
    in ``(0, 1/8]`` whose diameter ``w = (w/L)·N`` is below one bond (a tube as wide as a bond
    would forbid the chain's own bends)."""
    try:
        return Width.tube(n_beads, w_over_L=value).w_over_L
    except InvalidParameter as e:
        raise InvalidParameter(name, e.value, e.allowed, e.note) from None


def beads_for_width(w_over_L: float, epsilon: float,  # noqa: N803
                    rel_error: float = DISCRETISATION_REL_ERROR) -> int:
    """The N rule of the tube model at fixed ``w/L``: the fewest beads whose discretisation
    error stays below ``rel_error`` (relative), and a tube thinner than a bond.

    A chain of N unit bonds is a polygon: its ε lies *below* the continuous curve's by
    ``Δε/ε ≈ ε/(6N²)`` (exact at leading order for the regular polygon of a circular braid,
    ``ε_N = 2π²i² [sin(πi/N)/(πi/N)]²``, (eq. (30)); measured for 3_1 at w/L = 0.002,
    N = 100…300: after the correction the values agree to 3e-4, docs/thin-limit.md). So
    ``N = ⌈(ε / (6 rel_error))^½⌉``, with ``ε`` an upper estimate of the knot's energy (a
    larger ε gives more beads), at least :data:`MIN_BEADS`.

    Raises
    ------
    InvalidParameter
        When that N makes the tube ``w = (w/L)·N`` a bond or wider (w/L too large for the
        requested error).
    """
    rel_error = number("rel_error", rel_error, 0, 0.1, lo_open=True)
    n = max(MIN_BEADS, math.ceil(math.sqrt(epsilon / (6 * rel_error))))
    number("w_over_L", w_over_L, 0, MAX_W_OVER_L, lo_open=True)
    if w_over_L * n >= 1:
        raise InvalidParameter("w_over_L", w_over_L, f"below 1/N = {1 / n:.3g}",
                               f"the N rule needs N = {n} beads for a discretisation error "
                               f"below {rel_error:g}, and the tube must be thinner than a "
                               "bond; or give --beads")
    return n
