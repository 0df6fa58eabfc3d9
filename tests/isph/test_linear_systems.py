"""The PPE solver a user names is resolved in one place (``linear_systems.ppe_solver_name``), and the
form the adjoint-pair PPE reaches it in follows from that name."""
from types import SimpleNamespace

import pytest

from granudep.isph.linear_systems import LinearSystems, ppe_solver_name


def _n(solver, projection="adjoint_pair", operator="assembled"):
    return SimpleNamespace(pressure_solver=solver, projection=projection, ppe_operator=operator)


@pytest.mark.parametrize("solver, projection, runs", [("cg_dic", "adjoint_pair", "cg_ssor"),
                                                      ("cg_dic", "approximate", "cg_dic"),
                                                      ("cg_ssor", "adjoint_pair", "cg_ssor"),
                                                      ("cg_two_level", "adjoint_pair", "cg_two_level"),
                                                      ("direct", "adjoint_pair", "direct"),
                                                      ("amg_sa", "approximate", "amg_sa")])
def test_the_solver_that_runs(solver, projection, runs):
    assert ppe_solver_name(_n(solver, projection)) == runs


@pytest.mark.parametrize("solver, operator, form", [("cg_dic", "assembled", "triangles"),
                                                    ("cg_ssor", "matrix_free", "triangles"),
                                                    ("cg_two_level", "matrix_free", "free"),
                                                    ("cg_two_level", "assembled", "csr"),
                                                    ("cg", "assembled", "csr")])
def test_the_adjoint_pair_form_follows_the_solver(solver, operator, form):
    owner = SimpleNamespace(cfg=SimpleNamespace(numerics=_n(solver, operator=operator)))
    assert LinearSystems(owner).ppe_form == form
