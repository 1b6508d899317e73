"""simulate(..., interruptible=True): Ctrl-C ends the run with the accepted increments as a
partial result, status "interrupted" (issue 21, item 6); without it the exception propagates."""

import numpy as np
import pytest

from simulator import get_case, simulate


def _stop_after(n):
    seen = []

    def progress(done, total):
        seen.append(done)
        if len(seen) > n:
            raise KeyboardInterrupt

    return progress


def test_interrupt_keeps_the_accepted_increments():
    case = get_case("single_fold", thermal_steps=40)
    full = simulate(case.model, case.steps)
    n_before = sum(s.increments for s in full.steps[:-1])
    res = simulate(case.model, case.steps, progress=_stop_after(n_before + 5), interruptible=True)
    assert not res.success and res.status == "interrupted"
    assert [s.status for s in res.steps] == ["converged"] * (len(full.steps) - 1) + ["interrupted"]
    heat = res.steps[-1]
    assert heat.increments == 6 and "6 accepted increments of step 'heat'" in heat.message
    np.testing.assert_array_equal(heat.u_history, full.steps[-1].u_history[:6])   # same path
    np.testing.assert_array_equal(res.state.u, heat.u_history[-1])
    frame = res.to_frame()
    assert frame["step"].max() == n_before + 6


def test_interrupt_propagates_unless_asked():
    case = get_case("single_fold", thermal_steps=10)
    with pytest.raises(KeyboardInterrupt):
        simulate(case.model, case.steps, progress=_stop_after(3))
