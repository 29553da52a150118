"""Would a weighed test article reveal the hidden effects frequency-only discovery misses?

The hidden-effect study (``studies/hidden_effect_study.py``) misses three added masses that
the five design variables absorb, and it confidently names a joint for a longer tail pipe.
Here the hidden-effect "truths" (``hidden_effect_study.truth_model``) are solved at the true
design (seed Table 3 optimum).
The baseline model's five design variables are then re-calibrated to the noise-free true
frequencies twice: on frequencies alone, and with the true total mass as one more observation
(0.3 % sd, a scale's accuracy; objective weight (noise / mass sd)^2, so both terms are in units of
their own noise).  Printed per case:

* the largest frequency residual after re-calibration, in units of the 0.3 % frequency noise:
  what any discovery can still see;
* the mass residual in units of the mass sd.

Run:  .venv/bin/python studies/absorbed_effects_with_mass.py
"""

import os
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parent))

import numpy as np  # noqa: E402
from hidden_effect_study import N_MODES, truth_model  # noqa: E402

from bayesupdate.inference.optimize import CalibrationSettings, calibrate  # noqa: E402
from bayesupdate.inference.problem import ObjectiveSpec, build_problem  # noqa: E402
from bayesupdate.modal_data import ModalData  # noqa: E402
from bayesupdate.models.exhaust_paper import TABLE3_OPTIMUM_SI  # noqa: E402

NOISE = 0.003  # relative frequency noise of the study
MASS_SD = 0.003  # relative sd of the weighed mass
CASES = (
    "added_mass@4:m=0.2",
    "added_mass@19:m=0.2",
    "added_mass@19:m=0.5",
    "bend_flexibility@hot_bend1:factor=4",
    "joint_flexibility@cold_pipe/main_muffler:k_rot=1e3",
    "geometry:tail_length=0.30",
)


def recalibrated(base, f_true, mass_true, with_mass: bool) -> tuple[float, float]:
    """(max |f - f_true| / f_true / NOISE, (m - m_true) / m_true / MASS_SD) after the 4-start
    re-calibration of the design variables."""
    data = ModalData(f_true, frequency_sd_hz=NOISE * f_true)
    objective = ObjectiveSpec(mass_true, mass_weight=(NOISE / MASS_SD) ** 2) if with_mass else None
    problem = build_problem(base, data, None, pairing="order", objective=objective)
    fit = calibrate(problem, CalibrationSettings(starts=4, seed=0, max_nfev=100, polish=False))
    freq = float(np.max(np.abs(fit.frequencies_hz - f_true) / f_true)) / NOISE
    return freq, (fit.mass_kg - mass_true) / mass_true / MASS_SD


def main() -> None:
    print(f"{'case':<52}{'true kg':>9}{'freq only: f, m':>18}{'with mass: f, m':>18}")
    for case in CASES:
        true_model, _, base = truth_model(case)
        truth = true_model.predict(TABLE3_OPTIMUM_SI, N_MODES)
        f_true = np.sort(truth.frequencies_hz)
        rows = [recalibrated(base, f_true, truth.mass_kg, w) for w in (False, True)]
        cells = "".join(f"{f:>10.1f}{m:>+8.1f}" for f, m in rows)
        print(f"{case:<52}{truth.mass_kg:>9.3f}{cells}")
    print("(f: max frequency residual / noise; m: mass residual / mass sd)")


if __name__ == "__main__":
    main()
