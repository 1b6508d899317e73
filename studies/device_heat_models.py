"""The paper's devices with both heat-loss models, checked against the 3-D FE (issue 19, item 5).

Question
--------
The chain model (theory 4.3-4.4: beta = 20 deg, t_env = 1.5 L, N = 10, fitted by the paper)
needs 42.4 mW (cycle 4) and 23.4 mW (cycle 9) for the gripper's full function, where the
paper measured 29.8 and 21.6 mW on devices near those designs. What does the boundary-integral
model (theory 4.7, nothing fitted) give? How differently do the double fold (fold 2 hotter
than fold 1) and the Miura lifter on its substrate fold and heat with the two models, and
where they differ by more than 10 %, which one is closer to the 3-D finite-element reference
(docs/heat_fe.md)?

Method
------
* Models: each device's own chain parameters, and the same model with
  ``loss=IntegralLoss()`` (its defaults: ``refinement`` m = 3,
  Richardson-extrapolated from m = 2 and 3, corrected between rebuilds; theory 4.7) over
  the isothermal substrate plane: the plane of the model's thermal boundary panel (the
  substrate), as the 3-D FE uses it (``substrate="model"``); all with the chains' T3 sheet
  conduction (:data:`CONDUCTION`; the integral loss's default is the monotone one of theory
  4.9), so that they differ in the heat loss only.
* Gripper: the coordinate-descent designs of cycles 4 and 9
  (``results/gripper_optimization/gripper_optimization.csv``), evaluated as in that study
  (``evaluate_gripper``, bisect, the :class:`~design.GripperProblem` defaults) with
  ``GripperHeatModel(loss_model=...)``; the integral model also at m = 2 without extrapolation
  (the default before 6 Dec 2026, 4-7 % hot on folded shapes). Full-function power =
  2 base creases x assembly power + 2 arm creases x grip power (the paper's measured
  quantity). ``--quick``: cycle 9 only, no m = 2.
* Double fold: ``get_case("double_fold")`` (both creases to 10 mW, 250 increments; quick 30).
  Miura lifter: ``get_case("miura_lifter", cells_x=4, cells_y=2, substrate=True)`` (9 mW per
  crease, 250 increments; quick: 2 x 2 cells, 30 increments).
* 3-D FE check, for every case with a quantity differing by more than 10 %: at the final
  (stopping) state of each model, ``solve_fe3d`` on that shape with the same crease powers
  (level 1; quick 0), and both models' steady temperatures on the same shape and powers. A
  temperature is judged on the model's own final state (model against FE, same shape);
  a mechanical quantity (fold angle, lift, power) by the heated creases' actuation
  temperature rise at the model's own final state (folding follows from it). The gripper's
  powers are also converted to an FE-implied power (the heat problem is linear at a fixed
  shape and the mechanics needs the same actuation temperature): assembly
  ``P_FE = P dT_model / dT_FE`` of the base creases at the assembly state; grip by
  superposing FE solves of each circuit at the grip state, so that the arm creases reach the
  model's actuation temperature with the base at its FE-implied power (0 where the base
  circuit alone makes them warm enough).

Outputs (``results/device_heat_models/``)
-----------------------------------------
``device_heat_models.csv``: one long table, the ``table`` column tells the row kind:

* ``gripper`` - one row per design and model: ``cycle``, ``model`` (``chain``,
  ``integral``), ``integral_refinement [-]``, the design ``W [um]``, ``La [um]``, ``L1 [um]``,
  ``L2 [um]``, ``assembly_power [mW]``, ``grip_power [mW]`` (per heated crease),
  ``full_function_power [mW]``, ``measured_power [mW]`` (the paper's device),
  ``descent_power [mW]`` (chain rows: the full-function power of the coordinate descent's
  table, which the chain row reproduces),
  ``assembly_temperature [degC]``, ``grip_temperature [degC]`` (centre-line mean of the
  hottest heated crease at the stopping power), ``success``, ``status``, ``message``,
  ``wall_time [s]``.
* ``sweep`` - ``case`` (``double_fold``, ``miura_lifter``), ``model``, ``step``,
  ``power [mW]`` (per crease), ``fold``/``crease`` and ``fold_angle [deg]``,
  ``temperature [degC]`` (actuation), ``temperature_centre [degC]`` (double fold), or
  ``lift [um]`` (Miura).
* ``fe`` - one row per FE check, crease and shape: ``case``, ``shape`` (whose final state),
  ``point`` (gripper: ``assembly``/``grip``; else ``final``), ``crease``, ``power [mW]``,
  ``chain``/``integral``/``fe`` ``_temperature [degC]`` (actuation temperature, the same
  shape and powers), ``chain_error [%]``, ``integral_error [%]`` (of the rise over room
  temperature, against the FE), ``fe_level``, ``fe_dofs``, ``fe_status``.
* ``comparison`` - one row per reported quantity: ``case``, ``quantity``, ``unit``,
  ``chain``, ``integral``, ``difference [%]`` (integral / chain - 1), ``over_10pct``,
  ``fe_chain_shape``, ``fe_integral_shape`` (the FE value of the quantity, or the FE-implied
  power, on each model's final shape), ``chain_fe_error [%]``, ``integral_fe_error [%]``,
  ``closer`` (``chain``, ``integral``; empty where the models agree within 10 %), ``basis``.
  A simulation that fails is kept as data: a row ``quantity = "run"`` with its ``message``
  (cases), or the ``gripper`` row's ``success``/``message``; its quantities are not compared.

Figure: ``device_heat_models.png``: (a) gripper full-function power (chain, integral,
FE-implied, measured), (b) double-fold fold angles and (c) Miura lift vs power with both models,
(d) each model's crease temperature rise against the 3-D FE on the same shapes.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time

import numpy as np
import pandas as pd

from design import GripperDesign, GripperHeatModel, evaluate_gripper, make_gripper_model
from design.devices import ARM_CREASES, BASE_CREASES
from simulator import IntegralLoss, Substrate, simulate
from simulator.fe import solve_fe3d
from simulator.thermal import ThermalModel, crease_limit_temperatures, crease_temperatures
from simulator.cases import get_case
from studies._common import progress_bar, study_main
from studies.gripper_optimization import PAPER_DEVICES
from studies.gripper_shapes import _cd_csv, _cd_cycles, gripper_states
from studies.miura_lifter import lift_um

__all__ = ["main", "plot", "run", "integral_model"]

logger = logging.getLogger(__name__)

NAME = "device_heat_models"
MODELS = ("chain", "integral")
#: Differences above this fraction are checked against the 3-D FE.
THRESHOLD = 0.10
FE_LEVEL, FE_LEVEL_QUICK = 1, 0
#: The integral model's default refinement (ThermalParameters), the one compared and plotted.
DEFAULT_M = 3
#: Integral refinements of the gripper evaluations (full run; quick: the default only).
GRIPPER_REFINEMENTS = (DEFAULT_M, 2)
STEPS, STEPS_QUICK = 250, 30
MIURA, MIURA_QUICK = dict(cells_x=4, cells_y=2), dict(cells_x=2, cells_y=2)
FOLDS = {1: 2, 2: 5}                      # double fold: fold number -> crease id
#: The sheet conduction of every model here: the chains' T3, which the FE of the chain model
#: uses too, so that the models differ in the heat loss only (not the integral loss's default
#: monotone conduction, theory 4.9).
CONDUCTION = "t3"
#: The sheet on the mesh triangles for every model (theory 4.11): the FE meshes the medium
#: around the same P1 sheet, so the models differ in the heat loss only.
SHEET = 1
GRIP_STATE_INCREMENTS = 10
POWER, TEMP, TEMP_CL = "power [mW]", "temperature [degC]", "temperature_centre [degC]"


# ----------------------------------------------------------------------------- models
def integral_model(model, refinement: int = DEFAULT_M):
    """``model`` with the integral heat loss (theory 4.7) over its substrate, the plane of its
    thermal boundary panels (``Substrate()``, as ``solve_fe3d(substrate="model")`` takes it),
    and the model's own sheet conduction (the chains' T3, which the FE of the chain model uses
    too; not the integral loss's default monotone one, theory 4.9)."""
    thermal = dataclasses.replace(model.thermal, loss=IntegralLoss(refinement=refinement),
                                  substrate=Substrate(),
                                  conduction=model.thermal.conduction_method,
                                  sheet_refinement=SHEET)
    return dataclasses.replace(model, thermal=thermal)


def _actuation(mesh, T) -> np.ndarray:
    """(C,) actuation temperatures [degC] (theory 5.1) of nodal temperatures ``T`` (n,)."""
    return crease_temperatures(T, mesh)


def _centre(mesh, T) -> np.ndarray:
    """(C,) centre-line means (A, B, Ctr) [degC] of nodal temperatures ``T``: the measure of
    the 1.2 T_g limit (:func:`simulator.thermal.crease_limit_temperatures`)."""
    return crease_limit_temperatures(T, mesh)


def _rise_error(value, fe, room):
    """Error of a temperature's rise over ``room`` against the FE's [%]."""
    return 100 * ((value - room) / (fe - room) - 1)


# ----------------------------------------------------------------------------- FE checks
def _three_models(models, x, q, level):
    """Nodal temperatures (chain, integral, FE) on positions ``x`` for nodal heat ``q``."""
    chain, integral = (ThermalModel(models[m].mesh, models[m].thermal).solve(x, q)
                       for m in MODELS)
    fe = solve_fe3d(models["chain"], heat=q, positions=x, level=level)
    if not fe.success:
        raise RuntimeError(f"3-D FE failed: {fe.message}")
    return {"chain": chain, "integral": integral, "fe": fe.temperature}, fe


def _fe_rows(case, shape, point, models, T, fe, creases, power) -> list:
    mesh, room = models["chain"].mesh, models["chain"].thermal.room_temperature
    rows = []
    for c in creases:
        r = mesh.crease_row_of(c)
        t = {m: float(_actuation(mesh, T[m])[r]) for m in T}
        rows.append({"table": "fe", "case": case, "shape": shape, "point": point,
                     "crease": c, POWER: 1e3 * float(power[r]),
                     **{f"{m}_temperature [degC]": t[m] for m in T},
                     **{f"{m}_error [%]": _rise_error(t[m], t["fe"], room) for m in MODELS},
                     "fe_level": fe.mesh.level, "fe_dofs": fe.mesh.n_dofs,
                     "fe_status": fe.status})
    return rows


# ----------------------------------------------------------------------------- gripper
def _designs(quick):
    cycles = _cd_cycles(_cd_csv())
    chosen = PAPER_DEVICES[1:] if quick else PAPER_DEVICES
    out = []
    for cycle, measured in chosen:
        row = cycles[cycles["cycle"] == cycle].iloc[0]
        geometry = {v: 1e-6 * float(row[f"{v} [um]"]) for v in ("W", "La", "L1", "L2")}
        descent = 2 * float(row["assembly_power [mW]"]) + 2 * float(row["grip_power [mW]"])
        out.append((cycle, (measured, descent), geometry))
    return out


def _evaluate(cycle, powers, geometry, model, m):
    """Evaluate one design with one model; ``powers``: (measured, the descent's full-function
    power [mW]). Returns (GripperResult, ``gripper`` row)."""
    t0 = time.perf_counter()
    res = evaluate_gripper(GripperDesign(**geometry), heat=GripperHeatModel(
        loss_model=model, integral_refinement=m, conduction=CONDUCTION, sheet_refinement=SHEET))
    d = res.to_dict()
    full = (2e3 * (res.assembly.power_per_crease + res.grip.power_per_crease)
            if res.success else None)
    return res, {"table": "gripper", "cycle": cycle, "model": model,
                 "integral_refinement [-]": m if model == "integral" else None,
                 **{f"{k} [um]": 1e6 * v for k, v in geometry.items()},
                 "assembly_power [mW]": d["assembly_power [mW]"],
                 "grip_power [mW]": d["grip_power [mW]"], "full_function_power [mW]": full,
                 "measured_power [mW]": powers[0],
                 "descent_power [mW]": powers[1] if model == "chain" else None,
                 "assembly_temperature [degC]": res.assembly.temperature,
                 "grip_temperature [degC]": res.grip.temperature, "success": res.success,
                 "status": res.status, "message": res.message,
                 "wall_time [s]": time.perf_counter() - t0}


def _gripper_fe(cycle, geometry, results, level):
    """FE checks at both models' stopping states.

    Returns the ``fe`` rows and, per shape (model), {quantity: (that model's value on its
    re-simulated stopping state, the FE's value or FE-implied power there)}, powers in mW.
    """
    models = {m: make_gripper_model(GripperDesign(**geometry), heat=GripperHeatModel(
        loss_model=m, conduction=CONDUCTION, sheet_refinement=SHEET))[0] for m in MODELS}
    case, rows, checks = f"gripper cycle {cycle}", [], {}
    room = models["chain"].thermal.room_temperature
    for shape, res in results.items():
        pa, pg = res.assembly.power_per_crease, res.grip.power_per_crease
        model, states = gripper_states(GripperDesign(**geometry), pa, pg, GRIP_STATE_INCREMENTS,
                                       GripperHeatModel(loss_model=shape, conduction=CONDUCTION,
                                                        sheet_refinement=SHEET))
        mesh = model.mesh
        tm = ThermalModel(mesh, model.thermal)
        base, arm = ([mesh.crease_row_of(c) for c in cs] for cs in (BASE_CREASES, ARM_CREASES))
        st_a, st_g = states["assembly"].state, states["grip"].state
        T, fe = _three_models(models, mesh.nodes + st_a.u,
                              tm.heat_vector(st_a.crease_power), level)
        rows += _fe_rows(case, shape, "assembly", models, T, fe, BASE_CREASES,
                         st_a.crease_power)
        rise = {m: _actuation(mesh, T[m]) - room for m in T}
        pa_fe = pa * rise[shape][base].mean() / rise["fe"][base].mean()
        checks[shape] = {"assembly temperature": tuple(
            float(_centre(mesh, T[m])[base].max()) for m in (shape, "fe"))}
        # the grip state by circuits: base-only and arm-only heat, superposed
        on_base = np.isin(np.arange(mesh.n_creases), base)
        q_base = tm.heat_vector(np.where(on_base, st_g.crease_power, 0.0))
        q_arm = tm.heat_vector(np.where(on_base, 0.0, st_g.crease_power))
        Tb, _ = _three_models(models, mesh.nodes + st_g.u, q_base, level)
        Ta, fe = _three_models(models, mesh.nodes + st_g.u, q_arm, level)
        T = {m: Tb[m] + Ta[m] - room for m in Tb}
        rows += _fe_rows(case, shape, "grip", models, T, fe, BASE_CREASES + ARM_CREASES,
                         st_g.crease_power)
        need = _actuation(mesh, T[shape])[arm].mean() - room
        from_base = (_actuation(mesh, Tb["fe"])[arm].mean() - room) * pa_fe / pa
        per_watt = (_actuation(mesh, Ta["fe"])[arm].mean() - room) / pg
        pg_fe = max((need - from_base) / per_watt, 0.0)
        checks[shape].update({
            "grip temperature": tuple(float(_centre(mesh, T[m])[arm].max())
                                      for m in (shape, "fe")),
            "assembly power per crease": (1e3 * pa, 1e3 * pa_fe),
            "grip power per crease": (1e3 * pg, 1e3 * pg_fe),
            "full-function power": (2e3 * (pa + pg), 2e3 * (pa_fe + pg_fe))})
    return rows, checks


_GRIPPER_QUANTITIES = {"full-function power": ("mW", "full_function_power [mW]"),
                       "assembly power per crease": ("mW", "assembly_power [mW]"),
                       "grip power per crease": ("mW", "grip_power [mW]"),
                       "assembly temperature": ("degC", "assembly_temperature [degC]"),
                       "grip temperature": ("degC", "grip_temperature [degC]")}


def _gripper_comparison(cycle, rows, checks, room) -> list:
    """Rows ``comparison`` of one gripper design (the evaluations at the default m)."""
    by_model = {r["model"]: r for r in rows
                if r["cycle"] == cycle and r["integral_refinement [-]"] in (None, DEFAULT_M)}
    out = []
    for quantity, (unit, col) in _GRIPPER_QUANTITIES.items():
        values = {m: by_model[m][col] for m in MODELS}
        fe = {m: checks[m][quantity] for m in MODELS} if checks else None
        errors = distance = None
        if fe:
            distance = {m: abs(fe[m][0] - fe[m][1]) for m in MODELS}
            errors = {m: (_percent(fe[m][0], fe[m][1]) if unit == "mW"
                          else _rise_error(fe[m][0], fe[m][1], room)) for m in MODELS}
        basis = ("the model's power against the FE-implied power on its stopping shape"
                 if unit == "mW" else "the quantity on each model's stopping shape against "
                 "the FE there")
        out.append(_verdict(f"gripper cycle {cycle}", quantity, unit, values,
                            None if fe is None else {m: fe[m][1] for m in MODELS}, errors,
                            basis, distance))
    return out


def _percent(value, ref):
    """``value / ref - 1`` [%], None where ``ref`` is 0 (e.g. an FE-implied power of 0)."""
    return 100 * (value / ref - 1) if ref else None


def _verdict(case, quantity, unit, values, fe, errors, basis, distance=None) -> dict:
    """One ``comparison`` row: both models, the FE on each model's shape, which is closer
    (by the smaller |error|, or by ``distance`` {model: |value - FE|} where an error is
    undefined)."""
    chain, integral = values["chain"], values["integral"]
    row = {"table": "comparison", "case": case, "quantity": quantity, "unit": unit,
           "chain": chain, "integral": integral}
    if chain is None or integral is None or not (math.isfinite(chain)
                                                 and math.isfinite(integral)):
        return {**row, "over_10pct": None}          # a model failed: no comparison
    over = _differs(chain, integral)
    row.update({"difference [%]": 100 * (integral / chain - 1) if chain else None,
                "over_10pct": over})
    if over and fe is not None:
        row.update({"fe_chain_shape": fe["chain"], "fe_integral_shape": fe["integral"],
                    "chain_fe_error [%]": errors["chain"],
                    "integral_fe_error [%]": errors["integral"],
                    "closer": min(MODELS, key=lambda m: abs(errors[m]) if None not in
                                  errors.values() else distance[m]), "basis": basis})
    return row


def _run_gripper(quick, level, progress):
    rows, fe_rows, comparison = [], [], []
    refinements = GRIPPER_REFINEMENTS[:1] if quick else GRIPPER_REFINEMENTS
    for cycle, powers, geometry in progress_bar(_designs(quick), enabled=progress,
                                                desc="gripper designs"):
        results = {}
        for model in MODELS:
            for m in refinements if model == "integral" else (DEFAULT_M,):
                res, row = _evaluate(cycle, powers, geometry, model, m)
                rows.append(row)
                if m == DEFAULT_M:
                    results[model] = res
        checks = None
        for model, res in results.items():
            if not res.success:                    # a finding, kept as data
                logger.warning("gripper cycle %s with the %s model: %s", cycle, model,
                               res.message)
        if all(r.success for r in results.values()):
            more, checks = _gripper_fe(cycle, geometry, results, level)
            fe_rows += more
        room = make_gripper_model(GripperDesign(**geometry), heat=GripperHeatModel(
            loss_model="chain"))[0].thermal.room_temperature
        comparison += _gripper_comparison(cycle, rows, checks, room)
    return pd.DataFrame(rows), pd.DataFrame(fe_rows), pd.DataFrame(comparison)


# ----------------------------------------------------------------------------- cases
def _cases(quick):
    steps = STEPS_QUICK if quick else STEPS
    return {"double_fold": get_case("double_fold", thermal_steps=steps),
            "miura_lifter": get_case("miura_lifter", **(MIURA_QUICK if quick else MIURA),
                                     substrate=True, thermal_steps=steps)}


def _sweep(name, case, model, res) -> pd.DataFrame:
    mesh, h = case.model.mesh, res.history
    if name == "miura_lifter":
        return pd.DataFrame({"table": "sweep", "case": name, "model": model,
                             "step": np.arange(len(h["power"])),
                             POWER: 1e3 * h["power"].max(axis=1), "lift [um]": lift_um(case, res)})
    recs = np.flatnonzero(h["stage_name"] == "heat")
    if not len(recs):                              # failed before heating
        return pd.DataFrame()
    recs = np.r_[recs[0] - 1, recs]
    parts = []
    for fold, crease in FOLDS.items():
        r = mesh.crease_row_of(crease)
        parts.append(pd.DataFrame({
            "table": "sweep", "case": name, "model": model, "step": recs, "fold": fold,
            "crease": crease, POWER: 1e3 * h["power"][recs, r],
            "fold_angle [deg]": np.degrees(res.fold_angle[recs, r]),
            TEMP: res.crease_temperature[recs, r],
            TEMP_CL: res.crease_temperature_centre_line[recs, r]}))
    return pd.concat(parts, ignore_index=True)


def _quantities(name, case, res) -> dict:
    """The case's reported quantities {(quantity, unit): value} at the final state."""
    mesh, T = case.model.mesh, res.state.temperature
    if name == "double_fold":
        out = {}
        for fold, crease in FOLDS.items():
            r = mesh.crease_row_of(crease)
            out[(f"fold {fold} angle", "deg")] = float(np.degrees(res.fold_angle[-1, r]))
            out[(f"fold {fold} actuation temperature", "degC")] = float(_actuation(mesh, T)[r])
            out[(f"fold {fold} centre-line temperature", "degC")] = float(_centre(mesh, T)[r])
        return out
    return {("lift of the free end", "um"): float(lift_um(case, res)[-1]),
            ("mean |fold angle|", "deg"): float(np.degrees(np.abs(res.fold_angle[-1])).mean()),
            ("mean actuation temperature", "degC"): float(_actuation(mesh, T).mean()),
            ("hottest centre-line temperature", "degC"): float(_centre(mesh, T).max())}


def _fe_value(name, quantity, mesh, T):
    """The FE's value of a temperature quantity (nodal FE temperatures ``T``), else None."""
    if not quantity.endswith("temperature"):
        return None
    if name == "double_fold":
        r = mesh.crease_row_of(FOLDS[int(quantity.split()[1])])
        return float((_actuation if "actuation" in quantity else _centre)(mesh, T)[r])
    if quantity.startswith("mean"):
        return float(_actuation(mesh, T).mean())
    return float(_centre(mesh, T).max())


def _run_cases(quick, level, progress):
    sweeps, fe_rows, comparison = [], [], []
    for name, case in progress_bar(_cases(quick).items(), enabled=progress, desc="cases"):
        models = {"chain": case.model, "integral": integral_model(case.model)}
        results, values = {}, {}
        for m, model in models.items():
            res = simulate(model, case.steps)
            sweeps.append(_sweep(name, case, m, res))
            if not res.success:                    # a finding, kept as data
                logger.warning("%s with the %s model failed: %s", name, m, res.message)
                comparison.append({"table": "comparison", "case": name, "quantity": "run",
                                   "unit": "-", "over_10pct": None,
                                   "message": f"the {m} model failed: {res.message}"})
                continue
            results[m], values[m] = res, _quantities(name, case, res)
        if len(values) < len(MODELS):
            continue
        checked = any(_differs(values["chain"][k], values["integral"][k]) for k in values["chain"])
        fe = {}
        if checked:
            mesh = case.model.mesh
            for shape, res in results.items():
                tm = ThermalModel(mesh, models[shape].thermal)
                x = mesh.nodes + res.state.u
                T, info = _three_models(models, x, tm.heat_vector(res.state.crease_power), level)
                fe[shape] = {**T, "power": res.state.crease_power}
                fe_rows += _fe_rows(name, shape, "final", models, T, info, mesh.crease_ids,
                                    res.state.crease_power)
        comparison += _comparison(name, case, values, fe)
    return (pd.concat(sweeps, ignore_index=True), pd.DataFrame(fe_rows),
            pd.DataFrame(comparison))


def _differs(a, b) -> bool:
    return abs(b / a - 1) > THRESHOLD if a else b != 0


def _comparison(name, case, values, fe) -> list:
    """Rows ``comparison`` of a case: both models, the FE on each final shape, the verdict."""
    mesh, room = case.model.mesh, case.model.thermal.room_temperature
    heat_err = {m: float(np.mean(np.abs(_rise_error(
        _actuation(mesh, fe[m][m])[heated], _actuation(mesh, fe[m]["fe"])[heated], room))))
        for m, heated in ((m, np.flatnonzero(fe[m]["power"] > 0)) for m in fe)}
    rows = []
    for quantity, unit in values["chain"]:
        pair = {m: values[m][(quantity, unit)] for m in MODELS}
        ref = err = None
        if fe:
            ref = {m: _fe_value(name, quantity, mesh, fe[m]["fe"]) for m in MODELS}
            if ref["chain"] is not None:
                err = {m: _rise_error(pair[m], ref[m], room) for m in MODELS}
                basis = "the quantity on each model's final shape against the FE there"
            else:
                ref, err = {m: None for m in MODELS}, heat_err
                basis = ("mean |error| of the heated creases' actuation temperature rise at "
                         "each model's final state (folding follows from it)")
        rows.append(_verdict(name, quantity, unit, pair, ref, err, basis if fe else ""))
    return rows


def run(quick: bool = False, progress: bool = True) -> pd.DataFrame:
    """Gripper designs, double fold and Miura lifter with both models; see the docstring."""
    level = FE_LEVEL_QUICK if quick else FE_LEVEL
    gripper, fe_g, comp_g = _run_gripper(quick, level, progress)
    sweeps, fe_c, comp_c = _run_cases(quick, level, progress)
    df = pd.concat([gripper, sweeps, fe_g, fe_c, comp_g, comp_c], ignore_index=True)
    first = ["table", "case", "cycle", "model", "quantity"]
    return df[first + [c for c in df.columns if c not in first]]


# ----------------------------------------------------------------------------- plot
def plot(df: pd.DataFrame):
    """The summary figure (a)-(d); see the module docstring."""
    from matplotlib.figure import Figure

    from studies._device_heat_plots import plot_gripper, plot_parity, plot_sweeps
    from studies.plotting import environment_note, note_assumptions

    fig = Figure(figsize=(12.5, 9.5), layout="constrained")
    (ax_g, ax_f), (ax_l, ax_p) = fig.subplots(2, 2)
    parts = {t: df[df["table"] == t] for t in ("gripper", "sweep", "fe", "comparison")}
    plot_gripper(ax_g, parts["gripper"], parts["comparison"])
    plot_sweeps(ax_f, ax_l, parts["sweep"], parts["comparison"])
    plot_parity(ax_p, parts["fe"])
    fig.suptitle("The devices with the chain and the integral heat-loss model, checked "
                 "against the 3-D FE", fontsize="large")
    levels = sorted(parts["fe"]["fe_level"].dropna().astype(int).unique())
    note_assumptions(fig, environment_note("air", 0.026, 0, extra=[
        "heat loss: the chains (the paper's: t_env = 1.5 x the mean arm length on the "
        "gripper, beta = 20 deg) beside the integral model (calibration-free: m = "
        f"{DEFAULT_M}, extrapolated, image of the substrate plane, the boundary panel's); "
        "sheet conduction T3 for both", f"3-D FE level {', '.join(map(str, levels))}",
        "FE-implied power: the model's actuation temperatures reached with the FE's heat "
        "loss (linear heat at the stopping shape; mean over both models' shapes)",
        "measured: the paper's devices near cycles 4 and 9"]))
    return fig


def main(argv=None):
    return study_main(NAME, __doc__, run, plot, argv)


if __name__ == "__main__":
    main()
