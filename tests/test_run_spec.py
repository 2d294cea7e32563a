"""The run's typed spec: nested, frozen parts, with the flat names kept working."""

import dataclasses
import json

import pytest

from ledsim.errors import LedsimError
from ledsim.loop.run_config import (
    FLAT,
    PARTS,
    EstimatorPart,
    RunConfig,
    RunSpec,
    TaskPart,
    WorldPart,
)
from ledsim.radiometry.link_presets import default_distance


def test_a_spec_is_four_frozen_parts_and_reads_its_flat_names():
    spec = RunSpec(estimator="ekf", seconds=5.0, link="luma")
    assert [f.name for f in dataclasses.fields(spec)] == list(PARTS)
    assert spec.estimation == EstimatorPart(estimator="ekf")
    assert spec.task == TaskPart(seconds=5.0)
    assert spec.estimator == "ekf" and spec.seconds == 5.0 and spec.scenario == "align"
    assert spec.distance == default_distance("luma")  # the preset's, as before
    with pytest.raises(dataclasses.FrozenInstanceError):
        spec.estimator = "ukf"
    with pytest.raises(TypeError, match="unexpected keyword argument 'estimatr'"):
        RunSpec(estimatr="ekf")


def test_parts_and_flat_names_mix_and_replace_takes_flat_names():
    spec = RunSpec(world=WorldPart(torque_limit=0.02), estimator="ukf")
    assert spec.torque_limit == 0.02 and spec.estimator == "ukf"
    other = dataclasses.replace(spec, estimator="pf", seeds=2)
    assert other.estimator == "pf" and other.seeds == 2 and other.torque_limit == 0.02
    assert spec.estimator == "ukf"  # untouched
    assert RunSpec.of(world=spec.world, estimation=spec.estimation) == \
        RunSpec(torque_limit=0.02, estimator="ukf")


def test_the_old_name_is_the_spec():
    assert RunConfig is RunSpec
    assert RunConfig(supervision=False) == RunSpec(task=TaskPart(supervision=False))


def test_flat_names_are_every_parts_field_once():
    names = [f.name for kind in PARTS.values() for f in dataclasses.fields(kind)]
    assert len(names) == len(set(names)) == len(FLAT) == len(RunSpec().flat())


@pytest.mark.parametrize("form", ["nested", "flat"])
def test_a_saved_spec_reads_back_nested_or_flat(form):
    spec = RunSpec(estimator="ekf", disturbances=("vibration",), link="luma", window=2.0)
    saved = dataclasses.asdict(spec) if form == "nested" else spec.flat()
    assert RunSpec.from_dict(json.loads(json.dumps(saved))) == spec


def test_a_saved_spec_with_a_stray_part_is_refused_in_one_line():
    with pytest.raises(LedsimError, match="'vehicle' in a run configuration by parts"):
        RunSpec.from_dict({"world": {}, "vehicle": {}})
    with pytest.raises(LedsimError, match="unknown key 'estimatr'"):
        RunSpec.from_dict({"estimatr": "ekf"})


def test_the_env_takes_the_specs_names_and_its_old_positional_order():
    import pickle

    from ledsim.envs.arguments import POSITIONAL, SPEC_NAMES
    from ledsim.envs.link_align import LinkAlignEnv

    assert set(SPEC_NAMES) >= {f.name for f in dataclasses.fields(WorldPart)}
    env = LinkAlignEnv("align", 0.1, 2.0, ("vibration",), 0.04, imu=False)
    assert (env.cfg.distance, env.cfg.noise_scale, env.cfg.disturbances,
            env.cfg.torque_limit, env.cfg.imu) == (0.1, 2.0, ("vibration",), 0.04, False)
    assert len(POSITIONAL) == 23
    by_name = LinkAlignEnv(scenario="align", distance=0.1, noise_scale=2.0,
                           disturbances="vibration", torque_limit=0.04, imu=False,
                           imu_noise=("dvl_noise=0.01",))  # a world field the env lacked
    assert by_name.cfg.imu_noise == ("dvl_noise=0.01",)
    copy = pickle.loads(pickle.dumps(by_name))
    assert copy.cfg == by_name.cfg
    with pytest.raises(TypeError, match="unexpected keyword argument 'estimator'"):
        LinkAlignEnv(estimator="ekf")


def test_results_carry_the_spec_that_reruns_them(tmp_path):
    from ledsim.loop.report import run_many

    spec = RunSpec(estimator="ekf", seconds=0.3, seeds=1, workers=1, imu=False)
    summary, _ = run_many(spec, progress=False)
    saved = json.loads(json.dumps(summary.to_dict() if hasattr(summary, "to_dict")
                                  else dataclasses.asdict(summary)))
    assert RunSpec.from_dict(saved["spec"]) == spec
