"""Theory of stiff knots: planar elastica constants (Appendix D), energy bounds (§IV–IX) and
the thin-limit energies of structures (§V B).

Docstrings throughout stiffknots cite the paper (Gallotti & Pierre-Louis, "Stiff knots",
Phys. Rev. E 2007) by section and printed equation number. The printed numbers of the
equations the LaTeX source labels (one sequence (1)–(55) in the main text; (B1)…, (C1)…, (D1)…
in the appendices; checked by compiling the source) are::

    printed label                  section
    (1)    e:length               §II
    (2)    e:E                    §II
    (3)    e:small_deformations   §II
    (4)    e:F                    §II
    (5)    e:variation_F          §III
    (6)    e:A                    §III
    (7)    e:var_E_1              §III
    (8)    e:var_E_3              §III
    (9)    e:bridge_k             §IV
    (10)   e:total_curv           §IV
    (11)   e:epsilon              §IV
    (13)   e:epsilon_sup_n2       §IV
    (15)   e:0_to_id              §V A
    (16)   e:self_consistency_E   §V A
    (17)   e:E_P                  §V B 2
    (18)   e:F_P                  §V B 2
    (19)   e:variation_F_P        §V B 2
    (20)   e:A_P                  §V B 2
    (21)   e:var_E_1_P            §V B 2
    (22)   e:var_E_3_P            §V B 2
    (23)   e:grouping_bc          §V B 2
    (24)   e:BC_P_A               §V B 2
    (25)   e:BC_P_Q               §V B 2
    (26)   e:mu_closed            §V B 2
    (27)   e:epsilon*_parts       §V B 2
    (28)   e:L_P_parts            §V B 2
    (29)   e:epsilon*_SBL         §VI A
    (30)   e:epsilon*_CB          §VI A
    (31)   e:epsilon_ineq_0       §VI A
    (32)   e:epsilon_ineq         §VI A
    (39)   e:hierarchy            §VII
    (40)   e:excess_length        §VIII
    (41)   e:tension_energy       §VIII
    (42)   e:epsilon_e            §VIII
    (45)   e:mu_ineq              §VIII
    (B1)   e:upper_bound_e0       §B
    (B2)   e:local_schwarz        §B
    (B3)   e:local_tangent_jump   §B 1
    (B4)   e:tang_continuity      §B 1
    (B6)   e:no_knot_loc          §B 2
    (C1)   e:mu_P                 §C 1 a
    (C2)   e:sum_mu_closed        §C 1 a
    (C3)   e:mu_E_L               §C 1 a
    (C4)   e:normalized_parts     §C 1 b
    (C6)   e:epsilon*_parts_app   §C 1 b
    (C7)   e:sum_mu_open          §C 2 a
    (D1)   e:2D_elastica          §D 1
    (D5)   e:alpha_loop           §D 1
    (D8)   e:epsilon_loop_calc    §D 1
"""

from stiffknots.theory.bounds import (
    ArcAnsatz,
    ClosedBounds,
    OpenBounds,
    RestrictedCurvatureBounds,
    closed_bounds,
    eps_e,
    minimize_pbl_arc_ansatz,
    open_bounds,
    pbl_arc_length,
    restricted_curvature_bounds,
    self_consistency_limit,
    tension_from_energy,
    tension_from_eps_e,
    thick_knot_bound,
)
from stiffknots.theory.elastica import (
    EPS_0,
    METHODS,
    PAPER_VALUES,
    ElasticaConstants,
    Hierarchy,
    StructureEnergy,
    discrete_epsilon,
    eight_curve,
    eighty_curve,
    elastica_constants,
    eps_80,
    eps_cb,
    eps_pbl,
    eps_structure,
    hierarchy,
    loop_curve,
    solve_eight,
    solve_loop,
)

__all__ = [
    "ArcAnsatz",
    "ClosedBounds",
    "EPS_0",
    "ElasticaConstants",
    "Hierarchy",
    "METHODS",
    "OpenBounds",
    "PAPER_VALUES",
    "RestrictedCurvatureBounds",
    "StructureEnergy",
    "closed_bounds",
    "discrete_epsilon",
    "eight_curve",
    "eighty_curve",
    "elastica_constants",
    "eps_80",
    "eps_cb",
    "eps_e",
    "eps_pbl",
    "eps_structure",
    "hierarchy",
    "loop_curve",
    "minimize_pbl_arc_ansatz",
    "open_bounds",
    "pbl_arc_length",
    "restricted_curvature_bounds",
    "self_consistency_limit",
    "solve_eight",
    "solve_loop",
    "tension_from_energy",
    "tension_from_eps_e",
    "thick_knot_bound",
]
