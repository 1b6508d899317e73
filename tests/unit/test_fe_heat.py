"""The FE reference of heat transfer (simulator.thermal.fe), coarse levels (CI): analytic
sphere and disk, mesh and box convergence, a 1-D fin, warnings and errors, and the strip
against the chain model (numbers reported, agreement only sensible)."""

import functools
import logging
import math

import numpy as np
import pytest

pytest.importorskip("skfem")
pytest.importorskip("gmsh")

from simulator.errors import ParameterError  # noqa: E402
from simulator.thermal.fe import fe_disk, fe_sphere, solve_fe2d, solve_fe3d  # noqa: E402


@functools.lru_cache(maxsize=None)
def _disk(level, box_factor=4.0, far_field="robin", height=None):
    """Q / (8 k a) of the unit disk (k = 1), computed once per setting."""
    return fe_disk(1.0, 1.0, height, level=level, box_factor=box_factor,
                   far_field=far_field).conductance / 8


@pytest.mark.parametrize("far_field, exact", [("robin", 4 * math.pi),
                                              ("dirichlet", 4 * math.pi / (1 - 1 / 4))])
def test_sphere_is_exact_to_the_faceting_and_converges(far_field, exact):
    """1-D check: Q = 4 pi k a (free space, the Robin far field is exact for a monopole) or
    4 pi k / (1/a - 1/R) in a ball at room temperature; the error (faceting of the sphere)
    falls with the level."""
    err = [abs(fe_sphere(1.0, 1.0, level=lv, far_field=far_field).conductance / exact - 1)
           for lv in (0, 1)]
    assert err[0] < 0.015 and err[1] < err[0]


def test_disk_conducts_8ka_within_2_percent():
    r = fe_disk(2e-3, 0.026, level=0, accuracy=0.03)
    assert r.success and r.status == "converged"
    assert r.conductance == pytest.approx(8 * 0.026 * 2e-3, rel=0.02)
    assert r.free_space_ratio > 1.0           # the Dirichlet principle: the FE bounds from above
    assert r.free_space_ratio == pytest.approx(_disk(0), rel=1e-6)    # scale-free


def test_disk_mesh_convergence_is_monotone():
    q = [_disk(lv) for lv in (0, 1)]
    assert q[0] > q[1] > 1.0 and q[1] - 1 < 0.6 * (q[0] - 1)


def test_disk_box_convergence_is_monotone_and_robin_beats_dirichlet():
    d = [_disk(0, b, "dirichlet") for b in (3.0, 6.0)]
    assert d[0] > d[1] > _disk(0, 3.0) > 1.0
    assert d[0] - _disk(0, 3.0) == pytest.approx(0.7 / 3, rel=0.3)   # monopole's Q/(4 pi k R)


def test_disk_near_a_plane_conducts_more():
    assert _disk(0, height=0.5) > 1.5 * _disk(0)


def test_fin_in_2d_without_medium_is_the_1d_solution():
    """A uniformly heated line held at both ends, medium negligible: T = q L / (8 k t)."""
    r = solve_fe2d([0.4, 0.2, 0.4], [2.0, 2.0, 2.0], [0.4, 0.2, 0.4], 1e-9,
                   room_temperature=0.0, level=0)
    assert r.success
    assert r.segment_temperature[1] == pytest.approx(1.0 * 1.0 / (8 * 2.0), rel=1e-6)


def test_2d_section_is_hotter_with_a_larger_box():
    t = [solve_fe2d([1.0, 0.4, 1.0], [0.003, 3e-4, 0.003], [0.0, 0.004, 0.0], 0.026,
                    box_factor=b, level=0).segment_temperature[1] for b in (3.0, 6.0)]
    assert t[1] > t[0] > 21.0


def test_coarse_mesh_for_the_stated_accuracy_warns(caplog):
    with caplog.at_level(logging.WARNING, logger="simulator.thermal.fe"):
        r = fe_disk(1.0, 1.0, level=0, accuracy=0.005)
    assert r.success and r.status == "accuracy_warning" and "accuracy" in r.message and r.warnings
    assert any("refine the mesh" in m for m in caplog.messages)


def test_a_box_too_small_for_the_stated_accuracy_warns(caplog):
    """A fine mesh does not make up for a small box: level 2 (0.3 %) in a Dirichlet box of
    factor 3 (its monopole error 27 %), or a Robin box of 1.6 (3 %), warns before meshing."""
    from simulator.thermal.fe.accuracy import accuracy_warnings, estimated_error

    assert estimated_error(2, 8.0, "robin") < 0.005 < estimated_error(2, 1.6, "robin")
    with caplog.at_level(logging.WARNING, logger="simulator.thermal.fe"):
        for box, far in ((3.0, "dirichlet"), (1.6, "robin")):
            err, warns = accuracy_warnings(2, box, far, 0.02, "fe_disk")
            assert err > 0.02 and len(warns) == 1 and "enlarge the box" in warns[0]
        assert accuracy_warnings(2, 8.0, "robin", 0.02, "fe_disk")[1] == ()
    assert sum("box_factor" in m for m in caplog.messages) == 2


@pytest.mark.parametrize("kw, match", [(dict(level=7), "level"),
                                       (dict(box_factor=1.2), "box_factor"),
                                       (dict(far_field="neumann"), "far_field")])
def test_bad_input_names_the_field(kw, match):
    with pytest.raises(ParameterError, match=match):
        fe_disk(1.0, 1.0, **kw)


def test_strip_against_the_chain_model():
    """The SU-8 strip in air, W/L = 0.4: FE and chain agree within tens of percent (the chain
    model's error is what the study reports; it is not asserted here)."""
    from studies.heat_loss_calibration import crease_temperatures, strip_case

    case = strip_case(0.4, 20.0, 1.5, 10, 0.3, 0.026)
    chain = crease_temperatures(case)
    r = solve_fe3d(case.model, [10 * 0.4 * 1.0 * 0.001], level=0, accuracy=0.05)
    assert r.success and r.mesh.n_dofs > 1000
    fe = (r.crease_t_ctr[0], r.crease_t_ave[0])
    print(f"strip W/L 0.4 SU-8/air: chain T_max {chain[0]:.4g} T_ave {chain[1]:.4g}; "
          f"FE {fe[0]:.4g} {fe[1]:.4g}")
    assert 0.7 < chain[0] / fe[0] < 1.3 and 0.7 < chain[1] / fe[1] < 1.3
    assert r.crease_temperature_max[0] >= r.crease_t_ctr[0] >= r.crease_t_ave[0] > 0


def test_held_nodes_stay_at_room_temperature_and_power_scales_linearly():
    from studies.heat_loss_calibration import strip_case

    case = strip_case(0.4, 20.0, 1.5, 10, 315.0, 0.026)
    r1, r2 = (solve_fe3d(case.model, [p], level=0, accuracy=0.05, room_temperature=0.0)
              for p in (1e-3, 2e-3))
    held = list(case.model.thermal.room_temperature_nodes)
    assert np.all(r1.temperature[held] == 0.0)
    np.testing.assert_allclose(r2.temperature, 2 * r1.temperature, rtol=1e-8, atol=1e-14)


def test_double_fold_over_its_substrate_plane():
    """The flat double fold over its substrate (boundary panel 3 gives the plane): the
    substrate nodes lie on the plane at room temperature and fold 2, farther from the
    anchor, runs hotter than fold 1."""
    from simulator import get_case

    model = get_case("double_fold").model
    r = solve_fe3d(model, [10e-3, 10e-3], level=0)          # crease rows: pattern edges 2, 5
    assert r.success
    sub = np.unique(model.mesh.triangles[model.mesh.triangle_panel == 3])
    assert np.all(r.temperature[sub] == r.room_temperature)
    assert r.crease_temperature[1] > r.crease_temperature[0] > r.room_temperature + 10


def test_structure_below_the_substrate_is_refused():
    from simulator import get_case

    model = get_case("double_fold").model
    x = model.mesh.nodes.copy()
    x[4, 2] = -1e-3
    with pytest.raises(ParameterError, match="below the substrate"):
        solve_fe3d(model, np.full(model.mesh.n_creases, 1e-3), positions=x, level=0)
    with pytest.raises(ParameterError, match="substrate"):
        solve_fe3d(model, np.full(model.mesh.n_creases, 1e-3), substrate="floor")


def test_nodal_heat_equals_the_crease_power_it_comes_from():
    from simulator.thermal import ThermalModel
    from studies.heat_loss_calibration import strip_case

    model = strip_case(0.4, 20.0, 1.5, 10, 150.0, 0.6).model
    q = ThermalModel(model.mesh, model.thermal).heat_vector([4e-3])
    a = solve_fe3d(model, [4e-3], level=0)
    b = solve_fe3d(model, heat=q, level=0)
    np.testing.assert_allclose(a.temperature, b.temperature, rtol=1e-10)
    assert a.heat_input == pytest.approx(4e-3)
    with pytest.raises(ParameterError, match="not both"):
        solve_fe3d(model, [4e-3], heat=q)
