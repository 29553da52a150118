"""Shared test set-up.  The problems here are small (n <= ~1000): BLAS threads only add contention
on a 2-core machine, so tests run single-threaded unless the caller says otherwise."""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
# every build of a reduced basis is a build (a cache hit depends on the order tests run in); the
# cache's own tests turn it on in a temporary folder
os.environ.setdefault("BAYESUPDATE_NO_CACHE", "1")

import matplotlib  # noqa: E402

matplotlib.use("Agg")


#: test files by measured cost, heaviest first (summed durations, `pytest -n 2 --dist loadfile
#: --durations=0` on 2026-11-24 at f953698, idle: 63, 47, 40, 37, 35, 22, 22, 13, 12, 9 s;
#: test_discovery_workflow 86 s then, about 70 s since its posterior step uses DE moves; the
#: files added since by their CPU time at 548f2a1: test_nastran_discover 25.5 s,
#: test_reduced_lines 9.9 s, test_nastran_sample 9.0 s, test_report_exhaust_comparison 8.3 s).
#: With `--no-loadscope-reorder` (pyproject's addopts) xdist hands files out in collection order,
#: so sending the longest first (the LPT rule, Graham 1969) keeps one worker from running a long
#: file alone at the end; xdist's own order (most tests first) sent them last.
HEAVIEST_FIRST = (
    "test_discovery_workflow.py",
    "test_inference_cli.py",
    "test_dask_executor.py",
    "test_calibration_exhaust.py",
    "test_discovery_cli.py",
    "test_faults.py",
    "test_nastran_discover.py",
    "test_reproducibility.py",
    "test_parallel_executor.py",
    "test_calibrate_effect.py",
    "test_fe_shell.py",
    "test_reduced_lines.py",
    "test_nastran_sample.py",
    "test_bad_input.py",
    "test_report_exhaust_comparison.py",
)


def pytest_collection_modifyitems(items):
    """Heaviest files first, each file's own order kept; the same order on every worker."""
    rank = {name: i for i, name in enumerate(HEAVIEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))
