"""Dampers as data: a two-mass chain with a dashpot between the masses and one
to ground gives the textbook damping matrix; a damper in a rotated frame transforms as
R^T c R; normal modes ignore dampers; bad damping values are one-line errors."""

import numpy as np
import pytest

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe import StructureBuilder
from bayesupdate.fe.elements.damper import damping_matrix


def _two_masses(frame=None):
    b = StructureBuilder()
    n0, n1 = b.add_node((0, 0, 0)), b.add_node((0, 0, 0))
    for n in (n0, n1):
        b.add_point_mass(n, 2.0, "mass", inertia=np.eye(3) * 0.01)
    b.add_spring(n0, None, [1e4] * 6, "mount")
    b.add_spring(n0, n1, [2e4] * 6, "link")
    b.add_damper(n0, None, [3.0, 0, 0, 0, 0, 0], "mount")
    b.add_damper(n0, n1, [5.0, 0, 0, 0, 0, 0], "link", frame=frame)
    return b.build()


def test_chain_damping_matrix_is_the_textbook_one():
    C = damping_matrix(_two_masses().dampers, 2).toarray()
    x = [0, 6]  # the x DOFs of the two nodes
    np.testing.assert_array_equal(C[np.ix_(x, x)], [[3.0 + 5.0, -5.0], [-5.0, 5.0]])
    assert np.count_nonzero(C) == 4


def test_damper_in_a_rotated_frame_transforms_as_r_t_c_r():
    angle = 0.3
    R = np.array([[np.cos(angle), np.sin(angle), 0], [-np.sin(angle), np.cos(angle), 0], [0, 0, 1]])
    C = damping_matrix(_two_masses(frame=R).dampers, 2).toarray()
    link = 5.0 * np.outer(R[0], R[0])  # 5 N s/m along the frame's first axis
    np.testing.assert_allclose(C[6:9, 6:9], link, atol=1e-15)
    np.testing.assert_allclose(C[0:3, 6:9], -link, atol=1e-15)


def test_normal_modes_ignore_dampers():
    from bayesupdate.fe import FEModel

    damped = _two_masses()
    b = StructureBuilder()
    n0, n1 = b.add_node((0, 0, 0)), b.add_node((0, 0, 0))
    for n in (n0, n1):
        b.add_point_mass(n, 2.0, "mass", inertia=np.eye(3) * 0.01)
    b.add_spring(n0, None, [1e4] * 6, "mount")
    b.add_spring(n0, n1, [2e4] * 6, "link")
    plain = b.build()
    f = [FEModel(s, {}, {}, {}).solve(n_modes=4, method="dense").frequencies_hz
         for s in (damped, plain)]  # fmt: skip
    np.testing.assert_array_equal(f[0], f[1])


@pytest.mark.parametrize("bad", [[-1.0, 0, 0, 0, 0, 0], [1.0, 2.0], [np.nan] * 6])
def test_bad_damping_is_a_one_line_error(bad):
    b = StructureBuilder()
    n0 = b.add_node((0, 0, 0))
    with pytest.raises(BayesUpdateError, match="damper in part 'd': damping must be 6 values"):
        b.add_damper(n0, None, bad, "d")
