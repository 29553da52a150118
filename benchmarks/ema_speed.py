"""Speed of the whole identification: 40 FRFs x 4096 lines, stabilization up to order 60.

Data: the virtual impact test of the 12-mode exhaust-like model (seed layout, 1 % noise),
0-150 Hz at 4096 lines.  Ours: ``identify`` on the band 0-150 Hz with orders 2..60 (LSCE with
one QR for all orders + stabilization + clustering + LSFD + shapes), and the default automatic
narrow bands.  pLSCF (``method="plscf"``) likewise.  Peers: sdypy-EMA's LSCE and LSCF
(``get_poles(method="lsce"|"lscf")``, pol_order_high=30, i.e. 60 poles) on the same FRFs,
poles picked by its ``select_closest_poles`` at the true frequencies (LSCE); for its LSCF that
selection returns zeros, so the highest order's pole nearest each true frequency is taken.
Prints median times of repeats, the time ratios and the accuracies; the band rows are repeated
without the refinement of the poles at the range's ends (``refine=False``) to show its cost.

BLAS threads: with OpenBLAS's default of one thread per core, small matrix products slow down
5-10x when other processes load the cores (threads spin-wait for each other).  The benchmark
therefore sets OPENBLAS_NUM_THREADS / OMP_NUM_THREADS (``--threads``, default 1) before numpy
loads, for both ours and sdypy-EMA.

Run: .venv/bin/python benchmarks/ema_speed.py [--repeats 5] [--threads 1]
"""

import argparse
import os
import sys
import warnings
from pathlib import Path

if __name__ == "__main__":
    _threads = "1"
    if "--threads" in sys.argv:
        _threads = sys.argv[sys.argv.index("--threads") + 1]
    for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_var, _threads)

import numpy as np  # noqa: E402
from timing import time_median  # noqa: E402

from bayesupdate.correlation import mac_matrix  # noqa: E402
from bayesupdate.ema import FrfSet, identify, virtual_impact_test  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from synthetic_models import exhaust_like_model  # noqa: E402  (the tests' model)


def make_data(seed: int = 3) -> tuple[FrfSet, tuple]:
    model = exhaust_like_model()
    # 32768 samples at 1200 Hz: df = 150/4096 Hz, lines 0..4095 cover 0-150 Hz
    frfs = virtual_impact_test(
        *model,
        f_max_hz=150.0,
        sample_rate_hz=1200.0,
        duration_s=32768 / 1200.0,
        noise=0.01,
        seed=seed,
    )
    cut = FrfSet(
        frfs.frequencies_hz[:4096],
        frfs.frf[:, :4096],
        frfs.response_labels,
        frfs.reference_labels,
        frfs.kind,
        source="benchmark",
    )
    return cut, model


def accuracy(freq, zeta, fn, zn):
    """Max relative frequency and damping error over the true modes (nearest estimate)."""
    freq, zeta = np.asarray(freq), np.asarray(zeta)
    idx = [int(np.argmin(np.abs(freq - f))) for f in fn]
    return (np.max(np.abs(freq[idx] - fn) / fn), np.max(np.abs(zeta[idx] - zn) / zn))


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--threads", default="1", help="BLAS threads (set before numpy loads)")
    args = parser.parse_args()
    print(f"BLAS threads: {os.environ.get('OPENBLAS_NUM_THREADS')}")
    frfs, (fn, zn, shapes, labels) = make_data()
    print(
        f"data: {frfs.n_frf} FRFs x {frfs.frequencies_hz.size} lines, "
        f"{frfs.frequencies_hz[0]:.1f}-{frfs.frequencies_hz[-1]:.2f} Hz"
    )
    rows = []
    for name, kwargs in (
        (
            "ours, band 0-150 Hz, orders 2..60",
            {"band_hz": (0.0, 149.9), "max_order": 60, "band_lines": 4096},
        ),
        ("ours, automatic bands, orders 2..40", {}),
        (
            "ours pLSCF, band 0-150 Hz, orders 2..60",
            {"band_hz": (0.0, 149.9), "max_order": 60, "band_lines": 4096, "method": "plscf"},
        ),
        ("ours pLSCF, automatic bands, orders 2..40", {"method": "plscf"}),
        (
            "  same as row 1, no end-pole refinement",
            {"band_hz": (0.0, 149.9), "max_order": 60, "band_lines": 4096, "refine": False},
        ),
        (
            "  same as row 3, no end-pole refinement",
            {
                "band_hz": (0.0, 149.9),
                "max_order": 60,
                "band_lines": 4096,
                "method": "plscf",
                "refine": False,
            },
        ),
    ):
        t, res = time_median(lambda kw=kwargs: identify(frfs, **kw), args.repeats)
        m = res.modes
        ferr, derr = accuracy(m.frequencies_hz, m.damping_ratio, fn, zn)
        true = shapes[[labels.index(lab) for lab in m.dof_labels]]
        idx = [int(np.argmin(np.abs(m.frequencies_hz - f))) for f in fn]
        mac = np.diag(mac_matrix(true, m.shapes[:, idx])).min()
        rows.append((name, t, m.n_modes, ferr, derr, mac))
    try:
        from sdypy import EMA

        def peer(method):
            model = EMA.Model(
                frf=frfs.frf,
                freq=frfs.frequencies_hz,
                lower=0.0,
                upper=float(frfs.frequencies_hz[-1]),
                pol_order_high=30,
                frf_form="accelerance",
            )
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                model.get_poles(method=method, show_progress=False)
            return model

        peer_t = {}
        for method in ("lsce", "lscf"):
            t_peer, model = time_median(lambda m=method: peer(m), max(1, min(args.repeats, 3)))
            if method == "lsce":
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    model.select_closest_poles(list(fn), f_window=5)
                freq, zeta = model.nat_freq, model.nat_xi
            else:
                top = np.asarray(model.all_poles[-1])
                freq, zeta = np.abs(top) / (2 * np.pi), -top.real / np.abs(top)
            ferr, derr = accuracy(freq, zeta, fn, zn)
            name = f"sdypy-EMA {method.upper()} (poles only, 60 poles)"
            rows.append((name, t_peer, len(fn), ferr, derr, np.nan))
            peer_t[method] = t_peer
    except ImportError:
        peer_t = {}
        print("sdypy-EMA not installed: peer timing skipped")
    print(
        f"{'method':40s} {'median s':>9} {'modes':>6} {'max f err %':>12} "
        f"{'max zeta err %':>15} {'min MAC':>8}"
    )
    for name, t, n, ferr, derr, mac in rows:
        print(f"{name:40s} {t:9.3f} {n:6d} {100 * ferr:12.4f} {100 * derr:15.2f} {mac:8.4f}")
    if peer_t:
        print(
            f"time ratio sdypy LSCE (poles only) / ours LSCE (whole identification, band): "
            f"{peer_t['lsce'] / rows[0][1]:.1f}x"
        )
        print(
            f"time ratio sdypy LSCF (poles only) / ours pLSCF (whole identification, band): "
            f"{peer_t['lscf'] / rows[2][1]:.1f}x"
        )
        print(
            f"  without end-pole refinement (IdentifySettings.refine=False): LSCE "
            f"{peer_t['lsce'] / rows[4][1]:.1f}x, pLSCF {peer_t['lscf'] / rows[5][1]:.1f}x"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
