"""Bad test geometry input: one ``BayesUpdateError`` line each, naming the node, point or
setting at fault (``bayesupdate.testgeom`` and the study file's ``[test]`` table)."""

import numpy as np
import pytest

from bayesupdate.config import parse_study
from bayesupdate.errors import BayesUpdateError
from bayesupdate.testgeom import (
    ModelMesh,
    PairingSettings,
    from_matrix,
    icp,
    make_geometry,
    pair_test,
    read_geometry,
    resolve_dofs,
)
from bayesupdate.testgeom.align import IcpSettings
from bayesupdate.testgeom.units import length_unit


def _raises(match, call, *args, **kwargs):
    with pytest.raises(BayesUpdateError, match=match) as info:
        call(*args, **kwargs)
    assert "\n" not in str(info.value)
    return str(info.value)


def _mesh():
    nodes = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.2], [0.5, 0.5, 1.0]], float)
    none = np.zeros((0, 2), int)
    return ModelMesh(nodes, np.arange(1, 6), none, np.zeros((0, 4), int), np.zeros((0, 3), int),
                     "m", 1.0)  # fmt: skip


def test_a_dof_on_a_node_the_geometry_lacks():
    g = make_geometry([1, 2], [[0, 0, 0], [1, 0, 0]], source="test.unv")
    message = _raises("node 7 is not in test.unv", resolve_dofs, g, ["1V", "7V"])
    assert "test DOF '7V'" in message


def test_a_node_given_twice(tmp_path):
    path = tmp_path / "twice.csv"
    path.write_text("node,x,y,z\n1,0,0,0\n2,1,0,0\n1,0,1,0\n")
    _raises("node 1 appears twice", read_geometry, path)


def test_a_geometry_file_that_is_not_text(tmp_path):
    """A binary file given as the test geometry: one line naming it (was an internal
    UnicodeDecodeError)."""
    path = tmp_path / "bin.csv"
    path.write_bytes(b"\xff\xfe\x00bin")
    _raises(
        "bin.csv: not a text CSV file .* export the test geometry as UTF-8", read_geometry, path
    )


def test_a_point_beyond_the_tolerance_is_named_with_its_distance():
    mesh = _mesh()
    g = make_geometry([1, 2, 3], [[0, 0, 0.001], [1, 0, 0], [0.5, 0.5, 0.3]])
    dofs = resolve_dofs(g, ["1V", "2V", "3V"])
    settings = PairingSettings(align="none", tolerance=0.01, on_elements=False)
    # point 3 is 0.7 m below node 5 (0.5, 0.5, 1.0), sqrt(0.51) = 0.714 m from node 4
    message = _raises("test point 3 is 0.7 m", pair_test, g, dofs, mesh, settings)
    assert "(700 mm)" in message and "pair_tolerance 10 mm" in message


def test_too_few_pairs_a_scaled_fit_a_sheared_matrix_and_no_convergence():
    mesh = _mesh()
    g = make_geometry([1, 2, 3, 4], mesh.nodes[:4] * 1.05)
    dofs = resolve_dofs(g, ["1V", "2V", "3V", "4V"])
    two = PairingSettings(pairs=((1, 1), (2, 2)))
    _raises("2 node pairs; an alignment needs at least three", pair_test, g, dofs, mesh, two)
    four = PairingSettings(pairs=((1, 1), (2, 2), (3, 3), (4, 4)))
    _raises("scales the test by 0.9524 ", pair_test, g, dofs, mesh, four)  # 1 / 1.05
    shear = np.hstack([np.eye(3) + [[0, 0.02, 0], [0, 0, 0], [0, 0, 0]], np.zeros((3, 1))])
    _raises("not a rotation within 1 %", from_matrix, shear, False)
    _raises("did not converge", icp, mesh.nodes[:4], mesh.nodes, False,
            IcpSettings(max_iterations=1))  # fmt: skip


def test_pairs_no_rigid_transform_relates():
    mesh = _mesh()
    moved = mesh.nodes[:4].copy()
    moved[3] += [0.0, 0.0, 0.05]  # one pair 50 mm off: not a rigid picture of the rest
    g = make_geometry([1, 2, 3, 4], moved)
    dofs = resolve_dofs(g, ["1V"])
    settings = PairingSettings(pairs=((1, 1), (2, 2), (3, 3), (4, 4)))
    _raises("not a rigid transform", pair_test, g, dofs, mesh, settings)


def test_a_direction_code_outside_three_and_a_zero_vector(tmp_path):
    g = make_geometry([7], [[0, 0, 0]])
    _raises("direction code \\+4 is outside", resolve_dofs, g, ["7+4"])
    _raises("direction code -0 is outside", resolve_dofs, g, ["7-0"])
    path = tmp_path / "zero.csv"
    path.write_text("node,x,y,z\n7,0,0,0\ndof,7S,7,0,0,0\n")
    _raises("DOF '7S': direction vector \\[0.0, 0.0, 0.0\\] is zero", read_geometry, path)


def test_a_length_unit_that_does_not_parse():
    _raises("length_unit = 'furlong': unknown length unit", length_unit, "furlong")
    study = {"test": {"geometry": "t.csv", "length_unit": "parsec"}}
    _raises("test.length_unit = 'parsec'", parse_study, study)
    study = {"test": {"geometry": "t.csv", "pair_tolerance": "5 leagues"}}
    _raises("test.pair_tolerance = '5 leagues'", parse_study, study)


def test_study_test_table_keys_and_values():
    _raises("test.geometry: give", parse_study, {"test": {"align": "auto"}})
    _raises("test.scal: unknown key", parse_study, {"test": {"geometry": "g.unv", "scal": 1}})
    _raises("test.align = 'best'", parse_study, {"test": {"geometry": "g.unv", "align": "best"}})
    _raises("3x4 matrix", parse_study, {"test": {"geometry": "g.unv", "align": [[1, 0, 0]]}})
    _raises("test.pairs: give", parse_study, {"test": {"geometry": "g.unv", "pairs": [[1]]}})
    both = {"model": {"source": "deck.bdf", "test_points": {"1": 11}},
            "test": {"geometry": "g.unv"}}  # fmt: skip
    _raises("not both", parse_study, both)
    to_fe = [[0, 1, 0, -15.55], [-1, 0, 0, 0], [0, 0, 1, 0]]
    ok = parse_study({"test": {"geometry": "g.unv", "pair_tolerance": "0.2 in", "align": to_fe}})
    assert abs(ok.test.pair_tolerance - 0.00508) < 1e-15
    assert ok.test.align[0] == (0.0, 1.0, 0.0, -15.55)
    assert ok.to_dict()["test"]["geometry"] == "g.unv"
