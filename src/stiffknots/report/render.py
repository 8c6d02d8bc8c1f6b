"""Pictures of chains: one consistent style for every figure of the package.

Every chain (closed knot or open string) is drawn as a shaded tube around its centre line, as in
the 3D renderings of the annealed knots of Gallotti & Pierre-Louis (Fig. 6). The tube is a
polygon mesh built from rings of ``n_sides`` vertices, one ring per bead, oriented with a
parallel-transport (rotation-minimising) frame so that the mesh does not twist; each ring lies in
the plane bisecting the two bonds at its bead and is stretched there into the mitre ellipse, so
that every vertex lies at exactly the tube radius from both bonds. The faces are drawn as one
matplotlib :class:`~mpl_toolkits.mplot3d.art3d.Poly3DCollection` with Lambert shading from a
light fixed relative to the viewer; the colour runs along the arclength (a cyclic colour map for
closed chains, so that there is no seam) or is a single colour.

Public functions
----------------
tube_mesh
    The mesh itself (vertices, quadrilateral faces, end caps), for tests and other renderers.
plot_tube
    Draw a chain as a tube on a 3D matplotlib axis.
plot_chain
    The package-wide picture of a chain: :func:`plot_tube` with the default style.
save_chain_png
    Write the picture of a chain to a PNG file.
contact_pairs
    Pairs of beads closer than a cut-off (to mark contacts).
best_view
    A proper rotation that puts the principal axes of a chain along x, y, z, and a view for it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import matplotlib
import matplotlib.colors as mcolors
import numpy as np  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d import proj3d  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection  # noqa: E402

from stiffknots.fileio import atomic_path

__all__ = [
    "DEFAULT_RADIUS",
    "TubeMesh",
    "tube_mesh",
    "plot_tube",
    "plot_chain",
    "save_chain_png",
    "contact_pairs",
    "best_view",
]

#: Default tube radius: half the bead exclusion distance 1/sqrt(2) of the paper's chain (§VII).
DEFAULT_RADIUS = 1.0 / (2.0 * np.sqrt(2.0))

#: Colour map along the arclength of closed chains: cyclic, muted, no seam at bead 0.
_CYCLIC = mcolors.LinearSegmentedColormap.from_list(
    "stiffknots_cyclic",
    ["#2f6db3", "#3aa3a0", "#e0b43a", "#d9623b", "#8e4fa3", "#2f6db3"],
)
#: Colour map along the arclength of open chains.
_LINEAR = "viridis"

_MITRE_LIMIT = 2.0  # at most this stretch of a ring at a sharp bend (bend angle 120°)


def _resolve(coords, closed: bool | None) -> tuple[object, bool]:
    """Coordinates and closure of an array or a :class:`~stiffknots.chain.Chain`-like object.

    ``closed=None`` takes the object's ``closed`` attribute if it has one, else True.
    """
    if hasattr(coords, "coords"):
        if closed is None:
            closed = bool(getattr(coords, "closed", True))
        coords = coords.coords
    return coords, (True if closed is None else bool(closed))


def _as_coords(coords, closed: bool = True) -> np.ndarray:
    """Check and convert bead coordinates to a float64 ``(N, 3)`` array."""
    try:
        x = np.asarray(coords, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"coords must be an (N, 3) array of numbers: {exc}") from None
    if x.ndim != 2 or x.shape[1] != 3:
        raise ValueError(f"coords must have shape (N, 3), got {x.shape}")
    if len(x) < 3:
        raise ValueError(f"a chain needs at least 3 beads to be drawn, got N = {len(x)}")
    if not np.all(np.isfinite(x)):
        raise ValueError("coords contain NaN or infinite values")
    bonds = np.diff(np.vstack([x, x[:1]]) if closed else x, axis=0)
    if np.any(np.linalg.norm(bonds, axis=1) < 1e-12):
        raise ValueError("two consecutive beads coincide (a bond of zero length)")
    return x


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _perpendicular(t: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to the unit vector ``t``."""
    a = np.eye(3)[int(np.argmin(np.abs(t)))]
    return _unit(a - (a @ t) * t)


def _rotate(v, a, b) -> tuple[float, float, float]:
    """Rotate ``v`` by the smallest rotation taking unit vector ``a`` to unit vector ``b``
    (Rodrigues' formula on plain floats: the frame is transported bead by bead, and numpy's
    per-call cost on 3-vectors made this loop most of the time of an atlas page)."""
    v0, v1, v2 = v
    a0, a1, a2 = a
    b0, b1, b2 = b
    x0, x1, x2 = a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0  # axis = a × b
    s = math.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
    c = min(1.0, max(-1.0, a0 * b0 + a1 * b1 + a2 * b2))
    if s < 1e-12:
        if c > 0:
            return v0, v1, v2
        # antiparallel: rotate by pi about any axis perpendicular to a
        k0, k1, k2 = _perpendicular(np.array(a, dtype=float))
        d = 2.0 * (v0 * k0 + v1 * k1 + v2 * k2)
        return d * k0 - v0, d * k1 - v1, d * k2 - v2
    k0, k1, k2 = x0 / s, x1 / s, x2 / s
    kv = (k0 * v0 + k1 * v1 + k2 * v2) * (1.0 - c)
    return (v0 * c + (k1 * v2 - k2 * v1) * s + k0 * kv,
            v1 * c + (k2 * v0 - k0 * v2) * s + k1 * kv,
            v2 * c + (k0 * v1 - k1 * v0) * s + k2 * kv)


def _transported(v, a, b) -> tuple[float, float, float]:
    """``v`` rotated from tangent ``a`` to tangent ``b``, made exactly perpendicular to ``b``
    and unit."""
    w0, w1, w2 = _rotate(v, a, b)
    b0, b1, b2 = b
    d = w0 * b0 + w1 * b1 + w2 * b2
    w0, w1, w2 = w0 - d * b0, w1 - d * b1, w2 - d * b2
    r = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    return w0 / r, w1 / r, w2 / r


@dataclass(frozen=True)
class TubeMesh:
    """A tube around a polygonal centre line.

    Attributes
    ----------
    vertices : ndarray
        Shape ``(R, S, 3)``: ring ``k`` (one per bead, ``R = N``) has ``S = n_sides`` vertices.
    quads : ndarray of int
        Shape ``(F, 4)``: faces as indices into ``vertices.reshape(-1, 3)``, counter-clockwise seen
        from outside; ``F = N * S`` for a closed chain, ``(N - 1) * S`` for an open one.
    caps : ndarray of int
        Shape ``(C, S)``: end caps (``C = 2`` for an open chain, 0 for a closed one), indices as for
        ``quads``.
    centres : ndarray
        Shape ``(R, 3)``: the centre of each ring (the bead).
    tangents : ndarray
        Shape ``(R, 3)``: unit normal of the plane of each ring (the bisector of the two bonds at
        the bead).
    radius : float
    closed : bool
    """

    vertices: np.ndarray
    quads: np.ndarray
    caps: np.ndarray
    centres: np.ndarray
    tangents: np.ndarray
    radius: float
    closed: bool

    @property
    def points(self) -> np.ndarray:
        """All vertices as an ``(R * S, 3)`` array (what ``quads`` and ``caps`` index)."""
        return self.vertices.reshape(-1, 3)

    def face_polygons(self) -> np.ndarray:
        """The quadrilateral faces as an ``(F, 4, 3)`` array of corner coordinates."""
        return self.points[self.quads]


def tube_mesh(coords, radius: float = DEFAULT_RADIUS, *, closed: bool = True,
              n_sides: int = 12) -> TubeMesh:
    """Mesh of a tube of radius ``radius`` around a chain.

    Parameters
    ----------
    coords : array_like, shape (N, 3)
        Bead coordinates, ``N >= 3``.
    radius : float
        Tube radius (> 0).
    closed : bool
        Join the last bead to the first.
    n_sides : int
        Vertices per ring (>= 3).

    Returns
    -------
    TubeMesh
        One ring per bead. The rings are oriented with a discrete parallel-transport frame
        (each frame is the previous one rotated by the smallest rotation between consecutive
        tangents); for a closed chain the holonomy of the frame around the loop is spread
        evenly along the arclength, so that the last ring joins the first without a twist. Each
        ring lies in the plane bisecting the bonds at its bead and is the mitre ellipse there,
        so that all its vertices are at distance ``radius`` from the lines of both bonds: the
        faces between rings ``k`` and ``k + 1`` lie on the cylinder of radius ``radius`` around
        bond ``k`` (the stretch is capped at ``2``, i.e. for bends sharper than 120°, where the
        distance is then smaller than ``radius`` on the outer side of the bend).

    Raises
    ------
    ValueError
        If the coordinates are not an ``(N, 3)`` array of finite numbers with ``N >= 3``, two
        consecutive beads coincide, ``radius <= 0`` or ``n_sides < 3``.
    """
    x = _as_coords(coords, closed)
    if not (np.isfinite(radius) and radius > 0):
        raise ValueError(f"the tube radius must be > 0, got {radius}")
    if int(n_sides) != n_sides or n_sides < 3:
        raise ValueError(f"n_sides must be an integer >= 3, got {n_sides}")
    n_sides = int(n_sides)
    n = len(x)
    if closed:
        u = _unit(np.roll(x, -1, axis=0) - x)  # bond k: bead k -> k+1
        u_in, u_out = np.roll(u, 1, axis=0), u  # bonds arriving at / leaving bead k
    else:
        b = _unit(np.diff(x, axis=0))
        u_in = np.vstack([b[:1], b])
        u_out = np.vstack([b, b[-1:]])
    s = u_in + u_out
    ns = np.linalg.norm(s, axis=1)
    # a full reversal (u_out = -u_in) has no bisector: use the outgoing bond there
    t = np.where((ns > 1e-9)[:, None], s / np.maximum(ns, 1e-300)[:, None], u_out)

    # parallel transport of the normal along the tangents
    tl = t.tolist()
    frame = [tuple(_perpendicular(t[0]).tolist())]
    for k in range(1, n):
        frame.append(_transported(frame[-1], tl[k - 1], tl[k]))
    normals = np.array(frame)
    if closed:
        # close the frame: transport once more back to bead 0 and spread the mismatch angle
        v = np.array(_transported(frame[-1], tl[-1], tl[0]))
        phi = np.arctan2(np.cross(normals[0], v) @ t[0], normals[0] @ v)
        arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(x, axis=0), axis=1))])
        total = arc[-1] + np.linalg.norm(x[0] - x[-1])
        ang = -phi * arc / total
        bi = np.cross(t, normals)
        normals = np.cos(ang)[:, None] * normals + np.sin(ang)[:, None] * bi
    binormals = np.cross(t, normals)

    theta = 2.0 * np.pi * np.arange(n_sides) / n_sides
    q = (np.cos(theta)[None, :, None] * normals[:, None, :]
         + np.sin(theta)[None, :, None] * binormals[:, None, :])  # (N, S, 3) unit circle
    # mitre: stretch along the in-plane bend direction by 1 / cos(half bend angle)
    cos_half = np.clip(np.einsum("ij,ij->i", u_out, t), 1.0 / _MITRE_LIMIT, 1.0)
    bend = u_out - u_in
    bend = bend - np.einsum("ij,ij->i", bend, t)[:, None] * t
    nb = np.linalg.norm(bend, axis=1)
    e1 = np.where((nb > 1e-12)[:, None], bend / np.maximum(nb, 1e-300)[:, None], 0.0)
    stretch = (1.0 / cos_half - 1.0)[:, None, None]
    q = q + stretch * np.einsum("rsk,rk->rs", q, e1)[:, :, None] * e1[:, None, :]
    verts = x[:, None, :] + radius * q

    rings = n if closed else n - 1
    k = np.arange(rings)[:, None]
    j = np.arange(n_sides)[None, :]
    k1, j1 = (k + 1) % n, (j + 1) % n_sides
    quads = np.stack([k * n_sides + j, k * n_sides + j1, k1 * n_sides + j1, k1 * n_sides + j],
                     axis=-1).reshape(-1, 4)
    if closed:
        caps = np.empty((0, n_sides), dtype=int)
    else:
        ring = np.arange(n_sides)
        caps = np.stack([ring[::-1], (n - 1) * n_sides + ring])
    return TubeMesh(vertices=verts, quads=quads, caps=caps, centres=x, tangents=t,
                    radius=float(radius), closed=bool(closed))


def best_view(coords) -> tuple[np.ndarray, tuple[float, float]]:
    """A rotation to the principal axes of a chain and a view angle that shows it well.

    Parameters
    ----------
    coords : array_like, shape (N, 3)

    Returns
    -------
    rotation : ndarray, shape (3, 3)
        A proper rotation (determinant +1, so a knot is never turned into its mirror image);
        ``(coords - centre) @ rotation`` puts the largest principal axis along x and the
        smallest along z.
    view : (elev, azim)
        Angles for :meth:`~mpl_toolkits.mplot3d.axes3d.Axes3D.view_init`. A near-planar chain is
        seen almost along its smallest principal axis (its knot diagram, with a slight tilt to
        show the relief); a fully 3D one from higher up on a diagonal.
    """
    x = np.asarray(coords, dtype=float)
    c = x - x.mean(axis=0)
    w, v = np.linalg.eigh(c.T @ c / len(c))  # ascending eigenvalues
    rot = v[:, ::-1].copy()  # columns: largest, middle, smallest principal axis
    if np.linalg.det(rot) < 0:
        rot[:, 2] *= -1.0
    w = np.maximum(w[::-1], 0.0)
    flat = float(np.sqrt(w[2] / w[1])) if w[1] > 0 else 0.0  # 0: planar, 1: round
    elev = 75.0 - 40.0 * min(1.0, flat / 0.8)
    return rot, (elev, -80.0)


def contact_pairs(coords, cutoff: float, *, closed: bool = True,
                  min_separation: int = 3) -> list[tuple[int, int]]:
    """Pairs of beads ``(i, j)``, ``i < j``, closer than ``cutoff``.

    Parameters
    ----------
    coords : array_like, shape (N, 3)
    cutoff : float
        Distance below which two beads are in contact.
    closed : bool
        Count index distances around the ring.
    min_separation : int
        Only pairs at index distance ``>= min_separation`` along the chain.

    Returns
    -------
    list of (int, int)
    """
    x = _as_coords(coords, closed)
    n = len(x)
    d = np.linalg.norm(x[:, None, :] - x[None, :, :], axis=2)
    idx = np.abs(np.arange(n)[:, None] - np.arange(n)[None, :])
    if closed:
        idx = np.minimum(idx, n - idx)
    a, b = np.nonzero((d < cutoff) & (idx >= min_separation))
    return [(int(i), int(j)) for i, j in zip(a, b, strict=True) if i < j]


def _eye_and_light(elev: float, azim: float) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors towards the viewer and towards the light (upper left, in front)."""
    e, a = np.deg2rad(elev), np.deg2rad(azim)
    eye = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    right = _unit(np.cross(np.array([0.0, 0.0, 1.0]), eye)) if abs(eye[2]) < 0.999 else \
        np.array([-np.sin(a), np.cos(a), 0.0])
    up = np.cross(eye, right)
    light = _unit(1.0 * eye + 0.55 * up - 0.45 * right)
    return eye, light


def _face_colors(mesh: TubeMesh, base: np.ndarray, eye: np.ndarray,
                 light: np.ndarray) -> np.ndarray:
    """Lambert shading (plus a weak specular highlight) of the faces, base colours (F, 4)."""
    p = mesh.face_polygons()
    normal = np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1])
    centre = p.mean(axis=1)
    ring = mesh.quads[:, 0] // mesh.vertices.shape[1]
    ring2 = mesh.quads[:, 2] // mesh.vertices.shape[1]
    axis_pt = 0.5 * (mesh.centres[ring] + mesh.centres[ring2])
    inward = np.einsum("ij,ij->i", normal, centre - axis_pt) < 0
    normal[inward] *= -1.0
    normal = _unit(normal)
    diffuse = np.clip(normal @ light, 0.0, 1.0)
    half = _unit(light + eye)
    spec = np.clip(normal @ half, 0.0, 1.0) ** 40
    shade = 0.32 + 0.68 * diffuse
    rgb = base[:, :3] * shade[:, None] + 0.35 * spec[:, None]
    out = np.empty((len(p), 4))
    out[:, :3] = np.clip(rgb, 0.0, 1.0)
    out[:, 3] = base[:, 3]
    return out


def _frame(ax, pts: np.ndarray, margin: float = 0.03) -> None:
    """Set the 2D view of a 3D axis to the projected bounding square of ``pts`` (tight)."""
    xs, ys, _ = proj3d.proj_transform(pts[:, 0], pts[:, 1], pts[:, 2], ax.get_proj())
    cx, cy = 0.5 * (xs.min() + xs.max()), 0.5 * (ys.min() + ys.max())
    h = 0.5 * max(np.ptp(xs), np.ptp(ys)) * (1.0 + 2.0 * margin)
    ax.viewLim.intervalx = (cx - h, cx + h)
    ax.viewLim.intervaly = (cy - h, cy + h)


def plot_tube(coords, ax=None, *, closed: bool | None = None, radius: float | None = None,
              color=None, cmap=None, contacts=None, contact_color="crimson",
              view: tuple[float, float] | None = None, title: str | None = None,
              n_sides: int | None = None):
    """Draw a chain as a shaded tube on a 3D matplotlib axis.

    Parameters
    ----------
    coords : array_like, shape (N, 3), or Chain
        Bead coordinates, ``N >= 3``, or a :class:`~stiffknots.chain.Chain`.
    ax : mpl_toolkits.mplot3d.axes3d.Axes3D, optional
        The axis to draw on; a new 5 × 5 in figure with one 3D axis filling it if None.
    closed : bool, optional
        Join the last bead to the first (a knot); an open chain gets flat end caps. Default: the
        ``closed`` attribute of a Chain, else True.
    radius : float, optional
        Tube radius; default :data:`DEFAULT_RADIUS` = 1/(2√2), half the bead exclusion
        distance, so that beads in contact show touching tubes.
    color : matplotlib colour, optional
        A single colour for the whole tube; default: colour along the arclength with ``cmap``.
    cmap : str or Colormap, optional
        Colour map along the arclength (default: a cyclic map for closed chains, so that bead
        0 shows no seam, and ``viridis`` for open chains). Ignored if ``color`` is given.
    contacts : float or sequence of (int, int), optional
        Bead pairs ``(i, j)`` to mark with a short segment between the beads and a dot at its
        middle, drawn over the tube; a number is a distance cut-off, and all pairs closer than
        it (index distance >= 3) are marked, see :func:`contact_pairs`.
    contact_color : matplotlib colour
        Colour of the contact marks.
    view : (elev, azim), optional
        View angles in the frame of the coordinates. Default (None): the chain is turned (by a
        proper rotation, never a mirror) to its principal axes and seen as :func:`best_view`
        says: nearly along its smallest principal axis if it is near-planar.
    title : str, optional
        Axis title.
    n_sides : int, optional
        Vertices per ring of the mesh (default 14 for N <= 400 beads, 10 above).

    Returns
    -------
    Axes3D
        The axis (its figure is ``ax.figure``).

    Raises
    ------
    ValueError
        For coordinates that are not an ``(N, 3)`` array of finite numbers with ``N >= 3``,
        a non-positive radius, or contact indices out of range.

    Notes
    -----
    The picture is framed tightly for the view it is drawn with (orthographic projection, the
    2D view limits set to the projected bounding square of the tube); after a later
    ``ax.view_init`` call it may need to be redrawn.
    """
    coords, closed = _resolve(coords, closed)
    x = _as_coords(coords, closed)
    n = len(x)
    r = DEFAULT_RADIUS if radius is None else float(radius)
    if contacts is None:
        pairs = []
    elif np.ndim(contacts) == 0:
        pairs = contact_pairs(x, float(contacts), closed=closed)
    else:
        pairs = [(int(i), int(j)) for i, j in contacts]
        bad = [p for p in pairs if not (0 <= p[0] < n and 0 <= p[1] < n)]
        if bad:
            raise ValueError(f"contact indices out of range 0..{n - 1}: {bad[:5]}")
    x = x - x.mean(axis=0)
    if view is None:
        rot, view = best_view(x)
        x = x @ rot
    elev, azim = float(view[0]), float(view[1])
    if n_sides is None:
        n_sides = 14 if n <= 400 else 10
    mesh = tube_mesh(x, r, closed=closed, n_sides=n_sides)

    if ax is None:
        fig = Figure(figsize=(5, 5))
        FigureCanvasAgg(fig)
        ax = fig.add_axes((0.0, 0.0, 1.0, 0.94 if title else 1.0), projection="3d")
    if not hasattr(ax, "get_zlim"):
        raise ValueError("ax must be a 3D axis (projection='3d')")

    # colours along the arclength, per face (ring of its first vertex)
    n_faces_ring = len(mesh.quads) // n_sides
    if color is not None:
        base = np.tile(np.array(mcolors.to_rgba(color)), (len(mesh.quads), 1))
    else:
        cm = matplotlib.colormaps.get_cmap(
            cmap if cmap is not None else (_CYCLIC if closed else _LINEAR))
        tpar = (np.arange(n_faces_ring) + 0.5) / (n if closed else n - 1)
        if not closed and cmap is None:
            tpar = 0.1 + 0.8 * tpar  # stay off viridis' darkest and lightest ends
        base = np.repeat(cm(tpar), n_sides, axis=0)
    eye, light = _eye_and_light(elev, azim)
    fc = _face_colors(mesh, base, eye, light)
    polys = list(mesh.face_polygons())
    if len(mesh.caps):
        cap_base = np.vstack([base[0], base[-1]])
        cap_normal = np.vstack([-mesh.tangents[0], mesh.tangents[-1]])
        diffuse = np.clip(cap_normal @ light, 0.0, 1.0)
        cap_fc = cap_base.copy()
        cap_fc[:, :3] *= (0.32 + 0.68 * diffuse)[:, None]
        # fan of degenerate quads (triangles with a repeated vertex): every polygon then has
        # 4 vertices; matplotlib pads ragged polygon lists with uninitialised values that
        # its 3D autoscaling can read (seen as a rare 'Axis limits cannot be NaN or Inf')
        cap_pts = mesh.points[mesh.caps]  # (2, S, 3)
        s_n = cap_pts.shape[1]
        for c in range(len(cap_pts)):
            for k in range(1, s_n - 1):
                tri = cap_pts[c, [0, k, k + 1, k + 1]]
                polys.append(tri)
        fc = np.vstack([fc, np.repeat(cap_fc, s_n - 2, axis=0)])
    coll = Poly3DCollection(polys, facecolors=fc, edgecolors=fc, linewidths=0.25,
                            zsort="average")
    ax.add_collection3d(coll)

    if pairs:
        a = np.array([p[0] for p in pairs])
        b = np.array([p[1] for p in pairs])
        segs = np.stack([x[a], x[b]], axis=1)
        ax.computed_zorder = False
        coll.set_zorder(1)
        ax.add_collection3d(Line3DCollection(segs, colors=contact_color, linewidths=1.4,
                                             zorder=3))
        mid = 0.5 * (x[a] + x[b])
        ax.scatter(mid[:, 0], mid[:, 1], mid[:, 2], s=14, color=contact_color,
                   edgecolors="white", linewidths=0.5, depthshade=False, zorder=4)

    pts = mesh.points
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = np.maximum(hi - lo, 1e-9)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(span)  # equal scale on the three axes
    ax.set_autoscale_on(False)
    ax.set_proj_type("ortho")
    ax.view_init(elev=elev, azim=azim)
    ax.set_axis_off()
    _frame(ax, pts)
    if title:
        ax.set_title(title, fontsize=10, pad=0)
    return ax


def plot_chain(coords, ax=None, *, closed: bool | None = None, title: str | None = None,
               contacts=None, **kwargs):
    """Draw a chain in the package's one style: a shaded tube, see :func:`plot_tube`.

    Parameters
    ----------
    coords : array_like, shape (N, 3), or Chain
        Bead coordinates.
    ax : Axes3D, optional
        A 3D matplotlib axis (created if None).
    closed : bool, optional
        Join the last bead to the first (default: a Chain's own ``closed``, else True).
    title : str, optional
        Axis title.
    contacts : float or sequence of (int, int), optional
        A distance cut-off (mark bead pairs at index distance >= 3 closer than this) or
        explicit bead pairs.
    **kwargs
        Passed on to :func:`plot_tube` (``radius``, ``color``, ``cmap``, ``view``, ...).

    Returns
    -------
    Axes3D
    """
    return plot_tube(coords, ax, closed=closed, title=title, contacts=contacts, **kwargs)


def save_chain_png(coords, path, *, title: str | None = None, closed: bool | None = None,
                   dpi: int = 120, size: float = 5.0, **kwargs) -> Path:
    """Write the picture of a chain (:func:`plot_tube`) to a PNG file and close the figure.

    Parameters
    ----------
    coords : array_like, shape (N, 3), or Chain
        Bead coordinates.
    path : str or Path
        Output file; its folder is created if needed.
    title : str, optional
        Title above the picture.
    closed : bool, optional
        Join the last bead to the first (default: a Chain's own ``closed``, else True).
    dpi : int
        Resolution (default 120, i.e. 600 × 600 pixels at the default size).
    size : float
        Width and height of the figure in inches.
    **kwargs
        Passed on to :func:`plot_tube`.

    Returns
    -------
    Path
        The file written.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig = Figure(figsize=(size, size))
    FigureCanvasAgg(fig)
    try:
        ax = fig.add_axes((0.0, 0.0, 1.0, 0.93 if title else 1.0), projection="3d")
        plot_tube(coords, ax, closed=closed, **kwargs)
        if title:
            fig.suptitle(title, fontsize=11, y=0.975)
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=dpi, facecolor="white", format=path.suffix.lstrip(".") or "png")
    finally:
        fig.clear()
    return path
