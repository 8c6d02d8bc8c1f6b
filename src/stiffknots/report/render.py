"""Pictures of chains: one consistent style for every figure of the package."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402,F401


def plot_chain(coords: np.ndarray, ax=None, *, closed: bool = True, title: str | None = None,
               contacts: float | None = None):
    """Draw a chain as a shaded tube seen in 3D (matplotlib), coloured along its arclength.

    Parameters
    ----------
    coords : (N, 3) bead coordinates.
    ax : a 3D matplotlib axis (created if None).
    closed : join the last bead to the first.
    title : axis title.
    contacts : if given, mark pairs of beads at index distance ≥ 3 closer than this distance.

    Returns
    -------
    The axis.
    """
    x = np.asarray(coords, dtype=float)
    if closed:
        x = np.vstack([x, x[:1]])
    if ax is None:
        fig = plt.figure(figsize=(5, 5))
        ax = fig.add_subplot(111, projection="3d")
    x = x - x.mean(axis=0)
    # depth shading: draw segments back to front with darker colour for far ones
    view = np.array([1.0, -1.0, 0.6])
    view /= np.linalg.norm(view)
    seg_mid = 0.5 * (x[1:] + x[:-1])
    depth = seg_mid @ view
    order = np.argsort(depth)
    cmap = plt.get_cmap("viridis")
    t = np.linspace(0, 1, len(seg_mid))
    dn = (depth - depth.min()) / (np.ptp(depth) + 1e-12)
    for q in order:
        c = np.array(cmap(t[q]))
        c[:3] *= 0.55 + 0.45 * dn[q]
        ax.plot(x[q:q + 2, 0], x[q:q + 2, 1], x[q:q + 2, 2], color=c, lw=5.0,
                solid_capstyle="round")
    if contacts is not None:
        n = len(coords)
        d = np.linalg.norm(coords[:, None, :] - coords[None, :, :], axis=2)
        idx = np.abs(np.arange(n)[:, None] - np.arange(n)[None, :])
        idx = np.minimum(idx, n - idx) if closed else idx
        a, b = np.nonzero((d < contacts) & (idx >= 3))
        sel = a < b
        pts = 0.5 * (coords[a[sel]] + coords[b[sel]]) - np.asarray(coords).mean(axis=0)
        if len(pts):
            ax.scatter(pts[:, 0], pts[:, 1], pts[:, 2], color="crimson", s=6, depthshade=False)
    r = np.max(np.abs(x)) * 1.05
    ax.set_xlim(-r, r)
    ax.set_ylim(-r, r)
    ax.set_zlim(-r, r)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=25, azim=-45)
    ax.set_axis_off()
    if title:
        ax.set_title(title, fontsize=10)
    return ax


def save_chain_png(coords: np.ndarray, path, *, title: str | None = None,
                   closed: bool = True) -> None:
    """Write one PNG of a chain (two views side by side)."""
    fig = plt.figure(figsize=(9, 4.5))
    ax1 = fig.add_subplot(121, projection="3d")
    plot_chain(coords, ax1, closed=closed)
    ax2 = fig.add_subplot(122, projection="3d")
    plot_chain(coords, ax2, closed=closed)
    ax2.view_init(elev=90, azim=-90)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
