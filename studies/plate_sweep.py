"""Real data check: modes of a free plate from five swept-sine repetitions (60-500 Hz).

Data: ../shared/data/plate_sweep beside the checkout (ladisk/mssp-image-tutorial, MIT; see its
README): force and acceleration at 25.6 kHz, 2 s per repetition, one driving-point-like FRF each.

For every repetition: H1 from the signals (Hann window, 1 s segments, 75 % overlap: df = 1 Hz),
then ``identify`` on 60-500 Hz (automatic narrow bands, no frequency guesses).  Modes of the
repetitions are grouped by frequency (within 1 %); a group found in at least 3 of 5 repetitions
is reported with its mean and scatter (sample standard deviation / mean).  Side by side,
sdypy-EMA's LSCE (optional peer) runs on the same FRF of the first repetition and its stable pole
closest to each of our modes is listed.

Band invariance, the path a user takes: ``bayesupdate frf`` on the four view-0
repetitions averaged (rectangular window on each whole 2 s record: 0.5 Hz lines; the lines the
force excites are written), then ``bayesupdate identify`` on the automatic band and on
60:500, 100:480 and 80:470, with both estimators (LSCE, pLSCF): the five clear peaks (126, 214,
264, 348 Hz within 1.5 %, the broad 440-460 Hz one within 2.5 %) and the other poles in
60-500 Hz are listed (``four_band_table``).

Run: .venv/bin/python studies/plate_sweep.py
"""

import glob
import os
import sys
import warnings
from pathlib import Path

import h5py
import numpy as np

from bayesupdate.ema import FrfSet, h1_h2_coherence, identify

# the shared data sit beside the checkout: <parent>/shared/data/plate_sweep
DATA = os.environ.get(
    "PLATE_SWEEP_DIR",
    str(Path(__file__).resolve().parents[2] / "shared" / "data" / "plate_sweep"),
)
BAND_HZ = (60.0, 500.0)


def repetition_files(folder: str = DATA) -> list[str]:
    return sorted(glob.glob(os.path.join(folder, "*.hdf5")))


def plate_frf(path: str) -> FrfSet:
    """H1 accelerance FRF (1 Hz lines) on 60-500 Hz of one repetition."""
    with h5py.File(path, "r") as fh:
        data = fh["InputTask/data"][()]
        fs = float(fh["InputTask/sample_rate"][()])
    force, accel = data[:, 0], data[:, 1]
    f, h1, _, coh = h1_h2_coherence(force, accel, fs, segment=int(fs), overlap=0.75, window="hann")
    keep = (f >= BAND_HZ[0]) & (f <= BAND_HZ[1])
    return FrfSet(
        f[keep],
        h1[None, keep],
        ("1V",),
        ("1V",),
        "accelerance",
        coherence=coh[None, keep],
        source=os.path.basename(path),
    )


def group_modes(freq_lists: list[np.ndarray], tol: float = 0.01) -> list[list[float]]:
    """Group frequencies of several runs: a value joins a group within ``tol`` of its mean."""
    groups: list[list[float]] = []
    for value in sorted(v for fl in freq_lists for v in fl):
        if groups and abs(value - np.mean(groups[-1])) < tol * value:
            groups[-1].append(value)
        else:
            groups.append([value])
    return groups


def sdypy_frequencies(
    frfs: FrfSet, approx_hz: np.ndarray, lower_hz: float, max_order: int = 40
) -> np.ndarray:
    """sdypy-EMA LSCE on the same FRF; its stable pole nearest each of ``approx_hz``.

    sdypy pads the lines below the FRF's first line with zeros.  With ``lower_hz`` = 0 its IRF
    covers 0-500 Hz at dt = 1/(2 * 500 Hz), which is right; with ``lower_hz`` > 0 it transforms
    only the lines above ``lower_hz`` but keeps dt = 1/(2 f_max) (EMA.py, _get_poles_lsce), so
    its frequencies are biased - the error the issue mentions, shown here as evidence.
    """
    from sdypy import EMA

    model = EMA.Model(
        frf=frfs.frf,
        freq=frfs.frequencies_hz,
        lower=lower_hz,
        upper=BAND_HZ[1],
        pol_order_high=max_order,
        frf_form="accelerance",
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.get_poles(method="lsce", show_progress=False)
        model.select_closest_poles(list(approx_hz), f_window=10)
    return np.asarray(model.nat_freq, dtype=float)


PEAKS_HZ = np.array([126.0, 214.0, 264.0, 348.0, 450.0])
PEAK_TOLERANCE = np.array([0.015, 0.015, 0.015, 0.015, 0.025])
BANDS = (None, "60:500", "100:480", "80:470")


def four_band_table(folder: str = DATA) -> list[tuple]:
    """(method, band, peaks found (5,) [Hz] or NaN, other poles in 60-500 Hz) per run."""
    import contextlib
    import io
    import json
    import tempfile

    from bayesupdate.cli import main as cli

    files = sorted(glob.glob(os.path.join(folder, "view_0*.hdf5")))
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        uff = os.path.join(tmp, "plate.uff")
        argv = ["frf", *files, "--force-channel", "force", "--response", "acc=1V"]
        argv += ["--reference", "1V", "--df", "0.5", "--window", "rect", "--out", uff]
        with contextlib.redirect_stdout(io.StringIO()):
            if cli(argv) != 0:
                raise SystemExit("bayesupdate frf failed on the plate")
        for method in ("lsce", "plscf"):
            for band in BANDS:
                argv = ["identify", uff, "--out", os.path.join(tmp, "m.h5"), "--force"]
                argv += ["--json", "--method", method] + (["--band", band] if band else [])
                buf = io.StringIO()
                with contextlib.redirect_stdout(buf):
                    cli(argv)
                found = np.array([m["frequency_hz"] for m in json.loads(buf.getvalue())["modes"]])
                near = np.array([found[np.argmin(np.abs(found - p))] for p in PEAKS_HZ])
                hit = np.abs(near / PEAKS_HZ - 1) <= PEAK_TOLERANCE
                others = [
                    x for x in found if 60 <= x <= 500 and not np.any(np.isclose(x, near[hit]))
                ]
                rows.append((method, band or "automatic", np.where(hit, near, np.nan), others))
    return rows


def main() -> int:
    print("four bands, four view-0 repetitions averaged (bayesupdate frf -> identify)")
    for method, band, peaks, others in four_band_table():
        print(
            f"  {method:5s} {band:9s} peaks "
            + " ".join(f"{p:6.1f}" for p in peaks)
            + f"  others in 60-500 Hz: {len(others)} "
            + "("
            + ", ".join(f"{x:.1f}" for x in others)
            + ")"
        )
    print()
    files = repetition_files()
    if not files:
        print(f"no data in {DATA}", file=sys.stderr)
        return 1
    runs = []
    for path in files:
        frfs = plate_frf(path)
        modes = identify(frfs).modes
        runs.append((frfs, modes))
        print(
            f"{os.path.basename(path):16s} " + " ".join(f"{f:7.2f}" for f in modes.frequencies_hz)
        )
    groups = group_modes([m.frequencies_hz for _, m in runs])
    print("\nmodes found in >= 3 of 5 repetitions")
    print(
        f"{'mean [Hz]':>10} {'found':>6} {'scatter %':>10} {'zeta %':>7} {'rep 1':>9} "
        f"{'sdypy [Hz]':>11} {'diff %':>7} {'sdypy lo=60':>13}"
    )
    frfs0, modes0 = runs[0]
    repeated = [g for g in groups if len(g) >= 3]
    ours0 = []
    for g in repeated:
        k = np.argmin(np.abs(modes0.frequencies_hz - np.mean(g)))
        ours0.append(modes0.frequencies_hz[k])
    try:
        peer = sdypy_frequencies(frfs0, np.array(ours0), 0.0)
        biased = sdypy_frequencies(frfs0, np.array(ours0), BAND_HZ[0])
    except ImportError:
        peer = biased = np.full(len(ours0), np.nan)
    for g, f0, fp, fb in zip(repeated, ours0, peer, biased, strict=True):
        k = np.argmin(np.abs(modes0.frequencies_hz - f0))
        scatter = 100 * np.std(g, ddof=1) / np.mean(g)
        print(
            f"{np.mean(g):10.2f} {len(g):6d} {scatter:10.3f} "
            f"{100 * modes0.damping_ratio[k]:7.2f} {f0:9.2f} {fp:11.2f} "
            f"{100 * (fp - f0) / f0:7.3f} {fb:13.2f}"
        )
    print(
        "(rep 1 = view_0; sdypy columns: its LSCE on the same FRF as rep 1; diff = sdypy - "
        "ours; last column: sdypy with lower=60 Hz, biased by its full-band time step)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
