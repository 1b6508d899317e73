"""Calibrate the chain model's environment (beta, t_env) to a reference (theory 4.8).

The chain model (theory 4.3-4.4) is fast and carries the medium's heat capacity, but its
dissipation angle beta and thickness t_env are fitted numbers (the paper's 20 deg and 1.5 L are
for its air-borne gripper). This fits them for a user's geometry, medium and shape to the
boundary-integral model (theory 4.7, nothing to fit) or to any other steady reference (the 3-D
FE of :mod:`simulator.thermal.fe`, measured temperatures): the crease-node temperature rises of
the chain model are matched in the least-squares sense (relative), and the fit residual is
reported, so a user knows how far the fast model stays from the reference.
"""

from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np
from scipy.optimize import least_squares

from .._result import ResultFiles
from .._validate import array, in_range, positive
from ..errors import ParameterError
from ..model.heat_loss import ChainLoss, Substrate
from ..model.model import Model
from .fixed_shape import resolve_substrate
from .steady import ThermalModel

__all__ = ["calibrate_environment", "CalibrationResult"]

logger = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class CalibrationResult(ResultFiles):
    """Outcome of :func:`calibrate_environment`.

    Attributes
    ----------
    success, status, message : bool, str, str
        ``status`` "converged" or "failed" (the optimiser's message).
    thermal : ThermalParameters
        The model's parameters with the chain loss of the fitted ``dissipation_angle`` and
        ``thickness`` (``loss=ChainLoss(...)``).
    dissipation_angle : float
        Fitted beta [rad].
    env_thickness : float
        Fitted t_env [m].
    rms_error : float
        RMS over the crease nodes (those not held at room temperature by either model) of the
        relative error of the temperature rise, after the fit.
    max_error : float
        Largest relative error of a crease node's rise after the fit.
    initial_rms_error : float
        The same RMS with the model's own (uncalibrated) beta and t_env.
    reference : str
        "integral", "fe" or "callable".
    """

    success: bool
    status: str
    message: str
    thermal: object
    dissipation_angle: float
    env_thickness: float
    rms_error: float
    max_error: float
    initial_rms_error: float
    reference: str

    _csv_name = "calibration.csv"

    def to_dict(self) -> dict:
        """The scalar outcome with units in the keys."""
        return {"success": self.success, "status": self.status, "message": self.message,
                "reference": self.reference,
                "dissipation_angle [deg]": math.degrees(self.dissipation_angle),
                "env_thickness [m]": self.env_thickness, "rms_error [-]": self.rms_error,
                "max_error [-]": self.max_error,
                "initial_rms_error [-]": self.initial_rms_error}


def _panel_length(mesh) -> float:
    """Root of the mean panel area [m] (a panel length, for the chains' starting t_env)."""
    tri = mesh.nodes[mesh.triangles]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    on_panel = mesh.triangle_panel >= 0
    return float(np.sqrt(area[on_panel].sum() / max(mesh.pattern.n_panels, 1)))


def _reference_solver(model: Model, reference, x, substrate):
    """``(x, q) -> temperatures (n,) [deg C]`` of the reference; the integral model and the FE
    over the plane ``substrate`` at positions ``x`` (:func:`calibrate_environment`)."""
    if callable(reference):
        return reference, "callable"
    if reference == "integral":
        plane = resolve_substrate(model, x, substrate)
        prm = dataclasses.replace(model.thermal.with_loss("integral"),
                                  substrate=Substrate.plane(plane[:3], plane[3:]) if plane
                                  else None)
        return (ThermalModel(model.mesh, prm, warn_no_plane=substrate is not None,
                             actuators=model.actuators).solve,
                "integral")
    if reference == "fe":
        try:
            import gmsh  # noqa: F401
            import skfem  # noqa: F401
            from .fe import solve_fe3d
        except ImportError as exc:
            raise ParameterError(
                "calibrate_environment(reference='fe') needs the 3-D FE reference "
                f"(simulator.thermal.fe, optional extra [fe]): {exc}. Install it with "
                "pip install 'etorigami[fe]', or use reference='integral' or a callable "
                "(x, q) -> temperatures.") from None

        plane = resolve_substrate(model, x, substrate)

        def solve(x, q):
            res = solve_fe3d(model, heat=q, positions=x,
                             substrate=Substrate.plane(plane[:3], plane[3:]) if plane
                             else None)
            if not res.success:
                raise ParameterError(f"calibrate_environment: the 3-D FE failed: {res.message}")
            return res.temperature
        return solve, "fe"
    raise ParameterError(f"reference = {reference!r}; use 'integral', 'fe' or a callable "
                         "(x (n, 3) [m], q (n,) [W]) -> temperatures (n,) [deg C].")


def calibrate_environment(model: Model, power, x=None, reference="integral",
                          beta_bounds=(0.0, math.radians(80)), t_env_bounds=None,
                          substrate="model") -> CalibrationResult:
    """Fit the chain model's beta and t_env to a reference's steady crease temperatures.

    Parameters
    ----------
    model : Model
        A model with thermal parameters (their layers N and medium are kept).
    power : (C,) array
        Power on each crease row [W] of the calibration load case.
    x : (n, 3) array, optional
        Node positions [m] (default: the mesh's nodes); calibrate on the shape that matters
        (e.g. the gripper at assembly).
    reference : {"integral", "fe"} or callable
        The boundary-integral model (:mod:`simulator.thermal.integral`), the 3-D FE
        (:mod:`simulator.thermal.fe`, when installed), both over ``substrate``, or ``f(x, q)
        -> temperatures`` (n,).
    beta_bounds : (float, float)
        Range of beta [rad] searched, within [0, pi/2).
    t_env_bounds : (float, float), optional
        Range of t_env [m] (default: 0.01 to 100 times the model's t_env; a model without
        chains starts from 1.5 times the root of its mean panel area, the paper's suggestion).
    substrate : "model", Substrate or None
        Isothermal substrate plane of the reference (integral model or FE): the model's own
        (``"model"``, ``ThermalParameters.substrate``: by default the plane of its thermal
        boundary panels at ``x``, none without them), a :class:`~simulator.model.heat_loss.
        Substrate`, none, or a given plane [m], as in
        :func:`~simulator.thermal.fixed_shape.fixed_shape_temperatures`.

    Returns
    -------
    CalibrationResult
        The fitted parameters and the residual (relative crease-node rises).
    """
    if not isinstance(model, Model) or model.thermal is None:
        raise ParameterError("calibrate_environment needs a Model with thermal parameters "
                             f"(got {type(model).__name__}).")
    chain = model.thermal.loss if model.thermal.loss.model == "chain" else ChainLoss(
        thickness=1.5 * _panel_length(model.mesh))       # the paper's t_env = 1.5 L as start
    prm = dataclasses.replace(model.thermal, loss=chain)
    if not prm.medium.thermal_conductivity > 0:
        raise ParameterError("calibrate_environment: the medium's conductivity is 0: there is "
                             "no environment to calibrate.")
    mesh = model.mesh
    x = mesh.nodes if x is None else array("x", x, mesh.nodes.shape, "m")
    lo_b, hi_b = (in_range(f"beta_bounds[{i}]", b, 0, math.pi / 2, "rad", open_high=True)
                  for i, b in enumerate(beta_bounds))
    if t_env_bounds is None:
        t_env_bounds = (0.01 * prm.loss.thickness, 100 * prm.loss.thickness)
    lo_t, hi_t = (positive(f"t_env_bounds[{i}]", t, "m") for i, t in enumerate(t_env_bounds))
    if not (lo_b < hi_b and lo_t < hi_t):
        raise ParameterError(f"beta_bounds = {beta_bounds!r}, t_env_bounds = {t_env_bounds!r}: "
                             "each must be (low, high) with low < high.")
    solve, name = _reference_solver(model, reference, x, substrate)
    chain = ThermalModel(mesh, prm, actuators=model.actuators)
    q = chain.heat_vector(power)
    if not q.sum() > 0:
        raise ParameterError("calibrate_environment: power must heat at least one crease (> 0).")
    ref_fixed = getattr(solve, "__self__", chain).held_nodes(x)    # the reference's own, if a model
    nodes = np.setdiff1d(np.unique(mesh.crease_nodes), np.union1d(chain.fixed_nodes, ref_fixed))
    if not len(nodes):
        raise ParameterError("calibrate_environment: every crease node is held at room "
                             "temperature; there is nothing to fit.")
    rt = prm.room_temperature
    target = np.asarray(solve(x, q), float)[nodes] - rt

    def rel_error(v):
        beta, t_env = v[0], math.exp(v[1])
        tm = ThermalModel(mesh, prm.with_loss(dissipation_angle=beta, thickness=t_env),
                          actuators=model.actuators)
        return (tm.solve(x, q)[nodes] - rt - target) / np.maximum(np.abs(target), 1e-300)

    beta0, t_env0 = prm.loss.dissipation_angle, prm.loss.thickness
    v0 = np.array([min(max(beta0, lo_b), hi_b), math.log(min(max(t_env0, lo_t), hi_t))])
    initial = float(np.sqrt(np.mean(rel_error([beta0, math.log(t_env0)]) ** 2)))
    fit = least_squares(rel_error, v0, bounds=([lo_b, math.log(lo_t)], [hi_b, math.log(hi_t)]),
                        x_scale=[0.1, 1.0], diff_step=1e-4)
    err = fit.fun
    beta, t_env = float(fit.x[0]), float(math.exp(fit.x[1]))
    logger.info("calibrated to %s: beta %.2f deg, t_env %.4g m, rms error %.3g (was %.3g)",
                name, math.degrees(beta), t_env, np.sqrt(np.mean(err ** 2)), initial)
    return CalibrationResult(
        success=bool(fit.success), status="converged" if fit.success else "failed",
        message=str(fit.message),
        thermal=prm.with_loss(dissipation_angle=beta, thickness=t_env),
        dissipation_angle=beta, env_thickness=t_env,
        rms_error=float(np.sqrt(np.mean(err ** 2))), max_error=float(np.max(np.abs(err))),
        initial_rms_error=initial, reference=name)
