"""Heat transfer (theory 4): reference verification numbers, physics checks and error paths."""

import csv
import math
import json
import pathlib

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from simulator.errors import ParameterError
from simulator.geometry.materials import AIR, Material
from simulator.model.mesh import make_mesh
from simulator.geometry.example_patterns import single_fold_pattern, strip_pattern
from simulator.thermal import ChainLoss
from simulator.thermal import REFERENCE_BETA, ThermalModel, ThermalParameters
from simulator.thermal.steady import heat_weights

DATA = pathlib.Path(__file__).resolve().parents[1] / "data"
FIXED = (0, 3, 5, 6)                      # reference room-temperature nodes 1, 4, 6, 7
CENTRE_LINE = [8, 9, 10]                  # reference nodes 9, 10, 11 (A, B, Ctr)


def _rows(name):
    with open(DATA / name, newline="") as fh:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(fh)]


def strip_model(k, W=0.4, L=1.0, tc=0.001, tp=0.01, L1=1.0, L2=1.0, **params):
    mat = Material("k", youngs_modulus=2e9, thermal_conductivity=k)
    mesh = make_mesh(strip_pattern(W=W, L=L, L1=L1, L2=L2, crease_thickness=tc,
                                     panel_thickness=tp, material=mat))
    prm = ThermalParameters(room_temperature=0.0, room_temperature_nodes=FIXED, **params)
    tm = ThermalModel(mesh, prm)
    return tm, tm.heat_vector([10 * W * L * tc])


def verification01(**geometry):
    return strip_model(1.0, loss=ChainLoss(thickness=1.0, layers=1),
                       medium=AIR.with_properties(thermal_conductivity=0.0), **geometry)


def verification02(W=0.4, L=1.0, beta=REFERENCE_BETA, t_env=3.0, N=10):
    return strip_model(0.3, W=W, L=L, medium=AIR,
                       loss=ChainLoss(thickness=t_env, layers=N, dissipation_angle=beta))


def single_fold(boundary=(2,), **kw):
    mesh = make_mesh(single_fold_pattern())
    prm = ThermalParameters(loss=ChainLoss(thickness=750e-6, dissipation_angle=REFERENCE_BETA),
                            medium=AIR.with_properties(thermal_conductivity=0.6),
                            boundary_panels=boundary, room_temperature_nodes=(0, 3), **kw)
    return mesh, ThermalModel(mesh, prm)


# ---------------------------------------------------------------- reference numbers (theory 10.7)
def test_verification01_full_vector():
    tm, q = verification01()
    T = tm.solve(tm.mesh.nodes, q)
    ref = [0, 0.2, 0.2, 0, 0.2, 0, 0, 0.2, 0.34949494949495, 0.34949494949495,
           0.45050505050505, 0.1, 0.1]
    np.testing.assert_allclose(T, ref, rtol=1e-9, atol=0)
    assert T[CENTRE_LINE].mean() == pytest.approx(0.3831649831649831, rel=1e-12)


def test_verification02_full_vector():
    tm, q = verification02()
    T = tm.solve(tm.mesh.nodes, q)
    ref = [0, 0.02402365018882517, 0.0240236501888252, 0, 0.0240236501888252, 0, 0,
           0.02402365018882519, 0.06174596255237099, 0.06174596255237101, 0.06815471201284226,
           0.003863605381535196, 0.003863605381535197]
    np.testing.assert_allclose(T, ref, rtol=1e-12, atol=0)
    assert tm.n_dof == 143


def _check_row(T, row):
    got = {"T_node9": T[8], "T_node10": T[9], "T_node11": T[10], "T_ave": T[CENTRE_LINE].mean(),
           "T_max": T[10], "T_node_max": T.max()}
    for key, value in got.items():
        assert value == pytest.approx(row[key], rel=1e-9), key


@pytest.mark.parametrize("row", _rows("verification01_within_structure.csv"),
                         ids=lambda r: "W{W}-L{L}-tc{tc}-tp{tp}-L1{L1}-L2{L2}".format(**r))
def test_verification01_sweep(row):
    tm, q = verification01(W=row["W"], L=row["L"], tc=row["tc"], tp=row["tp"], L1=row["L1"],
                           L2=row["L2"])
    assert tm.mesh.n_nodes == row["nodes"]
    _check_row(tm.solve(tm.mesh.nodes, q), row)


@pytest.mark.parametrize("row", _rows("verification02_heat_loss.csv"),
                         ids=lambda r: "W{W}-L{L}-b{beta_deg}-t{t_env}-N{N_layers}".format(**r))
def test_verification02_sweep(row):
    tm, q = verification02(W=row["W"], L=row["L"], beta=row["beta_deg"] / 180 * 3.14,
                           t_env=row["t_env"], N=int(row["N_layers"]))
    assert tm.n_dof == row["thermalDOF"]
    _check_row(tm.solve(tm.mesh.nodes, q), row)


def test_single_fold_first_increment_matches_reference():
    """Increment 1 of Example01 (0.2 mW, flat shape, substrate cap) from single_fold_res0.csv."""
    row = _rows("single_fold_res0.csv")[1]
    mesh, tm = single_fold()
    T = tm.solve(mesh.nodes, tm.heat_vector([row["power_mW"] / 1e3]))
    cn = mesh.crease_nodes[0]
    got = {"T_crease_weighted_C": T[cn] @ np.r_[[1 / 8] * 4, [1 / 6] * 3],
           "T_center_avg_C": T[cn[4:]].mean(), "T_center_max_C": T[cn[4:]].max(),
           "T_side_avg_C": T[cn[:4]].mean(), "T_node_max_C": T.max()}
    for key, value in got.items():
        assert value == pytest.approx(row[key], rel=1e-9), key


# ---------------------------------------------------------------- physics
def _full_solve(tm, x, q, rt):
    """Reference solve on the full (N+1)n system: K_FF T_F = q_F - K_FD T_D (theory 4.5)."""
    K = tm.conductivity_matrix(x).tocsr()
    n, N = tm.mesh.n_nodes, tm.params.loss.layers
    fixed = np.zeros(tm.n_dof, bool)
    fixed[N * n:] = True
    fixed[list(tm.params.room_temperature_nodes)] = True
    qf = np.r_[q, np.zeros(N * n)]
    T = np.full(tm.n_dof, float(rt))
    F = ~fixed
    T[F] = spla.spsolve(K[F][:, F].tocsc(), qf[F] - K[F][:, fixed] @ T[fixed])
    return K, T, qf, fixed


@pytest.mark.parametrize("rt", [0.0, 21.0])
def test_energy_balance_and_full_system(rt):
    tm, q = verification02()
    x = tm.mesh.nodes
    K, T, qf, fixed = _full_solve(tm, x, q, rt)
    np.testing.assert_allclose(tm.solve(x, q, rt), T[:tm.mesh.n_nodes], rtol=1e-12, atol=1e-14)
    outflow = -(K @ T - qf)[fixed]              # heat leaving into the far layer and fixed nodes
    n = tm.mesh.n_nodes
    far, nodes = outflow[-n:].sum(), outflow[:-n].sum()
    assert far > 0 and nodes > 0
    assert far + nodes == pytest.approx(q.sum(), rel=1e-9)
    assert abs(K.sum(axis=1)).max() < 1e-12 * abs(K).max()


def test_condensed_solve_matches_full_system_with_substrate():
    mesh, tm = single_fold()
    x = mesh.nodes.copy()
    x[[4, 5, 6, 7, mesh.panel_center[1]], 2] += 50e-6             # a deformed shape
    q = tm.heat_vector([1e-3])
    T = _full_solve(tm, x, q, 21.0)[1]
    np.testing.assert_allclose(tm.solve(x, q), T[:mesh.n_nodes], rtol=1e-12)


def test_no_heat_gives_room_temperature():
    mesh, tm = single_fold()
    T = tm.solve(mesh.nodes, np.zeros(mesh.n_nodes), room_temperature=35.0)
    np.testing.assert_allclose(T, 35.0, rtol=0, atol=1e-12)


def test_heat_vector_distribution():
    mesh, tm = single_fold()
    q = tm.heat_vector([0.24])
    np.testing.assert_allclose(q[mesh.crease_nodes[0]], 0.24 * heat_weights())
    assert q.sum() == pytest.approx(0.24) and np.count_nonzero(q) == 7


def test_rigid_motion_does_not_change_temperatures():
    tm, q = verification02()
    c, s = math.cos(0.7), math.sin(0.7)
    R = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]) @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    x = tm.mesh.nodes @ R.T + [1.0, -2.0, 3.0]
    np.testing.assert_allclose(tm.solve(x, q), tm.solve(tm.mesh.nodes, q), rtol=1e-12)


def test_tcap_values():
    mesh, tm = single_fold()
    cap = tm.environment.tcap(mesh.nodes)
    anchor = mesh.triangle_panel == 0
    np.testing.assert_allclose(cap[anchor], 150e-6, rtol=1e-12)      # anchor lies 150 um above
    assert np.all(cap[mesh.triangle_panel == 2] == 1e10)
    assert np.all(single_fold(boundary=())[1].environment.tcap(mesh.nodes) == 1e5)


def test_substrate_cap_lowers_crease_temperature():
    mesh, with_cap = single_fold((2,))
    without = single_fold(())[1]
    q = with_cap.heat_vector([1e-3])
    ctr = mesh.crease_nodes[0, 6]
    assert with_cap.solve(mesh.nodes, q)[ctr] < without.solve(mesh.nodes, q)[ctr] - 0.1


def test_folding_away_from_substrate_raises_crease_temperature():
    mesh, tm = single_fold()
    q = tm.heat_vector([1e-3])
    free = np.r_[4, 5, 6, 7, mesh.panel_center[1]]
    hinge_x = mesh.nodes[4, 0]
    temps = []
    for angle in (0.0, 0.3, 0.6):
        x = mesh.nodes.copy()
        dx = x[free, 0] - hinge_x
        x[free, 0] = hinge_x + dx * math.cos(angle)
        x[free, 2] += dx * math.sin(angle)
        temps.append(tm.solve(x, q)[mesh.crease_nodes[0, 6]])
    assert temps[0] < temps[1] < temps[2]


def test_uniform_strip_has_linear_profile():
    """Heat Q on the x = 0 edge, far edge at room temperature, no environment: 1-D conduction,
    T = Q (x_end - x) / (k t L), which the T3 mesh reproduces exactly (patch test)."""
    k, t, L, W, L1, L2, Q = 0.7, 0.02, 0.5, 0.3, 1.2, 0.8, 2.0
    mat = Material("k", youngs_modulus=2e9, thermal_conductivity=k)
    mesh = make_mesh(strip_pattern(W=W, L=L, L1=L1, L2=L2, crease_thickness=t,
                                    panel_thickness=t, material=mat))
    tm = ThermalModel(mesh, ThermalParameters(
        loss=ChainLoss(thickness=1.0, layers=3),
        medium=AIR.with_properties(thermal_conductivity=0.0), room_temperature=0.0,
        room_temperature_nodes=(5, 6)))
    q = np.zeros(mesh.n_nodes)
    q[[0, 3]] = Q / 2
    T = tm.solve(mesh.nodes, q)
    x_end = L1 + L2 + W
    np.testing.assert_allclose(T, Q * (x_end - mesh.nodes[:, 0]) / (k * t * L), rtol=1e-10,
                               atol=1e-12)


# ---------------------------------------------------------------- errors
@pytest.mark.parametrize("field, value", [
    ("thickness", 0.0), ("thickness", -1.0), ("thickness", math.nan), ("layers", 0),
    ("layers", 2.5), ("dissipation_angle", -0.1), ("dissipation_angle", math.pi / 2)])
def test_bad_chain_parameters(field, value):
    kw = {"thickness": 1e-3, field: value}
    with pytest.raises(ParameterError, match=f"ChainLoss.{field}"):
        ThermalParameters(loss=ChainLoss(**kw))


@pytest.mark.parametrize("field, value", [
    ("room_temperature", math.inf), ("boundary_panels", ("a",)), ("boundary_panels", (1.5,)),
    ("room_temperature_nodes", 3)])
def test_bad_parameters(field, value):
    with pytest.raises(ParameterError, match=f"ThermalParameters.{field}"):
        ThermalParameters(loss=ChainLoss(thickness=1e-3), **{field: value})


def test_bad_medium():
    with pytest.raises(ParameterError, match="thermal_conductivity = -0.1"):
        ThermalParameters(loss=ChainLoss(thickness=1e-3),
                          medium=AIR.with_properties(thermal_conductivity=-0.1))


def test_parameters_normalised_and_serialisable():
    prm = ThermalParameters(loss=ChainLoss(thickness=1e-3), boundary_panels=[2],
                            room_temperature_nodes=np.array([0, 3]))
    assert prm.boundary_panels == (2,) and prm.room_temperature_nodes == (0, 3)
    d = prm.to_dict()
    assert d["loss"] == {"model": "chain", "thickness": 1e-3, "layers": 10,
                         "dissipation_angle": math.radians(20)}
    assert d["medium"]["thermal_conductivity"] == 0.026 and d["substrate"] == "boundary_panels"
    assert ThermalParameters(**d) == prm                     # read back (FOLD model files)
    assert json.loads(json.dumps(d)) == d


def test_unknown_ids():
    mesh = make_mesh(single_fold_pattern())
    with pytest.raises(ParameterError, match="panel 7"):
        ThermalModel(mesh, ThermalParameters(loss=ChainLoss(thickness=1e-3), boundary_panels=(7,)))
    with pytest.raises(ParameterError, match="node 99"):
        ThermalModel(mesh, ThermalParameters(loss=ChainLoss(thickness=1e-3),
                                             room_temperature_nodes=(99,)))


def test_no_path_to_room_temperature():
    mesh = make_mesh(single_fold_pattern())        # substrate is a separate, unfixed part
    with pytest.raises(ParameterError, match="no heat path"):
        ThermalModel(mesh, ThermalParameters(
            loss=ChainLoss(thickness=1e-3), medium=AIR.with_properties(thermal_conductivity=0.0),
            room_temperature_nodes=(0,)))


def test_bad_inputs_to_methods():
    mesh, tm = single_fold()
    with pytest.raises(ParameterError, match="crease_power"):
        tm.heat_vector([1.0, 2.0])
    with pytest.raises(ParameterError, match="shape"):
        tm.solve(mesh.nodes, np.zeros(3))
    with pytest.raises(ParameterError, match="positions"):
        tm.solve(mesh.nodes[:4], np.zeros(mesh.n_nodes))
