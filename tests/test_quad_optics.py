"""The four-photodiode head on a pan-tilt gimbal (issue 48): each photodiode's azimuth and
elevation are about its own up, so the tilt reaches the powers, and the four powers,
normalised by their sum (which no gain changes), map one to one onto the two angles."""

from dataclasses import replace

import numpy as np

from ledsim.physics.batch import WorldBatch
from ledsim.physics.batch_sensor import BatchSensor
from ledsim.physics.layout import AZIMUTH, Photodiode, ReceiverLayout, quad_layout
from ledsim.physics.scene import WorldConfig
from ledsim.physics.sensor import IrradianceSensor
from ledsim.physics.sensor_rows import SensorRows
from ledsim.physics.world import LinkWorld
from ledsim.radiometry.link_presets import link_constants
from tests.test_two_axes import TILT

QUAD = quad_layout(0.1)  # pd0 on the boresight, then pq1-pq4

#: The head's angles the test looks over [rad]: within the bare detector's field of view.
SPAN = np.linspace(-0.3, 0.3, 13)


def quad_world(layout=QUAD) -> LinkWorld:
    c = replace(link_constants("luma", 30.0), receiver_layout=layout)
    return LinkWorld(WorldConfig(constants=c, depth=20.0))


def powers_at(world, pan: float, tilt: float) -> np.ndarray:
    world.reset(gimbal_angle=np.array([pan, tilt]), gimbal_rate=np.zeros(2))
    return IrradianceSensor(world, noise=False).read(noise=False).power_clean


def test_the_quad_sees_pan_and_tilt_apart():
    world = quad_world()
    p = powers_at(world, 0.0, 0.0)[1:]  # the four pointing photodiodes
    np.testing.assert_allclose(p, p[0], rtol=1e-3)  # aimed: the four alike (ring: 1e-4)
    p = powers_at(world, 0.1, 0.0)[1:]  # panned: the pan pair differs, the tilt pair not
    assert p[0] > 1.05 * p[1] and abs(p[2] / p[3] - 1) < 1e-3
    p = powers_at(world, 0.0, 0.1)[1:]  # tilted: the other way round
    assert p[2] > 1.05 * p[3] and abs(p[0] / p[1] - 1) < 1e-3


def normalised_map(layout) -> tuple[np.ndarray, np.ndarray]:
    """The head's angles (n, 2) [rad] and the last four photodiodes' powers (the quad's
    pointing ones) over their sum (n, 4) there."""
    world = quad_world(layout)
    angles, shares = [], []
    for pan in SPAN:
        for tilt in SPAN:
            p = powers_at(world, pan, tilt)[-4:]
            angles.append((pan, tilt))
            shares.append(p / p.sum())
    return np.array(angles), np.array(shares)


def one_to_one(angles: np.ndarray, shares: np.ndarray) -> float:
    """The smallest change of the normalised powers per radian between two directions
    of the grid [1/rad] (0: two directions give the same powers)."""
    dq = np.linalg.norm(angles[:, None] - angles[None], axis=-1)
    dn = np.linalg.norm(shares[:, None] - shares[None], axis=-1)
    off = ~np.eye(len(angles), dtype=bool)
    return float((dn[off] / dq[off]).min())


def test_four_powers_map_one_to_one_onto_azimuth_and_elevation():
    angles, shares = normalised_map(QUAD)
    assert one_to_one(angles, shares) > 0.05  # 0.18 measured
    # and without a fold: the log-ratios of each pair turn one way with their own angle
    lr_pan = np.log(shares[:, 0] / shares[:, 1]).reshape(len(SPAN), len(SPAN))
    lr_tilt = np.log(shares[:, 2] / shares[:, 3]).reshape(len(SPAN), len(SPAN))
    assert np.all(np.diff(lr_pan, axis=0) > 0) and np.all(np.diff(lr_tilt, axis=1) > 0)


def test_a_head_without_tilted_photodiodes_cannot_tell_elevations_apart():
    """The check can fail: four photodiodes all in the pan plane (two pairs) leave the
    elevation unobservable, and the map is not one to one."""
    flat = ReceiverLayout((Photodiode("pq1", "q1", 0.1), Photodiode("pq2", "q2", -0.1),
                           Photodiode("pq3", "q3", 0.0), Photodiode("pq4", "q4", -0.05)),
                          (AZIMUTH, TILT))
    angles, shares = normalised_map(flat)
    # 2.6e-4 measured: what is left is the ring's geometry, 700 times under the quad's
    assert one_to_one(angles, shares) < 0.005


def test_the_rows_and_the_batch_read_the_quad_as_one_world_does():
    worlds = [quad_world(), quad_world()]
    for world, q in zip(worlds, ([0.12, -0.07], [-0.05, 0.2]), strict=True):
        world.reset(gimbal_angle=np.array(q), gimbal_rate=np.zeros(2))
    sensors = [IrradianceSensor(w, noise=False) for w in worlds]
    alone = [s.read(noise=False) for s in sensors]
    rows = SensorRows(sensors).read()
    batch = WorldBatch(worlds, [[], []])
    clean, phi, *_ = BatchSensor(batch, sensors, 1).clean()
    for n, (a, r) in enumerate(zip(alone, rows, strict=True)):
        np.testing.assert_array_equal(r.power_clean, a.power_clean)
        np.testing.assert_array_equal(r.incidence_angle, a.incidence_angle)
        np.testing.assert_allclose(clean[n], a.power_clean, rtol=1e-12)
        np.testing.assert_allclose(phi[n], a.incidence_angle, atol=1e-12)


def model_error(world, span: float, sign: float = 1.0) -> float:
    """The largest relative gap between the ray sensor's powers and the head's model
    (:func:`~ledsim.radiometry.optics.head_power` at azimuth -q1, elevation -q2: both
    axes turn the head the way the pan does), each power over its own transmitter gain,
    over head angles within +-``span`` [rad]; ``sign`` -1 flips the model's elevation."""
    from ledsim.radiometry.optics import head_power, transmitter_gain

    c = world.config.constants
    worst = 0.0
    for q1 in np.linspace(-span, span, 5):
        for q2 in np.linspace(-span, span, 5):
            world.reset(gimbal_angle=np.array([q1, q2]), gimbal_rate=np.zeros(2))
            r = IrradianceSensor(world, noise=False).read(noise=False)
            gain = transmitter_gain(r.distance, r.emission_angle, c) * r.visible_fraction
            model = head_power(1.0, -q1, -sign * q2, c)
            worst = max(worst, float(np.max(np.abs(r.power_clean / gain / model - 1))))
    return worst


def test_the_heads_model_is_the_ray_sensor_to_within_its_parallax():
    """The estimators' model of the quad (a data detector on the boresight and four
    pointing photodiodes) against MuJoCo's rays: within 0.1 rad the gap is the ring's
    parallax (3.0e-4 measured), within 0.3 rad the cone's separability (7.0e-3)."""
    world = quad_world(QUAD)
    assert world.config.constants.layout.reference == 0  # the data detector, pd0
    assert model_error(world, 0.1) < 1e-3
    assert model_error(world, 0.3) < 1e-2
    assert model_error(world, 0.1, sign=-1.0) > 0.05  # the convention matters
