"""The mAEWing1 GVT (../shared/data/gvt_maewing1, see its README) as a user turns it into FRFs:
``bayesupdate frf`` per run, shaker force (0.4684 V/lbf) as reference 25V, the run's two
accelerometers (1.028 V/g) as nodes 2k-1 and 2k."""

from pathlib import Path

GVT = Path(__file__).resolve().parents[2] / "shared" / "data" / "gvt_maewing1" / "data"


def frf_argv(run: int, out) -> list[str]:
    """``bayesupdate frf`` arguments of run 1..5, writing ``out``."""
    return [str(a) for a in [
        "frf", GVT / f"run_Run{run}.mat", "--force-channel", "Force",
        "--response", f"Accel1={2 * run - 1}V", "--response", f"Accel2={2 * run}V",
        "--reference", "25V", "--force-unit", "lbf", "--force-sensitivity", "0.4684",
        "--response-unit", "g", "--response-sensitivity", "1.028", "--out", out,
    ]]  # fmt: skip
