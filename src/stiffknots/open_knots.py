"""Open knots under tension (paper §VIII): anneal at fixed excess length, measure the tension.

An open knot is a chain whose two end segments are clamped on the z axis, pointing along −z
and +z (:mod:`stiffknots.knots.open_embedding`). The kernel keeps the ends fixed, so the
end-to-end distance Δz and the excess length L_e = ∫ds − ∫dz = (N − 1) − Δz are fixed: this
is the fixed-extension ensemble. The force term −F·Δz of the fixed-force energy is then a
constant, and the tension is *measured*:

* from the scaling of the elastic energy, μ = E/L_e (paper §VIII: E = ε_e C/L_e, and
  μ = −dE/dL_e = ε_e C/L_e² = E/L_e), and
* independently, from the slope of E against L_e over a scan of excess lengths
  (:func:`tension_scan`, finite differences), which checks the relation above.

Fixed force F and fixed extension are Legendre-conjugate at T → 0: the excess length a force
F selects is L_e(F) = (ε_e C/F)^{1/2} (:func:`excess_length_for_force`).

Units: bond length b = 1 and bending rigidity C = 1, so μ is in C/b² and ε_e = E·L_e/C is
dimensionless. The paper's bounds are 2π²n₁² ≤ ε_e ≤ 2π² min(α²n₁², i₁²), n₁ = n − 1,
i₁ = i − 1 (§VIII, with the α² misprint fixed; see :func:`stiffknots.theory.bounds.open_bounds`).
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from stiffknots._json import json_default
from stiffknots._version import __version__
from stiffknots.engine.driver import (
    AnnealSettings,
    ReplicaResult,
    TopologyChangedError,
    default_workers,
    replica_seeds,
    run_replica,
)
from stiffknots.engine.pool import BestFirst, run_jobs
from stiffknots.engine.schedules import Schedule
from stiffknots.engine.state import MoveParams

DEFAULT_OPEN_MOVES = 30_000_000
TWO_PI2 = 2.0 * np.pi**2


def _fit_circle(pts: np.ndarray):
    """Plane (SVD) and circle (algebraic least squares in the plane) through ``pts``."""
    c0 = pts.mean(axis=0)
    _, sv, vt = np.linalg.svd(pts - c0, full_matrices=False)
    e1, e2, normal = vt
    u = (pts - c0) @ e1
    v = (pts - c0) @ e2
    a = np.column_stack([u, v, np.ones_like(u)])
    sol, *_ = np.linalg.lstsq(a, u * u + v * v, rcond=None)
    cu, cv = sol[0] / 2, sol[1] / 2
    radius = float(np.sqrt(max(sol[2] + cu * cu + cv * cv, 1e-300)))
    return c0 + cu * e1 + cv * e2, radius, normal, e1, e2


def open_shape(coords: np.ndarray, axis_distance: float = 2.0) -> dict:
    """Recognise the open trefoil's shape: a planar circular loop tangent to the straight ends.

    The beads farther than ``axis_distance`` from the z axis (the line of the clamped ends)
    give a first plane (SVD) and circle (algebraic least squares); every bead within
    0.1 R + 1 of that circle, in its plane, is then a loop bead, and the fit is repeated on
    them. The shape is ``"loop"`` when all hold:

    * planarity: RMS distance of loop beads from the plane < 0.1 R;
    * roundness: RMS deviation from the circle < 0.05 R;
    * closure: the loop beads cover ≥ 90 % of the circle's angles (in 10° bins);
    * tangency: the z axis lies in the loop's plane (|n·ẑ| < 0.25) and passes at distance
      D from the centre with |D/R − 1| < 0.5. In the thin limit D/R → 1 (the circle touches
      the line, paper §VIII); a finite thickness makes the string wrap part of the circle,
      which pulls the circle's centre towards the axis; D/R is reported so the trend shows.

    Otherwise ``"other"``. Returns ``{"label", "features"}``.
    """
    x = np.asarray(coords, dtype=float)
    rho = np.hypot(x[:, 0], x[:, 1])
    off = x[rho > axis_distance]
    feats: dict = {"loop_beads": 0}
    if len(off) < 12:
        return {"label": "other", "features": feats}
    centre, radius, normal, e1, e2 = _fit_circle(off)
    rel = x - centre
    h = rel @ normal
    r_in = np.hypot(rel @ e1, rel @ e2)
    near = (np.abs(r_in - radius) < 0.1 * radius + 1.0) & (np.abs(h) < 0.1 * radius + 1.0)
    loop = x[near]
    if len(loop) < 12:
        return {"label": "other", "features": feats}
    centre, radius, normal, e1, e2 = _fit_circle(loop)
    rel = loop - centre
    u, v, h = rel @ e1, rel @ e2, rel @ normal
    dev = np.hypot(u, v) - radius
    ang = np.arctan2(v, u)
    coverage = len(np.unique(np.floor((ang + np.pi) / (np.pi / 18)))) / 36
    axis_dist = float(np.hypot(centre[0], centre[1]))
    feats = {
        "loop_beads": int(len(loop)),
        "radius": radius,
        "planarity": float(np.sqrt(np.mean(h**2))) / radius,
        "roundness": float(np.sqrt(np.mean(dev**2))) / radius,
        "coverage": float(coverage),
        "normal_z": float(abs(normal[2])),
        "axis_distance_over_radius": axis_dist / radius,
    }
    ok = (feats["planarity"] < 0.1 and feats["roundness"] < 0.05 and coverage >= 0.9
          and feats["normal_z"] < 0.25 and abs(feats["axis_distance_over_radius"] - 1) < 0.5)
    return {"label": "loop" if ok else "other", "features": feats}


def excess_length_for_force(eps_e: float, force: float, C: float = 1.0) -> float:
    """The excess length a tension F selects at equilibrium: L_e = (ε_e C/F)^{1/2} (§VIII)."""
    if force <= 0:
        raise ValueError(f"the force must be > 0 (in units of C/b²), got {force}")
    return float(np.sqrt(eps_e * C / force))


@dataclass
class OpenResult(BestFirst):
    """Replicas of one open knot at one excess length, best first."""

    knot: str
    excess_length: float
    beads: int
    seed: int
    settings: dict
    replicas: list[ReplicaResult]
    wall_time: float
    interrupted: bool = False
    version: str = __version__
    bounds: dict = field(default_factory=dict)

    @property
    def eps_e(self) -> float:
        """ε_e = E·L_e/C of the best replica (paper §VIII)."""
        return self.best.epsilon

    @property
    def energy(self) -> float:
        return self.best.energy

    @property
    def tension(self) -> float:
        """μ = E/L_e (in C/b²) of the best replica (paper §VIII)."""
        return self.best.energy / self.excess_length

    def shape(self) -> dict:
        return open_shape(self.best.coords)

    def to_dict(self) -> dict:
        shape = self.shape() if self.replicas else {"label": None, "features": {}}
        return {
            "knot": self.knot,
            "excess_length": self.excess_length,
            "beads": self.beads,
            "seed": self.seed,
            "energy": self.energy if self.replicas else None,
            "eps_e": self.eps_e if self.replicas else None,
            "tension": self.tension if self.replicas else None,
            "shape": shape["label"],
            "shape_features": shape["features"],
            "bounds": self.bounds,
        } | self.provenance()

    def save(self, out: str | Path) -> dict[str, Path]:
        """Write ``result.json`` and the best chain as ``best.xyz`` (open chain)."""
        from stiffknots.chain import Chain, save

        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "result.json").write_text(json.dumps(self.to_dict(), indent=2, default=json_default))
        meta = {"knot": self.knot, "seed": self.best.seed, "eps_e": self.eps_e,
                "excess_length": self.excess_length, "version": self.version}
        save(Chain(self.best.coords, closed=False, meta=meta), out / "best.xyz")
        return {"result": out / "result.json", "best_xyz": out / "best.xyz"}



def _open_job(coords, settings, seed, replica, knot_name):
    """Worker: anneal one open replica and verify the knot type of its closure along z."""
    from stiffknots.knots.identify import close_open_chain_along_z, verify_knot

    res = run_replica(coords, settings, seed, replica)
    ok, found = verify_knot(close_open_chain_along_z(res.coords), knot_name, closed=True)
    res.knot = found
    res.knot_verified = bool(ok)
    return res


def open_chain(knot: str, excess_length: int, seed: int = 0) -> np.ndarray:
    """The starting chain of an open knot with the given (integer) excess length."""
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.knots.embedding import EmbeddingError
    from stiffknots.knots.open_embedding import embed_open

    k = get_knot(knot)
    if not k.braid_word:
        raise ValueError(f"{k.name} has no braid word in the catalogue; cannot embed it open")
    le = int(excess_length)
    if le != excess_length or le < 8:
        raise ValueError(f"excess_length must be an integer ≥ 8 (bond lengths), got "
                         f"{excess_length}")
    try:
        return embed_open(k.braid_word, k.braid_strands, le, expected=k.name, seed=seed)
    except EmbeddingError as exc:
        msg = str(exc).replace("n_beads", "excess_length")
        raise EmbeddingError(f"{k.name}: {msg}") from None


def anneal_open(
    knot: str,
    excess_length: int = 80,
    moves: int = DEFAULT_OPEN_MOVES,
    replicas: int = 2,
    seed: int = 0,
    *,
    params: MoveParams | None = None,
    schedule: Schedule | None = None,
    workers: int | None = None,
    quench_fraction: float = 0.1,
    on_replica_done: Callable[[ReplicaResult], None] | None = None,
) -> OpenResult:
    """Anneal an open knot at fixed excess length L_e (paper §VIII) and verify it.

    Parameters
    ----------
    knot : knot name ('3_1', '4_1', …).
    excess_length : L_e in bond lengths (integer; the knot needs a minimum, reported if
        too small).
    moves, replicas, seed, params, schedule, workers, quench_fraction, on_replica_done :
        as for :func:`stiffknots.anneal`. ``params.exclusion = "tube"`` with a small ``w``
        approaches the thin limit.

    Returns
    -------
    OpenResult — replicas sorted by energy; ``eps_e``, ``tension``, ``shape()``.

    Raises
    ------
    TopologyChangedError
        If the closure along z of any replica is not the requested knot (never expected).
    """
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.theory.bounds import open_bounds

    k = get_knot(knot)
    if replicas < 1:
        raise ValueError(f"replicas must be ≥ 1, got {replicas}")
    coords = open_chain(k.name, excess_length, seed=seed)
    settings = AnnealSettings(moves=int(moves), schedule=schedule or Schedule(),
                              params=params or MoveParams(), quench_fraction=quench_fraction,
                              closed=False)
    settings.validate()
    settings.params.validate(len(coords))
    seeds = replica_seeds(seed, replicas)
    nw = workers or default_workers(replicas)
    t0 = time.perf_counter()
    results, interrupted = run_jobs(
        _open_job, [(coords, settings, s, r, k.name) for r, s in enumerate(seeds)], nw,
        on_replica_done)
    results.sort(key=lambda r: r.energy)
    bad = [r for r in results if not r.knot_verified]
    if bad:
        raise TopologyChangedError(
            f"{len(bad)} open replica(s) of {k.name} closed along z as "
            f"{', '.join(str(r.knot) for r in bad)}; this is a bug, please report it "
            f"with seed {seed}")
    b = open_bounds(k.bridge_number, k.braid_index)
    bounds = {"eps_e_lower": b.lower, "eps_e_upper": b.upper}
    return OpenResult(knot=k.name, excess_length=float(excess_length), beads=len(coords),
                      seed=seed, settings=settings.as_dict(), replicas=results,
                      wall_time=time.perf_counter() - t0, interrupted=interrupted,
                      bounds=bounds)


@dataclass
class TensionScan:
    """μ against L_e for one knot (paper §VIII) and its fits."""

    knot: str
    n: int | None
    i: int | None
    points: list[dict]
    bounds: dict
    version: str = __version__

    @property
    def fit_eps_e(self) -> float:
        """Least-squares slope of μ against 1/L_e² through the origin: μ L_e²/C."""
        x = np.array([1 / p["excess_length"] ** 2 for p in self.points])
        y = np.array([p["tension"] for p in self.points])
        return float((x @ y) / (x @ x))

    def finite_differences(self) -> list[dict]:
        """μ = −dE/dL_e between neighbouring excess lengths, next to E/L_e at the midpoint
        (the paper's relation μ = E/L_e, checked by an independent estimate)."""
        pts = sorted(self.points, key=lambda p: p["excess_length"])
        out = []
        for a, b in zip(pts, pts[1:], strict=False):
            la, lb = a["excess_length"], b["excess_length"]
            mu_fd = -(b["energy"] - a["energy"]) / (lb - la)
            mid = float(np.sqrt(la * lb))
            # E/L_e at the geometric midpoint, with E ∝ 1/L_e interpolated
            mu_rel = float(np.sqrt(a["tension"] * b["tension"]))
            out.append({"L_e": mid, "mu_finite_difference": mu_fd, "mu_E_over_L": mu_rel})
        return out

    def to_dict(self) -> dict:
        return {"knot": self.knot, "n": self.n, "i": self.i, "points": self.points,
                "fit_eps_e": self.fit_eps_e, "finite_differences": self.finite_differences(),
                "bounds": self.bounds, "version": self.version}


def tension_scan(knot: str, excess_lengths: Sequence[int], moves: int = DEFAULT_OPEN_MOVES,
                 replicas: int = 2, seed: int = 0, *, params: MoveParams | None = None,
                 workers: int | None = None,
                 progress: Callable[[OpenResult], None] | None = None) -> TensionScan:
    """Anneal ``knot`` open at every excess length and collect (L_e, E, ε_e, μ, shape)."""
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.theory.bounds import open_bounds

    if not excess_lengths:
        raise ValueError("give at least one excess length")
    k = get_knot(knot)
    pts = []
    for le in excess_lengths:
        res = anneal_open(k.name, int(le), moves=moves, replicas=replicas, seed=seed,
                          params=params, workers=workers)
        d = res.to_dict()
        pts.append({key: d[key] for key in ("excess_length", "energy", "eps_e", "tension",
                                             "shape", "beads", "wall_time")}
                   | {"seed": seed, "min_segment_distance": res.best.min_segment_distance})
        if progress:
            progress(res)
    b = open_bounds(k.bridge_number, k.braid_index)
    return TensionScan(knot=k.name, n=k.bridge_number, i=k.braid_index, points=pts,
                       bounds={"eps_e_lower": b.lower, "eps_e_upper": b.upper})
