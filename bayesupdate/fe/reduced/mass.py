"""The total mass of a general structure (shells) without assembling K and M.

The total mass is the linear functional m(M) = (1/3) sum_{i=x,y,z} r_i^T M r_i of the mass
matrix, r_i the rigid translations (``GeneralAssembler.total_mass``).  M is an exact affine sum
(``reduced.shell_terms``): per shell group g with density rho_g and thickness parameter theta_g,
M_g = M_nsm + rho_g sum_p theta_g^p M_p, so

    m(theta) = m_beams(theta) + sum_g [m(M_nsm,g) + rho_g sum_p theta_g^p m(M_p,g)],

the scalars m(.) computed once.  Every registered element family keeps its own exact formula
(``Assembler.total_mass``, a loop over the families: a parametric family's ``masses`` such as
rho A(t) L of a tube beam, the other families' rigid-body mass), equal to the functional of its
assembled M: a rigid translation carries an element's mass alone.  One evaluation is a few
array operations on the shells' property arrays instead of an assembly of the full K and M.
"""

import weakref
from dataclasses import dataclass

import numpy as np

from bayesupdate.fe.assembly import check_properties
from bayesupdate.fe.mass_properties import RigidMassTerms
from bayesupdate.fe.model import FEModel


def _translational_mass(g, pos: np.ndarray, values: np.ndarray) -> float:
    """m(X) of the matrix with ``values`` on the general CSR positions ``pos``: the entries
    coupling the same translation direction of two nodes (DOF index mod 6 < 3, equal)."""
    rows, cols = g.rows[pos] % 6, g.cols[pos] % 6
    same = (rows == cols) & (rows < 3)
    return float(values[same].sum() / 3.0)


@dataclass(frozen=True, eq=False)
class ShellMassTerms:
    """Per shell group: ``nsm`` m(M_nsm,g) (n_groups,) and ``powers`` {p: m(M_p,g) (n_groups,)}
    [kg per unit density and theta^p]; ``line_terms`` ((name, theta0, m(dM)), ...) of a deck's
    linear line-element parameters
    (``NastranModel.line_terms``).  Holds no reference to its FE model (it is the value of a
    weak-keyed cache on that model)."""

    nsm: np.ndarray
    powers: dict
    line_terms: tuple = ()

    @classmethod
    def of(cls, fe: FEModel) -> "ShellMassTerms":
        g = fe.general
        nsm, powers = [], {}
        if fe.structure.shells is not None:
            for k, (pos, _, m0, Mp) in enumerate(g.terms):
                nsm.append(_translational_mass(g, pos, m0))
                for p, v in Mp.items():
                    powers.setdefault(p, np.zeros(len(g.terms)))[k] = _translational_mass(g, pos, v)
        line_terms = tuple(
            (t.name, t.theta0, _translational_mass(g, np.arange(g.nnz), t.dM))
            for t in getattr(fe, "line_terms", tuple)()
        )
        return cls(np.array(nsm), powers, line_terms)

    def total_mass(self, fe: FEModel, params) -> float:
        """Total mass [kg] of ``fe`` (the model these terms are of) at ``params`` (name -> SI
        value), the values validated as ``FEModel.total_mass`` validates them."""
        g = fe.general
        props = fe.element_properties(params)
        check_properties(fe.structure, props)
        with np.errstate(invalid="ignore", divide="ignore"):  # its CoG is 0/0 without beams
            m = g.beams.total_mass(props)[0]
        for name, theta0, dm in self.line_terms:
            m += (params[name] - theta0) * dm
        # a deck's line-element fields that do not enter linearly (``NastranModel``)
        m += getattr(fe, "line_mass_change", lambda _: 0.0)(params)
        if fe.structure.shells is None:
            return m
        t, _, rho = fe.shell_properties(params)
        rep = g.group_rep
        theta, rho_g = t[rep] / g.group_scale, rho[rep]
        shells = sum(theta**p * v for p, v in self.powers.items())
        return m + float(np.sum(self.nsm + rho_g * shells))


_TERMS: "weakref.WeakKeyDictionary[FEModel, ShellMassTerms]" = weakref.WeakKeyDictionary()


def total_mass(fe: FEModel, params) -> float:
    """Total mass [kg] of ``fe`` at ``params`` (name -> SI value, all names): ``FEModel.total_mass``
    on the banded beam path (no assembly there), the per-term masses on a general structure,
    computed once per FE model (the reduced models of one FE model share them).  A deck's line
    fields that do not enter linearly would convert their elements again at each call
    (``line_mass_change``); where the model's rigid-body mass matrix is a certified 6 x 6 sum
    (``fe.mass_properties.rigid_mass_terms``), the mass is trace(M_r[:3, :3]) / 3 of that sum
    (the same functional of the same M, in the model's mass unit, WTMASS included)."""
    if fe.general is None:
        return fe.total_mass(params)[0]
    rigid = _rigid_terms(fe)
    if rigid is not None:
        check_properties(fe.structure, fe.element_properties(params))
        return float(np.trace(rigid.rigid_mass(params)[:3, :3]) / 3.0)
    terms = _TERMS.get(fe)
    if terms is None:
        terms = _TERMS[fe] = ShellMassTerms.of(fe)
    return terms.total_mass(fe, params)


def _rigid_terms(fe: FEModel) -> RigidMassTerms | None:
    """The FE model's ``RigidMassTerms`` where its line fields need ``line_mass_change`` and the
    terms hold (built once, kept by the model: ``FEModel.mass_properties_function``), else None
    (the per-term masses are cheaper)."""
    if not getattr(fe, "line_nonlinear", ""):
        return None
    rigid = fe.mass_properties_function()
    return rigid if isinstance(rigid, RigidMassTerms) else None
