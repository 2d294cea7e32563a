"""The command line's flags of a run's spec (:class:`~ledsim.loop.run_config.RunSpec`),
one entry per spec name, and the spec a command line gives back.

A flag's spelling, default and destination come from the spec's field (``torque_limit``:
``--torque-limit``, the part's default); its entry here gives what the spec cannot: the
type that refuses a bad value in one line, the help, and the form (a switch that turns
a True default off, ``--no-imu``; one that turns a False default on; a repeatable
flag). :func:`add_spec_flags` adds them to a command, :func:`spec_values` reads them
back as spec names, and ``tests/test_cli_spec.py`` holds every spec name to a flag.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, fields
from typing import Any

#: A flag entry's default when it is the spec field's own.
SPEC_DEFAULT: Any = object()


@dataclass(frozen=True)
class Flag:
    """How one spec name is given on the command line.

    Attributes:
        help: the flag's help.
        type: the argparse type (None: a string).
        choices: the registry of allowed values (its keys).
        metavar: the value's name in the help.
        flag: the spelling, when not ``--`` and the name with dashes.
        form: ``value`` (a value), ``off`` (``--no-x`` turns a True default off),
            ``on`` (``--x`` turns a False default on), ``each`` (repeatable, each
            item kept whole) or ``items`` (repeatable, comma-joined items split).
        default: the flag's default (:data:`SPEC_DEFAULT`: the spec field's).
    """

    help: str
    type: Any = None
    choices: Any = None
    metavar: str | None = None
    flag: str | None = None
    form: str = "value"
    default: Any = SPEC_DEFAULT

    def default_for(self, name: str):
        """The flag's default: its own, or the spec field ``name``'s."""
        return spec_default(name) if self.default is SPEC_DEFAULT else self.default

    def spelling(self, name: str) -> str:
        if self.flag is not None:
            return self.flag
        prefix = "--no-" if self.form == "off" else "--"
        return prefix + name.replace("_", "-")


@functools.cache
def flags() -> dict[str, Flag]:
    """Every spec name's flag (built on first use: the command line imports lazily)."""
    from ledsim.cli.options import (
        ATTENUATION,
        BIT_RATE,
        DEPTH,
        DISTANCE,
        NOISE_SCALE,
        PARTICLES,
        SEA_DEPTH,
        SECONDS,
        SEEDS,
        TORQUE_LIMIT,
        TRANSMITTER_DEPTH,
        WORKERS,
        number,
    )
    from ledsim.loop.registry import (
        ACQUISITIONS,
        GIMBALS,
        LOOP_ESTIMATORS,
        MAX_INITIAL_ANGLE,
        OMEGA_MODELS,
        PHYSICS_SCENARIOS,
        RECEIVERS,
    )
    from ledsim.physics.disturbances import DISTURBANCES
    from ledsim.physics.scene import INTEGRATORS
    from ledsim.radiometry.link_presets import DEFAULT_LINK, LINK_PRESETS
    from ledsim.radiometry.water import WATER_TYPES

    return {
        # the world
        "distance": Flag("link distance d [m] (default: 0.085 for --link paper, the "
                         "preset's own otherwise)", DISTANCE),
        "link": Flag("the link: a real LED modem (docs/link.md), or paper: the paper's "
                     "8.5 cm bench", choices=LINK_PRESETS, default=DEFAULT_LINK),
        "water": Flag("water type (default: the preset's, clear-ocean)",
                      choices=WATER_TYPES),
        "attenuation": Flag("the water's beam attenuation c [1/m] instead of the type's",
                            ATTENUATION, metavar="C"),
        "bit_rate": Flag("the data's bit rate [bit/s] (default: the preset's; 1000 for the "
                         "paper's bench)", BIT_RATE, metavar="R"),
        "depth": Flag("the receiver vehicle's depth below the still surface [m]: the "
                      "waves' decay, flicker's daylight, the surface in the video", DEPTH,
                      metavar="D"),
        "transmitter_depth": Flag("the LED's depth [m] (default: the receiver's)",
                                  TRANSMITTER_DEPTH, metavar="D"),
        "sea_depth": Flag("the sea's depth [m]: the seabed stands there, at least 0.5 m "
                          "below both ends (default: 2.5 m under the deeper end; also the "
                          "waves' depth when they name none)", SEA_DEPTH, metavar="H"),
        "receiver_dome": Flag("the receiver's head turns inside a dome, out of the water's "
                              "flow (default: open to it, as on the paper's bench)",
                              form="on"),
        "gimbal": Flag("the receiver's gimbal: yaw (the paper's one axis, with the pair) "
                       "or pan-tilt (azimuth and elevation, with the quad) (default: the "
                       "--receiver's, or yaw)", choices=GIMBALS),
        "receiver": Flag("the receiver's photodiodes: pair (the paper's two, on the yaw "
                         "gimbal) or quad (a data detector on the boresight and four "
                         "pointing photodiodes, on the pan-tilt) (default: the --gimbal's)",
                         choices=RECEIVERS),
        "channel_mismatch": Flag("on the quad, the gain mismatch between opposite "
                                 "pointing photodiodes [-] (each pair reads 1 +- M/2 of "
                                 "its light; the estimators are told it, as calibrated)",
                                 number(0.0, 0.5, "-"), metavar="M"),
        "transmitter_aimed": Flag("the LED's axis points at the receiver (a node that "
                                  "faces the vehicle above or below it; default: level)",
                                  form="on"),
        "lens_field_deg": Flag("a lens in front of a physical receiver's detector: its "
                               "half-power field [deg] (narrower than the bare 30 deg; "
                               "the lens gathers the light of a larger aperture)",
                               number(1.0, 29.9, "deg"), metavar="F"),
        "scene": Flag("MJCF scene file (default: the shipped led_link.xml)"),
        "mission": Flag("a JSON or TOML file of waypoints (x ahead, y left of the start "
                        "[m], speed [m/s]) the vehicle flies, then holds the last "
                        "(docs/missions.md)", metavar="FILE"),
        "node_error": Flag("on the move, the error of the node's position as the "
                           "vehicle believes it [m] (per axis; 0: known); the vehicle "
                           "learns it from where its head finds the LED",
                           number(0.0, 100.0, "m"), metavar="M"),
        "integrator": Flag("MuJoCo integrator (docs/physics.md compares them)",
                           choices=INTEGRATORS),
        "torque_limit": Flag("[N m]", TORQUE_LIMIT),
        "noise_scale": Flag("multiplies the measurement-noise std", NOISE_SCALE),
        "station_keeping": Flag("the vehicle's thrusters stay idle: the hull drifts with "
                                "the water", form="off"),
        "imu_noise": Flag("a noise figure of the vehicle's sensors (ledsim.constants."
                          "NavigationNoise: gyro_noise_density, dvl_noise, fix_noise, ...; "
                          "repeatable or comma-joined)", metavar="KEY=VALUE", form="items"),
        "station_keeping_gains": Flag(
            "a gain of the station keeping (ledsim.agent.autopilot.StationKeeping: kp, kd, "
            "kp_pitch, kd_pitch, kp_yaw, kd_yaw, observer_time; repeatable or "
            "comma-joined)", metavar="KEY=VALUE", flag="--station-keeping-gain",
            form="items"),
        # the task
        "scenario": Flag("closed-loop scenario", choices=PHYSICS_SCENARIOS),
        "disturbances": Flag("name[:key=value,...] with name in " + ", ".join(DISTURBANCES)
                             + " (repeatable)", metavar="SPEC", flag="--disturbance",
                             form="each"),
        "seconds": Flag("length of each run [s] (default: the scenario's, 10 s)", SECONDS),
        "supervision": Flag("no loss detection, gain tracking or reacquisition scan: the "
                            "estimator alone drives the motor (and the KKL is the shipped "
                            "one of --distance)", form="off"),
        "initial_elevation": Flag("on a pan-tilt head, the LED's true elevation from the "
                                  "boresight at the start [rad] (default: 0, the tilt "
                                  "pointed at it)",
                                  number(-MAX_INITIAL_ANGLE, MAX_INITIAL_ANGLE, "rad"),
                                  metavar="RAD"),
        "initial_angle": Flag("true incidence angle phi at the start, at rest [rad] "
                              "(default: the scenario's; beyond about 0.6 rad the LED is "
                              "outside the field of view)",
                              number(-MAX_INITIAL_ANGLE, MAX_INITIAL_ANGLE, "rad"),
                              metavar="RAD"),
        "acquisition": Flag("minimum-time (the default): fix the beam from the pair of "
                            "powers and slew there at the torque limit on the encoder "
                            "(supervised runs); warm-up: hold while the estimator "
                            "converges, then slew at the control law's rate limit (the "
                            "default of ledsim 0.2 and before)", choices=ACQUISITIONS),
        # the estimation
        "estimator": Flag("estimator in the loop (oracle: handed the true state)",
                          choices=LOOP_ESTIMATORS),
        "particles": Flag("particle-filter size", PARTICLES),
        "checkpoint": Flag("KKL checkpoint trained on the MuJoCo world"),
        "omega_model": Flag("f used by the KKL's Omega correction", choices=OMEGA_MODELS),
        "filter_distance": Flag("what the EKF, UKF and PF know of the distance: the "
                                "configured one's model, or the nominal 0.085 m model plus "
                                "the supervisor's gain tracker (what the KKL knows)",
                                choices=("configured", "nominal")),
        "imu": Flag("the control step uses the photodiodes and the gimbal torque only, as "
                    "in the paper: no IMU, DVL or encoder feed-forward", form="off"),
        # the execution
        "seeds": Flag("Monte-Carlo runs (seeds 0..N-1)", SEEDS),
        "workers": Flag("processes", WORKERS),
        "window": Flag("also report the metrics of each window of this length [s], at most "
                       "the run's, in results.json (windows: availability, FEC share, the "
                       "hull's and the navigation's horizontal error), e.g. 60 for a long "
                       "run minute by minute", number(0.0, 86_400.0, "s", lo_open=True)),
    }


def spec_default(name: str):
    """The spec field ``name``'s default."""
    from ledsim.loop.run_config import FLAT, PARTS

    kind = PARTS[FLAT[name]]
    return next(f.default for f in fields(kind) if f.name == name)


def add_spec_flags(p, *names: str, **overrides: dict) -> None:
    """Add the flags of the spec ``names`` to parser ``p``; ``overrides[name]`` replaces
    parts of one flag's entry (``help``, ``type``, ``default``...) for this command."""
    table = flags()
    for name in names:
        f = table[name]
        if name in overrides:
            from dataclasses import replace

            f = replace(f, **overrides[name])
        kw: dict[str, Any] = {"help": f.help}
        if f.form in ("off", "on"):
            kw["action"] = "store_true"
        elif f.form in ("each", "items"):
            kw.update(action="append", default=[])
        else:
            kw["default"] = f.default_for(name)
            if f.type is not None:
                kw["type"] = f.type
        if f.choices is not None:
            kw.update(choices=list(f.choices), metavar="{" + ",".join(f.choices) + "}")
        if f.metavar is not None:
            kw["metavar"] = f.metavar
        p.add_argument(f.spelling(name), **kw)


#: The vehicle's spec names (``run``, ``render``, ``sweep`` and ``demo`` take them).
VEHICLE = ("imu", "station_keeping", "imu_noise", "station_keeping_gains")


def spec_values(args, names=None, exclude=()) -> dict:
    """The spec names a parsed command line gives (those of its flags, or of ``names``,
    less ``exclude``: flags a command reads otherwise, a sweep's grid) and their values:
    a switch's sense turned to the spec's, repeatable flags as tuples."""
    out = {}
    for name, f in flags().items():
        dest = f.spelling(name).lstrip("-").replace("-", "_")
        if not hasattr(args, dest) or (names is not None and name not in names) \
                or name in exclude:
            continue
        value = getattr(args, dest)
        if f.form == "off":
            value = not value
        elif f.form == "each":
            value = tuple(value)
        elif f.form == "items":
            value = tuple(item for spec in value for item in spec.split(",") if item)
        out[name] = value
    return out


def spec_argv(spec) -> list[str]:
    """The ``ledsim run`` arguments that give back ``spec`` (a
    :class:`~ledsim.loop.run_config.RunSpec`, or its :meth:`flat` dict as
    ``results.json`` keeps it): each name whose value is not the flag's default."""
    values = spec if isinstance(spec, dict) else spec.flat()
    argv: list[str] = []
    for name, f in flags().items():
        value = values[name]
        default = f.default_for(name)
        if f.form == "off":
            argv += [f.spelling(name)] if not value else []
        elif f.form == "on":
            argv += [f.spelling(name)] if value else []
        elif f.form in ("each", "items"):
            for item in value:
                argv += [f.spelling(name), str(item)]
        elif value != default and value is not None:
            argv += [f.spelling(name), repr(value) if isinstance(value, float) else str(value)]
        elif value is None and default is not None:
            raise ValueError(f"{name}=None has no flag (its flag's default is {default!r})")
    return argv
