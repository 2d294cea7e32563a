"""The receiver as data: the layout names the photodiodes and the axes, and no module
outside it reads one by position (beyond the modules listed, still to convert)."""

import ast
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from ledsim.constants import LinkConstants
from ledsim.loop.closed_loop import run_once
from ledsim.loop.run_config import RunConfig
from ledsim.physics.layout import AZIMUTH, LayoutError, Photodiode, ReceiverLayout, paper_layout
from ledsim.physics.scene import WorldConfig
from ledsim.physics.world import LinkWorld, WorldError
from ledsim.radiometry.optics import layout_power, layout_power_jacobian, received_power

ROOT = Path(__file__).resolve().parent.parent

#: Arrays whose last axis is the photodiodes or the state (an angle and a rate per axis).
LAYOUT_ARRAYS = {"power", "power_clean", "clean", "powers", "y", "y_gated", "yhat",
                 "y_model", "withheld", "incidence_angle", "emission_angle", "distance",
                 "visible_fraction", "x", "xhat", "x0", "xn", "state", "phi", "site_pos",
                 "photodiode_sites", "measurement_noise_std", "sigma0", "occluded"}
#: Modules that still read a photodiode or an axis by position, and how many times: the
#: one-axis gimbal's own models (their f and h are written for it, with per-sample fast
#: paths), the pair's shape inversion (a two-photodiode formula), and
#: a 3-vector helper the scan cannot tell apart. The count may only fall.
NOT_YET = {"ledsim/radiometry/optics.py": 2, "ledsim/paper/model.py": 5,
           "ledsim/physics/gimbal_system.py": 16,
           "observer/navigation/rotations.py": 3, "observer/kkl/scheduled_training.py": 1}


#: The modules that define where each photodiode and each axis sits: the layout, and the
#: agent's state over axes (angles, then rates; the one-axis fast path reads both).
DEFINES = ("ledsim/physics/layout.py", "ledsim/agent/axes.py")


def _name(node):
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        return node.attr
    return None


def _constant_last_index(sl) -> bool:
    el = sl.elts[-1] if isinstance(sl, ast.Tuple) else sl
    if isinstance(el, ast.UnaryOp) and isinstance(el.op, ast.USub):
        el = el.operand
    return isinstance(el, ast.Constant) and type(el.value) is int


def positional_reads(path: Path) -> list[int]:
    """Lines of ``path`` that index a photodiode or state array's last axis with a
    constant (``power[:, 0]``, ``x[1]``, ``y[..., -1]``)."""
    return sorted(node.lineno for node in ast.walk(ast.parse(path.read_text()))
                  if isinstance(node, ast.Subscript) and _name(node.value) in LAYOUT_ARRAYS
                  and _constant_last_index(node.slice))


def test_no_module_reads_a_photodiode_or_an_axis_by_position():
    found = {}
    for pkg in ("ledsim", "observer"):
        for path in sorted((ROOT / pkg).rglob("*.py")):
            rel = path.relative_to(ROOT).as_posix()
            if rel not in DEFINES and (lines := positional_reads(path)):
                found[rel] = lines
    over = {m: lines for m, lines in found.items() if len(lines) > NOT_YET.get(m, 0)}
    assert not over, ("read by position (use the receiver layout's names): "
                      + "; ".join(f"{m} lines {lines}" for m, lines in over.items()))


def test_the_scan_catches_positional_reads(tmp_path):
    f = tmp_path / "m.py"
    f.write_text("a = power[:, 0]\nb = r.power_clean[1]\nc = xhat[..., -1]\n"
                 "d = flags[:, 0]\ne = lay.reference_power(power)\n")
    assert positional_reads(f) == [1, 2, 3]


def test_the_paper_layout():
    lay = LinkConstants().layout
    assert lay == paper_layout(LinkConstants().dphi)
    assert lay.n_photodiodes == 2 and lay.n_axes == 1 and lay.n_state == 2
    assert lay.power_series == ("p1", "p2") and lay.state_series == ("phi", "phidot")
    assert lay.offsets == (0.0, LinkConstants().dphi) and lay.reference == 0
    cols = lay.power_columns(np.array([[1.0, 2.0], [3.0, 4.0]]), prefix="w_")
    assert list(cols) == ["w_p1", "w_p2"] and cols["w_p2"].tolist() == [2.0, 4.0]


@pytest.mark.parametrize("make, match", [
    (lambda: ReceiverLayout((), (AZIMUTH,)), "at least one photodiode"),
    (lambda: ReceiverLayout((Photodiode("a", "p1", 0.0),), ()), "at least one gimbal axis"),
    (lambda: ReceiverLayout((Photodiode("a", "p1", 0.0), Photodiode("a", "p2", 0.1)),
                            (AZIMUTH,)), "repeat"),
    (lambda: ReceiverLayout((Photodiode("a", "p1", 0.0),),
                            (AZIMUTH, replace(AZIMUTH, name="elevation"))).validate(),
     "2 gimbal axes are not supported yet"),
    (lambda: ReceiverLayout((Photodiode("a", "p1", 0.1),), (AZIMUTH,)).validate(),
     "no reference photodiode"),
])
def test_bad_layouts_are_refused(make, match):
    with pytest.raises(LayoutError, match=match):
        make()


def test_layout_power_follows_the_layout(monkeypatch):
    c = LinkConstants()
    three = ReceiverLayout(tuple(Photodiode(f"pd{i + 1}", f"p{i + 1}", o)
                                 for i, o in enumerate((0.0, c.dphi, -c.dphi))), (AZIMUTH,))
    monkeypatch.setattr(LinkConstants, "layout", property(lambda self: three))
    phi = np.linspace(-0.4, 0.4, 7)
    p = layout_power(0.5, phi, c)
    assert p.shape == (7, 3)
    np.testing.assert_array_equal(p[:, 2], received_power(0.5, phi - c.dphi, c.receiver))
    assert layout_power_jacobian(0.5, phi, c).shape == (7, 3, 2)
    # The scene has no third photodiode: the world says which site is missing.
    with pytest.raises(WorldError, match="no site named 'pd3'"):
        LinkWorld(WorldConfig(constants=c))


def test_traces_name_their_series_from_the_layout():
    s = run_once(RunConfig(seconds=0.2, imu=False), 1, keep_trace=True).trace.series()
    for key in ("phi", "phidot", "phi_hat", "phidot_hat", "p1", "p2", "withheld_p1",
                "withheld_p2"):
        assert key in s and len(s[key]) == 20
