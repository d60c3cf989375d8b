"""Exudyn peer for the constrained problems (four-bar, rolling disk).

Four-bar: three ObjectRigidBody2D (node = CoM: x, y, phi) joined by ObjectJointRevolute2D,
two of them to the ground; the loop is just the fourth revolute joint (redundant
coordinates, 9 ODE2 + 8 algebraic). Rolling disk: ObjectRigidBody on a NodeRigidBodyEP
(Euler parameters) with ObjectJointRollingDisc (ideal no-slip rolling on the ground's x-y
plane, gravity -z, disc axis = local x); the script maps its frames to kanesim's.

Exudyn's explicit integrators (DOPRI5 ...) do not take algebraic constraints, so both run
with its implicit fixed-step generalized-alpha solver in its Newmark (trapezoidal, second
order, no numerical damping) setting with index-2 (velocity-level) constraints, as Exudyn's
rollingCoinTest does (index 3 with spectral radius 1 diverged on the four-bar at h = 1e-2),
Newton tolerances 1e-12, swept over step sizes like MuJoCo. Time = wall time of SolveDynamic.
"""
import time
import warnings

import numpy as np
import exudyn as exu
import exudyn.itemInterface as eii

import fourbar_geometry
import problems as P

warnings.filterwarnings("ignore", category=DeprecationWarning)

STEPS = [1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5]
# Exudyn world (Z up) from kanesim's (y up): X = x, Y = -z, Z = y.
MX = np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])        # kanesim <- Exudyn
P_LOCAL = np.array([[0.0, 1, 0], [0, 0, 1], [1, 0, 0]])     # kanesim body <- Exudyn body


def settings(T, h):
    s = exu.SimulationSettings()
    ti = s.timeIntegration
    ti.endTime = T
    ti.numberOfSteps = int(round(T / h))
    ti.verboseMode = 0
    ti.newton.relativeTolerance = 1e-12
    ti.newton.absoluteTolerance = 1e-12
    ti.newton.useModifiedNewton = False
    ti.generalizedAlpha.useIndex2Constraints = True    # index 3 at spectral radius 1 diverges
    ti.generalizedAlpha.useNewmark = True              # trapezoidal Newmark: 2nd order, no damping
    ti.generalizedAlpha.computeInitialAccelerations = True
    s.solutionSettings.writeSolutionToFile = False
    s.solutionSettings.sensorsWritePeriod = 1e9
    s.displayComputationTime = False
    s.displayStatistics = False
    return s


class FourBar:
    def __init__(self, p):
        self.p = p
        fb = P.FOURBAR
        a, b, c, d = fb["a"], fb["b"], fb["c"], fb["d"]
        com, vel, ang, rate = zip(*fourbar_geometry.bodies(*P.fourbar_start(p)))
        self.SC = exu.SystemContainer()
        mbs = self.mbs = self.SC.AddSystem()
        ground = mbs.AddObject(eii.ObjectGround())
        self.nodes, bodies = [], []
        for k, L in enumerate((a, b, c)):
            n = mbs.AddNode(eii.NodeRigidBody2D(referenceCoordinates=[com[k][0], com[k][1], ang[k]],
                                                initialVelocities=[vel[k][0], vel[k][1], rate[k]]))
            m = fb["m"][k]
            bodies.append(mbs.AddObject(eii.ObjectRigidBody2D(physicsMass=m, physicsInertia=m * L ** 2 / 12,
                                                              nodeNumber=n)))
            self.nodes.append(n)
            mm = mbs.AddMarker(eii.MarkerBodyMass(bodyNumber=bodies[-1]))
            mbs.AddLoad(eii.LoadMassProportional(markerNumber=mm, loadVector=[0, -9.81, 0]))
        mk = lambda body, pos: mbs.AddMarker(eii.MarkerBodyPosition(bodyNumber=body, localPosition=pos))  # noqa: E731
        joints = [(mk(ground, [0, 0, 0]), mk(bodies[0], [-a / 2, 0, 0])),
                  (mk(bodies[0], [a / 2, 0, 0]), mk(bodies[1], [-b / 2, 0, 0])),
                  (mk(ground, [d, 0, 0]), mk(bodies[2], [-c / 2, 0, 0])),
                  (mk(bodies[1], [b / 2, 0, 0]), mk(bodies[2], [c / 2, 0, 0]))]
        for m0, m1 in joints:
            mbs.AddObject(eii.ObjectJointRevolute2D(markerNumbers=[m0, m1]))
        mbs.Assemble()

    def run(self, h):
        s = settings(self.p.T, h)
        self.mbs.systemData.SetSystemState(self.mbs.systemData.GetSystemState(exu.ConfigurationType.Initial),
                                           exu.ConfigurationType.Current)
        t0 = time.perf_counter()
        ok = exu.SolveDynamic(self.mbs, s, solverType=exu.DynamicSolverType.GeneralizedAlpha)
        wall = time.perf_counter() - t0
        phi = [self.mbs.GetNodeOutput(n, exu.OutputVariableType.Rotation)[-1] for n in self.nodes]
        q = np.array([phi[0], phi[1] - phi[0], phi[2]])
        return dict(ok=bool(ok) and bool(np.all(np.isfinite(q))), time=wall, q=q, steps=int(round(self.p.T / h)),
                    message="SolveDynamic failed")


class Disk:
    def __init__(self, p):
        self.p = p
        a, m = P.DISK["a"], P.DISK["m"]
        q0, u0 = P.disk_start()
        R_wb = P.quat_to_mat(q0[3:])                      # kanesim world <- kanesim body
        R_exu = MX.T @ R_wb @ P_LOCAL                     # Exudyn world <- Exudyn body
        pos = MX.T @ np.array(q0[:3])
        v = MX.T @ np.array(u0[:3])
        w = MX.T @ R_wb @ np.array(u0[3:])                # angular velocity in world axes
        self.SC = exu.SystemContainer()
        mbs = self.mbs = self.SC.AddSystem()
        from exudyn.rigidBodyUtilities import RigidBodyInertia
        inertia = RigidBodyInertia(mass=m, inertiaTensor=np.diag([m * a * a / 2, m * a * a / 4, m * a * a / 4]))
        body = mbs.CreateRigidBody(inertia=inertia, referencePosition=pos, referenceRotationMatrix=R_exu,
                                   initialVelocity=v, initialAngularVelocity=w, gravity=[0, 0, -9.81],
                                   nodeType=exu.NodeType.RotationEulerParameters, returnDict=True)
        self.node = body["nodeNumber"]
        ground = mbs.AddObject(eii.ObjectGround())
        mg = mbs.AddMarker(eii.MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, 0]))
        mb = mbs.AddMarker(eii.MarkerBodyRigid(bodyNumber=body["bodyNumber"], localPosition=[0, 0, 0]))
        mbs.AddObject(eii.ObjectJointRollingDisc(markerNumbers=[mg, mb], constrainedAxes=[1, 1, 1], discRadius=a))
        mbs.Assemble()

    def run(self, h):
        s = settings(self.p.T, h)
        self.mbs.systemData.SetSystemState(self.mbs.systemData.GetSystemState(exu.ConfigurationType.Initial),
                                           exu.ConfigurationType.Current)
        t0 = time.perf_counter()
        ok = exu.SolveDynamic(self.mbs, s, solverType=exu.DynamicSolverType.GeneralizedAlpha)
        wall = time.perf_counter() - t0
        pos = np.array(self.mbs.GetNodeOutput(self.node, exu.OutputVariableType.Position))
        R_exu = np.array(self.mbs.GetNodeOutput(self.node, exu.OutputVariableType.RotationMatrix)).reshape(3, 3)
        R_wb = MX @ R_exu @ P_LOCAL.T
        q = np.concatenate([MX @ pos, P.mat_to_quat(R_wb)])
        return dict(ok=bool(ok) and bool(np.all(np.isfinite(q))), time=wall, q=q, steps=int(round(self.p.T / h)),
                    message="SolveDynamic failed")


def runner(p):
    return FourBar(p) if p.kind == "fourbar" else Disk(p)


if __name__ == "__main__":
    for pr in (P.Problem("fourbar", 3, 2.0), P.Problem("disk", 7, 2.0)):
        r = runner(pr)
        for h in (1e-2, 1e-3, 1e-4):
            out = r.run(h)
            print(pr.name, h, "%.3g s" % out["time"], "error %.3g" % pr.error(out["q"]))
