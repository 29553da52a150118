"""Bad FE input through the public builder and ``FEModel``: each error names the
node or element, each number in the message is checked against the input that caused it.

- a node used by no element;
- an element with repeated nodes or zero area;
- a warped quad beyond the stated limit ``WARP_LIMIT`` (a warning, with the measured warp);
- a rigid element whose dependent DOF is also fixed or dependent elsewhere;
- a negative or zero thickness (on the element and as a parameter value);
- a mechanism (more zero modes than the supports allow), reported with the DOFs involved, and
  its counterpart: a zero mode the supports do allow (a plate on a hinge line) is a rigid mode.
"""

import re
import warnings

import numpy as np
import pytest

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe import Binding, FEModel, Material, StructureBuilder
from bayesupdate.fe import shell_mesh as sm
from bayesupdate.fe.shell_model import WARP_LIMIT, ShellMeshWarning

AL = Material(70e9, 0.33, 2700.0, "aluminium")


def _plate_builder(n=4, **kw):
    nodes, quads, _ = sm.plate(1.0, 1.0, n, n)
    b = StructureBuilder()
    ids = b.add_shells(nodes, quads, thickness=kw.pop("thickness", 2e-3), material=AL,
                       part="plate", **kw)  # fmt: skip
    return b, ids, nodes


def test_node_used_by_no_element_is_named():
    b, ids, _ = _plate_builder()
    lonely = b.add_node((3.0, 3.0, 0.0))
    assert lonely == 25
    with pytest.raises(BayesUpdateError, match=r"^node 25 is used by no element"):
        b.build()


def test_repeated_nodes_and_zero_area_name_the_element():
    nodes, quads, _ = sm.plate(1.0, 1.0, 2, 2)
    trias = sm.split_quads(quads)  # 8 triangles
    bad = trias.copy()
    bad[5, 2] = bad[5, 0]
    with pytest.raises(
        BayesUpdateError, match=re.escape(f"tria 5 repeats a node ({bad[5].tolist()})")
    ):
        StructureBuilder().add_shells(nodes, None, bad, thickness=1e-3, material=AL, part="p")
    flat = np.vstack([nodes, [[0.25, 0.0, 0.0]]])  # on the edge between nodes 0 and 3
    sliver = np.vstack([trias, [[0, 3, 9]]])  # collinear: zero area, element 8
    with pytest.raises(BayesUpdateError, match=r"part 'p'.*tria 8 has zero area.*\[0, 3, 9\]"):
        StructureBuilder().add_shells(flat, None, sliver, thickness=1e-3, material=AL, part="p")
    squashed = nodes.copy()
    squashed[[2, 5, 8]] = squashed[[1, 4, 7]]  # the top row of nodes onto the middle row
    with pytest.raises(BayesUpdateError, match=r"quad 1 has zero area.*\(nodes \[1, 4, 5, 2\]\)"):
        StructureBuilder().add_shells(squashed, quads, thickness=1e-3, material=AL, part="p")


def _twisted_quad(warp):
    """One unit square with node 2 lifted by h: the four nodes lie +-h/4 off the mean plane and
    the mean diagonal is sqrt(2), so the warp measure is h / (4 sqrt(2))."""
    nodes = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 4 * np.sqrt(2) * warp], [0, 1, 0]], float)
    return nodes, np.array([[0, 1, 2, 3]])


def test_warped_quad_warns_beyond_the_stated_limit_only():
    assert WARP_LIMIT == 0.01
    for warp, expect in ((0.9 * WARP_LIMIT, False), (1.1 * WARP_LIMIT, True)):
        nodes, quad = _twisted_quad(warp)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            StructureBuilder().add_shells(nodes, quad, thickness=1e-3, material=AL, part="p")
        found = [w for w in caught if issubclass(w.category, ShellMeshWarning)]
        assert bool(found) == expect
        if expect:
            assert f"quad 0 (warp {warp:.3g})" in str(found[0].message)
            assert f"beyond {WARP_LIMIT:g}" in str(found[0].message)
    nodes, quad = _twisted_quad(0.02)  # a stated, looser limit silences it
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        StructureBuilder().add_shells(nodes, quad, thickness=1e-3, material=AL, part="p",
                                      warp_limit=0.03)  # fmt: skip


def test_rigid_element_dependent_dof_fixed_or_dependent_twice_is_named():
    b, ids, _ = _plate_builder()
    ref = b.add_node((0.5, 0.5, 0.2))
    b.add_rbe3(ref, ids[[0, 4, 20, 24]])
    b.add_support(ref, "3")
    with pytest.raises(
        BayesUpdateError, match=r"rbe3 0: its dependent DOF node 25 uz is also fixed"
    ):
        FEModel(b.build(), {}, {}, {})
    b, ids, _ = _plate_builder()
    b.add_rbe2(ids[0], [ids[6]], "3")
    b.add_rbe2(ids[12], [ids[6]], "36")
    with pytest.raises(
        BayesUpdateError, match=r"node 6 uz is a dependent DOF of both rbe2 0 and rbe2 1"
    ):
        FEModel(b.build(), {}, {}, {})


@pytest.mark.parametrize("t", [0.0, -1e-3])
def test_zero_or_negative_thickness_is_named(t):
    thickness = np.full(16, 2e-3)
    thickness[11] = t
    with pytest.raises(
        BayesUpdateError, match=rf"part 'plate'.*quad 11 has thickness = {t}; it must be > 0"
    ):
        _plate_builder(thickness=thickness)
    b, _, _ = _plate_builder()
    model = FEModel(
        b.build(), {"t": Binding("plate", "thickness")}, {"t": 2e-3}, {"t": (1e-3, 3e-3)}
    )
    with pytest.raises(
        BayesUpdateError, match=rf"parameter t = {t}: thickness must be finite and > 0"
    ):
        model.solve({"t": t})


def _two_plates(hinge_nodes, components="123"):
    """Plate A clamped on x = 0; plate B beside it (x in [1.25, 2.25]) tied to A's free edge by
    RBE2s with ``components`` at ``hinge_nodes`` of that edge (translations only: B can swing
    about the line through them)."""
    b, ids, nodes = _plate_builder()
    for n in ids[nodes[:, 0] == 0.0]:
        b.add_support(n)
    ids_b = b.add_shells(nodes + [1.25, 0, 0], sm.plate(1.0, 1.0, 4, 4)[1], thickness=2e-3,
                         material=AL, part="flap")  # fmt: skip
    edge_a, edge_b = ids[nodes[:, 0] == 1.0], ids_b[nodes[:, 0] == 0.0]
    for k in hinge_nodes:
        b.add_rbe2(edge_a[k], [edge_b[k]], components)
    return b.build(), ids_b


def test_mechanism_is_reported_with_the_moving_dofs():
    structure, flap = _two_plates([1, 3])  # two pins on one line: one free rotation
    with pytest.raises(BayesUpdateError, match=r"mechanism: 1 zero-energy mode\(s\)") as err:
        FEModel(structure, {}, {}, {}).solve(n_modes=4)
    moving = [int(n) for n in re.findall(r"node (\d+)", str(err.value).split("moves")[1])]
    assert moving and set(moving) <= set(flap.tolist())  # only the flap's DOFs are named
    tied, _ = _two_plates([2], "123456")  # one node tied in all six components: no mechanism
    r = FEModel(tied, {}, {}, {}).solve(n_modes=4)
    assert r.modes.n_rigid == 0 and r.frequencies_hz[0] > 0.1


def test_zero_mode_that_the_supports_allow_is_a_rigid_mode_not_a_mechanism():
    """A plate pinned ('123') along one edge turns freely about it: the supports allow that
    rigid rotation, so it is the one rigid-body mode, with an eigenvalue at round-off (its
    frequency measured at 6e-6 of the first elastic one)."""
    b, ids, nodes = _plate_builder()
    for n in ids[nodes[:, 1] == 0.0]:
        b.add_support(n, "123")
    r = FEModel(b.build(), {}, {}, {}).solve(n_modes=4)
    assert r.modes.n_rigid == 1
    assert r.modes.rigid_frequencies_hz[0] < 1e-4 * r.frequencies_hz[0]  # round-off: 6e-6
