"""Analysis of knot shapes: contacts, line-braids and point-braids, shape classes, states.

Implements the structural reading of §V (line-braids, point-braids, multiple points, the
structure graph; Figs 5 and 7 of Gallotti & Pierre-Louis, "Stiff knots", PRE 2007) and the
shape classes of the Monte Carlo study of §VII (circular braid, 4-fold cage, "80"; Figs 6 and 7).

Public API
----------
:func:`contact_map`
    Non-adjacent beads within the contact distance (:class:`ContactMap`).
:func:`analyse_structure`
    Local multiplicity, line-braids, contact zones and the structure graph (:class:`Structure`);
    :func:`local_multiplicity`, :func:`line_braids`, :func:`structure_graph` for the parts.
:func:`classify`
    ``"CB"`` (with its index ``i``), ``"4C"``, ``"80"`` or ``"other"`` from geometric and
    structural features (:class:`Shape`).
:func:`group_states`
    Ground state and metastable states of a set of annealed chains (:class:`StateGroups`).
:mod:`stiffknots.analysis.synthetic`
    Synthetic chains of each class for tests and illustrations.
"""

from stiffknots.analysis.contacts import (
    DEFAULT_CONTACT_FACTOR,
    DEFAULT_D,
    DEFAULT_MIN_SEP,
    ContactMap,
    contact_map,
)
from stiffknots.analysis.shapes import LABELS, Shape, Thresholds, classify, shape_features
from stiffknots.analysis.states import StateGroup, StateGroups, group_states
from stiffknots.analysis.structure import (
    DEFAULT_TANGENT_ANGLE,
    ContactZone,
    Edge,
    LineBraid,
    Node,
    Structure,
    StructureGraph,
    analyse_structure,
    line_braids,
    local_multiplicity,
    structure_graph,
    structure_name,
)

__all__ = [
    "DEFAULT_CONTACT_FACTOR",
    "DEFAULT_D",
    "DEFAULT_MIN_SEP",
    "DEFAULT_TANGENT_ANGLE",
    "LABELS",
    "ContactMap",
    "ContactZone",
    "Edge",
    "LineBraid",
    "Node",
    "Shape",
    "StateGroup",
    "StateGroups",
    "Structure",
    "StructureGraph",
    "Thresholds",
    "analyse_structure",
    "classify",
    "contact_map",
    "group_states",
    "line_braids",
    "local_multiplicity",
    "shape_features",
    "structure_graph",
    "structure_name",
]
