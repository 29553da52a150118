"""The walkers' batches split with a local worker process (``inference.evaluators.SplitDensity``,
``sample_posterior(..., executor=...)``): the chain, its log-densities and the evaluation counts
are the serial run's bit for bit, on a screened run with the default mixture moves and on the
exhaust's reduced basis (whose products over the batch give each point the same bits in any
batch, ``compute.batch_rows``, so a batch is cut anywhere)."""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from bayesupdate.compute.batch_rows import MIN_ROWS  # noqa: E402
from bayesupdate.compute.executors import (  # noqa: E402
    PartnerProcess,
    ProcessExecutor,
    SerialExecutor,
)
from bayesupdate.compute.settings import a_core_is_free  # noqa: E402
from bayesupdate.inference import (  # noqa: E402
    CalibrationSettings,
    LikelihoodSpec,
    LogPosterior,
    SamplerSettings,
    build_problem,
    calibrate,
    sample_posterior,
)
from bayesupdate.inference.evaluators import (  # noqa: E402
    SPLIT_MIN_POINTS,
    SplitDensity,
    split_densities,
    split_pays,
    split_point,
)
from bayesupdate.modal_data import ModalData  # noqa: E402
from bayesupdate.models import get_model  # noqa: E402
from bayesupdate.models.shear_building import shear_building_frequencies  # noqa: E402


def _square(_shared, x: int) -> int:
    return x * x


@pytest.fixture(scope="module", params=["partner", "pool"])
def one_worker(request):
    """One spawned local worker (it imports numpy and bayesupdate when it starts: seconds): a
    partner process on a pipe (what ``sample`` starts of its own) or a pool of one process
    (``--workers``)."""
    with PartnerProcess() if request.param == "partner" else ProcessExecutor(1) as ex:
        # started here, so a short run does not spend itself waiting for the worker's imports
        # (until its warm-up ends, a run evaluates every batch in this process)
        assert ex.map(_square, [3]) == [9]
        yield ex


@pytest.fixture(scope="module")
def shear():
    data = ModalData(frequencies_hz=shear_building_frequencies(np.array([1.1, 0.9])) * [1.01, 0.99])
    bounds = {"theta_1": {"bounds": [0.2, 3.0]}, "theta_2": {"bounds": [0.2, 3.0]}}
    problem = build_problem(get_model("shear_building"), data, bounds, pairing="order")
    return problem, calibrate(problem, CalibrationSettings(starts=8, seed=0))


@pytest.mark.parametrize(
    "n, cut", [(1, 0), (9, 0), (10, 5), (11, 6), (15, 8), (16, 8), (17, 9), (32, 16), (500, 250)]
)
def test_the_cut_is_half_the_batch_the_larger_half_here(n, cut):
    assert SPLIT_MIN_POINTS == 2 * MIN_ROWS == 10  # each part: rows independent of the batch
    assert split_point(n) == cut


def _run(problem, optimum, executor):
    """(exact posterior, result) of a screened 32-walker run with the default moves."""
    exact = LogPosterior(problem, LikelihoodSpec(sigma=0.05))
    # the screen's sigma 4 % larger: a surrogate that differs from the target
    screen = LogPosterior(problem, LikelihoodSpec(sigma=0.052))
    settings = SamplerSettings(
        walkers=32, steps=20, seed=4, check_every=10, adapt_steps=20, min_autocorr_times=1e9
    )
    post = sample_posterior(exact, optimum, settings, screen=screen, executor=executor)
    return exact, post


def test_a_split_run_is_the_serial_run_bit_for_bit(shear, one_worker):
    problem, optimum = shear
    _, serial = _run(problem, optimum, None)
    split_exact, split = _run(problem, optimum, one_worker)
    assert split.diagnostics["moves"]["kind"] == serial.diagnostics["moves"]["kind"] == "mixture"
    np.testing.assert_array_equal(split.chain, serial.chain)
    np.testing.assert_array_equal(split.log_prob, serial.log_prob)
    assert split.evaluations == serial.evaluations == split_exact.evaluations
    assert split.screen_evaluations == serial.screen_evaluations > 32 * 3 * 20
    # the exact and screen batches of 16 and 32 walkers went half to the worker
    assert split.diagnostics["split"]["batches"] > 20
    assert split.diagnostics["split"]["stopped"] == ""
    assert "split" not in serial.diagnostics
    assert np.ptp(serial.chain[-1, :, 0]) > 0.01  # the walkers spread out: a chain that can differ


def test_a_split_pays_for_the_exhaust_not_for_an_analytic_model(shear, exhaust_rom_posterior):
    """The automatic split (``pipelines.sample.split_executor``) measures a batch's CPU: the
    exhaust's reduced, shape-paired posterior costs ~1 ms a point, the shear building's
    closed-form frequencies microseconds; neither count moves."""
    problem, optimum = shear
    small = LogPosterior(problem, LikelihoodSpec(sigma=0.05))
    assert not split_pays(small, optimum.theta) and small.evaluations == 0
    rom = exhaust_rom_posterior
    before = rom.evaluations
    theta = 0.5 * (rom.problem.lower + rom.problem.upper)
    assert split_pays(rom, theta) and rom.evaluations == before


@pytest.mark.parametrize("cores, load, free", [(1, 0.0, False), (2, 0.2, True), (2, 1.4, True),
                                               (2, 1.6, False), (16, 9.0, True)])  # fmt: skip
def test_a_core_is_free_below_cores_less_half_a_process(cores, load, free):
    assert a_core_is_free(cores, load) is free


def test_no_split_without_local_worker_processes(shear):
    problem, _ = shear
    exact = LogPosterior(problem, LikelihoodSpec(sigma=0.05))
    assert split_densities((exact, None), SerialExecutor()) == (exact, None)
    assert split_densities((exact, None), None) == (exact, None)


def test_a_split_density_counts_the_workers_points_and_keeps_the_values(shear, one_worker):
    problem, _ = shear
    exact = LogPosterior(problem, LikelihoodSpec(sigma=0.05))
    (split,) = split_densities((exact,), one_worker)
    split.wait_started()
    rng = np.random.default_rng(0)
    theta = problem.lower + rng.random((40, 2)) * (problem.upper - problem.lower)
    theta[3] = problem.upper * 2  # outside the prior: -inf, not evaluated, not counted
    whole = LogPosterior(problem, LikelihoodSpec(sigma=0.05))
    expected = whole(theta)
    np.testing.assert_array_equal(split(theta), expected)
    assert exact.evaluations == whole.evaluations == 39
    assert isinstance(split, SplitDensity) and split.splits == 1 and split.checked
    assert np.isinf(expected[3]) and np.all(np.isfinite(np.delete(expected, 3)))


@pytest.fixture(scope="module")
def exhaust_rom_posterior():
    """The exhaust's shape-paired posterior on its certified reduced basis (14 modes)."""
    from bayesupdate.fe.reduced import reduced_model_for
    from bayesupdate.inference import load_modal_data

    rom = reduced_model_for(get_model("exhaust"), tol=1e-4, seed=0, n_modes=14)
    problem = build_problem(rom, load_modal_data("paper:ema"))
    return LogPosterior(problem, LikelihoodSpec(sigma=0.05))


def test_every_point_of_the_reduced_posterior_is_the_same_bits_in_any_batch(
    exhaust_rom_posterior,
):
    """A BLAS product over the batch rounds a row by its place in the kernel's block (OpenBLAS's
    SkylakeX kernels: blocks of 12 rows, so a batch of 32 cut at 16 differed in rows 12-15 and
    24-27, by up to 2e-10 in the log-density, and every split of the exhaust's posterior was
    stopped); with the products in calls of a fixed size (``compute.batch_rows``) a batch cut
    anywhere into parts of ``MIN_ROWS`` points or more gives the whole batch's bits."""
    log_post = exhaust_rom_posterior
    problem = log_post.problem
    rng = np.random.default_rng(11)
    theta = problem.lower + rng.random((32, 5)) * (problem.upper - problem.lower)
    whole = log_post(theta)
    assert np.all(np.isfinite(whole)) and np.ptp(whole) > 1.0
    for cut in (5, 12, 16, 20, 27):
        np.testing.assert_array_equal(
            np.concatenate([log_post(theta[:cut]), log_post(theta[cut:])]), whole
        )
    five_by_five = np.concatenate([log_post(theta[i : i + 5]) for i in range(0, 30, 5)])
    np.testing.assert_array_equal(five_by_five, whole[:30])


@pytest.mark.parametrize("n", [10, 13, 16, 21, 29, 32])
def test_the_reduced_basis_split_is_the_whole_batch_bit_for_bit(
    exhaust_rom_posterior, one_worker, n
):
    """A batch cut in halves (odd batches too), one on the worker: the whole batch's values."""
    log_post = exhaust_rom_posterior
    assert log_post.mode == "shape-batch"
    problem = log_post.problem
    rng = np.random.default_rng(n)
    theta = problem.lower + rng.random((n, 5)) * (problem.upper - problem.lower)
    whole = log_post(theta)
    (split,) = split_densities((log_post,), one_worker)
    split.wait_started()
    np.testing.assert_array_equal(split(theta), whole)
    assert split.splits == 1 and split.stopped == ""
    assert np.all(np.isfinite(whole)) and np.ptp(whole) > 1.0


def test_the_sampler_starts_a_worker_of_its_own_only_where_it_pays(
    shear, exhaust_rom_posterior, monkeypatch
):
    """``pipelines.sample.split_executor`` on a serial run: a worker for the exhaust when a
    core is free, none for a closed-form model, none when the user asked for one process
    (``--workers 1``: ``split=None``), none when no core is free."""
    from types import SimpleNamespace

    from bayesupdate.compute.executors import SerialExecutor
    from bayesupdate.pipelines import sample

    serial, rom = SerialExecutor(), exhaust_rom_posterior
    at_rom = SimpleNamespace(theta=0.5 * (rom.problem.lower + rom.problem.upper))
    problem, optimum = shear
    small = LogPosterior(problem, LikelihoodSpec(sigma=0.05))
    for free, options, density, point, expected in [
        (True, sample.SamplingOptions(), rom, at_rom, "partner"),
        (True, sample.SamplingOptions(), small, optimum, None),
        (True, sample.SamplingOptions(split=None), rom, at_rom, None),
        (False, sample.SamplingOptions(), rom, at_rom, None),
    ]:
        monkeypatch.setattr(sample, "a_core_is_free", lambda free=free: free)
        with sample.split_executor(options, serial, density, point) as chosen:
            assert (None if chosen is None else chosen.kind) == expected
            assert chosen is None or chosen.workers == 1


def _fails_on_negative(_shared, x: int) -> int:
    if x < 0:
        raise ValueError(f"negative: {x}")
    return 2 * x


def test_a_partner_process_returns_in_order_raises_the_tasks_error_and_is_closed():
    with PartnerProcess() as partner:
        assert partner.map(_fails_on_negative, [1, 2, 3]) == [2, 4, 6]
        with pytest.raises(ValueError, match="negative: -1"):
            partner.submit(_fails_on_negative, -1).result()
        assert partner.submit(_fails_on_negative, 5).result() == 10  # it goes on after an error
        process = partner._process
    assert not process.is_alive()


def test_a_killed_partner_ends_the_splitting_with_the_same_values(shear):
    problem, _ = shear
    exact = LogPosterior(problem, LikelihoodSpec(sigma=0.05))
    rng = np.random.default_rng(1)
    theta = problem.lower + rng.random((32, 2)) * (problem.upper - problem.lower)
    expected = LogPosterior(problem, LikelihoodSpec(sigma=0.05))(theta)
    with PartnerProcess() as partner:
        (split,) = split_densities((exact,), partner)
        split.wait_started()
        np.testing.assert_array_equal(split(theta), expected)
        partner._process.kill()
        partner._process.join()
        np.testing.assert_array_equal(split(theta), expected)  # this process did it all
        np.testing.assert_array_equal(split(theta), expected)
    assert split.splits == 1 and exact.evaluations == 3 * 32


def test_a_partner_killed_while_starting_ends_the_splitting_with_the_same_values(shear):
    problem, _ = shear
    exact = LogPosterior(problem, LikelihoodSpec(sigma=0.05))
    width = problem.upper - problem.lower
    theta = problem.lower + np.random.default_rng(2).random((16, 2)) * width
    expected = LogPosterior(problem, LikelihoodSpec(sigma=0.05))(theta)
    with PartnerProcess() as partner:
        partner._process.kill()
        partner._process.join()
        assert split_densities((exact,), partner) == (exact,)  # not split: nobody to split with
    with PartnerProcess() as partner:
        (split,) = split_densities((exact,), partner)
        partner._process.kill()  # while it starts
        partner._process.join()
        np.testing.assert_array_equal(split(theta), expected)
    assert split.splits == 0 and exact.evaluations == 16


def test_a_row_product_gives_each_row_the_same_bits_in_any_batch():
    """``compute.batch_rows.row_product``: C @ T to round-off, and each row's bits whatever the
    rows around it in a batch of ``MIN_ROWS`` or more (batches cut anywhere, more rows than one
    call); a smaller batch is one plain product."""
    from bayesupdate.compute.batch_rows import MIN_ROWS, PRODUCT_ROWS, row_product

    rng = np.random.default_rng(3)
    C, T = rng.standard_normal((PRODUCT_ROWS + 13, 24)), rng.standard_normal((24, 1764))
    whole = row_product(C, T)
    np.testing.assert_allclose(whole, C @ T, rtol=0, atol=1e-12 * np.abs(C @ T).max())
    for cut in (MIN_ROWS, 7, 12, 16, 29, PRODUCT_ROWS, PRODUCT_ROWS + 5):
        np.testing.assert_array_equal(
            np.vstack([row_product(C[:cut], T), row_product(C[cut:], T)]), whole
        )
    np.testing.assert_array_equal(row_product(C[9 : 9 + MIN_ROWS], T), whole[9 : 9 + MIN_ROWS])
    np.testing.assert_array_equal(row_product(C[:2], T), C[:2] @ T)
    v = rng.standard_normal(24)
    np.testing.assert_array_equal(row_product(C[5:12], v), row_product(C, v)[5:12])
