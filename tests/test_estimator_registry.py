"""The estimator registry: one list, from which every other list of names is derived."""

import pytest

from ledsim.errors import LedsimError
from ledsim.experiment.estimators import (
    CLOSED_FORM_ESTIMATORS,
    COMPARED_ESTIMATORS,
    ESTIMATORS,
    LOOP_ESTIMATORS,
    LOOP_KKL_ESTIMATORS,
    REGISTRY,
    entry,
)


def test_the_lists_are_the_registrys_and_keep_their_old_names_and_order():
    from ledsim.loop import run_config as config
    from ledsim.loop import validation
    from ledsim.loop.build import estimation
    from ledsim.paper import evaluate

    assert list(ESTIMATORS) == [e.name for e in REGISTRY]
    assert CLOSED_FORM_ESTIMATORS == ("kkl", "kkl-paper", "kkl-handover", "kkl-scheduled",
                                      "ekf", "ukf", "pf")
    assert LOOP_ESTIMATORS == ("kkl", "kkl-scheduled", "kkl-bank", "ekf", "ukf", "pf",
                               "oracle", "es", "scan-ekf")
    assert COMPARED_ESTIMATORS == ("kkl", "kkl-bank", "ekf", "ukf", "pf", "oracle")
    assert LOOP_KKL_ESTIMATORS == ("kkl", "kkl-scheduled", "kkl-bank")
    # The names where they were first defined still work (aliases).
    assert evaluate.CLOSED_FORM_ESTIMATORS is CLOSED_FORM_ESTIMATORS
    assert config.LOOP_ESTIMATORS is LOOP_ESTIMATORS
    assert config.COMPARED_ESTIMATORS is COMPARED_ESTIMATORS
    assert estimation.KKL_ESTIMATORS is LOOP_KKL_ESTIMATORS
    assert validation.KKL_ON_BENCH is LOOP_KKL_ESTIMATORS


def test_every_entry_names_a_family_and_a_world():
    for e in REGISTRY:
        assert e.family in ("kkl", "bayes", "oracle", "scanning"), e
        assert e.closed_form or e.loop, e
        assert e.loop or not e.compared, e


def test_an_unknown_estimator_is_one_line_naming_the_choices():
    with pytest.raises(LedsimError, match="unknown estimator 'kf': choose one of kkl, "):
        entry("kf")


def test_a_link_preset_names_the_designs_its_run_loads():
    # Issue 47: what differs between the bench and a physical link is asked of the
    # preset, not of its name; the shipped checkpoints it names exist.
    from ledsim.files.resources import require_shipped_checkpoint
    from ledsim.radiometry.link_presets import LINK_PRESETS

    for name, p in LINK_PRESETS.items():
        bench = name == "paper"
        assert p.kkl_design == ("default" if bench else "lens"), name
        assert p.scheduled_design == ("scheduled" if bench else "scheduled-lens"), name
        assert p.holds_gain_when_driven is not bench, name
        require_shipped_checkpoint(0.085, "mujoco", p.scheduled_design)


def test_each_entry_builds_its_estimator():
    """The registry carries the builders: build_estimator asks the entry, not the name."""
    from ledsim.experiment.estimators import REGISTRY, build_estimator
    from ledsim.files.resources import shipped_checkpoint
    from ledsim.paper.model import LEDLinkModel

    model = LEDLinkModel()
    kinds = {"ekf": "ExtendedKalmanFilter", "ukf": "UnscentedKalmanFilter",
             "pf": "ParticleFilter", "oracle": "NoneType"}
    for e in REGISTRY:
        if e.name in kinds:
            est = build_estimator(e.name, model, particles=50)
            assert type(est).__name__ == kinds[e.name]
    assert build_estimator("kkl", model, checkpoint=shipped_checkpoint(0.085)) is not None
    with pytest.raises(LedsimError, match="needs a checkpoint"):
        build_estimator("kkl-paper", model)
    with pytest.raises(LedsimError, match="'es' runs on the pan-tilt head only"):
        build_estimator("es", model)  # the paper's one axis has no data detector
