"""Flag groups several ``ledsim`` commands share (the world, the scene, the run's knobs,
its start, the vehicle, the loop)."""

from __future__ import annotations

from ledsim.cli.options import (
    ATTENUATION,
    BIT_RATE,
    DEPTH,
    DISTANCE,
    PARTICLES,
    SECONDS,
    TORQUE_LIMIT,
    TRANSMITTER_DEPTH,
    number,
)


def choices(registry) -> dict:
    return dict(choices=list(registry), metavar="{" + ",".join(registry) + "}")


def add_world_args(p, distance_help="link distance d [m] (default: 0.085 for --link "
                   "paper, the preset's own otherwise)") -> None:
    p.add_argument("--distance", type=DISTANCE, default=None, help=distance_help)
    add_link_args(p)
    add_scene_args(p)


def add_link_args(p, sea: bool = True) -> None:
    """The physical link: its preset, the water and the data's bit rate (and, with
    ``sea``, the vehicles' depths)."""
    from ledsim.radiometry.link_presets import DEFAULT_LINK, LINK_PRESETS
    from ledsim.radiometry.water import WATER_TYPES

    p.add_argument("--link", default=DEFAULT_LINK, **choices(LINK_PRESETS),
                   help="the link: a real LED modem (docs/link.md), or paper: the "
                   "paper's 8.5 cm bench")
    p.add_argument("--water", default=None, **choices(WATER_TYPES),
                   help="water type (default: the preset's, clear-ocean)")
    p.add_argument("--attenuation", type=ATTENUATION, default=None, metavar="C",
                   help="the water's beam attenuation c [1/m] instead of the type's")
    p.add_argument("--bit-rate", type=BIT_RATE, default=None, metavar="R",
                   help="the data's bit rate [bit/s] (default: the preset's; 1000 for the "
                   "paper's bench)")
    if sea:
        from ledsim.physics.scene import DEFAULT_DEPTH

        p.add_argument("--depth", type=DEPTH, default=DEFAULT_DEPTH, metavar="D",
                       help="the receiver vehicle's depth below the still surface [m]: the "
                       "waves' decay, flicker's daylight, the surface in the video")
        p.add_argument("--transmitter-depth", type=TRANSMITTER_DEPTH, default=None,
                       metavar="D", help="the LED's depth [m] (default: the receiver's)")
        p.add_argument("--receiver-dome", action="store_true",
                       help="the receiver's head turns inside a dome, out of the water's "
                       "flow (default: open to it, as on the paper's bench)")


def resolved_distance(args) -> float:
    """``--distance``, or the ``--link`` preset's default distance [m]."""
    from ledsim.radiometry.link_presets import DEFAULT_LINK, default_distance

    d = getattr(args, "distance", None)
    return default_distance(getattr(args, "link", DEFAULT_LINK)) if d is None else d


def add_scene_args(p) -> None:
    from ledsim.physics.scene import INTEGRATORS

    p.add_argument("--scene", help="MJCF scene file (default: the shipped led_link.xml)")
    from ledsim.loop.run_config import WorldPart

    p.add_argument("--integrator", default=WorldPart.integrator, **choices(INTEGRATORS),
                   help="MuJoCo integrator (docs/physics.md compares them)")


def add_run_knobs(p) -> None:
    """Knobs every run of ``run`` and ``sweep`` shares: length, particles, torque limit."""
    from ledsim.loop.run_config import EstimatorPart, WorldPart

    p.add_argument("--torque-limit", type=TORQUE_LIMIT, default=WorldPart.torque_limit,
                   help="[N m]")
    p.add_argument("--seconds", type=SECONDS, default=None,
                   help="length of each run [s] (default: the scenario's, 10 s)")
    p.add_argument("--particles", type=PARTICLES, default=EstimatorPart.particles,
                   help="particle-filter size")


def add_start_arg(p) -> None:
    """The run's start and acquisition (run, render, sweep)."""
    from ledsim.loop.run_config import ACQUISITIONS, MAX_INITIAL_ANGLE, TaskPart

    p.add_argument("--acquisition", default=TaskPart.acquisition, **choices(ACQUISITIONS),
                   help="minimum-time (the default): fix the beam from the pair of "
                   "powers and slew there at the torque limit on the encoder (supervised "
                   "runs); warm-up: hold while the estimator converges, then slew at the "
                   "control law's rate limit (the default of ledsim 0.2 and before)")
    p.add_argument("--initial-angle", type=number(-MAX_INITIAL_ANGLE, MAX_INITIAL_ANGLE,
                                                  "rad"),
                   default=None, metavar="RAD",
                   help="true incidence angle phi at the start, at rest [rad] (default: "
                   "the scenario's; beyond about 0.6 rad the LED is outside the field of "
                   "view)")


def add_vehicle_args(p) -> None:
    """The vehicle's flags (run, render, sweep, demo)."""
    p.add_argument("--no-imu", action="store_true",
                   help="the control step uses the photodiodes and the gimbal torque only, "
                   "as in the paper: no IMU, DVL or encoder feed-forward")
    p.add_argument("--no-station-keeping", action="store_true",
                   help="the vehicle's thrusters stay idle: the hull drifts with the water")
    p.add_argument("--imu-noise", action="append", default=[], metavar="KEY=VALUE",
                   help="a noise figure of the vehicle's sensors (ledsim.constants."
                   "NavigationNoise: gyro_noise_density, dvl_noise, fix_noise, ...; "
                   "repeatable or comma-joined)")
    p.add_argument("--station-keeping-gain", action="append", default=[],
                   metavar="KEY=VALUE",
                   help="a gain of the station keeping (ledsim.agent.autopilot."
                   "StationKeeping: kp, kd, kp_pitch, kd_pitch, kp_yaw, kd_yaw, "
                   "observer_time; repeatable or comma-joined)")


def add_loop_args(p) -> None:
    from ledsim.loop.run_config import LOOP_ESTIMATORS, PHYSICS_SCENARIOS, EstimatorPart, TaskPart
    from ledsim.physics.disturbances import DISTURBANCES

    p.add_argument("--scenario", default=TaskPart.scenario, **choices(PHYSICS_SCENARIOS),
                   help="closed-loop scenario")
    p.add_argument("--estimator", default=EstimatorPart.estimator,
                   **choices(LOOP_ESTIMATORS),
                   help="estimator in the loop (oracle: handed the true state)")
    p.add_argument("--disturbance", action="append", default=[], metavar="SPEC",
                   help="name[:key=value,...] with name in " + ", ".join(DISTURBANCES)
                   + " (repeatable)")
    p.add_argument("--filter-distance", default=EstimatorPart.filter_distance,
                   **choices(("configured", "nominal")),
                   help="what the EKF, UKF and PF know of the distance: the configured "
                   "one's model, or the nominal 0.085 m model plus the supervisor's gain "
                   "tracker (what the KKL knows)")
    p.add_argument("--no-supervision", action="store_true",
                   help="no loss detection, gain tracking or reacquisition scan: the "
                   "estimator alone drives the motor (and the KKL is the shipped one of "
                   "--distance)")
    add_vehicle_args(p)
    add_world_args(p)
