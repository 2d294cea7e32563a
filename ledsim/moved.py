"""Where ledsim's modules moved (issue 47: the agent apart from the plant, one name for
one thing). Each old path is an alias of its new home, through :mod:`observer.moved`'s
import hook: ``from ledsim.step import ControlStep`` still works and gives the same class.
"""

from observer.moved import install

# old module -> its home now (aliases)
MOVED: dict[str, str] = {
    "ledsim.config": "ledsim.constants",
    "ledsim.control": "ledsim.agent.laws",
    "ledsim.estimators": "ledsim.experiment.estimators",
    "ledsim.layout": "ledsim.physics.layout",
    "ledsim.linkbudget": "ledsim.radiometry.data_channel",
    "ledsim.loop.acquisition": "ledsim.agent.acquisition",
    "ledsim.loop.batched": "ledsim.loop.closed_loop",
    "ledsim.loop.beamfix": "ledsim.agent.beamfix",
    "ledsim.loop.bound": "ledsim.loop.pcrb_runs",
    "ledsim.loop.config": "ledsim.loop.run_config",
    "ledsim.loop.estimation": "ledsim.loop.build.estimation",
    "ledsim.loop.gate": "ledsim.agent.gate",
    "ledsim.loop.held": "ledsim.agent.held",
    "ledsim.loop.link_gain": "ledsim.agent.link_gain",
    "ledsim.loop.metrics": "ledsim.loop.run_metrics",
    "ledsim.loop.slew": "ledsim.agent.slew",
    "ledsim.loop.start": "ledsim.loop.build.start",
    "ledsim.loop.supervisor": "ledsim.agent.supervisor",
    "ledsim.loop.training": "ledsim.loop.world_training",
    "ledsim.montecarlo": "ledsim.experiment.montecarlo",
    "ledsim.optics": "ledsim.radiometry.optics",
    "ledsim.outputs": "ledsim.files.outputs",
    "ledsim.paper.bound": "ledsim.paper.pcrb_tables",
    "ledsim.physics.batch_system": "ledsim.physics.gimbal_system_batch",
    "ledsim.physics.keeping": "ledsim.agent.keeping",
    "ledsim.physics.navigation": "ledsim.physics.nav_sensors",
    "ledsim.physics.system": "ledsim.physics.gimbal_system",
    "ledsim.physics.vehicle": "ledsim.agent.autopilot",
    "ledsim.physics.water": "ledsim.physics.flow",
    "ledsim.plotting": "ledsim.experiment.plotting",
    "ledsim.presets": "ledsim.experiment.observer_presets",
    "ledsim.radiometry.presets": "ledsim.radiometry.link_presets",
    "ledsim.resources": "ledsim.files.resources",
    "ledsim.results": "ledsim.files.results",
    "ledsim.scenario": "ledsim.experiment.scenario",
    "ledsim.step": "ledsim.agent.step",
    "ledsim.workers": "ledsim.experiment.workers",
}

install(MOVED)
