"""Bar and rotational-spring kernels: finite differences, rigid-body checks, analytic values."""

import numpy as np
import pytest
from fd_harness import check_kernel

from simulator import _jit
from simulator.mechanics.elements.bars import bar_kernel
from simulator.mechanics.elements import _springs_jit
from simulator.mechanics.elements.springs import (fold_angle, fold_angle_derivatives, spring_kernel,
                                        spring_kernel_numpy)

RNG = np.random.default_rng(42)


def _bars(n=40, scale=1e-3):
    X = RNG.normal(size=(n, 2, 3)) * scale
    L0 = np.linalg.norm(X[:, 1] - X[:, 0], axis=1)
    x = X + RNG.normal(size=X.shape) * 0.1 * scale
    return x, L0, RNG.uniform(1e-3, 1e2, n)


def _bar_of_positions(dX, L0, EA):
    """The bar kernel as a function of current end positions (for the FD harness)."""
    return lambda y: bar_kernel(dX, (y[:, 1] - y[:, 0]) - dX, L0, EA)


def test_bar_finite_differences():
    x, L0, EA = _bars()
    dX = x[:, 1] - x[:, 0] + RNG.normal(size=(len(L0), 3)) * 1e-4
    check_kernel(_bar_of_positions(dX, np.linalg.norm(dX, axis=1), EA), x)


def test_bar_finite_differences_with_edited_reference():
    """Stored length differs from the node distance (gripper node edits): still consistent."""
    x, L0, EA = _bars()
    dX = x[:, 1] - x[:, 0] + RNG.normal(size=(len(L0), 3)) * 1e-4
    check_kernel(_bar_of_positions(dX, L0, EA), x)


def test_bar_axial_stiffness_is_EA_over_L():
    L, EA = 2e-3, 5.0
    dX = np.array([[L, 0, 0]])
    _, g, H = bar_kernel(dX, np.zeros((1, 3)), np.array([L]), np.array([EA]))
    assert np.allclose(g, 0)
    assert H[0, 3, 3] == pytest.approx(EA / L, rel=1e-14)
    assert H[0, 4, 4] == pytest.approx(0, abs=1e-14)      # no initial-stress term at zero strain
    # small stretch: force = EA * strain
    d = 1e-9
    _, g, _ = bar_kernel(dX, np.array([[d, 0, 0]]), np.array([L]), np.array([EA]))
    assert g[0, 3] == pytest.approx(EA * d / L, rel=1e-6)


def _springs(n=60, scale=1e-3):
    x = RNG.normal(size=(n, 4, 3)) * scale
    return x, RNG.uniform(1e-10, 1e-6, n), RNG.uniform(0.5, 2 * np.pi - 0.5, n)


def test_fold_angle_derivatives_finite_differences():
    x, _, _ = _springs()
    theta = fold_angle(x)
    ok = (theta > 0.2) & (theta < 2 * np.pi - 0.2)           # away from the 0 / 2 pi wrap
    check_kernel(lambda y: fold_angle_derivatives(y), x[ok])


def test_spring_finite_differences():
    x, k, t0 = _springs()
    theta = fold_angle(x)
    ok = (theta > 0.2) & (theta < 2 * np.pi - 0.2)
    check_kernel(lambda y: spring_kernel(y, k[ok], t0[ok]), x[ok])


def test_spring_near_flat_finite_differences():
    """Near theta = pi the angle is computed with atan2 and stays exact."""
    base = np.array([[0, 1, 0], [0, 0, 0], [1, 0, 0], [0.5, -1, 0]], float) * 1e-3
    x = base + RNG.normal(size=(30, 4, 3)) * 1e-6
    check_kernel(lambda y: spring_kernel(y, np.full(30, 1e-8), np.full(30, np.pi)), x)


@pytest.mark.parametrize("phi", [-2.5, -1.0, -0.3, 0.0, 0.3, 1.0, 2.5])
def test_fold_angle_convention(phi):
    """Axis j-k along x, i at -y (so z((x_j - x_i) x (x_k - x_j)) <= 0); wing l rotated by phi
    about x towards +z gives theta = pi + phi: up-folding increases theta."""
    x = np.array([[[0.3, -1, 0], [0, 0, 0], [1, 0, 0], [0.6, np.cos(phi), np.sin(phi)]]])
    z = np.cross(x[0, 1] - x[0, 0], x[0, 2] - x[0, 1])[2]
    assert z <= 0
    assert fold_angle(x)[0] == pytest.approx(np.pi + phi, abs=1e-13)


def test_flat_angle_is_exactly_pi():
    x = np.array([[[0.3e-3, -1e-3, 0], [0, 0, 0], [1e-3, 0, 0], [0.6e-3, 1e-3, 0]]])
    assert fold_angle(x)[0] == np.pi


def test_numpy_spring_kernel_finite_differences():
    x, k, t0 = _springs()
    theta = fold_angle(x)
    ok = (theta > 0.2) & (theta < 2 * np.pi - 0.2)
    check_kernel(lambda y: spring_kernel_numpy(y, k[ok], t0[ok]), x[ok])


@pytest.mark.skipif(not _jit.AVAILABLE, reason="numba not installed")
def test_compiled_spring_kernel_equals_numpy_kernel():
    x, k, t0 = _springs(200)
    for a, b in zip(_springs_jit.spring_kernel_jit(x, k, t0), spring_kernel_numpy(x, k, t0)):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * np.abs(b).max())
    e, g, h = _springs_jit.spring_kernel_jit(x, k, t0, hessian=False)
    assert h is None and np.allclose(g, spring_kernel_numpy(x, k, t0)[1])


def test_spring_kernel_backend_selects_the_kernel(monkeypatch):
    """One backend per block or process; both kernels give the same values."""
    from simulator import ParameterError
    from simulator.kernels import spring_kernel_backend

    x, k, t0 = _springs(20)
    calls = []
    monkeypatch.setattr(_springs_jit, "spring_kernel_jit",
                        lambda *a: calls.append("numba") or spring_kernel_numpy(*a))
    with spring_kernel_backend("numpy"):
        spring_kernel(x, k, t0)
        assert calls == []
        if _jit.AVAILABLE:
            with spring_kernel_backend("numba"):
                spring_kernel(x, k, t0)
            assert calls == ["numba"]
        spring_kernel(x, k, t0)

    assert _jit._backend is None                           # restored: the default again
    monkeypatch.setenv("ETORIGAMI_JIT", "0")
    assert _springs_jit.default_backend() == "numpy"
    monkeypatch.setenv("ETORIGAMI_JIT", "1")
    assert _springs_jit.default_backend() == ("numba" if _jit.AVAILABLE else "numpy")
    with pytest.raises(ParameterError, match="backend 'cuda'; use one of 'numba', 'numpy'"):
        with spring_kernel_backend("cuda"):
            pass


def test_compile_kernel_returns_the_kernel_or_none_with_one_warning(caplog):
    """The one lazy-compilation helper of every compiled kernel."""
    import logging

    from simulator._jit import compile_kernel

    def broken():
        raise RuntimeError("no compiler today")
    with caplog.at_level(logging.INFO, logger="simulator._jit"):
        assert compile_kernel("test kernel", lambda: abs, "using numpy") is abs
        assert compile_kernel("test kernel", broken, "using numpy") is None
    warnings = [r for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warnings) == 1
    assert warnings[0].getMessage() == ("numba could not compile the test kernel (RuntimeError: "
                                        "no compiler today); using numpy")
    assert "compiling the test kernel with numba" in caplog.text


def test_compiled_bar_kernel_equals_numpy_kernel_bit_for_bit():
    from simulator.mechanics.elements import _bars_jit
    from simulator.kernels import spring_kernel_backend

    x, L0, EA = _bars(500)
    dX = RNG.normal(size=(500, 3)) * 1e-3
    du = (x[:, 1] - x[:, 0]) - dX
    with spring_kernel_backend("numba"):
        assert _bars_jit.use_compiled()
        for hessian in (True, False):
            fast = _bars_jit.bar_kernel_jit(dX, du, L0, EA, hessian)
            ref = bar_kernel(dX, du, L0, EA, hessian)
            for a, b in zip(fast, ref):
                assert (a is None and b is None) or np.array_equal(a, b)


def test_large_model_evaluation_takes_the_compiled_bar_kernel_with_numba(monkeypatch):
    from simulator.kernels import spring_kernel_backend
    from simulator.mechanics.elements import _bars_jit
    from simulator.geometry.example_patterns import miura_sheet_pattern
    from simulator.model.model import Supports, make_model
    from simulator.model.properties import BarHingeParameters
    from simulator.mechanics import equilibrium_system
    from simulator.steps import initial_state

    model = make_model(miura_sheet_pattern(m=4, n=4), None, BarHingeParameters())
    model = make_model(model.mesh, Supports.nodes(model.mesh.panel_nodes(0)))
    u = RNG.normal(size=(model.mesh.n_nodes, 3)) * 1e-6
    rest = initial_state(model).spring_rest
    calls = []
    original = _bars_jit.bar_kernel_jit
    monkeypatch.setattr(_bars_jit, "bar_kernel_jit", lambda *a: calls.append(1) or original(*a))
    out = {}
    for backend in ("numba", "numpy"):
        with spring_kernel_backend(backend):
            system = equilibrium_system(model)
            assert not system.uses_fused                      # the large-model path
            out[backend] = system.evaluate(u, rest)
    assert calls == [1]                                       # numba only
    f = out["numpy"].f_int                                   # springs differ by rounding
    np.testing.assert_allclose(out["numba"].f_int, f, rtol=1e-12, atol=1e-12 * np.abs(f).max())
    np.testing.assert_allclose(out["numba"].K.toarray(), out["numpy"].K.toarray(), rtol=1e-12,
                               atol=1e-12 * abs(out["numpy"].K).max())
