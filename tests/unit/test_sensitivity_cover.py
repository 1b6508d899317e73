"""Adjoint sensitivities (simulator.sensitivity, theory 12) against central finite differences
on the cases of issue 32's acceptance not covered by ``test_sensitivity.py``, with the chain
heat loss, for every parameter kind: the double fold with contact active, 2 x 2 and 3 x 3-cell
Miura lifters over a substrate and the gripper.

The finite-difference rule and the solver tolerances are ``test_sensitivity.py``'s
(``h = eps^(1/3) max(|p|, scale)``, Newton 1e-15 N, coupling 1e-10 K): each parameter is
moved by +-h, the whole coupled solve re-run from scratch, and the adjoint gradient must agree
with the central difference to a relative 1e-5.

Which crease's power, rest offset or expansion mismatch is moved, and which crease's fold and
temperature are the objectives, is drawn per test from a seeded generator: the seed is
``ETORIGAMI_FD_SEED`` (default 32), so that other combinations can be tried with
``ETORIGAMI_FD_SEED=7 python -m pytest tests/unit/test_sensitivity_cover.py`` (seeds 1, 2,
3, 7, 11, 13, 17, 19, 23, 29 and 32 pass).

The objectives are the quantities the moved parameter moves: the drawn crease's fold (and its
temperature for the heat-balance kinds) and the height of the node that moves most between
p - h and p + h. A derivative many orders below its objective, such as the fold of one gripper
arm per watt on the other (2.2e-6 rad/W, against 51 rad/W for its own crease's), is below the
difference's resolution at this step (the values' noise, 1e-13 of themselves, over h); with
steps 10 to 10^4 times larger the differences converge to the adjoint's (that one: 2.1931812e-6
at h = 0.14 mW against the adjoint's 2.1931766e-6).
"""

from __future__ import annotations

import dataclasses
import os
import zlib

import numpy as np
import pytest
from test_sensitivity import (OPTIONS, RTOL, _bimorph_models, _error, _medium_models, _step,
                              _value)

from simulator import Heat, IntegralLoss, SelfFold, simulate
from simulator.cases import get_case
from simulator.mechanics.equilibrium import equilibrium_system
from simulator.sensitivity import (CreaseTemperature, FoldAngle, NodeCoordinate,
                                   differentiate)

SEED = int(os.environ.get("ETORIGAMI_FD_SEED", "32"))
#: Every parameter of differentiate's kinds: per crease (the crease drawn by the seed) or one.
KINDS = ("power", "rest_offset", "delta_alpha", "E1", "t1", "E2", "t2",
         "medium_conductivity")


def _rng(*key) -> np.random.Generator:
    """The generator of one test: the seed and the test's key (stable across runs)."""
    return np.random.default_rng([SEED, zlib.crc32(repr(key).encode())])


@dataclasses.dataclass(frozen=True)
class Device:
    """A model heated from its self-folded state to a steady coupled state.

    ``pre``: the loading steps between the self-fold and the heating (gravity);
    ``folds``, ``power``: the self-fold angles [rad] and heater powers [W] per crease."""

    name: str
    model: object
    pre: tuple
    folds: dict
    power: dict
    increments: int = 5

    def run(self, model=None, folds=None, power=None):
        steps = [SelfFold(self.folds if folds is None else folds, increments=20), *self.pre,
                 Heat(self.power if power is None else power, increments=self.increments,
                      coupling="settled", coupling_tol=1e-10)]
        result = simulate(self.model if model is None else model, steps, options=OPTIONS)
        assert result.success, result.message
        return result


def _moved(device, name, c):
    """``(gradient key, h, (run kwargs at p + h, at p - h))`` for one parameter."""
    if name == "power":
        p = device.power[c]
        h = _step(p, "power")
        return f"power[{c}]", h, [dict(power={**device.power, c: p + s * h}) for s in (1, -1)]
    if name == "rest_offset":
        p = device.folds[c]
        h = _step(p, "rest_offset")
        return f"rest_offset[{c}]", h, [dict(folds={**device.folds, c: p + s * h})
                                        for s in (1, -1)]
    model = device.model
    if name == "delta_alpha":
        acts = model.actuators
        da = acts.delta_alpha[c]
        h = _step(da, "delta_alpha")
        models = [dataclasses.replace(model, actuators=dataclasses.replace(
            acts, delta_alpha={**acts.delta_alpha, c: da + s * h})) for s in (1, -1)]
        return f"delta_alpha[{c}]", h, [dict(model=m) for m in models]
    if name == "medium_conductivity":
        h, models = _medium_models(model)
    else:
        h, models = _bimorph_models(model, name, name[0])
    return name, h, [dict(model=m) for m in models]


def _check(device, result, kind, moved, objectives, contacts=None):
    """Every objective's adjoint derivative in the parameter ``kind`` of crease ``moved``
    against the central difference, and that of the height of the node the parameter moves
    most (by the central difference); ``contacts``: the active contact pairs, asserted the
    same at p + h and p - h (no switch between)."""
    key, h, (plus, minus) = _moved(device, kind, moved)
    runs = [device.run(**plus), device.run(**minus)]
    if contacts is not None:
        assert [_contact_pairs(r) for r in runs] == [contacts, contacts]
    dz = runs[0].steps[-1].state.u[:, 2] - runs[1].steps[-1].state.u[:, 2]
    objectives = (*objectives, NodeCoordinate(int(np.argmax(np.abs(dz))), "z"))
    grads = [differentiate(result, o, "bimorph" if kind[0] in "Et" else kind)
             for o in objectives]
    assert all(g.success and g.status == "converged" for g in grads), grads[0].message
    fds = [(_value(runs[0], o) - _value(runs[1], o)) / (2 * h) for o in objectives]
    errors = [_error(g.gradient[key], fd) for g, fd in zip(grads, fds)]
    assert max(errors) <= RTOL, f"{key}: " + "; ".join(
        f"{o}: adjoint {g.gradient[key]:.9e} fd {fd:.9e} error {e:.1e}"
        for o, g, fd, e in zip(objectives, grads, fds, errors))


def _contact_pairs(result) -> tuple:
    state = result.steps[-1].state
    ev = equilibrium_system(result.model).evaluate(state.u, state.spring_rest)
    pairs = () if ev.contact_pairs is None else tuple(sorted(map(int, ev.contact_pairs)))
    return ev.n_contacts, pairs


def _draw(device, result, kind) -> tuple:
    """``(crease, objectives)`` of one test: a crease drawn (seeded) among those that fold
    (|fold| > 1 mrad: not a crease between clamped panels), and its fold and, for the kinds
    that act on the heat balance, its temperature."""
    model, state = result.model, result.steps[-1].state
    folding = [int(c) for c in model.mesh.crease_ids
               if abs(FoldAngle(int(c)).terms(model, state.u, state.temperature)[0]) > 1e-3]
    c = int(_rng(device.name, kind).choice(folding))
    objectives = [FoldAngle(c)]
    if kind in ("power", "medium_conductivity"):
        objectives.append(CreaseTemperature(c, "centre_line"))
    return c, objectives


# ------------------------------------------------------------------ double fold, contact active
@pytest.fixture(scope="module")
def double_on_substrate():
    return _double_on_substrate()


def _double_on_substrate():
    """The double fold (gravity) at 0.5 and 0.6 mW: its second panel still rests on the
    substrate (two contact pairs, at its free edge; they open between 1 and 2 mW per
    crease)."""
    case = get_case("double_fold", thermal_steps=5, coupling="settled")
    device = Device("double_fold", case.model, tuple(case.steps[1:-1]), {2: 0.0, 5: 0.0},
                    {2: 0.0005, 5: 0.0006})
    result = device.run()
    contacts = _contact_pairs(result)
    assert contacts[0] == 2
    return device, result, contacts


@pytest.mark.parametrize("kind", KINDS)
def test_double_fold_contact_active(double_on_substrate, kind):
    device, result, contacts = double_on_substrate
    moved, objectives = _draw(device, result, kind)
    _check(device, result, kind, moved, objectives, contacts)


# ------------------------------------------------------------------ Miura lifter and gripper
def _miura(cells=2):
    """The ``cells`` x ``cells`` lifter over its substrate at the case's 9 mW per crease, each
    crease's power varied by up to +-20 % (seeded) so that the creases differ."""
    case = get_case("miura_lifter", substrate=True, cells_x=cells, cells_y=cells)
    (key, power), = case.steps[0].power.items()
    rng = _rng("miura", cells)
    powers = {int(c): float(power * rng.uniform(0.8, 1.2)) for c in key}
    device = Device(f"miura_lifter_{cells}x{cells}", case.model, (), {c: 0.0 for c in powers}, powers,
                    increments=20)
    return device, device.run()


def _gripper():
    """The default gripper with the chain heat loss, after gravity, its four creases heated
    to 1.5-2.5 mW each (seeded)."""
    from design.devices.gripper import GripperDesign, make_gripper_model
    from design.devices.gripper_heat import GripperHeatModel

    model, pre = make_gripper_model(GripperDesign(), heat=GripperHeatModel(loss_model="chain"))
    rng = _rng("gripper")
    creases = [int(c) for c in model.mesh.crease_ids]
    device = Device("gripper", model, tuple(pre), {c: 0.0 for c in creases},
                    {c: float(rng.uniform(1.5e-3, 2.5e-3)) for c in creases})
    return device, device.run()


def _with_integral(make):
    """The device of ``make`` with the integral heat loss (extrapolated levels 3 and 2, the
    monotone conduction, over its substrate) rebuilt at every shape (no correction between
    rebuilds: the end state is the accurate operator's own) on the unrefined sheet (a
    refined sheet's structured sub-triangles sit at the operator's rule thresholds, which the
    differences may cross: theory 12.6)."""
    def device():
        base, _ = make()
        thermal = dataclasses.replace(base.model.thermal, sheet_refinement=1,
                                      loss=IntegralLoss(shape_tol=0.0, correction_tol=0.0))
        out = dataclasses.replace(base, name=base.name + "_integral", model=dataclasses.replace(
            base.model, thermal=thermal), power={c: p / 4 for c, p in base.power.items()})
        # a quarter of the chains' powers: the integral loss runs the creases hotter
        return out, out.run()
    return device


_DEVICES = {"miura_lifter_2x2": _miura, "miura_lifter_3x3": lambda: _miura(3),
            "gripper": _gripper, "miura_lifter_2x2_integral": _with_integral(_miura),
            "gripper_integral": _with_integral(_gripper)}


@pytest.fixture(scope="module", params=sorted(_DEVICES))
def heated(request):
    """Each device of :data:`_DEVICES` at its heated steady state (built once per module)."""
    return _DEVICES[request.param]()


@pytest.mark.parametrize("kind", KINDS)
def test_miura_lifter_and_gripper(heated, kind):
    device, result = heated
    moved, objectives = _draw(device, result, kind)
    _check(device, result, kind, moved, objectives)
