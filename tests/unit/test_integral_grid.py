"""The integral heat loss's far field on a grid (simulator.thermal.integral_grid, theory 4.7):
the Ewald split of 1/r against the direct sum, its compiled pair kernel against numpy, and the
fast path with it against the dense operator."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simulator.model import get_stack, stack_model
from simulator.geometry.example_patterns import miura_sheet_pattern
from simulator.model.mesh import make_mesh
from simulator.thermal import integral_fast
from simulator.thermal._single_layer import mirror
from simulator.thermal.integral import IntegralOperator
from simulator.thermal.integral_grid import GridFarField, grid_pairs, smooth_kernel
from simulator.thermal import IntegralLoss, Substrate
from simulator.thermal import ThermalModel

PLANE = (np.array([0.0, 0.0, -3e-4]), np.array([0.0, 0.0, 1.0]))


def _centroids(cells=6):
    """Sub-triangle centroids and areas (m = 1) of a Miura sheet bent out of plane."""
    mesh = make_mesh(miura_sheet_pattern(m=cells, n=cells))
    x = mesh.nodes.copy()
    x[:, 2] += 2e-4 * np.sin(x[:, 0] / 3e-3) * np.cos(x[:, 1] / 4e-3)
    sub = IntegralOperator(mesh.triangles, mesh.n_nodes, 0.026, 1).sub_triangles(x)
    area = 0.5 * np.linalg.norm(np.cross(sub[:, 1] - sub[:, 0], sub[:, 2] - sub[:, 0]), axis=1)
    return sub.mean(axis=1), area


def test_smooth_kernel_is_erf_over_r_with_its_limit_at_zero():
    r = np.array([0.0, 1e-3, 2e-3])
    g = smooth_kernel(r, 1e-3)
    assert g[0] == pytest.approx(2 / (1e-3 * np.sqrt(np.pi)))
    assert g[1] == pytest.approx(0.8427007929 / 1e-3, rel=1e-9)
    assert g[2] == pytest.approx(0.9953222650 / 2e-3, rel=1e-9)


@pytest.mark.parametrize("plane", [None, PLANE])
def test_grid_far_field_matches_the_direct_sum(plane):
    """The sum of all pairs (with images of opposite sign) to 1e-4 of the largest potential,
    for random heats on a bent 6 x 6-cell Miura sheet (504 points; measured 2e-5 free, 6e-5
    over the plane)."""
    c, area = _centroids()
    grid = GridFarField(c, 2 * np.sqrt(area.mean()), plane)
    p = np.random.default_rng(3).normal(size=len(c))
    if plane is None:
        ref = integral_fast.direct_potential(c, p, compiled=False)
    else:
        both = np.concatenate([c, mirror(c, plane)])
        ref = integral_fast.direct_potential(both, np.concatenate([p, -p]), compiled=False,
                                             n_targets=len(c))
    assert np.abs(grid.potential(p) - ref).max() <= 1e-4 * np.abs(ref).max()


@pytest.mark.parametrize("image", [False, True])
def test_grid_pair_values_compiled_match_numpy(image):
    c, area = _centroids(3)
    grid = GridFarField(c, 2 * np.sqrt(area.mean()), PLANE)
    g = grid._kernel(-1e-4 if image else None)
    rng = np.random.default_rng(4)
    rows, cols = rng.integers(0, len(c), 300), rng.integers(0, len(c), 300)
    a = grid_pairs(grid._base, grid._u, rows, cols, g, grid.shape[2], image, compiled=False)
    b = grid_pairs(grid._base, grid._u, rows, cols, g, grid.shape[2], image, compiled=True)
    assert np.allclose(a, b, rtol=1e-12, atol=1e-12 * np.abs(a).max())


def test_grid_self_pairs_are_the_smooth_kernel_at_zero_to_the_interpolation_error():
    """The grid's own value of each self pair (subtracted exactly) is erf(r/sigma)/r at r = 0
    to the interpolation error, largest there (measured 1.3 %)."""
    c, area = _centroids(3)
    grid = GridFarField(c, 2 * np.sqrt(area.mean()))
    g0 = 2 / (grid.sigma * np.sqrt(np.pi))
    assert np.abs(grid.self_value - g0).max() <= 3e-2 * g0


@pytest.mark.parametrize("plane", [None, Substrate.plane((0.0, 0.0, -2e-4), (0.0, 0.0, 1.0))])
def test_fast_path_on_the_grid_agrees_with_dense(plane, monkeypatch):
    """Plain m = 2 on a 4 x 4-cell Miura bent out of plane (896 sub-triangles), the far field
    forced onto the grid: within 1e-4 of the largest rise of the dense operator (measured on
    5 x 5 cells: 1.6e-5 free, 6.9e-5 over the plane)."""
    monkeypatch.setattr(integral_fast, "GRID_MIN", 0)
    pattern = miura_sheet_pattern(m=4, n=4)
    model = stack_model(pattern, get_stack("su8-au"), list(pattern.creases))
    x = model.mesh.nodes.copy()
    x[:, 2] += 3e-4 * np.sin(x[:, 0] / 1.5e-3) ** 2
    out = {}
    for op in ("dense", "fast"):
        prm = dataclasses.replace(model.thermal, substrate=plane, sheet_refinement=1,
                                  loss=IntegralLoss(operator=op, refinement=2))
        tm = ThermalModel(model.mesh, prm, warn_no_plane=False)
        out[op] = tm.solve(x, tm.heat_vector(np.full(model.mesh.n_creases, 1e-3))) \
            - prm.room_temperature
    fast_levels = tm.integral.terms(x)
    assert all(S.far_field == "grid" for _, _, S in fast_levels)
    assert np.abs(out["fast"] - out["dense"]).max() <= 1e-4 * out["dense"].max()
