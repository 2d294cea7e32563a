import numpy as np
import pytest
import torch

from ledsim.paper.scenarios import Noise, get_scenario, run
from observer.exceptions import ObserverError
from observer.kkl.fixed_gain import KKLDesign, series_encoder, stationary_noise_covariance
from observer.kkl.maps import TanhMLP
from observer.metrics import rmse


def test_paper_design_is_literal():
    d = KKLDesign.paper(0.01)
    np.testing.assert_allclose(d.eigenvalues, [0.99, 0.98, 0.96, 0.94, 0.92, 0.90])
    np.testing.assert_array_equal(d.B_array, np.ones((6, 2)))


def test_split_design_feeds_each_output_separately():
    d = KKLDesign.split(0.01, (2, 4))
    np.testing.assert_array_equal(d.B_array, [[1, 0], [1, 0], [0, 1], [0, 1]])


def test_stationary_covariance_solves_lyapunov(rng):
    lam = np.array([0.9, 0.95, 0.7])
    B = rng.normal(size=(3, 2))
    R = np.diag([1e-3, 2e-3])
    P = stationary_noise_covariance(lam, B, R)
    A = np.diag(lam)
    np.testing.assert_allclose(P, A @ P @ A.T + B @ R @ B.T, rtol=1e-12)


def test_numpy_export_matches_torch(rng):
    net = TanhMLP(3, 16, 2, [0.1, 0, 0], [0.5, 1, 2], [1.0, -1.0], [3.0, 0.1])
    v = rng.normal(size=(7, 3))
    with torch.no_grad():
        ref = net(torch.as_tensor(v)).numpy()
    np.testing.assert_allclose(net.export()(v), ref, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(net.export().vector(v[0]), ref[0], rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("layers", [2, 3])
def test_deep_numpy_export_matches_torch(rng, layers):
    net = TanhMLP(3, 16, 2, [0.1, 0, 0], [0.5, 1, 2], [1.0, -1.0], [3.0, 0.1], n_layers=layers)
    v = rng.normal(size=(5000, 3))  # past one chunk of the batched path
    with torch.no_grad():
        ref = net(torch.as_tensor(v)).numpy()
    out = net.export()
    assert len(out.mid) == layers - 1
    np.testing.assert_allclose(out(v), ref, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(out.vector(v[0]), ref[0], rtol=1e-12, atol=1e-12)


def test_deep_warm_started_decoder_trains_saves_and_loads(system, tmp_path):
    from ledsim.experiment.observer_presets import observer_preset
    from observer.kkl import checkpoint
    from observer.kkl.training import train_kkl

    design, cfg = observer_preset("default", system.Te)
    cfg.n_samples, cfg.hidden, cfg.decoder_hidden = 5000, 60, 40
    cfg.decoder_layers, cfg.finetune_epochs = 2, 1
    obs, rep = train_kkl(system, design, cfg, progress=False)
    assert len(obs.decoder_T_star.mid) == 1 and np.isfinite(rep.loss_recon)
    path = checkpoint.save(obs, tmp_path / "deep.pt")
    back = checkpoint.load(path, system)
    z = obs.encode(system.sample_domain(np.random.default_rng(0), 50))
    np.testing.assert_array_equal(back.decode(z), obs.decode(z))


def exact_T(obs, system, x):
    return series_encoder(system, obs.eigenvalues, obs.B, x)


def test_learned_T_solves_the_kkl_pde(tiny_observer, system, rng):
    x = system.sample_domain(rng, 200)
    z_true = exact_T(tiny_observer, system, x)
    rel = np.sqrt(((tiny_observer.encode(x) - z_true) ** 2).mean(axis=0)) / z_true.std(axis=0)
    # The fast filters are learned to <1%; the slowest (eigenvalue 0.98) is the hard one.
    assert np.median(rel) < 0.02 and rel.max() < 0.3


def test_decoder_inverts_encoder(tiny_observer, system, rng):
    x = system.sample_domain(rng, 500)
    err = rmse(tiny_observer.decode(tiny_observer.encode(x)), x)
    assert np.all(err < 0.02)


def test_noise_free_observer_converges_from_the_domain_centre(tiny_observer, system):
    sc = get_scenario("open-loop")
    noise = Noise.draw(system, sc.n_steps(system.Te), 0)
    noise.measurement[:] = 0
    noise.process[:] = 0
    out = run(system, sc, tiny_observer, noise)
    assert np.all(rmse(out.xhat, out.x, sc.steady_step(system.Te)) < [1e-2, 2e-2])
    # and it really started away from the truth
    assert abs(out.xhat[0, 0] - out.x[0, 0]) > 0.1


def test_batched_run_equals_step_by_step(tiny_observer, system, rng):
    ys = system.h(system.sample_domain(rng, 60)).reshape(20, 3, 2)
    batch_free = tiny_observer.run_trajectories(ys)
    for j in range(3):
        tiny_observer.reset()
        for k in range(20):
            np.testing.assert_allclose(tiny_observer.update(ys[k, j]), batch_free[k, j],
                                       atol=1e-10)
            tiny_observer.predict(0.0)


def test_omega_correction_vanishes_at_u_bar_and_helps_under_input(tiny_observer, system):
    z = tiny_observer.encode(np.array([[0.1, 0.05]]))
    np.testing.assert_allclose(tiny_observer.omega_correction(z, 0.0), 0.0, atol=1e-12)
    sc = get_scenario("if2")
    noise = Noise.draw(system, sc.n_steps(system.Te), 3)
    noise.measurement[:] = 0
    errs = {}
    for flag in (True, False):
        tiny_observer.use_omega = flag
        out = run(system, sc, tiny_observer, noise)
        errs[flag] = rmse(out.xhat, out.x, sc.steady_step(system.Te))[1]
    tiny_observer.use_omega = True
    assert errs[True] < errs[False]


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_missing_measurements_never_enter_z(tiny_observer, system, bad):
    sc = get_scenario("open-loop")
    noise = Noise.draw(system, sc.n_steps(system.Te), 1)
    drop = np.zeros((sc.n_steps(system.Te), 2), bool)
    drop[1200:1250, 0] = True  # half a second without photodiode 1
    drop[1300:1320] = True  # 0.2 s without both
    tiny_observer.reset()
    out = run(system, sc, tiny_observer, noise, dropout=drop)
    assert np.all(np.isfinite(out.xhat))
    assert np.all(np.isfinite(tiny_observer.z))
    assert rmse(out.xhat, out.x, 1400)[0] < 0.01
    ys = out.y.copy()
    ys[drop] = bad
    # Step by step, an inf or NaN power is held exactly like the NaN dropout above ...
    tiny_observer.reset()
    for k, y in enumerate(ys):
        np.testing.assert_array_equal(tiny_observer.update(y), out.xhat[k])
        tiny_observer.predict(0.0)
    # ... and the batched path, which has no hold, refuses them.
    with pytest.raises(ObserverError, match="every sample usable"):
        tiny_observer.run_trajectories(ys[:, None, :])


def test_handover_seeds_the_slow_bank_from_the_fast_estimate():
    from ledsim.constants import LinkConstants
    from ledsim.experiment.estimators import build_estimator
    from ledsim.paper.evaluate import default_checkpoint
    from ledsim.paper.model import LEDLinkModel

    system = LEDLinkModel(LinkConstants(distance=0.2))
    est = build_estimator("kkl-handover", system, checkpoint=default_checkpoint(0.2),
                          slow_checkpoint=default_checkpoint(0.2, "slow"))
    k = est.handover_steps
    assert k == 300
    sc = get_scenario("if1")
    out = run(system, sc, est, Noise.draw(system, sc.n_steps(system.Te), 0), [0.3, 0.0])
    err = np.abs(out.xhat[:, 0] - out.x[:, 0])
    assert err[k - 20:k].max() < 0.05  # the fast bank has converged by the handover
    assert err[k:k + 20].max() < 0.05  # and the slow one starts where it was: no jump
    np.testing.assert_allclose(out.xhat[-1], est.slow.decode(est.slow.z), atol=0.05)
    # The slow bank, started from the guess on its own, is still far off at the handover.
    alone = run(system, sc, est.slow, Noise.draw(system, sc.n_steps(system.Te), 0),
                [0.3, 0.0])
    assert np.abs(alone.xhat[k - 20:k, 0] - alone.x[k - 20:k, 0]).max() > 0.05
