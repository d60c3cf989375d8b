"""Exudyn peer: the problem as one ObjectKinematicTree (minimal coordinates, one
NodeGenericODE2 holding the N joint angles), integrated by Exudyn's adaptive explicit
Dormand-Prince 5(4) (DynamicSolverType.DOPRI5, automaticStepSize, rtol = atol).
Time = wall time of mbs.SolveDynamic (Exudyn's own assembly is done before).
"""
import time
import warnings

import numpy as np
import exudyn as exu
import exudyn.itemInterface as eii

warnings.filterwarnings("ignore", category=DeprecationWarning)


class Runner:
    def __init__(self, p):
        self.p = p
        self.SC = exu.SystemContainer()
        self.mbs = self.SC.AddSystem()
        n = p.n
        I = p.m * p.L ** 2 / 12
        types = [exu.JointType.RevoluteZ if ax == "z" else exu.JointType.RevoluteY for ax in p.axes]
        node = self.mbs.AddNode(eii.NodeGenericODE2(referenceCoordinates=[0.0] * n,
                                                     initialCoordinates=[p.q0] * n,
                                                     initialCoordinates_t=[0.0] * n,
                                                     numberOfODE2Coordinates=n))
        self.mbs.AddObject(eii.ObjectKinematicTree(
            nodeNumber=node, gravity=[0.0, -p.g, 0.0], jointTypes=types, linkParents=list(range(-1, n - 1)),
            jointTransformations=exu.Matrix3DList([np.eye(3)] * n),
            jointOffsets=exu.Vector3DList([[0.0, 0.0, 0.0]] + [[p.L, 0.0, 0.0]] * (n - 1)),
            linkInertiasCOM=exu.Matrix3DList([np.diag([0.0, I, I])] * n),
            linkCOMs=exu.Vector3DList([[p.L / 2, 0.0, 0.0]] * n),
            linkMasses=[p.m] * n))
        self.mbs.Assemble()

    def run(self, rtol):
        p = self.p
        s = exu.SimulationSettings()
        s.timeIntegration.endTime = p.T
        s.timeIntegration.numberOfSteps = 100
        s.timeIntegration.verboseMode = 0
        s.timeIntegration.automaticStepSize = True
        s.timeIntegration.absoluteTolerance = rtol
        s.timeIntegration.relativeTolerance = rtol
        s.solutionSettings.writeSolutionToFile = False
        s.solutionSettings.sensorsWritePeriod = 1e9
        s.displayComputationTime = False
        s.displayStatistics = False
        self.mbs.systemData.SetODE2Coordinates([p.q0] * p.n, configuration=exu.ConfigurationType.Initial)
        t0 = time.perf_counter()
        ok = self.mbs.SolveDynamic(s, solverType=exu.DynamicSolverType.DOPRI5)
        wall = time.perf_counter() - t0
        q = np.array(self.mbs.systemData.GetODE2Coordinates())
        return dict(ok=bool(ok) and bool(np.all(np.isfinite(q))), time=wall, q=q, message="SolveDynamic failed")


if __name__ == "__main__":
    import sys
    sys.path.insert(0, __file__.rsplit("/", 1)[0])
    from problems import Problem
    for pr in (Problem("pendulum", 2, 2.0), Problem("chain", 5, 1.0)):
        r = Runner(pr)
        for tol in (1e-4, 1e-8, 1e-10):
            out = r.run(tol)
            print(pr.name, tol, out["time"], pr.error(out["q"]))
