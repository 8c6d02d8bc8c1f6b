"""Chain file formats: every reader and writer (:func:`save` / :func:`load` dispatch on the
suffix).

==================  =====================================  ====================  ===========
suffix              what it holds                          closure recorded by   written
==================  =====================================  ====================  ===========
``.xyz``            vertex lines (topoly nxyz, KymoKnot,   a repeated first      yes (two
                    plain, molecular ``C x y z``)          vertex only           dialects)
``.txt`` ``.dat``   ``x y z`` table, white-space, tab or   a repeated first      no
``.tsv`` ``.csv``   comma separated, optional header       vertex only
``.json``           ``stiffknots-chain`` (or a bare list   ``"closed"``          yes
                    of ``[x, y, z]``)                      (bare list: repeat)
``.npz`` ``.npy``   ``coords`` [+ ``closed``, ``meta``];   ``closed``            yes (``.npz``)
                    ``.npy``: one (N, 3) array             (``.npy``: repeat
                                                           only)
``.obj``            ElasticKnots polyline (``v``, ``l``)   a loop of ``l``       yes
                                                           elements
``.vect``           Geomview VECT, one polyline            the sign of the       yes
                    (KnotPlot, ridgerunner)                vertex count
==================  =====================================  ====================  ===========

The closure rule
----------------
Every reader takes ``closed`` (``True``/``False``/``None``). ``True`` or ``False`` is obeyed (a
repeated closing vertex is then dropped for a closed chain). With ``None`` (the default):

1. a file whose last vertex repeats the first is closed, the repeat dropped (except that the
   explicit ``closed`` flag of the stiffknots ``.json``/``.npz`` formats always wins);
2. a format that records closure is obeyed: VECT's negative vertex count, an OBJ loop, the
   ``closed`` flag of ``.json``/``.npz``;
3. otherwise (plain vertex lists that do not repeat) the chain is **assumed closed** — a knot:
   a ring must never silently become an open chain (its closing bond and two bending terms
   would be lost).

Each reader records what was decided in ``chain.meta["closure"]``, one sentence starting with
``closed:``, ``open:`` or ``assumed closed:`` (the command line prints it), except where the
stiffknots ``.json``/``.npz`` flag is obeyed: their metadata round-trips exactly, and
:func:`closure_note` gives the sentence for any chain read by this module.

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
      requires them to differ). A count that disagrees with the number of lines is an error.

    No single file satisfies both readers (topoly would read KymoKnot's count line as a bead,
    KymoKnot rejects the index column), hence the two dialects. Floats are written with
    ``repr`` (shortest round-trip representation), so coordinates survive a round trip exactly.
    The xyz formats store no metadata; use ``.json`` or ``.npz`` for that. An *open* chain
    written as xyz does not repeat its first vertex, so it reads back as closed unless read
    with ``closed=False``.
``.txt``, ``.dat``, ``.tsv``, ``.csv``
    One vertex per line, separated by white space, tabs or commas; an optional header line
    (when it names ``x``, ``y``, ``z`` those columns are read). See :func:`from_text`.
``.json``
    ``{"format": "stiffknots-chain", "version": 1, "closed": ..., "coords": [[x, y, z], ...],
    "meta": {...}, "stiffknots_version": ...}``; exact float round trip. A bare JSON list of
    ``[x, y, z]`` triples is read too.
``.npz``
    NumPy archive with ``coords``, ``closed`` and ``meta`` (a JSON string); no pickles.
    ``.npy``: one float array of shape (N, 3).
``.obj``
    Wavefront OBJ polylines as written by ElasticKnots: ``v x y z`` vertex lines and ``l i j ...``
    line elements (1-based, negative indices relative). Reading orders the vertices along the
    line elements and detects closure; writing emits one ``l i i+1`` element per bond.
``.vect``
    Geomview VECT with one polyline, as KnotPlot and ridgerunner write them; a negative vertex
    count means closed. Files with several polylines (links) are refused. See
    :func:`from_vect`.

Unreadable or corrupt files raise :class:`ChainFormatError` (a ``ValueError``): one line naming
the file, the line where it can, and what was wrong.
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
from stiffknots.chain import FORMAT_NAME, FORMAT_VERSION, Chain, as_coords
from stiffknots.errors import ChainFormatError
from stiffknots.fileio import atomic_path

__all__ = [
    "READ_SUFFIXES",
    "ChainFormatError",
    "check_readable",
    "closure_note",
    "from_json",
    "from_npy",
    "from_npz",
    "from_obj",
    "from_text",
    "from_vect",
    "from_xyz",
    "load",
    "save",
    "to_json",
    "to_npz",
    "to_obj",
    "to_vect",
    "to_xyz",
]

PathLike = str | os.PathLike


def _fmt(v: float) -> str:
    return repr(float(v))


def _read_text(path: PathLike) -> str:
    # utf-8-sig: a byte-order mark (Notepad, Excel) is not text; read as a character it
    # turned the first vertex line into a header, dropping that vertex
    try:
        with open(path, encoding="utf-8-sig") as fh:
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
    """First and last bead equal (exactly, or within KymoKnot's 1e-6 ring tolerance and a
    thousandth of the typical bond: a curve drawn at 1e-300 is not closed by its size)."""
    if np.array_equal(x[0], x[-1]):
        return True
    gap = float(np.max(np.abs(x[0] - x[-1])))  # components: no overflow at 1e300
    if not gap < 1e-6 or len(x) < 3:
        return False
    bond = float(np.median(np.max(np.abs(np.diff(x, axis=0)), axis=1)))
    return gap < 1e-3 * bond and float(np.linalg.norm(x[0] - x[-1])) < 1e-6


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

    Accepts topoly's nxyz lines ``"i x y z"``, plain ``"x y z"`` lines, molecular-style
    ``"C x y z"`` lines (a label first), and KymoKnot files (a first line with the count,
    optionally followed by a non-numeric title line as in its LAMMPS variant); the same parser
    as :func:`from_text`. Blank lines and ``#`` comments are skipped.

    Parameters
    ----------
    closed : bool, optional
        ``None`` (default): the closure rule of this module (a repeated first vertex means
        closed, the repeat dropped; otherwise the chain is *assumed closed* and
        ``meta["closure"]`` says so). ``True``/``False`` force it; with ``True`` a repeated
        closing vertex is dropped.
    meta : dict, optional
        Metadata for the chain (the format stores none); ``{"source": path}`` by default.
    """
    return from_text(path, closed=closed, meta=meta)


def from_text(path: PathLike, closed: bool | None = None, meta: dict | None = None) -> Chain:
    """Read a chain from a plain table of vertices: ``x y z`` text, tsv or csv.

    One vertex per line, separated by white space, tabs or commas (sniffed from the first data
    line). An optional header line names the columns: when it names ``x``, ``y`` and ``z`` those
    columns are read (other columns ignored); otherwise the lines must have 3 columns, or 4 with
    an integer index (topoly's nxyz) or a label (molecular xyz) first. A first line holding one
    integer is a vertex count (KymoKnot, molecular xyz): the number of vertex lines must match
    it, and a non-numeric title line may follow it. Blank lines and ``#`` comments are skipped.

    Closure (``closed=None``): a file whose last vertex repeats the first is closed (the repeat
    dropped); otherwise the chain is *assumed* closed (a knot) and ``meta["closure"]`` says so.
    Pass ``closed=False`` for an open chain.
    """
    text = _read_text(path)
    lines = []
    for lineno, raw in enumerate(text.splitlines(), start=1):
        ln = raw.strip()
        if ln and not ln.startswith("#"):
            lines.append((lineno, ln))
    if not lines:
        raise ChainFormatError(f"{path}: empty file (no vertex lines)")
    delim = "," if "," in lines[0][1] else ("\t" if "\t" in lines[0][1] else None)

    def cells(ln: str) -> list[str]:
        if delim is None:
            return ln.split()
        tok = [c.strip().strip('"').strip("'") for c in ln.split(delim)]
        while tok and tok[-1] == "":
            tok.pop()
        return tok

    count = None
    cols: tuple[int, int, int] | None = None
    ncol = None
    first = cells(lines[0][1])
    if len(first) == 1 and delim is None:
        try:
            count = int(first[0])
        except ValueError:
            raise ChainFormatError(
                f"{path}, line {lines[0][0]}: {lines[0][1]!r} is neither a vertex line nor a "
                "vertex count"
            ) from None
        lines = lines[1:]
        if lines and not _is_number(cells(lines[0][1])[0]):
            lines = lines[1:]  # KymoKnot/LAMMPS or molecular-xyz title line
    elif not all(_is_number(t) for t in first) and not (
        len(first) == 4 and all(_is_number(t) for t in first[1:])
    ):
        names = [t.lower() for t in first]
        if all(c in names for c in ("x", "y", "z")):
            cols = (names.index("x"), names.index("y"), names.index("z"))
            ncol = len(names)
        elif len(first) in (3, 4):
            ncol = len(first)
        else:
            raise ChainFormatError(
                f"{path}, line {lines[0][0]}: header {lines[0][1]!r} has {len(first)} columns "
                "and does not name x, y and z"
            )
        lines = lines[1:]
    rows: list[list[float]] = []
    linenos: list[int] = []
    index: list[int] = []
    for lineno, ln in lines:
        tok = cells(ln)
        if tok in (["X"], ["END"]):
            raise ChainFormatError(
                f"{path}, line {lineno}: contains several chains (separator {tok[0]!r}); "
                "only one is supported"
            )
        if ncol is None:
            if len(tok) not in (3, 4):
                raise ChainFormatError(
                    f"{path}, line {lineno}: {ln!r} has {len(tok)} columns, "
                    "expected 'x y z' or 'i x y z'"
                )
            ncol = len(tok)
        if len(tok) != ncol:
            raise ChainFormatError(
                f"{path}, line {lineno}: {ln!r} has {len(tok)} columns, earlier lines have {ncol}"
            )
        pick = cols if cols is not None else (ncol - 3, ncol - 2, ncol - 1)
        try:
            if cols is None and ncol == 4 and _is_number(tok[0]):
                index.append(int(tok[0]))  # an index column must hold integers
            rows.append([float(tok[i]) for i in pick])
        except ValueError:
            raise ChainFormatError(f"{path}, line {lineno}: {ln!r} is not numeric") from None
        if not all(math.isfinite(v) for v in rows[-1]):
            raise ChainFormatError(f"{path}, line {lineno}: non-finite coordinates {ln!r}")
        linenos.append(lineno)
    if count is not None and count != len(rows):
        raise ChainFormatError(
            f"{path}: header announces {count} vertices but {len(rows)} vertex lines follow "
            "(several configurations in one file are not supported)"
        )
    if not rows:
        raise ChainFormatError(f"{path}: no vertex lines")
    x = np.array(rows, dtype=np.float64)
    if len(index) == len(rows):
        _check_index(path, index, linenos, bool(len(x) >= 2 and np.array_equal(x[0], x[-1])))
    return _closed_chain(x, closed, None, "", path, meta, linenos)


def _check_index(path: PathLike, index: list[int], linenos: list[int], repeated: bool) -> None:
    """An index column (topoly's nxyz) counts up by one from its first value; a closing line
    repeats the first index. A line lost or moved inside the file would otherwise go unseen:
    the chain would read as another one."""
    body = index[:-1] if repeated and len(index) >= 2 and index[-1] == index[0] else index
    for k, i in enumerate(body):
        if i != body[0] + k:
            raise ChainFormatError(
                f"{path}, line {linenos[k]}: index {i}, expected {body[0] + k} (the index "
                "column must count up by one: a line is missing or out of order)")


def _is_number(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return True


_CLOSURE_ASSUMED = (
    "assumed closed: the file does not record closure and its last vertex does not repeat the "
    "first; read it as open (closed=False, --open) if it is an open chain"
)


def closure_note(chain: Chain) -> str:
    """How the closure of a chain read by this module was decided (``meta["closure"]``, or the
    flag recorded by the stiffknots ``.json``/``.npz`` formats)."""
    note = chain.meta.get("closure") if isinstance(chain.meta, dict) else None
    if isinstance(note, str) and note:
        return note
    return f"{'closed' if chain.closed else 'open'}: recorded in the file ('closed')"


def _closed_chain(
    x: np.ndarray,
    closed: bool | None,
    recorded: bool | None,
    why: str,
    path: PathLike,
    meta: dict | None,
    linenos: list[int] | None = None,
    unit: str = "line",
    strict: bool = False,
) -> Chain:
    """Apply the closure rule and build the chain; ``meta["closure"]`` says what was decided.

    ``closed`` is the caller's choice (None: decide); ``recorded`` what the format itself
    records (``why`` says where), None when it records nothing; with ``strict`` (the stiffknots
    formats, which store the flag explicitly) the record wins over a repeated vertex.
    """
    repeated = len(x) >= 3 and _ends_coincide(x)
    if strict and recorded is not None and closed is None:
        closed_by_record = bool(recorded)
        note = f"{'closed' if closed_by_record else 'open'}: {why}"
        if closed_by_record and repeated:
            x = x[:-1]
        m = {"source": os.fspath(path)} if meta is None else dict(meta)
        if "closure" in m:  # a note carried over from an earlier read: bring it up to date
            m["closure"] = note
        return _make_chain(x, closed_by_record, m, path)
    if closed is not None:
        is_closed = bool(closed)
        note = f"{'closed' if is_closed else 'open'}: as requested"
    elif repeated:
        is_closed = True
        note = "closed: the last vertex repeats the first (the repeat is dropped)"
    elif recorded is not None:
        is_closed = bool(recorded)
        note = f"{'closed' if is_closed else 'open'}: {why}"
    else:
        is_closed = True
        note = _CLOSURE_ASSUMED
    if is_closed and repeated:
        x = x[:-1]
        if closed is not None:
            note += " (a repeated closing vertex is dropped)"
    d = x[1:] - x[:-1]
    dup = np.flatnonzero(~np.any(d != 0.0, axis=1))
    if len(dup):
        k = int(dup[0])
        where = (f"lines {linenos[k]} and {linenos[k + 1]}" if linenos is not None
                 else f"{unit}s {k + 1} and {k + 2}")
        raise ChainFormatError(
            f"{path}, {where}: the same vertex twice in a row (a zero-length bond)"
        )
    m = {"source": os.fspath(path)} if meta is None else dict(meta)
    m["closure"] = note
    return _make_chain(x, is_closed, m, path)


def to_json(chain: Chain, path: PathLike, indent: int | None = None) -> None:
    """Write the ``stiffknots-chain`` JSON format (coordinates, closure, metadata; exact floats).

    ``{"format": "stiffknots-chain", "version": 1, "stiffknots_version": ..., "closed": ...,
    "coords": [[x, y, z], ...], "meta": {...}}``. NumPy scalars/arrays in ``meta`` are
    converted; other non-JSON values raise ``TypeError``.
    """
    text = json.dumps(chain.to_dict(), indent=indent, default=json_default, allow_nan=False)
    with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8") as fh:
        fh.write(text + "\n")


def from_json(path: PathLike, closed: bool | None = None) -> Chain:
    """Read the ``stiffknots-chain`` JSON format written by :func:`to_json`, or a bare JSON list
    of ``[x, y, z]`` triples.

    The format's ``closed`` flag is obeyed unless ``closed`` is given; a bare list records no
    closure and follows the closure rule of this module (assumed closed unless the last vertex
    repeats the first).
    """
    text = _read_text(path)
    try:
        d = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ChainFormatError(
            f"{path}, line {exc.lineno}: not valid JSON ({exc.msg})") from None
    if isinstance(d, list):
        ok = all(isinstance(r, list) and len(r) == 3 and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in r) for r in d)
        if not ok or not d:
            raise ChainFormatError(f"{path}: a JSON list must hold [x, y, z] number triples")
        x = np.array(d, dtype=np.float64)
        if not np.all(np.isfinite(x)):
            raise ChainFormatError(f"{path}: non-finite coordinates")
        return _closed_chain(x, closed, None, "", path, None, unit="vertice")
    c = Chain.from_dict(d, source=os.fspath(path))
    return _closed_chain(c.coords, closed, c.closed, "recorded in the file ('closed')", path,
                         c.meta, unit="vertice", strict=True)


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


def from_npz(path: PathLike, closed: bool | None = None) -> Chain:
    """Read an archive written by :func:`to_npz` (no pickles are loaded).

    Its ``closed`` flag is obeyed unless ``closed`` is given; an archive with ``coords`` only
    follows the closure rule of this module (assumed closed unless the last vertex repeats
    the first)."""
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
            missing = [k for k in ("coords",) if k not in z.files]
            if missing:
                raise ChainFormatError(f"{path}: npz archive lacks {', '.join(missing)}")
            if "format" in z.files and str(z["format"]) != FORMAT_NAME:
                raise ChainFormatError(
                    f"{path}: npz 'format' is {str(z['format'])!r}, expected {FORMAT_NAME!r}"
                )
            coords = np.array(z["coords"])
            closed_arr = z["closed"] if "closed" in z.files else None
            meta_s = str(z["meta"]) if "meta" in z.files else "{}"
    except ChainFormatError:
        raise
    except FileNotFoundError:
        raise ChainFormatError(f"{path}: no such file") from None
    except (zipfile.BadZipFile, EOFError, OSError, ValueError, KeyError) as exc:
        raise ChainFormatError(f"{path}: not a readable npz archive ({exc})") from None
    if closed_arr is not None and (closed_arr.shape != () or closed_arr.dtype != np.bool_):
        raise ChainFormatError(f"{path}: 'closed' must be a boolean scalar")
    if coords.dtype.kind not in "fiu":
        raise ChainFormatError(f"{path}: 'coords' must be numeric, got dtype {coords.dtype}")
    try:
        meta = json.loads(meta_s)
    except json.JSONDecodeError as exc:
        raise ChainFormatError(f"{path}: 'meta' is not valid JSON ({exc.msg})") from None
    if not isinstance(meta, dict):
        raise ChainFormatError(f"{path}: 'meta' must be a JSON object")
    x = _coords_array(coords, path)
    recorded = None if closed_arr is None else bool(closed_arr)
    return _closed_chain(x, closed, recorded, "recorded in the archive ('closed')", path, meta,
                         unit="vertice", strict=True)


def from_npy(path: PathLike, closed: bool | None = None) -> Chain:
    """Read a NumPy ``.npy`` file holding one float array of shape (N, 3) (no pickles).

    The array records no closure: the closure rule of this module applies (assumed closed
    unless the last vertex repeats the first)."""
    try:
        arr = np.load(path, allow_pickle=False)
    except FileNotFoundError:
        raise ChainFormatError(f"{path}: no such file") from None
    except (OSError, ValueError, EOFError) as exc:
        raise ChainFormatError(f"{path}: not a readable .npy array ({exc})") from None
    if not isinstance(arr, np.ndarray) or arr.dtype.kind not in "fiu":
        raise ChainFormatError(f"{path}: expected a numeric array of shape (N, 3)")
    return _closed_chain(_coords_array(arr, path), closed, None, "", path, None, unit="vertice")


def _coords_array(coords: np.ndarray, path: PathLike) -> np.ndarray:
    try:
        return as_coords(coords, f"{path}: coordinates", item="vertex", first=1)
    except ValueError as exc:
        raise ChainFormatError(str(exc)) from None


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


def from_obj(path: PathLike, closed: bool | None = None, meta: dict | None = None) -> Chain:
    """Import a curve from a Wavefront OBJ file (ElasticKnots ``.obj`` centre lines).

    ``v x y z [w]`` lines give vertices; ``l i j k ...`` lines give polylines (1-based indices,
    negative ones relative to the vertices read so far, ``i/t`` forms allowed). The bonds of all
    line elements must form one simple path or one cycle; the vertices are ordered along it
    (from the lowest-index end of a path; a cycle starts at its lowest index and follows the
    direction in which its elements are written). A cycle gives a closed chain. A path whose end
    vertex repeats the coordinates of its start (a duplicated closing vertex) also gives a closed
    chain, the duplicate dropped. Without ``l`` lines the vertices are taken in file order and
    the closure rule of this module applies (closed if the last repeats the first, else assumed
    closed). ``closed=True/False`` overrides all of this. Vertices not on the line elements are
    ignored.
    Other OBJ statements (``vn``, ``vt``, ``o``, ``g``, ``s``, ``mtllib``, ...) are ignored;
    faces (``f``) are an error.
    """
    text = _read_text(path)
    verts: list[list[float]] = []
    vlines: list[int] = []
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
            vlines.append(lineno)
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
    if not has_lines:
        return _closed_chain(X, closed, None, "", path, meta, vlines)
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
    if cycle:
        # a loop through a duplicated vertex (e.g. the closing one repeated): drop the repeat
        same = np.all(x == np.roll(x, 1, axis=0), axis=1)
        if np.any(same) and len(x) - int(np.sum(same)) >= 3:
            keep = ~same
            x = x[keep]
            order = [o for o, k in zip(order, keep, strict=True) if k]
    why = ("the line elements form a loop" if cycle
           else "the line elements form a path with two ends")
    return _closed_chain(x, closed, cycle, why, path, meta, [vlines[o] for o in order])


def to_vect(chain: Chain, path: PathLike) -> None:
    """Write a Geomview VECT file with one polyline, as KnotPlot and ridgerunner read them: the
    vertex count is negative for a closed chain (the first vertex is not repeated), one colour.
    Floats are written with ``repr`` (exact round trip); metadata is not stored."""
    x = chain.coords
    n = len(x)
    out = ["VECT", f"1 {n} 1", str(-n if chain.closed else n), "1"]
    out += [f"{_fmt(p[0])} {_fmt(p[1])} {_fmt(p[2])}" for p in x]
    out.append("0 0 0 1")
    with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8", newline="\n") as fh:
        fh.write("\n".join(out) + "\n")


def from_vect(path: PathLike, closed: bool | None = None, meta: dict | None = None) -> Chain:
    """Read a Geomview VECT file with one polyline (KnotPlot, ridgerunner/plCurve).

    Layout (white space and line breaks are free; ``#`` starts a comment)::

        VECT
        NPOLYLINES NVERTICES NCOLORS
        Nv[0] ... Nv[NPOLYLINES-1]      vertices of each polyline; negative: closed
        Nc[0] ... Nc[NPOLYLINES-1]      colours of each polyline (0 or 1 ...)
        x y z                           NVERTICES vertices
        r g b a                         NCOLORS colours (ignored)

    Only one polyline (one component: a knot) is read; a file with several (a link) is refused
    with a message naming the count. Closure: the sign of the vertex count is obeyed (negative:
    closed) unless ``closed`` is given; a last vertex repeating the first also means closed
    (the repeat is dropped).
    """
    text = _read_text(path)
    toks: list[tuple[str, int]] = []
    for lineno, raw in enumerate(text.splitlines(), start=1):
        for t in raw.split("#", 1)[0].split():
            toks.append((t, lineno))
    if not toks:
        raise ChainFormatError(f"{path}: empty file")
    key, line1 = toks[0]
    if key.upper() == "4VECT":
        raise ChainFormatError(f"{path}, line {line1}: 4VECT (4-dimensional) is not supported")
    if key.upper() != "VECT":
        raise ChainFormatError(
            f"{path}, line {line1}: a VECT file starts with 'VECT', found {key!r}")
    pos = 1

    def ints(k: int, what: str) -> list[int]:
        nonlocal pos
        out = []
        for _ in range(k):
            if pos >= len(toks):
                raise ChainFormatError(f"{path}: the file ends before the {what}")
            t, ln = toks[pos]
            try:
                out.append(int(t))
            except ValueError:
                raise ChainFormatError(
                    f"{path}, line {ln}: {what}: expected an integer, found {t!r}") from None
            pos += 1
        return out

    npoly, nvert, ncolor = ints(3, "header counts (NPOLYLINES NVERTICES NCOLORS)")
    hdr_line = toks[pos - 1][1]
    if npoly < 1 or nvert < 1 or ncolor < 0:
        raise ChainFormatError(
            f"{path}, line {hdr_line}: header counts {npoly} {nvert} {ncolor} "
            "(polylines, vertices, colours) must be positive")
    if npoly > 1:
        raise ChainFormatError(
            f"{path}, line {hdr_line}: the file holds {npoly} polylines (components, a link "
            "or several curves); stiffknots reads one knot: keep one component in the file")
    (nv,) = ints(1, "vertex count of the polyline")
    nv_line = toks[pos - 1][1]
    (nc,) = ints(1, "colour count of the polyline")
    if abs(nv) != nvert:
        raise ChainFormatError(
            f"{path}, line {nv_line}: the polyline has {abs(nv)} vertices but the header "
            f"announces {nvert}")
    if nc != ncolor:
        raise ChainFormatError(
            f"{path}, line {toks[pos - 1][1]}: the polyline has {nc} colours but the header "
            f"announces {ncolor}")
    if abs(nv) < 2:
        raise ChainFormatError(f"{path}, line {nv_line}: a polyline of {abs(nv)} vertex")
    need = 3 * nvert
    if len(toks) - pos < need:
        have = (len(toks) - pos) // 3
        raise ChainFormatError(
            f"{path}: the file ends after {have} of the {nvert} vertices the header announces")
    vals = []
    lines = []
    for k in range(need):
        t, ln = toks[pos + k]
        try:
            v = float(t)
        except ValueError:
            raise ChainFormatError(
                f"{path}, line {ln}: vertex coordinate {t!r} is not a number") from None
        if not math.isfinite(v):
            raise ChainFormatError(f"{path}, line {ln}: non-finite vertex coordinate {t!r}")
        vals.append(v)
        if k % 3 == 0:
            lines.append(ln)
    pos += need
    left = len(toks) - pos
    if left != 4 * ncolor:
        raise ChainFormatError(
            f"{path}: after the vertices the header's {ncolor} colour(s) need {4 * ncolor} "
            f"numbers, found {left}")
    x = np.array(vals, dtype=np.float64).reshape(-1, 3)
    why = ("the VECT vertex count is negative" if nv < 0
           else "the VECT vertex count is positive")
    return _closed_chain(x, closed, nv < 0, why, path, meta, lines)


_READERS = {
    ".xyz": from_xyz, ".txt": from_text, ".dat": from_text, ".csv": from_text,
    ".tsv": from_text, ".json": from_json, ".npz": from_npz, ".npy": from_npy, ".obj": from_obj,
    ".vect": from_vect,
}
_WRITERS = {".xyz": to_xyz, ".json": to_json, ".npz": to_npz, ".obj": to_obj, ".vect": to_vect}

#: Suffixes :func:`load` reads.
READ_SUFFIXES = tuple(_READERS)


def save(chain: Chain, path: PathLike, **kwargs: Any) -> None:
    """Write ``chain`` in the format named by the suffix of ``path`` (``.xyz``, ``.json``,
    ``.npz``, ``.obj``, ``.vect``); keyword arguments go to the writer (e.g.
    ``dialect="kymoknot"``)."""
    if not isinstance(chain, Chain):
        raise TypeError(f"save() expects a Chain, got {type(chain).__name__}")
    suffix = Path(path).suffix.lower()
    if suffix not in _WRITERS:
        raise ChainFormatError(
            f"{path}: unknown chain file suffix {suffix!r}; use one of {', '.join(_WRITERS)}"
        )
    _WRITERS[suffix](chain, path, **kwargs)


def load(path: PathLike, closed: bool | None = None, **kwargs: Any) -> Chain:
    """Read a chain, choosing the format by the suffix of ``path`` (:data:`READ_SUFFIXES`:
    ``.xyz``, ``.txt``, ``.dat``, ``.csv``, ``.tsv``, ``.json``, ``.npz``, ``.npy``, ``.obj``,
    ``.vect``); keyword arguments go to the reader.

    ``closed``: None (default) applies the closure rule of this module (see its docstring):
    what the format records is obeyed, a repeated first vertex means closed, and otherwise the
    chain is *assumed closed*; ``meta["closure"]`` says which. True/False force it.
    """
    check_readable(path)
    return _READERS[Path(path).suffix.lower()](path, closed=closed, **kwargs)


def check_readable(path: PathLike) -> None:
    """Before any reading: ``path`` names an existing file (not '', not a folder) with one of
    the suffixes of :data:`READ_SUFFIXES`; ChainFormatError (one line) otherwise."""
    if str(path).strip() == "":
        raise ChainFormatError("no chain file given (an empty path)")
    p = Path(path)
    if p.is_dir():
        raise ChainFormatError(f"{path}: is a folder; give a chain file "
                               f"({', '.join(_READERS)})")
    suffix = p.suffix.lower()
    if suffix not in _READERS:
        raise ChainFormatError(
            f"{path}: unknown chain file suffix {suffix!r}; use one of {', '.join(_READERS)}"
        )
    if not p.exists():
        raise ChainFormatError(f"{path}: no such file")
