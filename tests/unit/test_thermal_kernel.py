"""Compiled thermal kernel (simulator.thermal._thermal_jit) against the numpy reference path."""

import logging
import os
import pathlib

import numpy as np
import pytest

from simulator.thermal import _thermal_jit
from simulator.mechanics.elements.contact import point_triangle_distance
from simulator.mechanics.elements.springs import spring_kernel_backend
from simulator.model.mesh import make_mesh
from simulator.geometry.example_patterns import single_fold_pattern
from simulator.geometry.materials import AIR
from simulator.thermal import ChainLoss
from simulator.thermal import ThermalModel, ThermalParameters

pytest.importorskip("numba")     # a test dependency (pyproject [test]); the kernel needs it


def _single_fold(boundary=(2,)):
    mesh = make_mesh(single_fold_pattern())
    prm = ThermalParameters(loss=ChainLoss(thickness=750e-6),
                            medium=AIR.with_properties(thermal_conductivity=0.6),
                            boundary_panels=boundary, room_temperature_nodes=(0, 3))
    return mesh, ThermalModel(mesh, prm)


def _deformed(mesh, seed):
    rng = np.random.default_rng(seed)
    return mesh.nodes + rng.normal(scale=30e-6, size=mesh.nodes.shape)


def _gripper_state():
    from design.devices.gripper import GripperDesign, GripperHeatModel, make_gripper_model
    from simulator.simulation import simulate
    from simulator.thermal import thermal_model
    model, pre = make_gripper_model(GripperDesign(),               # the chains with T3
                                    heat=GripperHeatModel(loss_model="chain"))
    state = simulate(model, pre).state
    return thermal_model(model), model.mesh.nodes + state.u, model.mesh.n_creases


@pytest.mark.parametrize("boundary", [(2,), ()])
def test_element_data_matches_numpy(boundary):
    mesh, tm = _single_fold(boundary)
    for seed in range(3):
        x = _deformed(mesh, seed)
        with spring_kernel_backend("numba"):
            K1, g1 = tm.structure_conductances(x)
        with spring_kernel_backend("numpy"):
            K0, g0 = tm.structure_conductances(x)
        np.testing.assert_allclose(K1, K0, rtol=1e-12, atol=1e-12 * abs(K0).max())
        np.testing.assert_allclose(g1, g0, rtol=1e-12)
        assert np.all(g0 > 0)


def test_gripper_temperatures_match_numpy():
    tm, x, n_creases = _gripper_state()
    q = tm.heat_vector(np.linspace(1e-3, 3e-3, n_creases))
    with spring_kernel_backend("numba"):
        T1 = tm.solve(x, q)
    with spring_kernel_backend("numpy"):
        T0 = tm.solve(x, q)
        T_sparse = tm._free_pattern.matrix(                     # the sparse (large-mesh) path
            [tm.structure_conductances(x)[0], tm.structure_conductances(x)[1][tm.free_nodes]])
    np.testing.assert_allclose(T1, T0, rtol=1e-13)
    from scipy.sparse.linalg import spsolve
    rise = spsolve(T_sparse.tocsc(), q[tm.free_nodes])
    np.testing.assert_allclose(T0[tm.free_nodes] - tm.params.room_temperature, rise, rtol=1e-11)
    assert T0.max() > tm.params.room_temperature + 1


def test_point_triangle_distance_all_regions():
    """The scalar distance of the kernel equals the exact numpy one in every Voronoi zone."""
    rng = np.random.default_rng(4)
    tri = rng.normal(size=(4000, 3, 3))
    p = rng.normal(scale=2.0, size=(4000, 3))
    d0, zone, _ = point_triangle_distance(p, tri)
    assert set(np.unique(zone)) == {0, 1, 2}
    assert _thermal_jit.use_compiled() or _thermal_jit._compile()
    fn = _thermal_jit._point_triangle_distance
    for f in (fn, fn.py_func):
        d1 = np.array([f(*pi, ti) for pi, ti in zip(p[:400], tri[:400])])
        np.testing.assert_allclose(d1, d0[:400], rtol=1e-10, atol=1e-14)
    seg = np.zeros((3, 3))
    seg[1, 0] = seg[2, 0] = 1.0                             # degenerate: a segment
    assert fn(0.5, 1.0, 0.0, seg) == pytest.approx(1.0, rel=1e-15)
    assert fn(2.0, 1.0, 0.0, seg) == pytest.approx(np.sqrt(2.0), rel=1e-15)
    assert fn(0.0, 0.0, 3.0, np.zeros((3, 3))) == 3.0       # a point


def test_floored_air_warns_on_both_paths(caplog):
    """A node lying on the substrate floors t_air, with a warning, on both backends."""
    mesh, tm = _single_fold()
    x = mesh.nodes.copy()
    sub = mesh.triangles[mesh.triangle_panel == 2]
    x[:, 2] = np.where(np.isin(np.arange(mesh.n_nodes), sub.ravel()), x[:, 2], x[sub[0, 0], 2])
    q = tm.heat_vector([1e-3])
    temps = []
    for backend in ("numba", "numpy"):
        caplog.clear()
        with caplog.at_level(logging.WARNING, logger="simulator.thermal.chains"), \
                spring_kernel_backend(backend):
            temps.append(tm.solve(x, q))
        assert "t_air floored" in caplog.text
    np.testing.assert_allclose(temps[0], temps[1], rtol=1e-12)


def test_factorisation_reused_on_the_same_shape(monkeypatch):
    """Solving again on the same positions reuses the factorisation; a new shape refactors."""
    mesh, tm = _single_fold()
    calls = []
    original = tm._factorize
    monkeypatch.setattr(tm, "_factorize", lambda *a: calls.append(1) or original(*a))
    x = _deformed(mesh, 0)
    T1 = tm.solve(x, tm.heat_vector([1e-3]))
    T2 = tm.solve(x.copy(), tm.heat_vector([2e-3]), room_temperature=30.0)
    assert len(calls) == 1
    np.testing.assert_allclose(T2 - 30.0, 2 * (T1 - 21.0), rtol=1e-12)   # linear in q
    x[5, 2] += 1e-6
    tm.solve(x, tm.heat_vector([1e-3]))
    assert len(calls) == 2


def test_background_compilation_fills_the_cache(tmp_path):
    """With an empty numba cache the kernel compiles in a separate process; this process then
    loads it from the cache (and gives the numpy path's temperatures)."""
    import subprocess
    import sys
    import textwrap
    script = textwrap.dedent("""
        import numpy as np
        from simulator.thermal import _thermal_jit
        from simulator.mechanics.elements.springs import spring_kernel_backend
        from simulator.geometry.example_patterns import single_fold_pattern
        from simulator.model.mesh import make_mesh
        from simulator.geometry.materials import AIR
        from simulator.thermal import ChainLoss
        from simulator.thermal import ThermalModel, ThermalParameters
        assert _thermal_jit.compile_in_background()                 # cold cache: started
        assert not _thermal_jit.compile_in_background()             # only once
        child = _thermal_jit._background
        mesh = make_mesh(single_fold_pattern())
        tm = ThermalModel(mesh, ThermalParameters(
            loss=ChainLoss(thickness=750e-6), medium=AIR.with_properties(thermal_conductivity=0.6),
            boundary_panels=(2,), room_temperature_nodes=(0, 3)))
        q = tm.heat_vector([1e-3])
        T1 = tm.solve(mesh.nodes, q)                                # waits, then loads
        assert _thermal_jit._background is None and child.returncode == 0
        assert _thermal_jit._compiled is not None
        with spring_kernel_backend("numpy"):
            T0 = tm.solve(mesh.nodes, q)
        assert np.allclose(T1, T0, rtol=1e-12, atol=0)
        print("ok")
    """)
    root = pathlib.Path(__file__).resolve().parents[2]
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path), PYTHONPATH=str(root))
    env.pop("ETORIGAMI_JIT", None)
    out = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"
    assert list(tmp_path.rglob("_thermal_jit._kernel-*.nbi"))                 # cache written
    # a warm cache starts nothing
    again = subprocess.run([sys.executable, "-c", "from simulator.thermal import _thermal_jit; "
                            "print(_thermal_jit.compile_in_background())"], env=env,
                           capture_output=True, text=True, timeout=120)
    assert again.stdout.strip() == "False", again.stderr


def test_first_evaluation_starts_no_background_compilation(monkeypatch):
    """A library call starts no process (issue 31): the model's first evaluation compiles the
    thermal kernel in this process; only the CLI asks for the background compilation."""
    from simulator.cases import get_case
    from simulator.mechanics.elements import _fused_jit
    from simulator.mechanics import equilibrium_system
    from simulator.steps import initial_state
    model = get_case("single_fold", gravity=True).model
    monkeypatch.setattr(_fused_jit, "needs_compiling", lambda: True)
    monkeypatch.setattr(_thermal_jit, "compile_in_background", lambda: pytest.fail("started"))
    system = equilibrium_system(model)
    state = initial_state(model)
    with spring_kernel_backend("numba"):
        ev = system.evaluate(state.u, state.spring_rest)
    assert np.all(np.isfinite(ev.f_int))            # evaluated here, nothing started
