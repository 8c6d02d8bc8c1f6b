"""Knot type of a 3D polygon, through the HOMFLY-PT polynomial computed by ``topoly``.

How it works
------------
1. The polygon is handed to topoly's HOMFLY-PT code as a closed chain (``Closure.CLOSED``: topoly
   joins the last point to the first with a straight segment, exactly the closing bond of our
   closed chains; the first point must not be repeated at the end, though a repeat is harmless).
   The polygon is first turned by a fixed generic rotation, because topoly projects along z and
   crashes (segmentation fault, which no ``try`` can catch) on degenerate projections such as
   the stacked strands of our braid embeddings seen from above.
   topoly first simplifies the chain with the KMT triangle-elimination algorithm
   (``ReduceMethod.KMT``: deterministic, removes a bead when the triangle it makes with its
   neighbours is pierced by no other bond, which preserves the knot type), projects it along z
   and computes the HOMFLY-PT polynomial of the diagram.  If the reduced diagram is too large
   for topoly's limit (``max_cross=60``, which in practice allows ~30 crossings), the reduced
   chain is viewed along 24 more fixed directions and the projection with the fewest crossings
   is used, with KMT and then topoly's fast Reidemeister I/II simplification ("EASY"); the full
   Reidemeister simplification was found far too slow on such diagrams.  No random closure is
   involved, and run_parallel/cuda are off: the answer is deterministic. The first attempt
   calls topoly's compiled steps directly (:mod:`stiffknots.knots.topoly_core`: the same code
   as :func:`topoly.homfly`, without its Python layer's 1–2 s import and ≈ 0.1–0.5 s a call);
   only the rare diagram too large for it goes through topoly's own API.
2. The polynomial (chiral: mirror images have mirrored polynomials) is looked up in topoly's
   bundled HOMFLY-PT table (all prime knots through 12 crossings plus many composite knots and
   links), without topoly's ``minimal`` filter, which silently drops the more complicated
   candidates of an ambiguous polynomial.
3. Names are made mirror-insensitive (the +/- chirality marks are dropped; for composite knots
   the sign pattern is kept up to a global mirror, so the granny ``3_1#3_1`` and the square knot
   ``3_1#-3_1`` stay distinct) and written as in KnotInfo (``3_1``, ``10_132``, ``11n_34``).

Why HOMFLY-PT
-------------
It is the strongest invariant for which topoly has a complete table: the Alexander polynomial
(also in topoly) does not even separate 5_1 from 10_132, 6_1 from 9_46, etc., the Jones
polynomial confuses more pairs.  The HOMFLY-PT polynomial separates all prime knots through 10
crossings except these unordered pairs (mirror-insensitive), which no polynomial in topoly can
separate:

    5_1 | 10_132,  8_8 | 10_129,  8_16 | 10_156,  10_25 | 10_56,  10_40 | 10_103

plus 9_12 | 4_1#5_2 (a composite knot), and through 12 crossings a few more coincidences with
11- and 12-crossing knots (e.g. 6_2 | 12n_25, 7_1 | 12n_749).  :func:`identify` reports such
cases honestly as all candidates joined by ``'|'``, sorted by crossing number (e.g.
``'5_1|10_132'``); ``max_crossings=10`` keeps only the candidates through 10 crossings.  A
polynomial not in the table gives ``'unknown'`` (a knot with more than 12 crossings, or a
composite/link not tabulated).

Chirality: topoly's answer is chiral (it tells the mirror images of 3_1 apart), but topoly's
+/- convention is not guaranteed to coincide with KnotInfo's, and the paper's energies do not
depend on chirality, so all names returned by :func:`identify` are mirror-insensitive.

One name per knot: :func:`identify_name`
----------------------------------------
:func:`identify_name` (and :func:`identify_details`, which also says how) breaks the HOMFLY-PT
ties with invariants of the knot complement computed from a diagram of the polygon
(:mod:`stiffknots.knots.exterior`): the hyperbolic volume (SnapPy) against KnotInfo's volume
column, knot Floer homology, and the isometry of the complement with the complement of each
candidate's KnotInfo diagram. Through 10 crossings every tie above is broken by the volume
(torus and composite knots are not hyperbolic). It also gives the chirality relative to
KnotInfo's diagram (``pd_notation``): ``'+'`` the same knot, ``'-'`` its mirror image, None for
amphichiral knots, the unknot, composite knots, or when no invariant decides. topoly's own
+/- marks are not used for this: they follow the orientation of the diagrams of topoly's
table, which matches KnotInfo's for some knots and not for others (measured in the tests).

Open chains (paper §VIII, straight tails along z) are closed by
:func:`close_open_chain_along_z` before identification.

A polygon of :data:`CHILD_FROM` vertices or more is identified in a forked child process:
topoly's compiled reduction takes seconds to minutes there, and a signal that arrives while
compiled code runs waits for it; the caller waits for the child instead, and Ctrl-C or
``kill PID`` stop it at once (the child is killed).
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import signal
import threading
from dataclasses import dataclass

import numpy as np

from stiffknots.errors import IdentificationError
from stiffknots.knots.topoly_core import homfly_kmt, kmt_reduce, polvalues

__all__ = [
    "IdentificationError",
    "KnotNaming",
    "identify",
    "identify_details",
    "identify_name",
    "identify_code",
    "verify_knot",
    "normalize_name",
    "close_open_chain_along_z",
    "homfly_code",
    "crossing_number_of_name",
]

# topoly's limit (it counts each crossing about twice); the HOMFLY-PT cost grows
# exponentially with the crossings of the reduced diagram
_MAX_CROSS = 60
_LOCK = threading.Lock()

#: from this many vertices the invariants are computed in a forked child (module docstring)
CHILD_FROM = 2_000
_IN_CHILD = [False]  # True in such a child: it computes in place


def _big(x) -> bool:
    return len(x) >= CHILD_FROM and hasattr(os, "fork") and not _IN_CHILD[0]


# --------------------------------------------------------------------------------------------
# names
# --------------------------------------------------------------------------------------------

_PRIME = re.compile(r"^([0-9]+)\s*([an]?)\s*[_.]?\s*([0-9]+)$", re.IGNORECASE)


def _normalize_prime(name: str) -> tuple[int, str]:
    """(sign, canonical prime name) with sign +1/-1 from a leading +/-, 0 if none."""
    s = name.strip()
    sign = 0
    while s and s[0] in "+-":
        sign = 1 if s[0] == "+" else -1
        s = s[1:]
    s = s.strip().rstrip("*!")
    if s.lower() in ("0_1", "0.1", "01", "unknot", "0"):
        return 0, "0_1"
    if s.upper().startswith("K") and len(s) > 1 and s[1].isdigit():
        s = s[1:]
    m = _PRIME.match(s)
    if not m:
        return sign, s
    c, letter, i = int(m.group(1)), m.group(2).lower(), int(m.group(3))
    if letter:
        return sign, f"{c}{letter}_{i}"
    return sign, f"{c}_{i}"


def crossing_number_of_name(name: str) -> int:
    """Total crossing number encoded in a (normalized) knot name, e.g. '5_2#4_1' -> 9."""
    total = 0
    for comp in name.split("#"):
        m = re.match(r"^[-+]?([0-9]+)", comp.strip())
        total += int(m.group(1)) if m else 0
    return total


def _natural_key(name: str):
    parts = re.split(r"([0-9]+)", name)
    return (crossing_number_of_name(name), [int(p) if p.isdigit() else p for p in parts])


def normalize_name(name: str) -> str:
    """Canonical mirror-insensitive knot name in KnotInfo style.

    '4.1', '4_1', 'K4_1', '+4_1', '-4_1' -> '4_1';  '12n25', '12n_25' -> '12n_25';
    '0_1', 'unknot' -> '0_1'; composite knots 'a#b' keep their relative chirality
    ('+3_1#-3_1' -> '3_1#-3_1', '-3_1#-3_1' -> '3_1#3_1'); candidate lists 'a|b' are
    normalized element-wise, deduplicated and sorted by crossing number.
    """
    name = str(name).strip()
    if "|" in name:
        cands = {normalize_name(c) for c in name.split("|") if c.strip()}
        return "|".join(sorted(cands, key=_natural_key))
    if name.lower() in ("unknown", "tmc", "toomanycrossings"):
        return "unknown"
    comps = [_normalize_prime(c) for c in name.split("#")]
    if len(comps) == 1:
        return comps[0][1]
    comps = [(sg, n) for sg, n in comps if n != "0_1"] or [(0, "0_1")]
    if len(comps) == 1:
        return comps[0][1]
    # choose the global mirror whose sign pattern (components in canonical order) is largest
    def render(flip: bool):
        out = [(n, -sg if flip else sg) for sg, n in comps]
        out.sort(key=lambda t: (_natural_key(t[0]), -t[1]))
        return out

    best = max(render(False), render(True), key=lambda r: [sg for _, sg in r])
    return "#".join(("-" if sg < 0 else "") + n for n, sg in best)


# --------------------------------------------------------------------------------------------
# topoly
# --------------------------------------------------------------------------------------------


@contextlib.contextmanager
def _keep_stdin():
    """Give file descriptor 0 back after a topoly call that closed it.

    topoly's compiled HOMFLY-PT code (``liblmpoly``) closes descriptor 0 on every call, whatever
    it is. Left closed, the next file or socket the process opens gets number 0 — and the next
    call closes *that*: a checkpoint being written, or a Dask connection (seen as "fd 0 added
    twice" and "Bad file descriptor" in a sweep's client). So descriptor 0 is duplicated before
    the call and put back after it; if another thread took number 0 in the meantime (a socket
    opened during the call), it is left alone — only then can the race still bite.
    """
    try:
        saved = os.dup(0)
    except OSError:  # already closed: hold number 0 with /dev/null for the call to close
        fd = os.open(os.devnull, os.O_RDONLY)
        if fd != 0:
            os.close(fd)
            yield
            return
        saved = os.dup(0)
    try:
        yield
    finally:
        try:
            os.fstat(0)
        except OSError:  # closed by the call: put the original back
            os.dup2(saved, 0)
        os.close(saved)


@contextlib.contextmanager
def _quiet():
    """Silence Python-level output on stdout/stderr during topoly calls, and keep descriptor
    0 open (:func:`_keep_stdin`).

    Only the Python streams are redirected: redirecting the file descriptors themselves breaks
    topoly's compiled extension (it then closes a descriptor it does not own).  In all our
    tests the compiled code printed nothing.
    """
    with _LOCK, _keep_stdin(), _keep_sigterm():
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            yield


@contextlib.contextmanager
def _keep_sigterm():
    """Give SIGTERM its disposition back after a topoly call.

    topoly's HOMFLY-PT library (``liblmpoly``) installs a C handler for SIGTERM (``signal``,
    its ``handle_sigterm``, which sets a flag of its own and reinstalls itself) and leaves it:
    afterwards ``kill PID`` no longer stopped a run (the handler swallows the signal), while
    Python still reported the default. The disposition Python knows is reinstalled after the
    call (in the main thread, the only one that may set handlers; in other threads
    :func:`homfly_code` runs topoly in a forked child anyway). During the call SIGTERM is
    blocked, so that one sent then waits and reaches that disposition afterwards instead of
    topoly's handler (a ``kill PID`` during a knot check was lost: the command line's stop,
    :mod:`stiffknots.cli.main`, never came). The mask is the calling thread's: it holds the
    signal back because topoly runs here only while this is the process's one Python thread
    (:func:`homfly_code` forks otherwise) and the threads numpy's OpenBLAS starts block SIGTERM
    when numpy loads with stiffknots (``stiffknots._numpy_threads_without_sigterm``; numpy
    loaded before stiffknots keeps threads that may take it during the call).
    """
    main = threading.current_thread() is threading.main_thread()
    saved = signal.getsignal(signal.SIGTERM) if main else None
    mask = main and hasattr(signal, "pthread_sigmask")
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGTERM}) if mask else None
    try:
        yield
    finally:
        if main and saved is not None:
            signal.signal(signal.SIGTERM, saved)
        if mask:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)


def _topoly():
    with _quiet():
        import topoly  # noqa: F401  (import is slow, ~1 s: tables)
        from topoly.params import Closure, ReduceMethod
        from topoly.polvalues import polvalues
    return topoly, Closure, ReduceMethod, polvalues


def close_open_chain_along_z(coords, far: float | None = None) -> np.ndarray:
    """Close an open chain far out along z, as for the open knots of the paper (§VIII).

    The end with the larger z is continued straight up to ``z_max + far``, the other end
    straight down to ``z_min - far``; the two far points are joined through two more points far
    out sideways (at distance ``far`` beyond the chain's extent in x), so the added arc passes
    nowhere near the chain.  This is the natural closure when the tails are straight along z and
    the ends are the extreme points in z (then it adds no crossing with the chain); for other
    chains it is one deterministic choice among many.

    Parameters
    ----------
    coords : array (N, 3)
        Open chain, beads 0 .. N-1.
    far : float, optional
        How far to go (default 10 × (extent of the chain + 1)).

    Returns
    -------
    numpy.ndarray (N + 4, 3)
        Closed polygon (last point joined to the first).
    """
    x = np.asarray(coords, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != 3 or len(x) < 2:
        raise ValueError(f"expected coordinates of shape (N, 3) with N >= 2, got {x.shape}")
    lo, hi = x.min(axis=0), x.max(axis=0)
    if far is None:
        far = 10.0 * (float(np.max(hi - lo)) + 1.0)
    top, bot = hi[2] + far, lo[2] - far
    side = hi[0] + far
    first, last = x[0], x[-1]
    # a chain that runs upwards sends its last end to +z, one that runs downwards to −z
    z_last, z_first = (top, bot) if last[2] >= first[2] else (bot, top)
    tail = [[last[0], last[1], z_last], [side, last[1], z_last],
            [side, first[1], z_first], [first[0], first[1], z_first]]
    return np.vstack([x, np.asarray(tail)])


def homfly_code(
    coords, closed: bool = True, *, max_cross: int = _MAX_CROSS, n_directions: int = 24
) -> str:
    """topoly's code of the HOMFLY-PT polynomial of the polygon (chiral); see
    ``_homfly_code()`` for the method.

    In a process with other threads running (a Dask worker: its event loop opens and uses
    sockets all the time) the computation runs in a forked child (``_in_child()``): topoly's
    compiled code closes descriptor 0 whatever it is, and while it is closed another thread's new
    socket takes that number — the next call then closes a live connection (seen as "Bad file
    descriptor" in the worker's heartbeats). ``_keep_stdin()`` alone cannot close that race.
    """
    if _threaded() or _big(coords):
        return _in_child(lambda: _homfly_code(coords, closed, max_cross=max_cross,
                                              n_directions=n_directions))
    return _homfly_code(coords, closed, max_cross=max_cross, n_directions=n_directions)


def _threaded() -> bool:
    return hasattr(os, "fork") and threading.active_count() > 1


#: forks of :func:`_in_child`, one at a time (two threads checking knots at once)
_FORK_LOCK = threading.Lock()
#: the process that is forking in :func:`_in_child` (None: none is)
_FORKING: list[int | None] = [None]


def _fork_quiet_hook(unraisable) -> None:
    """``sys.unraisablehook`` of a process that forks in :func:`_in_child`: in such a child,
    until its own code runs, an error of an after-fork handler is not reported. Python's own
    (``threading._after_fork``) re-initialises the locks of the parent's other threads, which
    the child does not have, and can fail at it in a process with several threads ("SystemError
    … _thread.RLock", tracebacks on the user's stderr with two ``sk.anneal`` calls in two
    threads); the child runs topoly alone and leaves by ``os._exit``. Everything else goes to
    the hook that was there before."""
    if _FORKING[0] is not None and os.getpid() != _FORKING[0]:
        return
    _PREVIOUS_HOOK[0](unraisable)


_PREVIOUS_HOOK: list = [None]


def _in_child(fn):
    """``fn()`` in a forked child process; its result (or exception) comes back pickled
    through a pipe. The child runs nothing but ``fn`` and leaves by ``os._exit``; what its
    after-fork handlers report is not shown (:func:`_fork_quiet_hook`)."""
    import pickle
    import sys

    with _FORK_LOCK:
        if sys.unraisablehook is not _fork_quiet_hook:
            _PREVIOUS_HOOK[0], sys.unraisablehook = sys.unraisablehook, _fork_quiet_hook
        r, w = os.pipe()
        _FORKING[0] = os.getpid()
        try:
            pid = os.fork()
        finally:
            if os.getpid() == _FORKING[0]:  # the parent (the child keeps it: its hook)
                _FORKING[0] = None
    if pid == 0:  # pragma: no cover (the child)
        code = 0
        _FORKING[0] = None  # the child's own errors are reported again
        _IN_CHILD[0] = True
        try:
            os.close(r)
            try:
                out = ("ok", fn())
            except BaseException as exc:  # noqa: BLE001 — sent to the parent, raised there
                out = ("err", exc)
            try:
                data = pickle.dumps(out)
            except Exception as exc:  # noqa: BLE001
                data = pickle.dumps(("err", IdentificationError(f"{type(exc).__name__}: {exc}")))
            view = memoryview(data)
            while view:
                view = view[os.write(w, view):]
        except BaseException:  # noqa: BLE001
            code = 1
        finally:
            os._exit(code)
    os.close(w)
    chunks = []
    try:
        with os.fdopen(r, "rb") as f:
            while chunk := f.read(1 << 16):
                chunks.append(chunk)
        _, status = os.waitpid(pid, 0)
    except BaseException:  # Ctrl-C, kill PID (KeyboardInterrupt): the child stops too
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGKILL)
        with contextlib.suppress(OSError):
            os.waitpid(pid, 0)
        raise
    if not chunks:
        raise IdentificationError(
            f"the HOMFLY-PT computation died (child status {status}): topoly crashed")
    kind, value = pickle.loads(b"".join(chunks))
    if kind == "err":
        raise value
    return value


def _homfly_code(
    coords, closed: bool = True, *, max_cross: int = _MAX_CROSS, n_directions: int = 24
) -> str:
    """topoly's code of the HOMFLY-PT polynomial of the polygon (chiral), e.g. for 4_1
    '[-1 0 [-1] 0 -1]|[0]|[1]'.

    topoly projects along z after KMT reduction; if that diagram has more than ``max_cross``
    crossings, the KMT-reduced chain is viewed along ``n_directions`` further (fixed,
    pseudo-random) directions and the one with the fewest crossings is used.  Raises
    :class:`IdentificationError` if no diagram small enough is found.
    """
    x = np.asarray(coords, dtype=np.float64)
    if not closed:
        x = close_open_chain_along_z(x)
    if x.ndim != 2 or x.shape[1] != 3:
        raise ValueError(f"expected coordinates of shape (N, 3), got {x.shape}")
    if len(x) < 3:
        return "[[1]]"
    if not np.all(np.isfinite(x)):
        raise ValueError("coordinates contain NaN or infinity")
    if len(x) > 3 and np.allclose(x[0], x[-1], atol=0.0, rtol=0.0):
        x = x[:-1]
    # A fixed generic rotation first: topoly projects along z and crashes (segmentation fault)
    # on degenerate projections, e.g. strands stacked exactly above each other as in our braid
    # embeddings, or a planar polygon seen edge-on.
    x = x @ _GENERIC_ROTATION.T
    try:
        with _quiet():   # topoly's compiled steps alone: topoly_core (the same code)
            code = homfly_kmt(x, max_cross)
    except Exception as exc:  # topoly raises assorted exceptions
        raise IdentificationError(
            f"topoly could not compute the HOMFLY-PT polynomial: {exc}") from exc
    if code is not None:
        return code
    # Too many crossings in the z projection even after KMT: reduce once, then look for the
    # projection direction with the fewest crossings among a fixed set of rotations (topoly's
    # own API: rare, and its EASY simplification is Python code of topoly's).
    topoly, Closure, ReduceMethod, _ = _topoly()
    with _quiet():
        y = kmt_reduce(x)
    if y.ndim != 2 or y.shape[1] != 3 or len(y) < 3:
        y = x
    rng = np.random.default_rng(12345)
    best, best_rot = _projected_crossings(y), np.eye(3)
    for _ in range(n_directions):
        rot = _rotation(rng)
        c = _projected_crossings(y @ rot.T)
        if c < best:
            best, best_rot = c, rot
    for method in (ReduceMethod.KMT, ReduceMethod.EASY):
        code = _homfly_once(topoly, Closure, ReduceMethod, y @ best_rot.T, max_cross, method)
        if code is not None:
            return code
    raise IdentificationError(
        f"HOMFLY-PT polynomial not computed: the chain is too entangled, its best projection "
        f"(of {n_directions + 1} tried) still has {best} crossings after KMT reduction "
        f"(limit max_cross={max_cross})"
    )


def _homfly_once(topoly, Closure, ReduceMethod, x, max_cross, method=None):
    method = ReduceMethod.KMT if method is None else method
    try:
        with _quiet():
            code = topoly.homfly(
                np.asarray(x).tolist(),
                closure=Closure.CLOSED,
                reduce_method=method,
                max_cross=max_cross,
                translate=False,
                poly_reduce=True,
                run_parallel=False,
                cuda=False,
            )
    except Exception as exc:  # topoly raises assorted exceptions
        raise IdentificationError(
            f"topoly could not compute the HOMFLY-PT polynomial: {exc}") from exc
    code = str(code).strip()
    if "TMC" in code or "Err" in code:
        return None
    return code


def _rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


_GENERIC_ROTATION = _rotation(np.random.default_rng(20070101))


def _projected_crossings(x: np.ndarray) -> int:
    """Number of crossings of the closed polygon projected on the xy plane."""
    p = np.asarray(x)[:, :2]
    q = np.roll(p, -1, axis=0)
    n = len(p)

    def orient(a, b, c):
        return (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1]) - (b[..., 1] - a[..., 1]) * (
            c[..., 0] - a[..., 0]
        )

    count = 0
    for i in range(n - 2):
        j = np.arange(i + 2, n if i > 0 else n - 1)
        a, b, c, d = p[i], q[i], p[j], q[j]
        hit = (orient(a, b, c) * orient(a, b, d) < 0) & (orient(c, d, a) * orient(c, d, b) < 0)
        count += int(np.count_nonzero(hit))
    return count


def identify(coords, closed: bool = True, *, max_crossings: int | None = None) -> str:
    """Knot type of a 3D polygon, mirror-insensitive, in KnotInfo naming.

    Parameters
    ----------
    coords : array (N, 3)
        Bead coordinates.  A closed chain is closed by the bond from the last bead to the first
        (do not repeat the first bead; a repeat is tolerated).
    closed : bool
        If False, the open chain is first closed by :func:`close_open_chain_along_z`.
    max_crossings : int, optional
        Keep only candidates with at most this many crossings (if some remain).  With 10,
        the 11- and 12-crossing knots that share a HOMFLY-PT polynomial with a smaller knot are
        dropped (e.g. '6_2|12n_25' -> '6_2'); the five 10-crossing pairs and
        9_12|4_1#5_2 remain ambiguous.

    Returns
    -------
    str
        '0_1', '3_1', '8_19', '5_2#4_1', ...; if the HOMFLY-PT polynomial is shared by several
        tabulated knots, all candidates joined by '|', sorted by crossing number
        (e.g. '5_1|10_132'); 'unknown' if the polynomial is not in topoly's table
        (more than 12 crossings, or an untabulated composite).

    Raises
    ------
    IdentificationError
        If the polynomial cannot be computed (far too many crossings after simplification).
    """
    return identify_code(homfly_code(coords, closed=closed), max_crossings=max_crossings)


def identify_code(code: str, *, max_crossings: int | None = None) -> str:
    """The knot names of a HOMFLY-PT polynomial (topoly's code, :func:`homfly_code`), as
    :func:`identify` returns them: mirror-insensitive KnotInfo names joined by '|', or
    'unknown' when the polynomial is not in topoly's table."""
    raw = polvalues()["HOMFLYPT"].get(code, "Unknown")
    if raw == "Unknown":
        return "unknown"
    cands = [c for c in raw.split("|") if "U" not in c and not c.lstrip("+-").startswith("L")]
    if not cands:  # only links/unlinks share the polynomial: not a knot we can name
        return "unknown"
    names = normalize_name("|".join(cands)).split("|")
    if max_crossings is not None:
        kept = [n for n in names if crossing_number_of_name(n) <= max_crossings]
        names = kept or names
    return "|".join(names)


def verify_knot(coords, expected: str, closed: bool = True) -> tuple[bool, str]:
    """Does the polygon have knot type ``expected`` (mirror-insensitive)?

    Returns ``(matches, found)`` where ``found`` is :func:`identify`'s answer; ``matches`` is
    True when the normalized expected name is one of the candidates, i.e. when the polygon's
    HOMFLY-PT polynomial is that of ``expected`` ('5_1' matches '5_1|10_132': the invariant
    cannot tell these two apart, see the module docstring).
    """
    found = identify(coords, closed=closed)
    want = normalize_name(expected)
    cands = found.split("|")
    return (want in cands, found)


# --------------------------------------------------------------------------------------------
# one name per knot
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class KnotNaming:
    """What :func:`identify_details` found.

    Attributes
    ----------
    name : str or None
        One catalogue name (mirror-insensitive, KnotInfo style), or None when a tie remains or
        the knot is not in the tables.
    candidates : tuple of str
        The names still possible: ``(name,)`` when named; several when a tie remains; empty
        when the polynomial is not in the tables.
    chirality : str or None
        ``'+'``, ``'-'`` or None, relative to KnotInfo's diagram of ``name`` (its ``pd_notation``):
        ``'+'`` the same knot, ``'-'`` the mirror image; None for amphichiral knots, the unknot,
        composite knots, ties, or when no invariant tells.
    homfly : str
        :func:`identify`'s answer (the HOMFLY-PT candidates, '|'-joined).
    decided_by : tuple of str
        The invariants that narrowed the candidates down, in order.
    chirality_by : str
        How the chirality was decided (or why not).
    volume : float or None
        Hyperbolic volume of the complement (SnapPy), None if not hyperbolic or not computed.
    crossings : int or None
        Crossings of the simplified diagram of the polygon (an upper bound on the crossing
        number), None if not computed.
    """

    name: str | None
    candidates: tuple[str, ...]
    chirality: str | None
    homfly: str
    decided_by: tuple[str, ...] = ()
    chirality_by: str = ""
    volume: float | None = None
    crossings: int | None = None

    def as_dict(self) -> dict:
        return {"knot": self.name, "candidates": list(self.candidates),
                "chirality": self.chirality, "homfly_candidates": self.homfly,
                "decided_by": list(self.decided_by), "chirality_by": self.chirality_by,
                "volume": self.volume, "diagram_crossings": self.crossings}


def identify_name(coords, closed: bool = True) -> tuple[str | None, tuple[str, ...], str | None]:
    """One name for the knot type of a polygon: ``(name, candidates, chirality)``.

    ``name`` is one catalogue name where the invariants can tell (HOMFLY-PT polynomial, then
    the hyperbolic volume, knot Floer homology and the isometry class of the complement), None
    where a tie remains (then ``candidates`` lists the names still possible) or the knot is not
    in the tables (``candidates`` empty). ``chirality`` is ``'+'`` (KnotInfo's knot), ``'-'``
    (its mirror image) or None (amphichiral, unknot, composite, tie, or undecided). See
    :func:`identify_details` for how each was decided.
    """
    r = identify_details(coords, closed=closed)
    return r.name, r.candidates, r.chirality


def identify_details(coords, closed: bool = True) -> KnotNaming:
    """:func:`identify_name` with the evidence: a :class:`KnotNaming`.

    Raises
    ------
    IdentificationError
        If the HOMFLY-PT polynomial cannot be computed (far too many crossings).
    ValueError
        If the polygon meets itself (no knot type):
        :class:`~stiffknots.knots.singular.SingularCurveError`.
    """
    from stiffknots.knots import exterior as ex
    from stiffknots.knots.singular import refuse_singular, rescaled

    # a knot type is scale invariant, floating point is not: 1e300 overflowed to 0_1
    x = rescaled(np.asarray(coords, dtype=np.float64))
    if not closed:
        x = close_open_chain_along_z(x)
    refuse_singular(x)  # its projection would resolve the crossing either way
    if _big(x):  # minutes of compiled code: in a child, the caller stays stoppable
        return _in_child(lambda: identify_details(x, closed=True))
    homfly = identify(x, closed=True)
    steps = ["HOMFLY-PT polynomial (topoly)"]
    if homfly == "unknown":
        return KnotNaming(None, (), None, homfly, tuple(steps),
                          "no name: the polynomial is not in the tables (beyond 12 crossings, "
                          "or an untabulated composite knot)")
    cands = homfly.split("|")
    if cands == ["0_1"]:
        return KnotNaming("0_1", ("0_1",), None, homfly, tuple(steps), "the unknot")
    d = ex.diagram_of(x)
    vol = d.volume()
    if len(cands) > 1:
        kept = [c for c in cands if _volume_fits(ex, d, vol, c)]
        if kept and len(kept) < len(cands):
            steps.append("hyperbolic volume of the complement (SnapPy) vs KnotInfo")
        cands = kept or cands
    if len(cands) > 1:
        kept = [c for c in cands if ex.hfk_matches(d, c) is not False]
        if kept and len(kept) < len(cands):
            steps.append("knot Floer homology (knot_floer_homology)")
        cands = kept or cands
    if len(cands) > 1 and vol is not None:
        kept = [c for c in cands if "#" not in c and ex.isometry_orientations(d, c)]
        if kept and len(kept) < len(cands):
            steps.append("isometry of the complements (SnapPy)")
        cands = kept or cands
    if len(cands) == 1 and "#" not in cands[0]:
        want = ex.knotinfo_volume(_knot(cands[0]))
        if vol is not None and want is not None and not ex.volumes_match(vol, want):
            return KnotNaming(None, (), None, homfly, tuple(steps),
                              f"no name: the HOMFLY-PT polynomial is that of {cands[0]} but the "
                              f"volume {vol:.6f} is not its {want:.6f} (a knot beyond the "
                              "tables?)", vol, d.crossings)
    if len(cands) > 1:
        return KnotNaming(None, tuple(cands), None, homfly, tuple(steps),
                          "not decided: the knot type is not decided", vol, d.crossings)
    name = cands[0]
    chir, how = ex.chirality_of(d, name)
    return KnotNaming(name, (name,), chir, homfly, tuple(steps), how, vol, d.crossings)


def _knot(name: str):
    from stiffknots.knots.catalogue import get_knot

    return get_knot(name)


def _volume_fits(ex, d, vol: float | None, name: str) -> bool:
    """Is the measured volume (None: not hyperbolic) that of the candidate? A non-hyperbolic
    candidate also needs positive evidence: a diagram that splits as a connected sum for a
    composite knot, equal knot Floer homology for a torus knot."""
    if "#" in name:
        return vol is None and d.deconnects() >= 2
    want = ex.knotinfo_volume(_knot(name))
    if not ex.volumes_match(vol, want):
        return False
    return want is not None or ex.hfk_matches(d, name) is True
