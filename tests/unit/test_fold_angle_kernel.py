"""The crossing watch's compiled fold angles and per-increment test
(simulator._angles_jit) against their numpy reference (simulator.events): the same
angles to 1e-14 rad on meshes of either panel orientation, of three to many corners per panel,
folded near +-180 deg; sharp and creaseless meshes keep fold_angles; the compiled test decides
as the numpy one, NaN included."""

import numpy as np
import pytest

from simulator import Pattern, make_mesh
from simulator.mechanics import fold_angles
from simulator.model import build_sharp_mesh
from simulator.cases import get_case
from simulator.events import LARGE_TURN, NEAR_FLAT, CrossingWatch, _crease_angles, _quiet
from simulator import _jit
from simulator import _angles_jit

pytestmark = pytest.mark.skipif(not _jit.AVAILABLE, reason="numba not installed")

V = np.array([[0, 0], [1, 0], [1, 2], [0, 2], [0, -1], [1, -1]]) * 1e-3


@pytest.fixture
def kernels(monkeypatch):
    """The compiled kernels, with numba selected whatever ETORIGAMI_JIT says."""
    monkeypatch.setattr(_jit, "_backend", "numba")
    angles, quiet = _angles_jit.fold_angles_kernel(), _angles_jit.quiet_kernel()
    assert angles is not None and quiet is not None, "numba could not compile the kernels"
    return angles, quiet


def _strip(flip):
    second = [1, 5, 4, 0] if flip else [0, 4, 5, 1]
    return make_mesh(Pattern(V, [[0, 1, 2, 3], second], crease_width=200e-6,
                              crease_thickness=1e-6, panel_thickness=10e-6))


def _meshes():
    from design.devices.gripper import GripperDesign, make_gripper_model

    cases = [("single_fold", {}), ("double_fold", {}), ("miura_lifter", {}), ("crane", {})]
    return ([(f"strip{'-flipped' * flip}", _strip(flip)) for flip in (False, True)]
            + [(name, get_case(name, **kw).model.mesh) for name, kw in cases]
            + [("gripper", make_gripper_model(GripperDesign())[0].mesh)])


def _turned(mesh, deg):
    """Node positions with the nodes of y < 0 turned by ``deg`` about the x axis (the strip's
    crease line)."""
    t, x = np.radians(deg), mesh.nodes.copy()
    side = x[:, 1] < -1e-12
    y, z = x[side, 1].copy(), x[side, 2].copy()
    x[side, 1], x[side, 2] = y * np.cos(t) - z * np.sin(t), y * np.sin(t) + z * np.cos(t)
    return x


@pytest.mark.parametrize("name, mesh", _meshes(), ids=lambda v: v if isinstance(v, str) else "")
def test_compiled_fold_angles_are_the_numpy_ones(name, mesh, kernels):
    angles = _crease_angles(mesh)
    rng = np.random.default_rng(11)
    size = np.ptp(mesh.nodes, axis=0).max()
    states = [np.zeros_like(mesh.nodes)] + [scale * size * rng.standard_normal(mesh.nodes.shape)
                                            for scale in (1e-6, 1e-3, 0.05, 0.3)]
    for u in states:
        a = angles(u, kernels[0])
        assert a.shape == (mesh.n_creases,) and a.dtype == np.float64
        np.testing.assert_allclose(a, angles.reference(mesh.nodes + u), rtol=0, atol=1e-14)
        np.testing.assert_allclose(a, fold_angles(mesh, mesh.nodes + u), rtol=0, atol=1e-12)


@pytest.mark.parametrize("flip", [False, True])
@pytest.mark.parametrize("deg", [-179.9, -179, 179, 179.9, 180.1, 181, 190, 270])
def test_compiled_fold_angles_near_and_past_180_deg(flip, deg, kernels):
    """Folded 0.1 deg from flat on either side, and past it (read as -179.9 deg ...)."""
    mesh = _strip(flip)
    angles = _crease_angles(mesh)
    u = _turned(mesh, deg) - mesh.nodes
    a = angles(u, kernels[0])
    np.testing.assert_allclose(a, angles.reference(mesh.nodes + u), rtol=0, atol=1e-14)
    assert abs(abs(np.degrees(a[0])) - abs((deg + 180) % 360 - 180)) < 1e-9


def test_sharp_and_creaseless_meshes_keep_fold_angles(kernels):
    from simulator.geometry.example_patterns import miura_sheet_pattern

    sharp = build_sharp_mesh(miura_sheet_pattern())
    plain = make_mesh(Pattern(V[:4], [[0, 1, 2, 3]], crease_width=200e-6,
                               crease_thickness=1e-6, panel_thickness=10e-6))
    for mesh in (sharp, plain):
        u = 1e-5 * np.random.default_rng(2).standard_normal(mesh.nodes.shape)
        np.testing.assert_array_equal(_crease_angles(mesh)(u, kernels[0]),
                                      fold_angles(mesh, mesh.nodes + u))
    assert _crease_angles(plain)(np.zeros_like(plain.nodes), kernels[0]).shape == (0,)


def test_compiled_quiet_test_decides_as_numpy(kernels):
    """Far from flat and no large turn, as np.fmax.reduce sees it: a NaN entry is skipped, an
    all-NaN array is not quiet."""
    quiet = kernels[1]
    rng = np.random.default_rng(4)
    far, nan = np.pi - NEAR_FLAT, np.nan
    cases = [(rng.uniform(-2, 2, 7), rng.uniform(-2, 2, 7)) for _ in range(200)]
    cases += [(np.array([far, 0.0]), np.array([far - LARGE_TURN, 0.0])),      # both on the
              (np.array([np.nextafter(far, 4), 0.0]), np.zeros(2)),           # boundary, just
              (np.array([0.0, LARGE_TURN]), np.array([0.0, -1e-300])),        # past it
              (np.array([nan, 0.1]), np.array([0.0, 0.0])),
              (np.array([nan, 3.0]), np.array([0.0, 0.0])),
              (np.array([nan, nan]), np.array([0.0, 0.0])),
              (np.array([0.2, 0.1]), np.array([nan, nan])),
              (np.array([-3.1]), np.array([3.1]))]
    for a, b in cases:
        assert quiet(a, b, LARGE_TURN, far) == _quiet(a, b) == _quiet(a, b, quiet)


def test_the_watch_uses_the_compiled_kernels_only_where_numba_is_selected(monkeypatch,
                                                                          kernels):
    mesh = _strip(False)
    u0 = _turned(mesh, 30) - mesh.nodes
    assert CrossingWatch(mesh, u0)._kernel is kernels[0]
    monkeypatch.setattr(_jit, "_backend", "numpy")
    watch = CrossingWatch(mesh, u0)
    assert watch._kernel is None and watch._quiet is None
    assert watch.check(_turned(mesh, 40) - mesh.nodes, 1, 0.5) is None
