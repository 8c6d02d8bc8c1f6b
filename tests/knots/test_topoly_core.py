"""topoly's compiled HOMFLY-PT steps called directly give topoly.homfly's own answer."""

import subprocess
import sys
import textwrap

import numpy as np
import pytest

from stiffknots.knots import identify as I
from stiffknots.knots.catalogue import get_knot, knot_names
from stiffknots.knots.starts import start_chain
from stiffknots.knots.topoly_core import homfly_kmt


def _topoly_api(x: np.ndarray, max_cross: int) -> str | None:
    """topoly.homfly through its Python layer, as identify used it before topoly_core."""
    topoly, Closure, ReduceMethod, _ = I._topoly()
    return I._homfly_once(topoly, Closure, ReduceMethod, x, max_cross)


def _both(name: str, noise: float, seed: int = 0, max_cross: int = I._MAX_CROSS):
    x = start_chain(get_knot(name), "braid", 150)
    if noise:
        x = x + np.random.default_rng(seed).normal(scale=noise, size=x.shape)
    y = x @ I._GENERIC_ROTATION.T
    with I._quiet():
        direct = homfly_kmt(y, max_cross)
    return direct, _topoly_api(y, max_cross)


@pytest.mark.parametrize("name", knot_names(7))
@pytest.mark.parametrize("noise", [0.0, 0.02])
def test_the_compiled_steps_give_topolys_code(name, noise):
    direct, api = _both(name, noise)
    assert direct == api
    assert I.identify_code(direct, max_crossings=7) == I.normalize_name(name)


@pytest.mark.slow
def test_the_compiled_steps_give_topolys_code_for_every_knot_through_10_crossings():
    names = [n for n in knot_names(10) if n != "0_1"]
    assert len(names) == 249
    differ = [(n, s) for n in names for s in (0.0, 0.02) if len(set(_both(n, s))) != 1]
    assert differ == []


def test_too_many_crossings_is_none_as_topolys_errtmc():
    direct, api = _both("10_123", 0.0, max_cross=4)
    assert direct is None and api is None
    direct, api = _both("10_123", 0.0, max_cross=60)
    assert direct == api is not None


def test_a_diagram_without_crossings_is_the_unknot():
    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    circle = np.column_stack([np.cos(t), np.sin(t), 0.1 * np.sin(3 * t)])
    with I._quiet():
        assert homfly_kmt(circle @ I._GENERIC_ROTATION.T, 60) == "[[1]]"
    assert I.identify(circle) == "0_1"


def test_a_knot_check_does_not_import_topolys_python_layer_and_topoly_still_loads_after():
    code = textwrap.dedent("""
        import sys
        import numpy as np
        from stiffknots.knots.catalogue import get_knot
        from stiffknots.knots.identify import identify
        from stiffknots.knots.starts import start_chain
        x = start_chain(get_knot("5_2"), "braid", 150)
        assert identify(x) == "5_2", identify(x)
        assert "topoly" not in sys.modules
        from stiffknots.knots.identify import identify_name
        assert identify_name(x)[0] == "5_2"
        assert "topoly" not in sys.modules, "the diagram's reduction imported topoly"
        assert not any(m.startswith("matplotlib") for m in sys.modules), "matplotlib loaded"
        import topoly
        from topoly.params import Closure
        assert "lmpoly" in dir(topoly.invariants)
        print(topoly.homfly(x.tolist(), closure=Closure.CLOSED, run_parallel=False, cuda=False,
                            translate=True))
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr
    assert "5_2" in out.stdout


@pytest.mark.parametrize("name", ["3_1", "8_19", "10_123"])
def test_the_compiled_kmt_reduction_gives_topolys_reduced_polygon(name):
    from stiffknots.knots.topoly_core import kmt_reduce

    x = start_chain(get_knot(name), "braid", 150) @ I._GENERIC_ROTATION.T
    topoly, _, ReduceMethod, _ = I._topoly()
    with I._quiet():
        red = topoly.reduce_structure(x.tolist(), reduce_method=ReduceMethod.KMT,
                                      output_type="xyz")
        y = kmt_reduce(x)
    want = np.array([[float(v) for v in ln.split()[-3:]]
                     for ln in str(red).strip().splitlines() if ln.strip()])
    assert 3 <= len(y) < len(x)
    np.testing.assert_allclose(y, want, rtol=0, atol=1e-9)
