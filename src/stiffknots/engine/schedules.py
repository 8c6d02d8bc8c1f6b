"""Temperature schedules for simulated annealing (paper §VII: "a power law decrease").

Every schedule maps the fraction s ∈ [0, 1] of the annealing moves done to a temperature
(k_B T in units of C, bond length 1). A zero-temperature quench follows the schedule in the
driver.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

SCHEDULES = ("power", "geometric")


@dataclass(frozen=True)
class Schedule:
    """Cooling from ``t_start`` to ``t_end``.

    ``power`` (the paper's form, §VII):  T(s) = t_start · (1 + s·c)^(−a), with
    c = (t_start/t_end)^(1/a) − 1 so that T(1) = t_end; ``a`` is the power-law exponent.
    ``geometric``:  T(s) = t_start · (t_end/t_start)^s.
    """

    kind: str = "power"
    t_start: float = 3e-2
    t_end: float = 1e-6
    exponent: float = 2.0

    def validate(self) -> None:
        if self.kind not in SCHEDULES:
            raise ValueError(f"unknown schedule {self.kind!r}; allowed: {', '.join(SCHEDULES)}")
        if not (self.t_start > 0 and self.t_end > 0 and self.t_end < self.t_start):
            raise ValueError(
                f"temperatures must satisfy 0 < t_end < t_start, got {self.t_start}, {self.t_end}"
            )
        if self.exponent <= 0:
            raise ValueError(f"the power-law exponent must be > 0, got {self.exponent}")

    def temperature(self, s: float | np.ndarray) -> float | np.ndarray:
        s = np.clip(s, 0.0, 1.0)
        if self.kind == "geometric":
            return self.t_start * (self.t_end / self.t_start) ** s
        c = (self.t_start / self.t_end) ** (1.0 / self.exponent) - 1.0
        return self.t_start * (1.0 + s * c) ** (-self.exponent)

    def as_dict(self) -> dict:
        return asdict(self)
