"""A plain pattern whose heating load control gives up is answered with what to change, in
CLI flags (issue 28: Pig, Kirby, Little Bird and Teddy Bear at 10 mm with 200 um creases
run with --crease-width 50 or --unit-scale 1e-1)."""

from types import SimpleNamespace as NS

from design.cli.plain import heat_failure_hint
from simulator.cases import single_fold_model

GAVE_UP = ("step 'heat': increment 1/200 (crease power up to 0.01 mW): gave up at t = 0.23 "
           "after 10 step cuts in a row, 57 in all (increment 4.55e-13): no convergence in 30 "
           "iterations (last residual 2.66e-12 N); the state there is critical, a bifurcation")


def _result(success=False, status="failed", message=GAVE_UP):
    return NS(success=success, status=status, message=message)


def test_the_hint_names_narrower_creases_and_a_larger_sheet_in_cli_flags():
    model = single_fold_model(contact=False, substrate=False)          # 200 um creases
    hint = heat_failure_hint({"heat": "all"}, model, _result(), 1e-2)
    assert "--crease-width 50 (now 200 um)" in hint
    assert "--unit-scale 0.1 (now 0.01)" in hint
    assert "\n" not in hint
    # a file with its own unit: --unit-scale does not apply
    assert "--unit-scale" not in heat_failure_hint({"heat": "all"}, model, _result(), None)


def test_no_hint_where_it_does_not_apply():
    model = single_fold_model(contact=False, substrate=False)
    assert heat_failure_hint({}, model, _result(), 1e-2) == ""            # not a plain pattern
    assert heat_failure_hint({"heat": "all"}, model, _result(True, "converged", "converged"),
                             1e-2) == ""
    assert heat_failure_hint({"heat": "all"}, model,
                             _result(status="panel_crossing", message="crease 3 passed 180 deg"),
                             1e-2) == ""
