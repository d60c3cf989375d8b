"""The run's graze guards as Model Exchange event indicators: a gap that dips below zero and
back inside one of the master's steps shows no sign change of the gap at the step's ends, but
its guard (minus the gap's rate) changes sign across the gap's minimum, so a master that
locates its indicators' roots (FMPy's CVODE) brackets the dip and finds the gap's crossing,
the impact `kanesim run` has there."""
import math

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

from test_events import G, impact_times, jumps, run

DELTA = 1e-6  # the apex above the ceiling: the gap is negative for 2 sqrt(2 DELTA / g) = 0.9 ms
V0 = math.sqrt(2 * G * (1 + DELTA))

CEILING = f"""
model Ceiling "A ball thrown up to {DELTA} m above a ceiling at 1 m, restitution 0.5"
  World world(g = {{0, -9.81, 0}});
  Prismatic lift(axis = {{0, 1, 0}}, q(start = 0), u(start = {V0!r}));
  Body ball(m = 1);
  PlaneContact roof(n = {{0, -1, 0}}, d = -1, restitution = 0.5);
equation
  connect(world.frame_b, lift.frame_a);
  connect(lift.frame_b, ball.frame_a);
  connect(lift.frame_b, roof.frame_a);
  annotation(experiment(StopTime = 1, Interval = 0.01, Tolerance = 1e-10));
end Ceiling;
"""


def test_a_graze_inside_a_master_step_is_the_runs_impact(export, write_model):
    path = write_model("ceiling.mech", CEILING)
    fmu = export(path, fmi=2, kind="me")
    assert validate_fmu(fmu) == []
    md = read_model_description(fmu)
    assert md.numberOfEventIndicators == 2  # the gap and its graze guard
    assert "graze guard" in [v for v in md.modelVariables if v.name == "eventIndicator[2]"][0].description
    ref, events = run(path)
    t_hit = (V0 - math.sqrt(V0 ** 2 - 2 * G)) / G  # y = 1 on the way up (closed form)
    impacts = impact_times(events)
    assert len(impacts) == 1 and impacts[0] == pytest.approx(t_hit, abs=1e-9)
    r = simulate_fmu(fmu, fmi_type="ModelExchange", stop_time=1, output_interval=0.01, relative_tolerance=1e-10,
                     record_events=True, output=["lift.q", "lift.u"])
    got = jumps(r, "lift.u")
    # The master's CVODE locates the gap's crossing to its own error there: ~1e-10 m in the
    # gap over the gap's rate sqrt(2 g DELTA) = 4.4e-3 m/s, about 2e-8 s.
    assert len(got) == 1 and got[0] == pytest.approx(t_hit, abs=1e-7)
    assert np.max(r["lift.q"]) < 1 + 1e-9  # never through the ceiling
    # Then 0.55 s of fall: the located time's 2e-8 s moves the rebound by g dt (1 + e), ~2e-7 m.
    assert r["lift.q"][-1] == pytest.approx(ref["lift.q"][-1], abs=1e-6)
