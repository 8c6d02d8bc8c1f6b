"""The common questions, as plain data for ``stiffknots db`` (the command formats them).

* :func:`describe_knot` — a knot's states: every ensemble of it with its ground and metastable
  states;
* :func:`ground_table` — all ground states, one row per knot × exclusion × beads × thickness;
* :func:`to_csv` — any list of row dicts as a CSV file.
"""

from __future__ import annotations

import csv
import json
import os
import tempfile
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from stiffknots.store.sqlite import Store

__all__ = ["describe_knot", "ground_table", "to_csv"]


def describe_knot(store: Store, knot: str, *, rel_tol: float = 0.01,
                  **filters: Any) -> dict[str, Any]:
    """Everything stored about one knot's states.

    Parameters
    ----------
    store : Store
    knot : str
        Knot name as stored (``"5_2"``).
    rel_tol : float, default 0.01
        Relative ε tolerance of one state.
    **filters
        Narrow the ensembles: ``exclusion``, ``beads``, ``thickness``, ``settings_hash``,
        ``problem``.

    Returns
    -------
    dict
        ``knot``, ``replicas`` (count over the ensembles shown) and ``ensembles``: one
        :meth:`Store.states` dict per ensemble (exclusion, beads, thickness, settings), in
        that order.

    Raises
    ------
    ValueError
        No replica of ``knot`` is stored (the message lists the stored knots).
    """
    ensembles = store.ensembles(knot=knot, **filters)
    if not ensembles:
        known = store.knots()
        raise ValueError(f"no stored replicas of knot {knot!r}"
                         + (f" with {filters}" if any(v is not None for v in filters.values())
                            else "")
                         + (f"; stored knots: {', '.join(known)}" if known
                            else f"; {store.path} is empty"))
    out = [store.states(e["knot"], e["exclusion"], e["beads"], e["thickness"],
                        e["settings_hash"], rel_tol=rel_tol) for e in ensembles]
    return {"knot": knot, "replicas": sum(e["replicas"] for e in out), "ensembles": out}


def ground_table(store: Store, *, rel_tol: float = 0.01, **filters: Any) -> list[dict[str, Any]]:
    """All ground states as a table: :meth:`Store.ground_states` (filters: ``knot``,
    ``exclusion``, ``beads``, ``thickness``, ``problem``, ``settings_hash``)."""
    return store.ground_states(rel_tol=rel_tol, **filters)


def _cell(v: Any) -> Any:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, Mapping | list | tuple):
        return json.dumps(v, sort_keys=True, ensure_ascii=False)
    return v


def to_csv(path: str | os.PathLike, rows: Iterable[Mapping[str, Any]],
           columns: Sequence[str] | None = None) -> Path:
    """Write rows (dicts) as a CSV file, atomically (a temporary file renamed into place).

    Parameters
    ----------
    path : str or Path
        The file; parent folders are created.
    rows : iterable of mappings
        E.g. :func:`ground_table` or :meth:`Store.replicas`.
    columns : sequence of str, optional
        Columns and their order; default: the keys of the rows, in order of first appearance.

    Returns
    -------
    Path
        The file written. Cells: None → empty, booleans → ``true``/``false``, floats by
        ``repr`` (round-trip exact), lists and dicts as JSON.
    """
    rows = list(rows)
    if columns is None:
        columns = list(dict.fromkeys(k for r in rows for k in r))
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=path.name + ".", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", newline="", encoding="utf-8") as f:
            w = csv.writer(f)
            w.writerow(columns)
            for r in rows:
                w.writerow([_cell(r.get(c)) for c in columns])
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path
