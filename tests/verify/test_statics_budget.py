"""The statics' contact search runs under the call's budget (issue 40): RBE, CRA and the tilt scan.

A spent budget is a fact, not a clock reading: ``Budget(limit=1e-9, started=0.0)`` and
``time_limit=1e-9`` are spent before the first check on any machine.
"""

import numpy as np
import pytest
import trimesh

from interlock.blocks import Assembly
from interlock.verify.budget import Budget, TimeLimitReached
from interlock.verify.statics import cra, rbe, thickness, tilt_scan
from interlock.verify.statics.equilibrium import CONTACTS_OUT_OF_TIME, EquilibriumSystem

SPENT = Budget(limit=1e-9, started=0.0)
DOWN = np.array([0.0, 0.0, -1.0])


def _stack():
    cubes = [trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in (0, 1)]
    return Assembly.from_meshes(cubes, frame=[0])


def test_thickness_stops_when_the_budget_is_spent():
    # a file read as one mesh per block has a hull per block to build: 0.7 s on a 300-block hexagon
    assert thickness(_stack()).tolist() == [1.0, 1.0]
    with pytest.raises(TimeLimitReached, match="the contacts"):
        thickness(_stack(), SPENT)


def test_a_system_without_contacts_for_lack_of_time_never_answers():
    # not "no contacts carry the load" (unstable): whatever budget it is solved under, it is out of time
    system = EquilibriumSystem.build(_stack(), 0.5, 1.0, None, "paper", 8, None, SPENT)
    assert system.contacts == () and system.parameters["contacts"]["model"] == CONTACTS_OUT_OF_TIME
    with pytest.raises(TimeLimitReached, match="the contacts"):
        system.feasible(DOWN)
    found = EquilibriumSystem.build(_stack(), 0.5, 1.0, None, "paper", 8, None, Budget.start(600))
    assert len(found.contacts) == 1 and found.feasible(DOWN)[0] is True


def test_rbe_and_cra_out_of_time_do_not_search_contacts():
    result = rbe(_stack(), 0.5, time_limit=1e-9)
    assert result.stable is None and result.message == "time limit reached in the contacts"
    assert result.contacts == ()
    result = cra(_stack(), 0.5, time_limit=1e-9)  # CRA searched every contact first, then said "out of time"
    assert result.status == "inconclusive" and result.message == "time limit reached in the contacts"
    assert result.contacts == () and result.parameters["contacts"]["model"] == CONTACTS_OUT_OF_TIME


@pytest.mark.parametrize("method", ["rbe", "cra"])
def test_the_tilt_scan_out_of_time_searches_no_contacts(method):
    scan = tilt_scan(_stack(), "x", 0.5, method=method, time_limit=1e-9)
    assert scan.status == "inconclusive" and scan.undecided == ((0.0, "time limit reached in the contacts"),)


def test_the_cra_tilt_scan_takes_hold_out():
    # stability --method cra --no-hold-out --tilt-axis x passed hold_out to the problem's build: a TypeError
    scan = tilt_scan(_stack(), "x", 0.5, method="cra", cra_options={"hold_out": False})
    assert scan.status == "decided" and abs(scan.angle - 26.57) < 0.2
