#!/usr/bin/env python3
"""Stepping from Python (docs/benchmarks.md "Stepping from Python"; issue 42's targets).

1. The overhead of one sim.step over the integration it does: the wall time of a loop of
   steps in Python minus the time spent inside the C++ Simulator::AdvanceTo
   (sim.stats()["advance_seconds"]): the call, the inputs dict, the GIL release, the reads
   of the outputs the controller uses. Target <= 5 us.
2. A PD-controlled two-link arm stepped at 1 kHz for 10 s from Python against the same PD
   law written in the .mech and integrated whole (one advance_to). Target <= 2x.
3. The same controller as a sampled-data law in the .mech (the law sampled every 1 ms and
   held: a zero-order hold), run whole: kanesim has no discrete variables or sample() yet,
   so the held torques are the coordinates of two force-free "hold" joints and the next
   sampling instant a third one's, reinit'ed by a `when time > ...` clause (docs/events.md):
   10 000 events located by root finding, the solver restarted after each.

Usage: PYTHONPATH=build/python python3 bench/stepping.py [--integrator dop853] [--rtol 1e-6]
"""
import argparse
import time

import kanesim

ARM = """
model Arm
  {decls}
  World world(g = {{0, -9.81, 0}});
  Revolute shoulder(axis = {{0, 0, 1}}, q(start = -1.2), u(start = 0));
  Rod upper(L = 0.6, m = 2);
  Revolute elbow(axis = {{0, 0, 1}}, q(start = 0.4), u(start = 0));
  Rod fore(L = 0.5, m = 1);
equation
  connect(world.frame_b, shoulder.frame_a);
  connect(shoulder.frame_b, upper.frame_a);
  connect(upper.frame_b, elbow.frame_a);
  connect(elbow.frame_b, fore.frame_a);
  shoulder.tau = {tau1};
  elbow.tau = {tau2};
end Arm;
"""
REF1, REF2 = 0.3, -0.5

# The sampled law: hold joints store the torques (N.m per radian), a clock joint the next
# sampling instant (s per radian); nothing turns them (their bodies' mass centres are on
# their axes), so they keep their values. Revolute about z like the arm's joints, so the
# model keeps the arm's planar recursion and an f evaluation costs what the arm's does.
HOLD = """
  parameter Real held(unit = "N.m/rad") = 1;
  parameter Real tick(unit = "s/rad") = 1;
  Revolute hold1(axis = {{0, 0, 1}}, q(start = {h1}));
  Body m1(m = 1, I = identity(3));
  Revolute hold2(axis = {{0, 0, 1}}, q(start = {h2}));
  Body m2(m = 1, I = identity(3));
  Revolute clock(axis = {{0, 0, 1}}, q(start = 0.001));
  Body m3(m = 1, I = identity(3));
equation
  connect(world.frame_b, hold1.frame_a);
  connect(hold1.frame_b, m1.frame_a);
  connect(world.frame_b, hold2.frame_a);
  connect(hold2.frame_b, m2.frame_a);
  connect(world.frame_b, clock.frame_a);
  connect(clock.frame_b, m3.frame_a);
  when time > tick * clock.q then
    reinit(hold1.q, ({law1}) / held);
    reinit(hold2.q, ({law2}) / held);
    reinit(clock.q, clock.q + 0.001 / tick);
  end when;
"""


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--integrator", default="dop853")
    ap.add_argument("--rtol", type=float, default=1e-6)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--kp", type=float, default=60.0)
    ap.add_argument("--kd", type=float, default=8.0)
    a = ap.parse_args()
    KP, KD = a.kp, a.kd
    law1 = f"{KP} * ({REF1} - shoulder.q) - {KD} * shoulder.u"
    law2 = f"{KP} * ({REF2} - elbow.q) - {KD} * elbow.u"
    in_mech = kanesim.loads(ARM.format(decls="", tau1=law1, tau2=law2))
    # The held torques start at the law's value at the start state (q = -1.2, 0.4; u = 0).
    hold = HOLD.format(h1=KP * (REF1 + 1.2), h2=KP * (REF2 - 0.4), law1=law1, law2=law2)
    sampled = kanesim.loads(ARM.replace("equation\n", hold.replace("{", "{{").replace("}", "}}"), 1)
                            .format(decls="", tau1="held * hold1.q", tau2="held * hold2.q"))
    plant = kanesim.loads(ARM.format(decls="input Real t1; input Real t2;", tau1="t1", tau2="t2"))
    outs = ["shoulder.q", "shoulder.u", "elbow.q", "elbow.u"]
    whole, stepped, overhead, bare, inside, zoh = [], [], [], [], [], []
    for _ in range(a.repeat):
        # 1. One step's own cost: a loop of steps with an inputs dict, nothing read.
        b = plant.simulator(rtol=a.rtol, integrator=a.integrator, outputs=outs)
        fixed = {"t1": 1.0, "t2": -0.5}
        t0 = time.perf_counter()
        for k in range(10000):
            b.step(1e-3, fixed)
        bare.append((time.perf_counter() - t0 - b.stats()["advance_seconds"]) / 10000)
        s = in_mech.simulator(rtol=a.rtol, integrator=a.integrator, outputs=outs)
        t0 = time.perf_counter()
        s.advance_to(10.0)
        whole.append(time.perf_counter() - t0)
        p = plant.simulator(rtol=a.rtol, integrator=a.integrator, outputs=outs)
        t0 = time.perf_counter()
        for k in range(1, 10001):
            q1, u1, q2, u2 = p.outputs
            p.advance_to(k * 1e-3, {"t1": KP * (REF1 - q1) - KD * u1, "t2": KP * (REF2 - q2) - KD * u2})
        dt = time.perf_counter() - t0
        stepped.append(dt)
        inside.append(p.stats()["advance_seconds"])
        evals = (s.stats()["rhs_evals"], p.stats()["rhs_evals"], s.stats()["steps"], p.stats()["steps"])
        overhead.append((dt - p.stats()["advance_seconds"]) / 10000)
        diff = max(abs(x - y) for x, y in zip(p.outputs, s.outputs))
        t0 = time.perf_counter()
        r = sampled.run(stop_time=10.0, rtol=a.rtol, interval=10.0, integrator=a.integrator, outputs=outs)
        zoh.append(time.perf_counter() - t0)
        zoh_diff = max(abs(r[name][-1] - x) for name, x in zip(outs, p.outputs))
        zoh_stats = (len(r.events), r.stats["steps"], r.stats["rhs_evals"])
    print(f"integrator {a.integrator}, rtol {a.rtol}, kp {KP}, kd {KD}")
    print(f"one step's overhead over its integration (inputs dict, nothing read): {min(bare) * 1e6:6.2f} us")
    print(f"PD in the .mech, whole run of 10 s:   {min(whole) * 1e3:8.2f} ms")
    print(f"PD from Python at 1 kHz, 10 s:        {min(stepped) * 1e3:8.2f} ms  ({min(stepped) / min(whole):.2f}x)")
    print(f"overhead per controller step (outputs read, law, step): {min(overhead) * 1e6:6.2f} us")
    print(f"final state apart by {diff:.2e} (the sampled law against the continuous one)")
    # The floor: the controller loop's own cost (everything but the integration) already
    # exceeds 2x the whole run wherever the whole run is cheaper than half of it.
    print(f"integration inside the 10 000 steps: {min(inside) * 1e3:8.2f} ms; solver steps whole {evals[2]}, "
          f"stepped {evals[3]}; f evaluations whole {evals[0]}, stepped {evals[1]}")
    print(f"the loop without its integration alone: {(min(stepped) - min(inside)) / min(whole):.1f}x the whole run")
    print(f"PD sampled at 1 kHz in the .mech (hold joints, when clause), whole: {min(zoh) * 1e3:8.2f} ms; "
          f"Python at 1 kHz is {min(stepped) / min(zoh):.3f}x of it; {zoh_stats[0]} events, {zoh_stats[1]} steps, "
          f"{zoh_stats[2]} f evaluations; final state {zoh_diff:.2e} from the Python loop's")


if __name__ == "__main__":
    main()
