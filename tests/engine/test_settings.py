"""The settings of a replica's run (:mod:`stiffknots.engine.settings`): bad values are refused
with a message that names them, and the record of a run names the powers of a ``tight``
plan only."""

from dataclasses import replace

import pytest

from stiffknots.engine.settings import DEFAULT_POWERS, AnnealSettings


@pytest.mark.parametrize("change, match", [
    ({"moves": 999}, "moves"),
    ({"quench_fraction": 1.5}, "quench_fraction"),
    ({"n_chunks": 0}, "n_chunks"),
    ({"plan": "slow"}, "unknown plan"),
    ({"plan": "tight", "powers": (1, 2.5)}, "powers"),
    ({"plan": "tight", "powers": ()}, "powers"),
])
def test_bad_settings_are_refused(change, match):
    with pytest.raises(ValueError, match=match):
        replace(AnnealSettings(), **change).validate()


def test_the_record_names_the_powers_of_a_tight_plan_only():
    AnnealSettings().validate()
    assert "powers" not in AnnealSettings().as_dict()
    tight = AnnealSettings(plan="tight")
    tight.validate()
    assert tight.as_dict()["powers"] == list(DEFAULT_POWERS)
