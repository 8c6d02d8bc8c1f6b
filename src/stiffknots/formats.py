"""Chain file formats: every reader and writer (:func:`save` / :func:`load` dispatch on the
suffix).

``.xyz``
    Plain text, one bead per line. Two dialects are written (and both, plus plain ``x y z``
    lines, are read):

    * ``dialect="topoly"`` (default): topoly's *nxyz* format, ``"i x y z"`` with a 1-based
      integer index, exactly what ``topoly`` writes itself. A closed chain repeats its first line
      (same index, same coordinates) at the end, which is how topoly recognises a closed chain
      (its ``check_close`` finds the arc returning to its first vertex). No header and no comment
      lines: topoly's format sniffing would misread them.
    * ``dialect="kymoknot"``: KymoKnot's input format, a first line with the number of lines that
      follow, then ``"x y z"`` lines separated by single spaces (KymoKnot tokenises on ``' '``
      only and refuses a fourth column). A ring repeats its first bead at the end (KymoKnot's
      ``KymoKnot_ring.x`` requires first and last lines to coincide; ``KymoKnot_linear.x``
      requires them to differ).

    No single file satisfies both readers (topoly would read KymoKnot's count line as a bead,
    KymoKnot rejects the index column), hence the two dialects. Floats are written with
    ``repr`` (shortest round-trip representation), so coordinates survive a round trip exactly.
    The xyz formats store no metadata; use ``.json`` or ``.npz`` for that.
``.json``
    ``{"format": "stiffknots-chain", "version": 1, "closed": ..., "coords": [[x, y, z], ...],
    "meta": {...}, "stiffknots_version": ...}``; exact float round trip.
``.npz``
    NumPy archive with ``coords``, ``closed`` and ``meta`` (a JSON string); no pickles.
``.obj``
    Wavefront OBJ polylines as written by ElasticKnots: ``v x y z`` vertex lines and ``l i j ...``
    line elements (1-based, negative indices relative). Reading orders the vertices along the
    line elements and detects closure; writing emits one ``l i i+1`` element per bond.

Unreadable or corrupt files raise :class:`ChainFormatError` (a ``ValueError``) naming the file
and what was wrong.
"""

from __future__ import annotations

import json
import math
import os
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from stiffknots._json import json_default
from stiffknots._version import __version__
from stiffknots.chain import FORMAT_NAME, FORMAT_VERSION, Chain
from stiffknots.errors import ChainFormatError
from stiffknots.fileio import atomic_path

__all__ = [
    "ChainFormatError",
    "from_json",
    "from_npz",
    "from_obj",
    "from_xyz",
    "load",
    "save",
    "to_json",
    "to_npz",
    "to_obj",
    "to_xyz",
]

PathLike = str | os.PathLike


def _fmt(v: float) -> str:
    return repr(float(v))


def _read_text(path: PathLike) -> str:
    try:
        with open(path, encoding="utf-8") as fh:
            return fh.read()
    except FileNotFoundError:
        raise ChainFormatError(f"{path}: no such file") from None
    except UnicodeDecodeError:
        raise ChainFormatError(f"{path}: not a text file (cannot decode as UTF-8)") from None
    except OSError as exc:
        raise ChainFormatError(f"{path}: cannot read: {exc.strerror or exc}") from None


def _make_chain(coords: Any, closed: bool, meta: dict, path: PathLike) -> Chain:
    try:
        return Chain(coords, closed, meta)
    except ValueError as exc:
        raise ChainFormatError(f"{path}: invalid chain: {exc}") from None


def _ends_coincide(x: np.ndarray) -> bool:
    """First and last bead equal (exactly, or within KymoKnot's 1e-6 ring tolerance)."""
    return bool(np.array_equal(x[0], x[-1]) or np.linalg.norm(x[0] - x[-1]) < 1e-6)


def to_xyz(chain: Chain, path: PathLike, dialect: str = "topoly") -> None:
    """Write the bead coordinates as plain text.

    Parameters
    ----------
    chain : Chain
    path : str or path-like
    dialect : {"topoly", "kymoknot"}
        ``"topoly"``: lines ``"i x y z"`` (1-based index; topoly's nxyz format). ``"kymoknot"``:
        a count line then ``"x y z"`` lines (KymoKnot's input format). In both a closed chain
        repeats its first bead (and, for topoly, its index) as the last line. Floats are written
        with ``repr``: the round trip is exact. Metadata is not stored.
    """
    if dialect not in ("topoly", "kymoknot"):
        raise ValueError(f"unknown xyz dialect {dialect!r}; use 'topoly' or 'kymoknot'")
    x = chain.coords
    rows = [(i + 1, x[i]) for i in range(len(x))]
    if chain.closed:
        rows.append((1, x[0]))
    if dialect == "topoly":
        lines = [f"{i} {_fmt(p[0])} {_fmt(p[1])} {_fmt(p[2])}" for i, p in rows]
    else:
        lines = [str(len(rows))] + [f"{_fmt(p[0])} {_fmt(p[1])} {_fmt(p[2])}" for _, p in rows]
    with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8", newline="\n") as fh:
        fh.write("\n".join(lines) + "\n")


def from_xyz(path: PathLike, closed: bool | None = None, meta: dict | None = None) -> Chain:
    """Read a chain from an xyz text file (one configuration).

    Accepts topoly's nxyz lines ``"i x y z"``, plain ``"x y z"`` lines, and KymoKnot files (a
    first line with the count, optionally followed by a non-numeric title line as in its LAMMPS
    variant). Blank lines and ``#`` comments are skipped.

    A cut or damaged file must not read as another chain. The rule:

    * a KymoKnot count line must equal the number of bead lines (ChainFormatError);
    * nxyz indices must count up by one from the first (a missing or swapped line is a
      ChainFormatError); a closing line repeats the first index;
    * a file that does not end with a newline may have lost the end of its last line: it is
      read, with a :class:`~stiffknots.errors.ChainFormatWarning`;
    * the closure: a file whose last bead repeats the first is a closed chain. A plain or nxyz
      file without that repeated bead cannot tell an open chain from a closed one written
      without it, or from a closed chain that lost its last lines: unless ``closed`` is given,
      it is read as open with a ChainFormatWarning saying so (a KymoKnot file with a count is
      complete, and KymoKnot's convention — linear chains do not repeat — decides silently).
      The chain's ``meta["closure"]`` (default metadata) records which closure was taken and
      why.

    Parameters
    ----------
    closed : bool, optional
        ``None`` (default): the chain is closed iff the last bead repeats the first (which is then
        dropped). ``True``/``False`` force it; with ``True`` a repeated closing bead is dropped.
    meta : dict, optional
        Metadata for the chain (the format stores none); ``{"source": path, "closure": ...}``
        by default.
    """
    import warnings

    from stiffknots.errors import ChainFormatWarning

    text = _read_text(path)
    if text.strip() and not text.endswith(("\n", "\r")):
        warnings.warn(f"{path}: the file does not end with a newline; its last line may be cut",
                      ChainFormatWarning, stacklevel=2)
    lines = [ln.strip() for ln in text.splitlines()]
    lines = [ln for ln in lines if ln and not ln.startswith("#")]
    if not lines:
        raise ChainFormatError(f"{path}: empty xyz file (no bead lines)")
    count = None
    first = lines[0].split()
    if len(first) == 1:
        try:
            count = int(first[0])
        except ValueError:
            raise ChainFormatError(
                f"{path}, line 1: {lines[0]!r} is neither a bead line nor a bead count"
            ) from None
        lines = lines[1:]
        if lines and not _is_number(lines[0].split()[0]):
            lines = lines[1:]  # KymoKnot/LAMMPS title line
    rows = []
    index = []
    ncol = None
    for k, ln in enumerate(lines):
        tok = ln.split()
        if tok in (["X"], ["END"]):
            raise ChainFormatError(
                f"{path}: contains several chains (separator {tok[0]!r}); only one is supported"
            )
        if len(tok) not in (3, 4):
            raise ChainFormatError(
                f"{path}: bead line {k + 1} {ln!r} has {len(tok)} columns, "
                "expected 'x y z' or 'i x y z'"
            )
        if ncol is None:
            ncol = len(tok)
        elif len(tok) != ncol:
            raise ChainFormatError(
                f"{path}: bead line {k + 1} {ln!r} has {len(tok)} columns, "
                f"earlier lines have {ncol}"
            )
        try:
            if ncol == 4:
                index.append(int(tok[0]))
            rows.append([float(v) for v in tok[ncol - 3 :]])
        except ValueError:
            raise ChainFormatError(f"{path}: bead line {k + 1} {ln!r} is not numeric") from None
    if count is not None and count != len(rows):
        raise ChainFormatError(
            f"{path}: header announces {count} beads but {len(rows)} bead lines follow "
            "(several configurations in one file are not supported)"
        )
    if not rows:
        raise ChainFormatError(f"{path}: no bead lines")
    x = np.array(rows, dtype=np.float64)
    if not np.all(np.isfinite(x)):
        raise ChainFormatError(f"{path}: non-finite coordinates")
    repeated = len(x) >= 2 and _ends_coincide(x)
    _check_indices(path, index, repeated)
    if closed is not None:
        is_closed, why = bool(closed), "given"
    elif repeated:
        is_closed, why = True, "the last bead repeats the first"
    elif count is not None:
        is_closed, why = False, "KymoKnot file whose last bead does not repeat the first"
    else:
        is_closed, why = False, "assumed: the last bead does not repeat the first"
        import warnings

        from stiffknots.errors import ChainFormatWarning

        warnings.warn(f"{path}: read as an open chain of {len(x)} beads, since its last bead "
                      "does not repeat the first; a closed chain written without the repeated "
                      "bead, or one that lost its last lines, reads the same: pass closed=True "
                      "or closed=False to say which", ChainFormatWarning, stacklevel=2)
    if is_closed and repeated:
        x = x[:-1]
    if meta is None:
        meta = {"source": os.fspath(path),
                "closure": f"{'closed' if is_closed else 'open'} ({why})"}
    return _make_chain(x, is_closed, meta, path)


def _check_indices(path: PathLike, index: list[int], repeated: bool) -> None:
    """nxyz indices count up by one from the first; a closing line repeats the first."""
    if not index:
        return
    body = index[:-1] if repeated and len(index) >= 2 and index[-1] == index[0] else index
    for k, i in enumerate(body):
        if i != body[0] + k:
            raise ChainFormatError(
                f"{path}: bead line {k + 1} has index {i}, expected {body[0] + k} (the indices "
                "must count up by one: a line is missing or out of order)")


def _is_number(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return True


def to_json(chain: Chain, path: PathLike, indent: int | None = None) -> None:
    """Write the ``stiffknots-chain`` JSON format (coordinates, closure, metadata; exact floats).

    ``{"format": "stiffknots-chain", "version": 1, "stiffknots_version": ..., "closed": ...,
    "coords": [[x, y, z], ...], "meta": {...}}``. NumPy scalars/arrays in ``meta`` are
    converted; other non-JSON values raise ``TypeError``.
    """
    text = json.dumps(chain.to_dict(), indent=indent, default=json_default, allow_nan=False)
    with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8") as fh:
        fh.write(text + "\n")


def from_json(path: PathLike) -> Chain:
    """Read the ``stiffknots-chain`` JSON format written by :func:`to_json`."""
    text = _read_text(path)
    try:
        d = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ChainFormatError(f"{path}: not valid JSON ({exc.msg} at line {exc.lineno})") from None
    return Chain.from_dict(d, source=os.fspath(path))


def to_npz(chain: Chain, path: PathLike) -> None:
    """Write a NumPy ``.npz`` archive: ``coords`` (float64), ``closed`` (bool), ``meta`` (JSON
    string), ``format`` and ``version``. Written to ``path`` as given (no suffix added)."""
    meta = json.dumps(chain.meta, default=json_default, allow_nan=False)
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        np.savez(
            fh,
            format=np.array(FORMAT_NAME),
            version=np.array(FORMAT_VERSION),
            stiffknots_version=np.array(__version__),
            coords=chain.coords,
            closed=np.array(chain.closed),
            meta=np.array(meta),
        )


def from_npz(path: PathLike) -> Chain:
    """Read an archive written by :func:`to_npz` (no pickles are loaded)."""
    try:
        with open(path, "rb") as fh:
            magic = fh.read(4)
    except FileNotFoundError:
        raise ChainFormatError(f"{path}: no such file") from None
    except OSError as exc:
        raise ChainFormatError(f"{path}: cannot read: {exc.strerror or exc}") from None
    if magic[:2] != b"PK":
        raise ChainFormatError(f"{path}: not an npz archive (no zip signature)")
    try:
        with np.load(path, allow_pickle=False) as z:
            missing = [k for k in ("coords", "closed") if k not in z.files]
            if missing:
                raise ChainFormatError(f"{path}: npz archive lacks {', '.join(missing)}")
            if "format" in z.files and str(z["format"]) != FORMAT_NAME:
                raise ChainFormatError(
                    f"{path}: npz 'format' is {str(z['format'])!r}, expected {FORMAT_NAME!r}"
                )
            coords = np.array(z["coords"])
            closed_arr = z["closed"]
            meta_s = str(z["meta"]) if "meta" in z.files else "{}"
    except ChainFormatError:
        raise
    except FileNotFoundError:
        raise ChainFormatError(f"{path}: no such file") from None
    except (zipfile.BadZipFile, EOFError, OSError, ValueError, KeyError) as exc:
        raise ChainFormatError(f"{path}: not a readable npz archive ({exc})") from None
    if closed_arr.shape != () or closed_arr.dtype != np.bool_:
        raise ChainFormatError(f"{path}: 'closed' must be a boolean scalar")
    if coords.dtype.kind not in "fiu":
        raise ChainFormatError(f"{path}: 'coords' must be numeric, got dtype {coords.dtype}")
    try:
        meta = json.loads(meta_s)
    except json.JSONDecodeError as exc:
        raise ChainFormatError(f"{path}: 'meta' is not valid JSON ({exc.msg})") from None
    if not isinstance(meta, dict):
        raise ChainFormatError(f"{path}: 'meta' must be a JSON object")
    return _make_chain(coords, bool(closed_arr), meta, path)


def to_obj(chain: Chain, path: PathLike) -> None:
    """Write a Wavefront OBJ polyline as ElasticKnots does: ``v x y z`` lines, then one
    ``l i i+1`` element per bond (1-based; a closed chain ends with ``l N 1``)."""
    x = chain.coords
    n = len(x)
    out = [f"v {_fmt(p[0])} {_fmt(p[1])} {_fmt(p[2])}" for p in x]
    out += [f"l {i + 1} {i + 2}" for i in range(n - 1)]
    if chain.closed:
        out.append(f"l {n} 1")
    with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8", newline="\n") as fh:
        fh.write("\n".join(out) + "\n")


def from_obj(path: PathLike, meta: dict | None = None) -> Chain:
    """Import a curve from a Wavefront OBJ file (ElasticKnots ``.obj`` centre lines).

    ``v x y z [w]`` lines give vertices; ``l i j k ...`` lines give polylines (1-based indices,
    negative ones relative to the vertices read so far, ``i/t`` forms allowed). The bonds of all
    line elements must form one simple path or one cycle; the vertices are ordered along it
    (from the lowest-index end of a path; a cycle starts at its lowest index and follows the
    direction in which its elements are written). A cycle gives a closed chain. A path whose end
    vertex repeats the coordinates of its start (a duplicated closing vertex) also gives a closed
    chain, the duplicate dropped. Without ``l`` lines the vertices are taken in file order
    (closed iff the last repeats the first). Vertices not on the line elements are ignored.
    Other OBJ statements (``vn``, ``vt``, ``o``, ``g``, ``s``, ``mtllib``, ...) are ignored;
    faces (``f``) are an error.
    """
    text = _read_text(path)
    verts: list[list[float]] = []
    succ: dict[int, list[int]] = {}
    edges: set[tuple[int, int]] = set()
    order_edges: list[tuple[int, int]] = []
    has_lines = False
    for lineno, raw in enumerate(text.splitlines(), start=1):
        ln = raw.split("#", 1)[0].strip()
        if not ln:
            continue
        tok = ln.split()
        kw = tok[0]
        if kw == "v":
            if len(tok) not in (4, 5):
                raise ChainFormatError(
                    f"{path}, line {lineno}: vertex line {raw.strip()!r} needs 'v x y z'"
                )
            try:
                p = [float(t) for t in tok[1:4]]
            except ValueError:
                raise ChainFormatError(
                    f"{path}, line {lineno}: non-numeric vertex {raw.strip()!r}"
                ) from None
            if not all(math.isfinite(v) for v in p):
                raise ChainFormatError(f"{path}, line {lineno}: non-finite vertex {raw.strip()!r}")
            verts.append(p)
        elif kw == "l":
            has_lines = True
            if len(tok) < 3:
                raise ChainFormatError(
                    f"{path}, line {lineno}: line element {raw.strip()!r} "
                    "needs two or more vertices"
                )
            idx = []
            for t in tok[1:]:
                try:
                    k = int(t.split("/", 1)[0])
                except ValueError:
                    raise ChainFormatError(
                        f"{path}, line {lineno}: bad vertex index {t!r}"
                    ) from None
                k = k - 1 if k > 0 else len(verts) + k
                if k < 0 or k >= len(verts) or t.split("/", 1)[0] in ("0", "-0"):
                    raise ChainFormatError(
                        f"{path}, line {lineno}: vertex index {t!r} out of range "
                        f"(1..{len(verts)} defined so far)"
                    )
                idx.append(k)
            for a, b in zip(idx[:-1], idx[1:], strict=True):
                if a == b:
                    raise ChainFormatError(
                        f"{path}, line {lineno}: line element joins vertex {a + 1} to itself"
                    )
                key = (min(a, b), max(a, b))
                if key in edges:
                    continue
                edges.add(key)
                order_edges.append((a, b))
        elif kw == "f":
            raise ChainFormatError(
                f"{path}, line {lineno}: faces ('f') found; expected a curve ('l' elements)"
            )
    if not verts:
        raise ChainFormatError(f"{path}: no vertices ('v x y z' lines)")
    X = np.array(verts, dtype=np.float64)
    src_meta = {"source": os.fspath(path)} if meta is None else meta
    if not has_lines:
        x = X
        closed = len(x) >= 4 and _ends_coincide(x)
        if closed:
            x = x[:-1]
        return _make_chain(x, closed, src_meta, path)
    if not edges:
        raise ChainFormatError(f"{path}: line elements contain no bonds")
    adj: dict[int, list[int]] = {}
    for a, b in order_edges:
        adj.setdefault(a, []).append(b)
        adj.setdefault(b, []).append(a)
        succ.setdefault(a, []).append(b)
    for v, nb in adj.items():
        if len(nb) > 2:
            raise ChainFormatError(
                f"{path}: vertex {v + 1} has {len(nb)} bonds; the line elements must form a single "
                "path or loop (no branching)"
            )
    ends = sorted(v for v, nb in adj.items() if len(nb) == 1)
    if ends:
        if len(ends) != 2:
            raise ChainFormatError(
                f"{path}: the line elements form {len(ends) // 2} separate pieces, "
                "expected one curve"
            )
        start = ends[0]
        nxt = adj[start][0]
        cycle = False
    else:
        start = min(adj)
        cand = succ.get(start, [])
        nxt = cand[0] if cand else adj[start][0]
        cycle = True
    order = [start]
    prev, cur = start, nxt
    while cur != start:
        order.append(cur)
        nb = adj[cur]
        if len(nb) == 1:
            break
        prev, cur = cur, (nb[0] if nb[1] == prev else nb[1])
    if len(order) != len(adj):
        raise ChainFormatError(
            f"{path}: the line elements form separate pieces ({len(order)} of {len(adj)} "
            "vertices connected); expected one curve"
        )
    x = X[order]
    closed = cycle
    if not cycle and len(x) >= 4 and _ends_coincide(x):
        x = x[:-1]
        closed = True
    elif cycle:
        # a loop through a duplicated vertex (e.g. the closing one repeated): drop the repeat
        same = np.all(x == np.roll(x, 1, axis=0), axis=1)
        if np.any(same) and len(x) - int(np.sum(same)) >= 3:
            x = x[~same]
    return _make_chain(x, closed, src_meta, path)


_READERS = {".xyz": from_xyz, ".json": from_json, ".npz": from_npz, ".obj": from_obj}
_WRITERS = {".xyz": to_xyz, ".json": to_json, ".npz": to_npz, ".obj": to_obj}


def save(chain: Chain, path: PathLike, **kwargs: Any) -> None:
    """Write ``chain`` in the format named by the suffix of ``path`` (``.xyz``, ``.json``,
    ``.npz``, ``.obj``); keyword arguments go to the writer (e.g. ``dialect="kymoknot"``)."""
    if not isinstance(chain, Chain):
        raise TypeError(f"save() expects a Chain, got {type(chain).__name__}")
    suffix = Path(path).suffix.lower()
    if suffix not in _WRITERS:
        raise ChainFormatError(
            f"{path}: unknown chain file suffix {suffix!r}; use one of {', '.join(_WRITERS)}"
        )
    _WRITERS[suffix](chain, path, **kwargs)


def load(path: PathLike, **kwargs: Any) -> Chain:
    """Read a chain, choosing the format by the suffix of ``path`` (``.xyz``, ``.json``,
    ``.npz``, ``.obj``); keyword arguments go to the reader."""
    suffix = Path(path).suffix.lower()
    if suffix not in _READERS:
        raise ChainFormatError(
            f"{path}: unknown chain file suffix {suffix!r}; use one of {', '.join(_READERS)}"
        )
    if not Path(path).exists():
        raise ChainFormatError(f"{path}: no such file")
    return _READERS[suffix](path, **kwargs)
