"""Peer check of the FE modal solver against OpenSeesPy on the same free-free frame.

The frame (``opensees_frame.example_frame``) has pipe runs with bends, an oval (muffler) shell, a
hanger rod, point masses with inertia (diagonal and full tensors, with and without an offset) and
a joint spring between two coincident nodes in a rotated frame.  ``benchmarks/opensees_frame.py``
builds it in OpenSees with OpenSees' own elements (ElasticTimoshenkoBeam / elasticBeamColumn with
consistent mass), rigid links and zeroLength springs; only the section numbers are shared.
Free-free pencils go to OpenSees' dense generalized (QZ) solver, never to its ARPACK, which
factorizes K at shift 0 and hits a zero pivot on a free body depending on round-off (it failed that
way on a fresh clone with numpy 2.5 / scipy 1.18); the six ~0 eigenvalues are dropped by count and
checked to be ~0. ARPACK is used where K is regular (the frame on ground springs). Agreement
reached: 1e-11 to 1e-9 relative on the first 12 elastic frequencies (the brief's target is 5e-4);
asserted at 1e-7, the Krylov solver's tolerance level. On this frame rotary inertia moves the
frequencies by up to 2.5 %, shear by 1.4 %, the oval's torsional inertia (polar moment vs J) by 2.9
%: the check sees each of them.

Like for like (``test_exhaust_like_for_like``): the 1e-10 - 1e-8 left above is the round-off of
OpenSees' QZ on the singular free-free pencil (scipy's QZ on *our* K, M is as far off).  OpenSees'
own assembled K and M (read with its GimmeMCK integrator) equal ours to 4e-16, and the two pencils
put through one shift-invert Lanczos solve give frequencies equal to <= 6e-11 (8 exhaust designs x
2 beam variants); a single rounding of K's entries (x (1 + 2e-16 noise)) already moves them by
1e-11 - 9e-11, so that is the agreement round-off allows.
"""

import importlib.util
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("openseespy.opensees")

from bayesupdate.fe import Binding, FEModel, solid_round  # noqa: E402

_PATH = Path(__file__).resolve().parents[1] / "benchmarks" / "opensees_frame.py"
_SPEC = importlib.util.spec_from_file_location("opensees_frame", _PATH)
opensees_frame = importlib.util.module_from_spec(_SPEC)
sys.modules["opensees_frame"] = opensees_frame
_SPEC.loader.exec_module(opensees_frame)

REL_TOL = 1e-7
N_MODES = 12
#: OpenSees' assembled K, M against ours, max |dX| / max |X| (measured <= 4.4e-16)
MATRIX_TOL = 1e-14
#: frequencies of the two pencils through one accurate solver, and our FEModel.solve against
#: OpenSees' pencil so solved (measured <= 1.2e-11 and <= 5.9e-11 at these four points; the
#: rounding floor of K alone reaches 9e-11, see the module docstring)
LIKE_FOR_LIKE_TOL = 2e-10


def _both(structure):
    ours = FEModel(structure, {}, {}, {}).solve(n_modes=N_MODES).frequencies_hz
    peer = opensees_frame.opensees_frequencies(structure, N_MODES)
    return ours, peer


def test_timoshenko_frame_matches_opensees():
    """Shear + rotary inertia (ElasticTimoshenkoBeam -cMass), no elbow factor."""
    structure = opensees_frame.example_frame(shear=True, rotary_inertia=True, elbow=False)
    info = opensees_frame.build_opensees(structure)
    assert info.element == "ElasticTimoshenkoBeam"
    assert info.n_rigid_links == 8  # internals: centre + 3 principal pairs; rod tip: centre
    assert opensees_frame.well_posed_solver(info.n_rigid_expected) == "-fullGenLapack"
    ours, peer = _both(structure)
    assert ours[0] > 20.0  # elastic modes, the six rigid ones are gone on both sides
    np.testing.assert_allclose(ours, peer, rtol=REL_TOL)


def test_euler_bernoulli_frame_with_elbow_factor_matches_opensees():
    """No shear, no rotary inertia (elasticBeamColumn -cMass), ASME B31.3 factor on the bends
    (passed to OpenSees as Iy/k, Iz/k)."""
    structure = opensees_frame.example_frame(shear=False, rotary_inertia=False, elbow=True)
    bends = structure.beam_bend_radius > 0
    k = opensees_frame.elbow_factor(
        structure.beam_thickness[bends],
        structure.beam_bend_radius[bends],
        structure.beam_width[bends],
    )
    assert k.min() > 2.0  # the factor really acts (h = t R / r^2 ~ 0.3 for these bends)
    ours, peer = _both(structure)
    np.testing.assert_allclose(ours, peer, rtol=REL_TOL)
    stiff = FEModel(opensees_frame.example_frame(False, False, elbow=False), {}, {}, {}).solve(
        n_modes=N_MODES
    )
    assert np.all(stiff.frequencies_hz[:4] > 1.01 * ours[:4])  # flexible bends lower the modes


def test_parametric_model_matches_opensees_off_default():
    """Parameters bound to thickness (re-assembled), density, Young's modulus, spring and mass
    factors, moved off their defaults: OpenSees built from the same element property values."""
    bindings = {
        "t_pipe": Binding("pipe", "thickness"),
        "rho_muffler": Binding("muffler", "density"),
        "E_tail": Binding("tail", "youngs_modulus"),
        "k_joint": Binding("joint", "stiffness_factor"),
        "m_internals": Binding("internals", "mass_factor"),
    }
    defaults = {"t_pipe": 1.5e-3, "rho_muffler": 1e4, "E_tail": 2.1e11, "k_joint": 1.0}
    defaults["m_internals"] = 1.0
    bounds = {name: (0.0, 1e12) for name in bindings}
    model = FEModel(opensees_frame.example_frame(), bindings, defaults, bounds)
    params = dict(t_pipe=2.2e-3, rho_muffler=1.7e4, E_tail=1.9e11, k_joint=0.3, m_internals=1.6)
    ours = model.solve(params, n_modes=N_MODES).frequencies_hz
    at_default = model.solve(n_modes=N_MODES).frequencies_hz
    assert np.max(np.abs(ours / at_default - 1)) > 0.05  # the parameters really moved the modes
    props = model.element_properties(params)
    peer = opensees_frame.opensees_frequencies(model.structure, N_MODES, props)
    np.testing.assert_allclose(ours, peer, rtol=REL_TOL)


def test_frame_on_soft_ground_springs_matches_opensees():
    """Three soft 6-DOF springs to ground (hangers): the six suspension modes store energy in the
    springs, so both codes report them as the six lowest elastic modes and no rigid mode."""
    s = opensees_frame.example_frame()
    hangers = [0, 20, s.n_nodes - 1]
    structure = replace(
        s,
        spring_nodes=np.vstack([s.spring_nodes, [[n, -1] for n in hangers]]),
        spring_k=np.vstack([s.spring_k, [[2e3, 2e3, 2e3, 1.0, 1.0, 1.0]] * 3]),
        spring_frame=np.concatenate([s.spring_frame, np.repeat(np.eye(3)[None], 3, axis=0)]),
        spring_part=np.concatenate([s.spring_part, [s.spring_part[0]] * 3]),
    )
    ours = FEModel(structure, {}, {}, {}).solve(n_modes=N_MODES + 6).modes
    opensees_frame.build_opensees(structure)
    peer, suspension = opensees_frame.eigen_frequencies(N_MODES, n_rigid=6)
    assert ours.n_rigid == 0
    f_suspension = ours.frequencies_hz[:6]
    assert 0.5 < f_suspension.min() and f_suspension.max() < 10.0
    np.testing.assert_allclose(ours.frequencies_hz[6:], peer, rtol=REL_TOL)
    np.testing.assert_allclose(f_suspension, np.sqrt(suspension) / (2 * np.pi), rtol=1e-5)


def test_exhaust_matches_opensees():
    """The built-in exhaust (elbow factor off, as OpenSees' Timoshenko beam cannot carry it with
    rotary inertia) at the paper's optimum design (seed Table 3)."""
    from bayesupdate.models import get_model
    from bayesupdate.models.exhaust_paper import TABLE3_OPTIMUM_SI

    model = get_model("exhaust", elbow_flexibility=False)
    params = dict(TABLE3_OPTIMUM_SI)
    ours = model.solve(params, n_modes=N_MODES).frequencies_hz
    peer = opensees_frame.opensees_frequencies(
        model.structure, N_MODES, model.element_properties(params)
    )
    np.testing.assert_allclose(ours, peer, rtol=REL_TOL)


def test_peer_check_sees_the_oval_torsional_inertia():
    """bayesupdate's torsional inertia is rho (Iy + Iz), OpenSees' rho J; they differ for the oval
    shell ((Iy + Iz) / J ~ 1.4 here).  With OpenSees' own value the frequencies move by far more
    than the tolerance, so the agreement above is not blind to this term."""
    structure = opensees_frame.example_frame()
    ours = FEModel(structure, {}, {}, {}).solve(n_modes=N_MODES).frequencies_hz
    own = opensees_frame.opensees_frequencies(structure, N_MODES, polar_torsion=False)
    assert np.max(np.abs(own / ours - 1)) > 1000 * REL_TOL


def test_solid_round_rod():
    ours, peer = _both(opensees_frame.example_frame(rod=solid_round))
    np.testing.assert_allclose(ours, peer, rtol=REL_TOL)


@pytest.mark.parametrize("beam", ["timoshenko", "euler_bernoulli_elbow"])
@pytest.mark.parametrize("design", ["initial", "optimum"])
def test_exhaust_like_for_like(beam, design):
    """The exhaust's K and M as OpenSees assembles them equal ours to round-off; through one solver
    their frequencies agree to ~1e-11, and OpenSees' own QZ solve is the part that differs more."""
    from bayesupdate.models import get_model
    from bayesupdate.models.exhaust_paper import TABLE3_OPTIMUM_SI

    model = get_model("exhaust", elbow_flexibility=beam != "timoshenko")
    if beam != "timoshenko":
        model = model.with_structure(replace(model.structure, shear=False, rotary_inertia=False))
    params = dict(TABLE3_OPTIMUM_SI) if design == "optimum" else None
    like = opensees_frame.like_for_like(model, params, N_MODES)
    assert like.matrix_k <= MATRIX_TOL and like.matrix_m <= MATRIX_TOL
    assert like.same_solver <= LIKE_FOR_LIKE_TOL
    assert like.our_solve <= LIKE_FOR_LIKE_TOL
    # QZ on the singular pencil: ~1e-10 - 1e-8 from the accurate solve, OpenSees' and scipy's alike
    assert like.peer_solve <= REL_TOL and like.qz_on_ours <= REL_TOL
