"""calibrate_environment: the chain model's beta and t_env fitted to a reference."""

import dataclasses
import math
import sys

import numpy as np
import pytest

import simulator
from simulator import ParameterError
from simulator.thermal import calibrate_environment
from simulator.cases import verification_strip
from simulator.thermal import ThermalModel


def _strip():
    return verification_strip().model


def test_recovers_the_parameters_of_a_chain_reference():
    model = _strip()
    truth = ThermalModel(model.mesh, model.thermal.with_loss(
        dissipation_angle=math.radians(35), thickness=1.2))
    res = calibrate_environment(model, [4e-3], reference=truth.solve)
    assert res.success and res.status == "converged" and res.reference == "callable"
    assert math.degrees(res.dissipation_angle) == pytest.approx(35, abs=0.05)
    assert res.env_thickness == pytest.approx(1.2, rel=1e-3)
    assert res.rms_error < 1e-5 < res.initial_rms_error
    assert res.thermal.loss.model == "chain" and res.thermal.loss.thickness == res.env_thickness


def test_fit_to_the_integral_model_reports_its_residual():
    res = calibrate_environment(_strip(), [4e-3])
    assert res.reference == "integral" and res.success
    assert 0 < res.rms_error <= res.initial_rms_error <= 1
    assert res.max_error >= res.rms_error
    row = res.to_frame().iloc[0]
    assert row["rms_error [-]"] == res.rms_error and "dissipation_angle [deg]" in row


def test_exported():
    thermal = simulator.thermal.__all__
    assert "calibrate_environment" in thermal and "CalibrationResult" in thermal


@pytest.mark.parametrize("kw, match", [
    (dict(reference="bem"), r"reference = 'bem'; use 'integral', 'fe' or a callable"),
    (dict(power=[0.0]), "must heat at least one crease"),
    (dict(beta_bounds=(0.5, 0.1)), "low < high"),
    (dict(t_env_bounds=(-1.0, 1.0)), r"t_env_bounds\[0\]"),
    (dict(x=np.zeros((3, 3))), "x"),
])
def test_bad_input_is_named(kw, match):
    args = {"power": [4e-3], **kw}
    with pytest.raises(ParameterError, match=match):
        calibrate_environment(_strip(), **args)


def test_fe_reference_needs_the_extra(monkeypatch):
    """Without the [fe] extra (hidden here: None in sys.modules makes its import fail)."""
    monkeypatch.setitem(sys.modules, "skfem", None)
    monkeypatch.setitem(sys.modules, "gmsh", None)
    with pytest.raises(ParameterError, match=r"needs the 3-D FE reference .*\[fe\]"):
        calibrate_environment(_strip(), [4e-3], reference="fe")


def test_fe_reference_gives_a_fit():
    pytest.importorskip("skfem")
    pytest.importorskip("gmsh")
    res = calibrate_environment(_strip(), [4e-3], reference="fe")
    assert res.reference == "fe" and res.success and res.rms_error <= res.initial_rms_error


def test_needs_thermal_parameters():
    with pytest.raises(ParameterError, match="needs a Model with thermal parameters"):
        calibrate_environment(object(), [1e-3])


def test_chains_cannot_represent_the_flat_crane():
    """Theory 4.8: on the flat crane at its 4 mW the case's chains are 81 % RMS off the
    integral model (monotone conduction, theory 4.9); the best fit improves that but leaves
    26 % (86 % at worst): seventeen creases sharing the air of one sheet."""
    from simulator.cases import get_case

    case = get_case("crane")
    fit = calibrate_environment(case.model, case.steps[0].power_array(case.model.mesh))
    assert fit.success, fit.message
    assert fit.initial_rms_error == pytest.approx(0.81, abs=0.01)
    assert 0.2 < fit.rms_error < 0.3 and fit.max_error > 0.8
    assert math.degrees(fit.dissipation_angle) == pytest.approx(5.1, abs=0.2)
    assert fit.env_thickness == pytest.approx(20.2e-3, rel=0.02)


def test_integral_reference_stands_on_the_boundary_panels_plane(caplog, monkeypatch):
    """A model with a substrate (boundary) panel: the integral reference takes that panel's
    plane by default, as the FE does (without it the medium would be unbounded below the
    sheet); calibrated on it, the chains fit as against a reference given that plane; at
    positions other than the mesh's the plane is taken there."""
    from simulator.thermal import boundary_panel_plane
    from simulator.cases import get_case
    from simulator.thermal import substrate

    monkeypatch.setattr(substrate, "_NO_PLANE_WARNED", [False])    # said once per process
    model = get_case("double_fold", thermal_steps=2).model
    plane = boundary_panel_plane(model)
    assert len(plane) == 6 and plane[5] > 0.99               # the substrate, normal up
    power = np.full(model.mesh.n_creases, 10e-3)
    with caplog.at_level("WARNING"):
        fit = calibrate_environment(model, power)
        unbounded = calibrate_environment(model, power, substrate=None)   # asked for: silent
    assert not [r for r in caplog.records if "substrate_plane" in r.getMessage()]
    explicit = ThermalModel(model.mesh, dataclasses.replace(
        model.thermal.with_loss("integral"), substrate=simulator.Substrate.plane(plane[:3],
                                                                                 plane[3:])))
    same = calibrate_environment(model, power, reference=explicit.solve)
    assert fit.rms_error == pytest.approx(same.rms_error, rel=1e-9)
    assert fit.env_thickness == pytest.approx(same.env_thickness, rel=1e-9)
    # the chains know the substrate (their cap): far from a reference without it
    assert unbounded.initial_rms_error > fit.initial_rms_error + 0.2
    moved = model.mesh.nodes + [0.0, 0.0, 1e-3]            # the whole model 1 mm up
    lifted = calibrate_environment(model, power, x=moved)
    assert lifted.env_thickness == pytest.approx(fit.env_thickness, rel=1e-6)


def test_no_plane_with_boundary_panels_warns_once_at_the_first_integral_solve(caplog,
                                                                             monkeypatch):
    """With boundary panels the default substrate is their plane (no warning). Told
    ``substrate=None``, the steady model warns once per process, at its first solve with the
    integral loss; not for the FE's or a transient run's use of the same parameters, nor
    where the caller of fixed_shape_temperatures chose no plane."""
    from simulator.thermal import boundary_panel_plane, fixed_shape_temperatures
    from simulator.cases import get_case
    from simulator.thermal import substrate

    monkeypatch.setattr(substrate, "_NO_PLANE_WARNED", [False])
    model = get_case("double_fold", thermal_steps=2).model
    q = ThermalModel(model.mesh, model.thermal).heat_vector(np.full(model.mesh.n_creases, 1e-3))
    default = model.thermal.with_loss("integral")
    with caplog.at_level("WARNING"):
        tm = ThermalModel(model.mesh, default)
        tm.solve(model.mesh.nodes, q)
    assert not [r for r in caplog.records if "substrate" in r.getMessage()]
    plane = boundary_panel_plane(model)
    np.testing.assert_allclose(np.concatenate(tm.plane), plane, atol=1e-15)
    prm = dataclasses.replace(default, substrate=None)
    integral = dataclasses.replace(model, thermal=prm)
    with caplog.at_level("WARNING"):
        fixed_shape_temperatures(integral, "integral", heat=q, substrate=None)
        tm = ThermalModel(model.mesh, prm)                   # built: not yet
        tm.heat_vector(np.full(model.mesh.n_creases, 1e-3))
        assert not [r for r in caplog.records if "substrate=None" in r.getMessage()]
        tm.solve(model.mesh.nodes, q)
        ThermalModel(model.mesh, dataclasses.replace(prm, medium=prm.medium.with_properties(
            thermal_conductivity=0.03))).solve(model.mesh.nodes, q)
    said = [r for r in caplog.records if "but substrate=None" in r.getMessage()]
    assert len(said) == 1 and "Substrate(), is the boundary panels' plane" in said[0].getMessage()


def test_non_coplanar_boundary_panels_name_the_way_out():
    from simulator.cases import get_case

    model = get_case("double_fold", thermal_steps=2).model
    bent = dataclasses.replace(model, thermal=dataclasses.replace(model.thermal,
                                                                  boundary_panels=(0, 3)))
    power = np.full(model.mesh.n_creases, 10e-3)
    with pytest.raises(ParameterError, match=r"not coplanar.*Substrate\.plane\(point, normal\).*substrate=None"):
        calibrate_environment(bent, power)
    fit = calibrate_environment(bent, power, substrate=None)
    assert fit.success and np.isfinite(fit.rms_error)
