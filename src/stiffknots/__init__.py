"""stiffknots: the mechanics of stiff (elastic) knots.

Implements Gallotti & Pierre-Louis, "Stiff knots", Phys. Rev. E (2007): bounds from the bridge
number and braid index, the planar elastica constants, Monte Carlo annealing of knotted chains,
open knots under tension and the restricted-curvature problem, for every knot in KnotInfo.
"""

from stiffknots._version import __version__

__all__ = ["__version__"]
