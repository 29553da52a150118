"""Every pole ``bayesupdate identify`` reports on the LADISK beam FRF, and which are real modes.

Data: ../shared/data/beam_frf_sdpy/data/measurement.uff (one measured accelerance, 1-10000 Hz;
README there).  The authors give 7 modes (176.07 ... 4181.72 Hz) from an LSCF fit over 10-5000
Hz; the file runs to 10 kHz, and the default (automatic-band) identification reports 13 poles.

1. The pole table: frequency, damping, stable orders, the pruning measures of
   ``ema.identify.modal_significance`` (share of the FRF explained at resonance, peak over the
   local fit residual), shape_sd_rel, |H| near the pole over the FRF's median.  MPC is n/a (one
   DOF).
2. Bending modes 8-11: free-free Euler-Bernoulli and Timoshenko frequencies fitted to the
   authors' 7 (tests/free_beam_theory.py; the README gives no geometry, so the Timoshenko
   slenderness r/L is fitted too) and extrapolated.  The implied length and thickness follow for
   steel (E/rho = 210e9/7850) or aluminium (69e9/2700), with the axial free-free sequence
   n c0 / (2 L) = n pi scale / s (material-free).
3. What the other poles could be: axial (n c0 / 2L), torsion (the b/h of a rectangle putting
   torsion mode 1 there) or in-plane bending (b/h = f / f_bending(n) to first order).  The
   width is not known and the file has one response direction, so this names candidates only.
4. sdypy-EMA's LSCF (optional peer, order 60 over 10-2500, 2500-4500 and 4500-10000 Hz): its
   stable pole nearest each of ours.

Run: .venv/bin/python studies/beam_frf_poles.py
"""

import contextlib
import io
import sys
import warnings
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from free_beam_theory import (  # noqa: E402
    BEAM_REFERENCE_HZ,
    euler_bernoulli_hz,
    timoshenko_fit,
    timoshenko_hz,
)

from bayesupdate.ema.identify import identify  # noqa: E402
from bayesupdate.pipelines.identify import read_frf_files  # noqa: E402

BEAM_UFF = Path(__file__).resolve().parents[2] / "shared" / "data" / "beam_frf_sdpy" / "data"
BEAM_UFF = BEAM_UFF / "measurement.uff"
#: longitudinal wave speeds sqrt(E / rho) [m/s] of the two likely materials
C0 = {"steel": np.sqrt(210e9 / 7850), "aluminium": np.sqrt(69e9 / 2700)}
NU = 0.3
MATCH = 0.01  # a pole "is" a predicted bending mode within 1 % (see the printed misfit)


def pole_rows(ident, frfs) -> list[dict]:
    """One dict per reported mode with the measures of the module docstring, item 1."""
    m, f = ident.modes, frfs.frequencies_hz
    level = np.abs(frfs.frf[0])
    med = np.median(level)
    rows = []
    for k, fk in enumerate(m.frequencies_hz):
        near = (f > fk * 0.998) & (f < fk * 1.002)
        rows.append(
            {
                "f": fk,
                "zeta": m.damping_ratio[k],
                "stable": int(m.extra["stable_orders"][k]),
                "share": m.extra["fit_share"][k],
                "peak": m.extra["peak_to_residual"][k],
                "sd": m.shape_sd_rel[k],
                "level": np.max(level[near]) / med if near.any() else np.nan,
            }
        )
    return rows


def classify(f: float, bending: np.ndarray) -> str:
    ref = np.abs(f / BEAM_REFERENCE_HZ - 1)
    if ref.min() <= 0.005:
        return f"authors' mode {int(np.argmin(ref)) + 1}"
    dev = f / bending - 1
    n = int(np.argmin(np.abs(dev)))
    if abs(dev[n]) <= MATCH:
        return f"bending mode {n + 1} ({100 * dev[n]:+.2f} % of Timoshenko)"
    return "other"


def torsion_aspect(f1: float, axial1: float) -> float:
    """b/h of a rectangular bar whose first free-free torsion mode is f1 [Hz]:
    f1 = c0 / (2L) sqrt(J / (2 (1 + nu) Ip)), J = (1 - 0.63 h / b) b h^3 / 3 (Roark),
    Ip = b h (b^2 + h^2) / 12; axial1 = c0 / (2 L) [Hz]."""

    def resid(a):
        j_over_ip = 4 * (1 - 0.63 / a) / (a**2 + 1)
        return axial1 * np.sqrt(j_over_ip / (2 * (1 + NU))) - f1

    return brentq(resid, 1.0, 50.0)


def peer_poles(frfs, rows) -> None:
    """sdypy-EMA's LSCF (optional peer): its stable pole nearest each pole we report, from a
    fit over the quarter of the range around it (order 60, as the authors' fit)."""
    try:
        from sdypy import EMA
    except ImportError:
        print("(sdypy-EMA not installed: peer check left out)")
        return
    print("\n== sdypy-EMA LSCF, nearest stable pole to each reported pole")
    for lo, hi in ((10.0, 2500.0), (2500.0, 4500.0), (4500.0, 10000.0)):
        ours = [r["f"] for r in rows if lo <= r["f"] < hi]
        model = EMA.Model(frf=frfs.frf, freq=frfs.frequencies_hz, lower=lo, upper=hi,
                          pol_order_high=60, frf_form="accelerance")  # fmt: skip
        quiet = contextlib.redirect_stderr(io.StringIO())  # its progress bars
        with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()), quiet:
            warnings.simplefilter("ignore")
            model.get_poles(method="lscf", show_progress=False)
            model.select_closest_poles(ours, f_window=50)
        for x, y in zip(ours, np.asarray(model.nat_freq, dtype=float), strict=True):
            print(f"{x:9.2f} -> {y:9.2f} ({100 * (y / x - 1):+.2f} %)")


def main() -> int:
    if not BEAM_UFF.is_file():
        print(f"shared data not found at {BEAM_UFF}")
        return 1
    frfs = read_frf_files([str(BEAM_UFF)]).frfs
    ident = identify(frfs)
    fit = timoshenko_fit()
    n_all = np.arange(1, 13)
    bending = timoshenko_hz(n_all, fit)
    rows = pole_rows(ident, frfs)
    print("== poles reported by the default identification (automatic band)")
    print(f"{'f [Hz]':>9} {'zeta':>7} {'stable':>6} {'share':>6} {'peak/res':>8} "
          f"{'shape_sd':>8} {'|H|/med':>7}  what")  # fmt: skip
    for r in rows:
        what = classify(r["f"], bending)
        print(f"{r['f']:9.2f} {r['zeta']:7.4f} {r['stable']:6d} {r['share']:6.2f} "
              f"{r['peak']:8.1f} {r['sd']:8.4f} {r['level']:7.2f}  {what}")  # fmt: skip
    dropped = np.sort(ident.extra["dropped_hz"])
    print(f"stable poles pruned as not physical: {', '.join(f'{x:.1f}' for x in dropped)} Hz")
    print("\n== free-free bending sequence fitted to the authors' 7, extrapolated")
    s, scale, rms = fit
    print(f"Timoshenko fit: r/L = {s:.5f}, rms misfit over the 7 = {100 * rms:.2f} %")
    eb = euler_bernoulli_hz(n_all)
    found = np.array([r["f"] for r in rows])
    print(f"{'mode':>4} {'EB [Hz]':>9} {'Timo [Hz]':>9} {'nearest':>9} {'vs EB':>7} {'vs Timo':>7}")
    for n in n_all[:11]:
        near = found[np.argmin(np.abs(found - bending[n - 1]))]
        src = "authors" if n <= 7 else "pole"
        near = BEAM_REFERENCE_HZ[n - 1] if n <= 7 else near
        print(f"{n:4d} {eb[n - 1]:9.1f} {bending[n - 1]:9.1f} {near:9.1f} "
              f"{100 * (near / eb[n - 1] - 1):+6.2f}% {100 * (near / bending[n - 1] - 1):+6.2f}%"
              f"  ({src})")  # fmt: skip
    axial1 = np.pi * scale / s
    print("\n== implied geometry (the README gives none)")
    for mat, c0 in C0.items():
        length = s * c0 / (2 * np.pi * scale)
        print(f"{mat}: L = {length:.3f} m, h = {1e3 * np.sqrt(12) * s * length:.1f} mm")
    print(f"axial modes n c0 / (2 L) = n x {axial1:.0f} Hz (any material)")
    print("\n== what the poles that are neither could be")
    for r in rows:
        if classify(r["f"], bending) != "other":
            continue
        fo = r["f"]
        inplane = ", ".join(f"b/h {fo / bending[n]:.2f} (mode {n + 1})" for n in range(3))
        print(f"{fo:.1f} Hz: axial n = {fo / axial1:.2f}; in-plane bending {inplane}")
        if fo < 2 * axial1:
            print(f"  torsion mode 1 if b/h = {torsion_aspect(fo, axial1):.2f}")
    peer_poles(frfs, rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
