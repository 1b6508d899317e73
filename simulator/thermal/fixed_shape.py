"""Steady temperatures of a model in a fixed shape under a chosen heat-loss model.

:func:`fixed_shape_temperatures` takes any model in a given shape (a simulation state or node
positions) and heat input, and solves steady heat with the chain model (theory 4.3-4.5), the
boundary-integral model (theory 4.7) or the 3-D FE reference (:func:`~simulator.thermal.fe.
solve_fe3d`, optional extra ``[fe]``): the mechanics is not re-run, so the models are compared
on the same shape and heat. The substrate plane of the integral model is by default the plane
of the model's thermal boundary panels, as in the FE.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from .._result import ResultFiles
from .._validate import array, integer, one_of
from ..errors import ParameterError
from .measures import crease_temperatures
from ..model.heat_loss import Substrate
from ..model.thermal_parameters import ThermalParameters
from .steady import ThermalModel
from .substrate import panels_plane, resolve_substrate as mesh_substrate

__all__ = ["fixed_shape_temperatures", "FixedShapeTemperatures", "boundary_panel_plane",
           "CreaseTemperatureTable"]

def crease_measures(T, mesh) -> dict:
    """The crease temperature fields of :class:`CreaseTemperatureTable` from node temperatures
    ``T`` (n,) [deg C] (:func:`~simulator.thermal.measures.crease_temperatures`)."""
    return {name: crease_temperatures(T, mesh, measure) for name, measure in (
        ("crease_temperature", "actuation"), ("crease_temperature_max", "crease_max"),
        ("crease_t_ctr", "centre"), ("crease_t_ave", "centre_line"))}


class CreaseTemperatureTable:
    """``to_frame`` of a result with the crease temperature fields ``temperature``,
    ``crease_temperature``, ``crease_temperature_max``, ``crease_t_ctr``, ``crease_t_ave``
    (this module's result and :class:`~simulator.thermal.fe.FE3DResult`; the fields:
    :func:`crease_measures`)."""

    def to_frame(self):
        """One row per crease: ``crease [-]`` and the four crease temperatures [degC]."""
        import pandas as pd

        if self.temperature is None:
            return pd.DataFrame()
        return pd.DataFrame({"crease [-]": np.arange(len(self.crease_t_ctr)),
                             "temperature [degC]": self.crease_temperature,
                             "temperature_max [degC]": self.crease_temperature_max,
                             "T_ctr [degC]": self.crease_t_ctr,
                             "T_ave [degC]": self.crease_t_ave})


@dataclass(frozen=True)
class FixedShapeTemperatures(CreaseTemperatureTable, ResultFiles):
    """Steady temperatures of :func:`fixed_shape_temperatures` (the fields of
    :class:`~simulator.thermal.fe.FE3DResult`, which the ``"fe"`` model returns).

    Attributes
    ----------
    success, status, message : outcome (status ``"converged"``: solved).
    temperature : (n,) array, node temperatures [deg C].
    crease_temperature : (C,) array, 7-node weighted mean (the actuation temperature) [deg C].
    crease_temperature_max : (C,) array, hottest of the 7 crease nodes [deg C].
    crease_t_ctr : (C,) array, T at the crease centre node Ctr [deg C].
    crease_t_ave : (C,) array, centre-line mean of A, B, Ctr (the limit measure) [deg C].
    heat_input : float, total heat [W].
    room_temperature : float [deg C].
    loss_model : str, ``"chain"`` or ``"integral"``.
    thermal : ThermalParameters, the parameters solved with.
    wall_time : float, operator build and solve [s].
    """

    success: bool
    status: str
    message: str
    temperature: np.ndarray
    crease_temperature: np.ndarray
    crease_temperature_max: np.ndarray
    crease_t_ctr: np.ndarray
    crease_t_ave: np.ndarray
    heat_input: float
    room_temperature: float
    loss_model: str
    thermal: ThermalParameters
    wall_time: float

    _csv_name = "fixed_shape_creases.csv"

    def _meta(self) -> dict:
        return {"heat_input [W]": self.heat_input, "loss_model": self.loss_model,
                "thermal": self.thermal.to_dict(), "wall_time [s]": self.wall_time}


def boundary_panel_plane(model, x=None) -> tuple:
    """The plane of the model's thermal boundary panels at positions ``x`` (n, 3) [m] (default:
    the mesh's) as 6 floats, a point and the unit normal towards the rest of the sheet, or ()
    without boundary panels: the plane the default substrate, ``Substrate()``, stands for
    (:func:`~simulator.thermal.substrate.panels_plane`)."""
    panels = tuple(model.thermal.boundary_panels) if model.thermal is not None else ()
    return panels_plane(model.mesh, panels, x)


def resolve_substrate(model, x, substrate):
    """``substrate`` ("model", None, (point, normal) or a :class:`~simulator.model.heat_loss.
    Substrate`) as a plane of 6 floats, or () for none: "model" is the model's own
    substrate (``ThermalParameters.substrate``: its plane, that of its boundary panels at
    ``x``, or none)."""
    return mesh_substrate(substrate, model.mesh, model.thermal, x)


def _shape_and_heat(model, tm, state, positions, crease_power, heat):
    mesh = model.mesh
    if positions is None:
        positions = mesh.nodes if state is None else mesh.nodes + np.asarray(state.u, float)
    x = array("positions", positions, mesh.nodes.shape, "m")
    if heat is not None:
        if crease_power is not None:
            raise ParameterError("give crease_power or heat, not both.")
        return x, array("heat", heat, (mesh.n_nodes,), "W", hint="one entry per mesh node")
    if crease_power is None:
        crease_power = None if state is None else state.crease_power
    if crease_power is None:
        raise ParameterError("crease_power (C,) [W] is required (or heat (n,) [W], or a state "
                             "with crease_power).")
    power = np.broadcast_to(np.asarray(crease_power, float), (mesh.n_creases,))
    return x, tm.heat_vector(power)


def fixed_shape_temperatures(model, loss_model: str = "integral", crease_power=None, *,
                             heat=None, state=None, positions=None, substrate="model",
                             refinement: int | None = None, extrapolation: bool | None = None,
                             fe_level: int = 1, room_temperature: float | None = None):
    """Steady temperatures of ``model`` in a fixed shape under a chosen heat-loss model.

    Parameters
    ----------
    model : Model
        A model with thermal parameters (sheet conduction, boundary panels, room-temperature
        nodes, medium conductivity; the chain parameters for ``"chain"``).
    loss_model : {"chain", "integral", "fe"}
        The paper's chains, the boundary-integral model, or the 3-D FE reference.
    crease_power : (C,) array or float, optional
        Power on each crease row [W] (default ``state.crease_power``).
    heat : (n,) array, optional
        Nodal heat input [W] instead of ``crease_power``.
    state : SimulationState, optional
        Shape ``mesh.nodes + state.u`` and default power; ``positions`` (n, 3) [m] overrides
        the shape. Default: the mesh's nodes.
    substrate : "model", Substrate or None
        Isothermal substrate plane of the integral model and the FE: the model's own
        (``"model"``, ``ThermalParameters.substrate``: by default the plane of its thermal
        boundary panels, none without them), a :class:`~simulator.model.heat_loss.Substrate`,
        none, or a given plane [m]. The chain model ignores it (its substrate is the
        boundary panels' distance cap).
    refinement : int, optional
        ``refinement`` of the integral loss (default: the model's, or
        :class:`~simulator.model.heat_loss.IntegralLoss`'s with the chains).
    extrapolation : bool, optional
        ``extrapolation`` of the integral loss (default: as for ``refinement``).
    fe_level : int
        Mesh level of the FE (0-3).
    room_temperature : float, optional
        [deg C], default ``model.thermal.room_temperature``.

    Returns
    -------
    FixedShapeTemperatures, or :class:`~simulator.thermal.fe.FE3DResult` for ``"fe"``
    (the same temperature fields).
    """
    one_of("loss_model", loss_model, ("chain", "integral", "fe"))
    if getattr(model, "mesh", None) is None or getattr(model, "thermal", None) is None:
        raise ParameterError("fixed_shape_temperatures needs a Model with thermal parameters "
                             f"(got {type(model).__name__}).")
    own = ThermalModel(model.mesh, model.thermal,       # its heat input (any loss model)
                       warn_no_plane=False, actuators=model.actuators)
    x, q = _shape_and_heat(model, own, state, positions, crease_power, heat)
    if loss_model == "fe":
        from .fe import solve_fe3d

        integer("fe_level", fe_level, 0, 3)
        plane = resolve_substrate(model, x, substrate)
        return solve_fe3d(model, heat=q, positions=x,
                          substrate=Substrate.plane(plane[:3], plane[3:]) if plane else None,
                          level=fe_level,
                          room_temperature=room_temperature, accuracy=1.0)
    t0 = time.perf_counter()
    prm = model.thermal.with_loss(loss_model)
    if loss_model == "integral":
        plane = resolve_substrate(model, x, substrate)
        changes = {k: v for k, v in (("refinement", refinement),
                                     ("extrapolation", extrapolation)) if v is not None}
        prm = dataclasses.replace(
            prm.with_loss(**changes),
            substrate=Substrate.plane(plane[:3], plane[3:]) if plane else None)
    tm = own if prm == model.thermal and loss_model == "chain" else ThermalModel(
        model.mesh, prm, warn_no_plane=substrate is not None, actuators=model.actuators)
    rt = prm.room_temperature if room_temperature is None else float(room_temperature)
    T = tm.solve(x, q, rt)
    return _result(model, T, q, tm, rt, time.perf_counter() - t0)


def _result(model, T, q, tm, rt, wall_time):
    return FixedShapeTemperatures(
        True, "converged", "solved", temperature=T, **crease_measures(T, model.mesh),
        heat_input=float(q.sum()), room_temperature=rt, loss_model=tm.params.loss.model,
        thermal=tm.params, wall_time=wall_time)
