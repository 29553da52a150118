"""A test that missed the model's lower modes, correlated through the user's commands: a public
deck's virtual test, identified, then paired with the deck (``inference.pairing.reach_modes``).

Data nobody here made: pyNastran's ``msc/64_bit/d173.bdf`` (MSC's wing box of PCOMP skins,
CSHEAR webs and CROD caps; BSD-3-Clause, commit 1d25a92), read as published.  Twelve test
points are the GRIDs ``POINTS`` (spread along the deck's GRID list, chosen once, before any
run); each measures V (z) and H (y).

The chain, every step a ``bayesupdate`` command as a user types it (``cli.main``):

1. ``simulate --model d173.bdf --test-points points.csv`` (the seed's roving-hammer test, 0-150
   Hz, 1 % noise, seed 0);
2. ``identify`` on its FRFs;
3. ``correlate --model d173.bdf --data modes.h5 --test-points points.csv``.

The deck's lowest modes (0.48-4.4 Hz) are not identified from this test (the virtual test's
frequency lines and its sensors do not resolve them), so the identified modes 1-4 are the
deck's higher ones; before ``reach_modes`` correlate solved only the first 4 + 2 model modes
and refused all four.

Measured (2026-11-30, this script): identified 6.40, 8.82, 10.56 and 11.65 Hz; paired with
model modes 9, 14, 16 and 20 (6.41, 8.84, 10.42, 11.66 Hz, MAC 0.998, 0.936, 0.910, 0.987);
the note says the first 6 model modes stop at 4.42 Hz and 24 were computed.  The deck's 20
simulated modes all lie below 11.7 Hz, in identify's first automatic band of 512 lines; the
same FRFs over ``--band 0:20`` give 18 of them (0.478-11.657 Hz) and over ``--band 0:6`` the 7
below 6 Hz (docs/validation/identification.md, "dense modes").

Run: PYTHONPATH=. python studies/correlate_missed_modes.py <pyNastran>/models
"""

import argparse
import contextlib
import io
import json
import tempfile
from pathlib import Path

from bayesupdate.cli import main as cli

DECK = "msc/64_bit/d173.bdf"
#: the test points: GRID ids of the deck, spread along its GRID list
POINTS = (5, 20, 36, 51, 67, 82, 102, 117, 133, 148, 164, 90)


def run(argv: list) -> dict:
    """``bayesupdate argv --json``'s object (its exit code must be 0)."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        code = cli([*map(str, argv), "--json", "--quiet"])
    if code != 0:
        raise SystemExit(f"{argv[0]} failed with exit code {code}")
    return json.loads(out.getvalue())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("models", type=Path, help="pyNastran's models folder")
    args = ap.parse_args()
    deck = args.models / DECK
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        points = folder / "points.csv"
        points.write_text("".join(f"{k + 1},{g}\n" for k, g in enumerate(POINTS)))
        run(["simulate", "--model", deck, "--test-points", points, "--out", folder / "t.uff"])
        ident = run(["identify", folder / "t.uff", "--out", folder / "modes.h5"])
        print("identified [Hz]:", [round(m["frequency_hz"], 2) for m in ident["modes"]])
        for band in ("0:20", "0:6"):  # the dense range analysed on its own
            low = run(["identify", folder / "t.uff", "--band", band, "--out", folder / "low.h5",
                       "--force"])  # fmt: skip
            print(f"  --band {band} [Hz]:", [round(m["frequency_hz"], 3) for m in low["modes"]])
        corr = run(["correlate", "--model", deck, "--data", folder / "modes.h5",
                    "--test-points", points])  # fmt: skip
    for row in corr["tests"]:
        print(f"  test {row['test']} {row['test_hz']:.2f} Hz: {row['status']}, model mode "
              f"{row['model']} ({row['model_hz']:.2f} Hz), MAC {row['mac']:.3f}")  # fmt: skip
    for note in corr["notes"][:1]:
        print("  note:", note)


if __name__ == "__main__":
    main()
