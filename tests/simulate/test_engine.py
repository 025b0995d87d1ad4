"""The Monte Carlo engine: kinematics, random streams, reproducibility, noise models."""

from __future__ import annotations

import math

import numpy as np
import pytest

from odomkit.errors import ModelError
from odomkit.integrate import dead_reckon
from odomkit.noise import ClassicalNoise, CompassNoise, GyroNoise, SpeedNoise, WheelNoise
from odomkit.path import Arc, KellyArc, Spin, Straight
from odomkit.simulate import SystematicErrors, simulate_runs
from odomkit.simulate.blocks import run_block
from odomkit.simulate.plan import make_plan


def _arc_end(left, right, b, pose0=(0.0, 0.0, 0.0)):
    """Closed-form end of one constant-curvature arc: radius r = d/Δθ about the ICC."""
    x0, y0, t0 = pose0
    d, dth = 0.5 * (left + right), (right - left) / b
    if dth == 0:
        return np.array([x0 + d * math.cos(t0), y0 + d * math.sin(t0), t0])
    r = d / dth
    return np.array([x0 + r * (math.sin(t0 + dth) - math.sin(t0)),
                     y0 - r * (math.cos(t0 + dth) - math.cos(t0)), t0 + dth])


@pytest.mark.parametrize("engine", ["numba", "numpy"])
def test_zero_noise_gives_nominal_pose(engine):
    mc = simulate_runs([Arc(3, 1)], WheelNoise(0.0, 0.0), 0.4, runs=5,
                       partitions=1000, seed=1, engine=engine)
    # Chong–Kleeman Table 1 "Theory" mean (their θ is −5 wrapped to [0, 2π): 1.28319)
    np.testing.assert_allclose(mc.final, np.tile([-0.38357, -0.286535, -5.0], (5, 1)), atol=6e-6)
    np.testing.assert_allclose(mc.final, np.tile(_arc_end(3, 1, 0.4), (5, 1)), rtol=0, atol=1e-13)


def test_zero_noise_multi_segment_path_and_segment_ends():
    path = [Arc(3, 1), Straight(2.0), Spin(1.0), Arc(-1, 0.5)]
    mc = simulate_runs(path, WheelNoise(0.0, 0.0), 0.5, runs=3, partitions=77,
                       seed=0, pose0=(1.0, -2.0, 0.3), segment_ends=True)
    pose = np.array([1.0, -2.0, 0.3])
    for j, seg in enumerate(path):
        pose = _arc_end(*seg.wheel_travel(0.5), 0.5, pose)
        np.testing.assert_allclose(mc.segment_ends[:, j], np.tile(pose, (3, 1)), atol=1e-12)
    np.testing.assert_array_equal(mc.final, mc.segment_ends[:, -1])


def _reference_runs(seed, runs, path_travels, k, kl, kr, b, pose0, factor0):
    """Block 0 rebuilt from the documented stream with the team's plain dead_reckon:
    SeedSequence(seed, spawn_key=(0,)) -> SFC64; 3 normals per run for the initial pose,
    then per partition (2, runs) normals (left, right)."""
    rng = np.random.Generator(np.random.SFC64(np.random.SeedSequence(seed, spawn_key=(0,))))
    start = pose0 + rng.standard_normal((runs, 3)) @ factor0.T
    z = np.concatenate([rng.standard_normal((k, 2, runs)) for _ in path_travels])
    out = []
    for r in range(runs):
        dl = np.concatenate([np.full(k, left / k) for left, _ in path_travels])
        dr = np.concatenate([np.full(k, right / k) for _, right in path_travels])
        dl = dl + kl * np.sqrt(np.abs(dl)) * z[:, 0, r]
        dr = dr + kr * np.sqrt(np.abs(dr)) * z[:, 1, r]
        out.append(dead_reckon(0.5 * (dl + dr), (dr - dl) / b, start[r])[-1])
    return np.array(out)


@pytest.mark.parametrize("engine", ["numba", "numpy"])
def test_matches_plain_dead_reckoning_of_the_same_noise(engine):
    """Same normals, integrated by odomkit.integrate.dead_reckon run by run: the engine's
    kinematics (incl. the numba rotation trick) agree to rounding, and the random stream
    is the documented one. Large noise and K = 40 make |Δθ/2| > 0.25 in some steps, so
    the kernel's sin/cos branch is exercised too."""
    cov0 = np.diag([1e-4, 4e-4, 1e-3])
    path = [Arc(3, 1), Spin(-2.0)]
    b, k, kl, kr = 0.4, 40, 0.05, 0.08
    mc = simulate_runs(path, WheelNoise(kl, kr), b, runs=50, partitions=k, seed=7,
                       pose0=(0.5, 0.2, 0.1), cov0=cov0, engine=engine)
    travels = [s.wheel_travel(b) for s in path]
    ref = _reference_runs(7, 50, travels, k, kl, kr, b, np.array([0.5, 0.2, 0.1]),
                          np.sqrt(cov0))
    np.testing.assert_allclose(mc.final, ref, rtol=0, atol=1e-12)


def test_numba_and_numpy_agree_to_rounding_on_long_paths():
    args = ([Arc(15, 10)], WheelNoise(0.01, 0.02), 0.4)
    a = simulate_runs(*args, runs=300, partitions=5000, seed=3, engine="numba")
    b = simulate_runs(*args, runs=300, partitions=5000, seed=3, engine="numpy")
    # 5000 steps of rounding at |pose| ~ 1: far below any statistical figure
    np.testing.assert_allclose(a.final, b.final, rtol=0, atol=1e-11)


@pytest.mark.parametrize("engine", ["numba", "numpy"])
def test_same_seed_bit_identical_whatever_chunks_and_workers(engine):
    args = ([Arc(3, 1), Straight(1.0)], WheelNoise(0.003, 0.002), 0.4)
    kw = dict(runs=1000, partitions=700, seed=42, engine=engine, segment_ends=True)
    ref = simulate_runs(*args, workers=1, chunk_runs=256, **kw)
    for workers, chunk in [(2, 256), (2, 512), (2, 1000), (1, 10_000), (3, 300)]:
        other = simulate_runs(*args, workers=workers, chunk_runs=chunk, **kw)
        assert np.array_equal(other.final, ref.final)
        assert np.array_equal(other.segment_ends, ref.segment_ends)
    different = simulate_runs(*args, workers=2, chunk_runs=256, **{**kw, "seed": 43})
    assert not np.any(different.final == ref.final)


def test_partition_chunking_never_changes_numbers():
    plan = make_plan([Arc(3, 1), Spin(1)], WheelNoise(0.01, 0.02), 0.4, 1000)
    a, ea = run_block(plan, 5, 2, 100, "numba", True, partition_chunk=512)
    b, eb = run_block(plan, 5, 2, 100, "numba", True, partition_chunk=37)
    assert np.array_equal(a, b) and np.array_equal(ea, eb)


def test_blocks_are_independent_streams():
    mc = simulate_runs([Straight(1.0)], WheelNoise(0.01, 0.01), 0.4, runs=512,
                       partitions=10, seed=0)
    first, second = mc.final[:256], mc.final[256:]
    assert not np.any(first == second)
    # the correlation of two independent blocks' x is N(0, 1/256): |r| < 4/16
    assert abs(np.corrcoef(first[:, 1], second[:, 1])[0, 1]) < 0.25


def test_singular_initial_covariance_is_sampled_in_its_span():
    """A rank-1 initial covariance (x and θ perfectly correlated): the runs of a zero-noise
    zero-length path reproduce it, within the Wishart standard error, and nothing leaks
    into the null space."""
    v = np.array([0.1, 0.0, 0.02])
    cov0 = np.outer(v, v)
    mc = simulate_runs([Straight(0.0)], WheelNoise(0.0, 0.0), 0.4, runs=20_000,
                       partitions=3, seed=2, cov0=cov0)
    err = mc.final
    np.testing.assert_allclose(err[:, 1], 0.0, atol=0)
    # on the span, x = 5 θ exactly (to rounding)
    np.testing.assert_allclose(err[:, 0], 5 * err[:, 2], atol=1e-15)
    cov = np.cov(err, rowvar=False)
    # SE of a sample variance σ²·√(2/(N−1)) = σ²·0.01: 5 SE tolerance
    np.testing.assert_allclose(cov[[0, 0, 2], [0, 2, 2]], cov0[[0, 0, 2], [0, 2, 2]], rtol=0.05)


@pytest.mark.parametrize("bad", [np.diag([1.0, -0.1, 1.0]), [[1, 2, 0], [0, 1, 0], [0, 0, 1]],
                                 [1.0, 2.0], [[np.nan, 0, 0], [0, 1, 0], [0, 0, 1]]])
def test_bad_initial_covariance_rejected(bad):
    with pytest.raises(ModelError, match="initial covariance"):
        simulate_runs([Straight(1)], WheelNoise(0, 0), 0.4, runs=2, cov0=bad)


@pytest.mark.parametrize("kwargs, match", [
    (dict(runs=0), "runs"), (dict(partitions=0), "partitions"), (dict(seed=-1), "seed"),
    (dict(workers=0), "workers"), (dict(chunk_runs=0), "chunk_runs"), (dict(pose0=(0, 0)), "initial pose"),
    (dict(path=[KellyArc(1, 0, 1)]), "not a diff-drive segment"), (dict(path=[]), "segment"),
    (dict(noise=SpeedNoise(1.0)), "not a simulation model"),
    (dict(wheel_base=None), "wheel_base"),
])
def test_user_errors_raise_model_error(kwargs, match):
    args = dict(wheel_base=0.4, noise=WheelNoise(0.001, 0.001), path=[Straight(1)],
                runs=10, partitions=10)
    args.update(kwargs)
    with pytest.raises(ModelError, match=match):
        simulate_runs(**args)


def test_systematic_errors_follow_borenstein_feng():
    """Zero noise, so each run is the deterministic true motion of a miscalibrated robot:
    straight 4 m with E_d = 1.01 is an arc with d_R/d_L = E_d (eq. 2.3) of average length
    E_s·4 m; a commanded 90° spin with E_b = 1.02 turns 90°/E_b (eq. 4.27's premise)."""
    sys_err = SystematicErrors(E_d=1.01, E_b=1.02, E_s=0.995)
    b = 0.34
    mc = simulate_runs([Straight(4.0), Spin(math.pi / 2)], WheelNoise(0, 0), b,
                       runs=2, partitions=50, seed=0, systematic=sys_err, segment_ends=True)
    d_l = 4.0 * 0.995 * 2 / 2.01
    d_r = 4.0 * 0.995 * 2 * 1.01 / 2.01
    assert d_r / d_l == pytest.approx(1.01)
    assert (d_l + d_r) / 2 == pytest.approx(4.0 * 0.995)
    end_straight = _arc_end(d_l, d_r, 1.02 * b)
    np.testing.assert_allclose(mc.segment_ends[0, 0], end_straight, atol=1e-12)
    # the spin: commanded wheel travels ∓(b/2)(π/2) scaled by E_s·2/(E_d+1) etc., over 1.02·b
    half = b / 2 * math.pi / 2
    turn = (half * 0.995 * 2 * 1.01 / 2.01 + half * 0.995 * 2 / 2.01) / (1.02 * b)
    assert mc.final[0, 2] - end_straight[2] == pytest.approx(turn, abs=1e-12)
    assert turn == pytest.approx(math.pi / 2 * 0.995 / 1.02)


def test_systematic_errors_validated():
    with pytest.raises(ModelError, match="E_b"):
        SystematicErrors(E_b=0.0)
    with pytest.raises(ModelError, match="diff model"):
        simulate_runs([KellyArc(1, 0, 1)], (SpeedNoise(0.01), GyroNoise(0.0)), runs=2,
                      systematic=SystematicErrors())


def _sample_cov_ok(final, mean, cov, n_se=4.5):
    """Every mean and covariance entry within n_se Monte Carlo standard errors."""
    n = final.shape[0]
    err = final - mean
    sigma2 = np.diag(cov)
    np.testing.assert_array_less(np.abs(err.mean(0)), n_se * np.sqrt(sigma2 / n) + 1e-15)
    se_cov = np.sqrt((np.outer(sigma2, sigma2) + cov**2) / (n - 1))
    np.testing.assert_array_less(np.abs(np.cov(err, rowvar=False) - cov), n_se * se_cov + 1e-15)


def test_gyro_model_on_a_straight_line_matches_kelly_eq13():
    """Kelly eq. (13), integrated heading on a straight line at speed V for time t:
    σxx = α_ss·s, σyy = σ_gg·s²t/3, σyθ = σ_gg·s·t/2, σθθ = σ_gg·t (s = V·t). The
    along-track error is linear in the noise; the cross-track one is first order in
    σθ ≈ 0.045 rad, so the linear covariance holds within the sampling error (its
    relative correction is O(σθ²) = 0.2 %, the standard error 1 %). The mean x is not
    linear: with θᵢ ~ N(0, σ_gg·tᵢ) independent of the distance noise,
    E[x] = Σ Δs·E[cos θᵢ] = Σ Δs·exp(−σ_gg·tᵢ/2) exactly, 23 standard errors short of s."""
    v, t, alpha, psd, k = 0.5, 20.0, 1e-4, 1e-4, 400
    s = v * t
    cov = np.array([[alpha * s, 0, 0], [0, psd * s * s * t / 3, psd * s * t / 2],
                    [0, psd * s * t / 2, psd * t]])
    mc = simulate_runs([KellyArc(v, 0.0, t)], (SpeedNoise(alpha), GyroNoise(psd)), runs=20_000,
                       partitions=k, seed=11)
    # the arc of partition i points along its mid heading, of variance σ_gg·t_mid; the
    # chord factor and the in-step noise change E[x] by O(σ_gg·Δt) = 5e-6 relative only
    t_mid = (np.arange(k) + 0.5) * t / k
    mean_x = np.sum(s / k * np.exp(-psd * t_mid / 2))
    _sample_cov_ok(mc.final, np.array([mean_x, 0.0, 0.0]), cov)


def test_compass_model_on_a_straight_line_matches_kelly_eq13():
    """Kelly eq. (13), direct heading, with the compass read every T: σxx = α_ss·s and
    σyy = V²σ_θθ·(t − T/2) (the first and last readings enter one step each: Kelly's
    |V|σ_θθ·s less a quarter reading at each end); the final θ is one reading, variance
    σ² = σ_θθ/T, and Cov(y, θ) = σ²·V·T/2 (it steered half the last step); the initial θ
    variance gives way to the first reading. The mean x is exact: between readings e_k,
    e_{k+1} the arc's chord is d·sinc(Δ/2)·cos(m) with Δ = e_{k+1} − e_k ~ N(0, 2σ²)
    independent of m = (e_k + e_{k+1})/2 ~ N(0, σ²/2), and E[sin u/u] = ∫₀¹ e^{−τ²v/2} dτ
    for u ~ N(0, v); so E[x] = s·e^{−σ²/4}·√(π/σ²)·erf(σ/2), 30 standard errors short of
    s. K = 500 partitions: two steps per reading (the q steps make up the same arc)."""
    from math import erf, pi, sqrt

    v, t, alpha, psd, period, k = 0.5, 20.0, 1e-4, 1e-4, 0.05, 500
    s, sigma2 = v * t, psd / period
    mc = simulate_runs([KellyArc(v, 0.0, t)], (SpeedNoise(alpha), CompassNoise(psd)),
                       runs=20_000, partitions=k, seed=12, compass_period=period,
                       cov0=[0.0, 0.0, 1.0])
    assert mc.partitions == 800
    cov = np.diag([alpha * s, v * v * psd * (t - period / 2), sigma2])
    cov[1, 2] = cov[2, 1] = sigma2 * v * period / 2
    mean_x = s * np.exp(-sigma2 / 4) * sqrt(pi / sigma2) * erf(sqrt(sigma2) / 2)
    assert s - mean_x > 25 * sqrt(alpha * s / 20_000)  # the nonlinearity is detectable
    _sample_cov_ok(mc.final, np.array([mean_x, 0.0, 0.0]), cov)


def test_classical_noise_depends_on_the_partition_count():
    """Chong–Kleeman section 1: the classical model's variance grows with the number of
    steps a path is cut into (one step of 2D vs two of D): var θ = K·σ_α² exactly, so K=1
    and K=4 differ by a factor 4 (within sampling error)."""
    noise = ClassicalNoise(sigma_distance=0.01, sigma_angle=0.01)
    var = [np.var(simulate_runs([Straight(2.0)], noise, 0.4, runs=20_000,
                                partitions=k, seed=k).final[:, 2]) for k in (1, 4)]
    # SE of a sample variance σ²·√(2/N) = 1 %: 5 % tolerance
    assert var[0] == pytest.approx(1e-4, rel=0.05)
    assert var[1] == pytest.approx(4e-4, rel=0.05)


def test_memory_stays_bounded():
    """Chunked over runs and partitions: 1000 runs × 10 000 partitions need 2·10⁷ normals
    (160 MB at once); numpy reports its allocations to tracemalloc, and the peak stays
    at a few per-block buffers of 512 partitions (2 MB each)."""
    import tracemalloc

    args = ([Arc(3, 1)], WheelNoise(0.001, 0.001), 0.4)
    simulate_runs(*args, runs=2, partitions=2)  # imports and kernel loading, not traced
    tracemalloc.start()
    try:
        simulate_runs(*args, runs=1000, partitions=10_000, seed=0, workers=2)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 16 * 2**20


@pytest.mark.parametrize("workers", [1, 2])
def test_progress_reports_every_run_once(workers):
    from odomkit.progress import RecordingProgress

    seen = RecordingProgress()
    simulate_runs([Straight(1.0)], WheelNoise(0.001, 0.001), 0.4, runs=1000, partitions=5,
                  workers=workers, progress=seen)
    (stage,) = seen.stages
    assert stage.total == stage.done == 1000 and stage.closed
    assert stage.advances == 4  # four blocks of ≤ 256 runs
