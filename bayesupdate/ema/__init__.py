"""Experimental modal analysis: time signals -> FRFs -> LSCE or pLSCF -> stabilization ->
automatic poles -> LSFD shapes -> :class:`~bayesupdate.modal_data.ModalData` (seed section 4,
eqs 4-18).

Main entry points: :func:`identify` (whole pipeline), :func:`h1_h2_coherence` (FRFs from
signals), :func:`virtual_impact_test` (synthetic test data), :func:`read_uff58` /
:func:`write_uff58` / :func:`read_uff55` / :func:`write_uff55`, :func:`write_modal_h5` /
:func:`read_modal_h5`.
"""

from bayesupdate.ema.frf_estimation import (
    correct_exponential_window,
    frf_from_signals,
    h1_h2_coherence,
)
from bayesupdate.ema.frf_set import FrfSet, merge_frf_sets
from bayesupdate.ema.identify import Identification, identify
from bayesupdate.ema.lsce import lsce
from bayesupdate.ema.modal_h5 import read_modal_h5, write_modal_h5
from bayesupdate.ema.plscf import plscf
from bayesupdate.ema.synthesis import poles_from_modal, synthesize_frf, synthesize_from_modes
from bayesupdate.ema.uff_io import read_uff55, read_uff58, write_uff55, write_uff58
from bayesupdate.ema.virtual_test import seed_layout, virtual_impact_test

__all__ = [
    "FrfSet",
    "Identification",
    "identify",
    "lsce",
    "plscf",
    "h1_h2_coherence",
    "frf_from_signals",
    "merge_frf_sets",
    "correct_exponential_window",
    "virtual_impact_test",
    "seed_layout",
    "poles_from_modal",
    "synthesize_frf",
    "synthesize_from_modes",
    "read_uff58",
    "write_uff58",
    "read_uff55",
    "write_uff55",
    "read_modal_h5",
    "write_modal_h5",
]
