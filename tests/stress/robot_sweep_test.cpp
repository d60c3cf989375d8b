// Failures of the robot sweep (bench/event_sweeps.py robot, issue 41): the Franka Panda of
// tests/import/data/panda.urdf with exact Coulomb friction and damping on every joint, its
// <limit>s as end stops (restitution 0) and a random start (models/panda_friction_stops.mech,
// the sweep's URDF as a model whose draws are --set). The fingers' <mimic> is a coupling row,
// so these run the stops' and friction's code beside constraint rows. What must hold
// whatever the integrator: exit 0, no output row with a joint past its stop, T + V never
// rising across an event instant, the integrators agreeing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "run_kanesim.h"

namespace kanesim::stress {
namespace {

struct Limit {
  const char* joint;
  double lo, hi;
};

// The robot's joints' limits: `defaults` (the URDF's) unless `sets` changes them.
std::vector<Limit> Limits(std::vector<Limit> l, const std::vector<std::string>& sets) {
  for (Limit& k : l)
    for (const std::string& s : sets) {
      const std::string j = k.joint;
      if (s.rfind(j + ".q_min=", 0) == 0) k.lo = std::stod(s.substr(j.size() + 7));
      if (s.rfind(j + ".q_max=", 0) == 0) k.hi = std::stod(s.substr(j.size() + 7));
    }
  return l;
}

const std::vector<Limit> kPanda = {{"panda_joint1", -2.8973, 2.8973}, {"panda_joint2", -1.7628, 1.7628},
                                   {"panda_joint3", -2.8973, 2.8973}, {"panda_joint4", -3.0718, -0.0698},
                                   {"panda_joint5", -2.8973, 2.8973}, {"panda_joint6", -0.0175, 3.7525},
                                   {"panda_joint7", -2.8973, 2.8973}};
const std::vector<Limit> kSolo12 = {{"FL_HAA", -10, 10}, {"FL_HFE", -10, 10}, {"FL_KFE", -10, 10},
                                    {"FR_HAA", -10, 10}, {"FR_HFE", -10, 10}, {"FR_KFE", -10, 10},
                                    {"HL_HAA", -10, 10}, {"HL_HFE", -10, 10}, {"HL_KFE", -10, 10},
                                    {"HR_HAA", -10, 10}, {"HR_HFE", -10, 10}, {"HR_KFE", -10, 10}};

// Runs `model` (tests/stress/models/) with `sets` to t_end in each integrator and checks:
// exit 0 at t_end; no joint past its stop by more than 1e-9 rad in any row; T + V not rising
// across an event instant beyond 1e-9 of max(1 J, |T + V|); at least `min_instants` event
// instants; T + V at the end within tol (tol_bdf for CVODE-BDF) of the first integrator's.
// Under sanitizers CVODE alone to t_short, just past the instant the case is about.
void RunRobot(const std::string& model, const std::vector<Limit>& defaults, const std::vector<std::string>& sets,
              double t_end, double t_short, double tol, double tol_bdf, int min_instants) {
#ifdef KANESIM_STRESS_SHORT
  const std::vector<const char*> integrators = {"cvode"};
  t_end = t_short;
  min_instants = 1;
#else
  (void)t_short;
  const std::vector<const char*> integrators = {"dop853", "cvode", "cvode-bdf", "ida", "arkode"};
#endif
  const std::vector<Limit> limits = Limits(defaults, sets);
  double E_ref = NAN;
  for (const char* how : integrators) {
    std::vector<std::string> args = {"--integrator", how, "--stop-time", std::to_string(t_end), "--rtol", "1e-8",
                                     "--output", "kinetic_energy", "--output", "potential_energy"};
    for (const Limit& k : limits) args.insert(args.end(), {"--output", std::string(k.joint) + ".q"});
    for (const std::string& s : sets) args.insert(args.end(), {"--set", s});
    const RunResult r = RunKanesim("tests/stress/models/" + model, args);
    ASSERT_EQ(r.exit_code, 0) << how << ": " << r.stderr_text;
    const std::vector<double> t = r.Column("time"), T = r.Column("kinetic_energy"), V = r.Column("potential_energy");
    ASSERT_GT(t.size(), 50u) << how;
    EXPECT_GE(t.back(), t_end - 1e-12) << how;
    for (const Limit& k : limits) {
      const std::vector<double> q = r.Column(std::string(k.joint) + ".q");
      for (size_t i = 0; i < q.size(); ++i) {
        EXPECT_GE(q[i], k.lo - 1e-9) << how << " " << k.joint << " past q_min at t = " << t[i];
        EXPECT_LE(q[i], k.hi + 1e-9) << how << " " << k.joint << " past q_max at t = " << t[i];
      }
    }
    int instants = 0;
    for (size_t i = 1; i < t.size(); ++i) {
      if (t[i] != t[i - 1]) continue;
      ++instants;
      const double E0 = T[i - 1] + V[i - 1], E1 = T[i] + V[i];
      EXPECT_LE(E1 - E0, 1e-9 * std::max(1.0, std::abs(E0))) << how << " across the event at t = " << t[i];
    }
    EXPECT_GE(instants, min_instants) << how;
    const double E = T.back() + V.back();
    if (std::isnan(E_ref)) E_ref = E;
    EXPECT_NEAR(E, E_ref, std::string(how) == "cvode-bdf" ? tol_bdf : tol) << how << " against " << integrators[0];
  }
}

// Sweep seed 12, trial 1: friction 0.5 N m, no damping, the URDF's limits. At t = 0.5538147
// panda_joint5 strikes q_max and the pull on it passes its static friction: it leaves, sliding
// away. 1.3e-4 s later panda_joint2 reverses (its speed through 0) and slides forwards; beside
// constraint rows EndStopEvents::RestOnRows set every stop within the tolerance's reach at rest
// that joint2's slide presses, and so zeroed panda_joint5's speed, -0.002 rad/s leaving q_max
// 1.3e-7 rad away: T + V rose 4.6e-4 J across that instant in all five integrators. Now a side
// moving faster than the rest speed is left to its motion (max rise 1.4e-14 J).
TEST(RobotSweep, AJointLeavingItsStopIsNotSetAtRestByAnotherJointsSlide) {
  RunRobot("panda_friction_stops.mech", kPanda, {
      "fric=0.5", "fric_f=0.5", "damp=0.0", "damp_f=0.0", "panda_joint2.q_min=-1.7628", "panda_joint2.q_max=1.7628",
      "panda_joint4.q_min=-3.0718", "panda_joint4.q_max=-0.06979999999999986",
      "panda_joint6.q_min=-0.01750000000000007", "panda_joint6.q_max=3.7525", "panda_finger_joint1.q_min=0.0",
      "panda_finger_joint1.q_max=0.04", "panda_joint1.q.start=0.39746970671297266",
      "panda_joint1.u.start=-1.2014656938728803", "panda_joint2.q.start=0.042899051724862636",
      "panda_joint2.u.start=1.2769994836151475", "panda_joint3.q.start=0.9462153730495277",
      "panda_joint3.u.start=1.1915040863276531", "panda_joint4.q.start=-2.685696753882877",
      "panda_joint4.u.start=1.675626845979234", "panda_joint5.q.start=1.6670386631301684",
      "panda_joint5.u.start=0.6481810065783833", "panda_joint6.q.start=0.9284668065882346",
      "panda_joint6.u.start=1.9578077193240517", "panda_joint7.q.start=-0.3973448720708421",
      "panda_joint7.u.start=-0.22502720020629097", "panda_finger_joint1.q.start=0.025791124338175635",
      "panda_finger_joint1.u.start=0.09426428099732026"},
           0.8, 0.56, 2e-5, 2e-5, 6);
}

// Sweep seed 22, trial 3: friction 0.5 N m, damping 0.01 N m s/rad, limits shrunk to a tenth
// of their range. At t = 0.2163829 panda_joint7 strikes q_max; the impulse lets joint3, joint5
// and joint6 go from q_min (pulled beyond their static friction), joint3 at 1.5e-6 rad/s.
// 1.5e-5 s later joint6 reverses and slides back onto q_min, where it rests; under the laws that
// left, joint3 accelerates into q_min (-1.08 rad/s^2) from a gap of ~1e-11. After a friction
// event the stops were settled twice only, and the run stopped (exit 2 "... at q_min at rest
// after the event ... and accelerates into it without resting on it") in all five
// integrators. Now they settle again while such a side is left (as after a stop's event), and
// joint3 rests on q_min. CVODE-BDF's T + V is 3e-4 J off the others' at t = 0.8 (rtol 1e-8).
TEST(RobotSweep, AJointThatALaterSlideDrivesBackOntoItsStopRestsThere) {
  RunRobot("panda_friction_stops.mech", kPanda, {
      "fric=0.5", "fric_f=0.5", "damp=0.01", "damp_f=0.01", "panda_joint1.q_min=-0.28973",
      "panda_joint1.q_max=0.28973", "panda_joint2.q_min=-0.17628", "panda_joint2.q_max=0.17628",
      "panda_joint3.q_min=-0.28973", "panda_joint3.q_max=0.28973", "panda_joint4.q_min=-1.7208999999999999",
      "panda_joint4.q_max=-1.4207", "panda_joint5.q_min=-0.28973", "panda_joint5.q_max=0.28973",
      "panda_joint6.q_min=1.6789999999999998", "panda_joint6.q_max=2.056", "panda_joint7.q_min=-0.28973",
      "panda_joint7.q_max=0.28973", "panda_finger_joint1.q_min=0.018000000000000002",
      "panda_finger_joint1.q_max=0.022", "panda_joint1.q.start=-0.16101205833913595",
      "panda_joint1.u.start=-1.8520990293378072", "panda_joint2.q.start=0.011249220373653834",
      "panda_joint2.u.start=1.1836291485679764", "panda_joint3.q.start=0.07670303303248399",
      "panda_joint3.u.start=-1.1939700944549507", "panda_joint4.q.start=-1.5184785779755723",
      "panda_joint4.u.start=-1.7916316629930158", "panda_joint5.q.start=-0.046546879438722044",
      "panda_joint5.u.start=1.3124029978384932", "panda_joint6.q.start=2.0103504219419923",
      "panda_joint6.u.start=-0.15769624581278618", "panda_joint7.q.start=0.18072191658393905",
      "panda_joint7.u.start=-0.005873420607014346", "panda_finger_joint1.q.start=0.02008623978263177",
      "panda_finger_joint1.u.start=0.01690863115221939"},
           0.8, 0.22, 2e-5, 1e-3, 6);
}

// Solo12 (fixed base), sweep seed 11, trial 3: friction 0.1 N m, damping 0.3 N m s/rad,
// limits shrunk to 0.3 of their range. From t = 0.018 FL_HAA slides at -0.1429 rad/s while
// its deceleration falls to 0: its graze guard (minus its sliding speed's rate) crosses 0 at
// t = 0.0520743, a minimum far from rest, no event. That guard is a difference of
// accelerations whose round-off is exactly 0 over ~1e-15 s there, and SUNDIALS, checking a
// small step past the root it had returned, found it 0 again: CV_ILL_INPUT "Root found at and
// very near t" (exit 2 in CVODE-BDF). Now a guard's exact zero is taken as just past its
// minimum. Seed 26, trial 0 (the URDF's limits), stopped CVODE-BDF and IDA so; with that
// fixed CVODE-BDF then got a root return at t = 0.1211 that named no function, which was
// taken for a when clause's event (there is none) and the run crashed (SIGSEGV). Seed 1,
// trial 3 (Panda, friction 2 N m) stopped CVODE-BDF with "the events make no progress" on the
// same round-off. All five now run to the end and agree.
TEST(RobotSweep, AGrazeGuardsRoundOffZeroIsNotARootTwice) {
  RunRobot("solo12_friction_stops.mech", kSolo12, {
      "fric=0.1", "damp=0.3", "FL_HAA.q_min=-3.0", "FL_HAA.q_max=3.0", "FL_HFE.q_min=-3.0", "FL_HFE.q_max=3.0",
      "FL_KFE.q_min=-3.0", "FL_KFE.q_max=3.0", "FR_HAA.q_min=-3.0", "FR_HAA.q_max=3.0", "FR_HFE.q_min=-3.0",
      "FR_HFE.q_max=3.0", "FR_KFE.q_min=-3.0", "FR_KFE.q_max=3.0", "HL_HAA.q_min=-3.0", "HL_HAA.q_max=3.0",
      "HL_HFE.q_min=-3.0", "HL_HFE.q_max=3.0", "HL_KFE.q_min=-3.0", "HL_KFE.q_max=3.0", "HR_HAA.q_min=-3.0",
      "HR_HAA.q_max=3.0", "HR_HFE.q_min=-3.0", "HR_HFE.q_max=3.0", "HR_KFE.q_min=-3.0", "HR_KFE.q_max=3.0",
      "FL_HAA.q.start=-0.8807786831961673", "FL_HAA.u.start=-0.7551614841048235",
      "FL_HFE.q.start=-2.6181926399021487", "FL_HFE.u.start=-0.3597963226425498", "FL_KFE.q.start=2.283377601483129",
      "FL_KFE.u.start=-1.4616141245845573", "FR_HAA.q.start=1.1178865577701487", "FR_HAA.u.start=-1.956179944876033",
      "FR_HFE.q.start=-0.18932483118834975", "FR_HFE.u.start=-0.05270683235889306",
      "FR_KFE.q.start=0.9832181857540734", "FR_KFE.u.start=-1.246458129661534", "HL_HAA.q.start=0.04787337504100675",
      "HL_HAA.u.start=1.9411256233422223", "HL_HFE.q.start=1.4554187857152687",
      "HL_HFE.u.start=-0.32307801712408324", "HL_KFE.q.start=-0.6277403441880414",
      "HL_KFE.u.start=-0.42058651385439605", "HR_HAA.q.start=2.6462821345737177",
      "HR_HAA.u.start=-1.9981163659752914", "HR_HFE.q.start=1.9674032885060972", "HR_HFE.u.start=1.8994282425466626",
      "HR_KFE.q.start=0.500799388009189", "HR_KFE.u.start=1.9916148747463556"},
           1.0, 0.06, 1e-7, 1e-7, 8);
  RunRobot("solo12_friction_stops.mech", kSolo12, {
      "fric=0.1", "damp=0.3", "FL_HAA.q.start=-1.2157584964213655", "FL_HAA.u.start=0.17605751922003288",
      "FL_HFE.q.start=-6.698295757368843", "FL_HFE.u.start=1.8046817113283615",
      "FL_KFE.q.start=-0.40943048334678345", "FL_KFE.u.start=0.9206849242268484", "FR_HAA.q.start=2.221371241280991",
      "FR_HAA.u.start=-1.3135300983356326", "FR_HFE.q.start=-1.2672343316138726",
      "FR_HFE.u.start=-1.030200899041965", "FR_KFE.q.start=4.45927688005963", "FR_KFE.u.start=0.8688843799872235",
      "HL_HAA.q.start=-5.365012838293018", "HL_HAA.u.start=0.7699950328992307", "HL_HFE.q.start=6.40680760531313",
      "HL_HFE.u.start=0.6666402500240358", "HL_KFE.q.start=6.375979796059955", "HL_KFE.u.start=-1.4231869241770698",
      "HR_HAA.q.start=-5.103115269882666", "HR_HAA.u.start=-0.06728017810407261", "HR_HFE.q.start=4.774891951830153",
      "HR_HFE.u.start=-0.4452794085657974", "HR_KFE.q.start=-4.614380949002431", "HR_KFE.u.start=0.3365981588003235"},
           1.0, 0.13, 1e-7, 1e-7, 8);
}

// Sweep seed 29, trial 3: friction 0.1 N m (0.2 N on the fingers' leader, holding both), no
// damping, the URDF's limits. At t = 0.6499711 the fingers, stuck, slip. The slip's
// StopOnRows took the finger's speed "as the last evaluation solved it" from the workspace,
// but that evaluation had ended in the resting stops' holding columns, whose unit speed it
// held: 1 m/s for a finger at rest, and the correction set both fingers moving at -1 m/s,
// +0.015 J across the instant in all five integrators (the sliding joints' event functions
// beside rows read the same). The speeds are now noted from the plain evaluation.
TEST(RobotSweep, ASlipBesideRowsReadsItsJointsSpeedNotAHoldingColumns) {
  RunRobot("panda_friction_stops.mech", kPanda, {
      "fric=0.1", "damp=0.0", "fric_f=0.1", "damp_f=0.0", "panda_joint2.q_min=-1.7628", "panda_joint2.q_max=1.7628",
      "panda_joint4.q_min=-3.0718", "panda_joint4.q_max=-0.06979999999999986",
      "panda_joint6.q_min=-0.01750000000000007", "panda_joint6.q_max=3.7525", "panda_finger_joint1.q_min=0.0",
      "panda_finger_joint1.q_max=0.04", "panda_joint1.q.start=1.2612471690910452",
      "panda_joint1.u.start=1.375985504200656", "panda_joint2.q.start=0.46871692980937696",
      "panda_joint2.u.start=-0.48664045734329564", "panda_joint3.q.start=-1.4427834151196677",
      "panda_joint3.u.start=-1.1865868379476598", "panda_joint4.q.start=-0.5756318722986808",
      "panda_joint4.u.start=0.12911701928419506", "panda_joint5.q.start=2.311918752822619",
      "panda_joint5.u.start=-1.0921928619917165", "panda_joint6.q.start=2.967655613751086",
      "panda_joint6.u.start=-1.995632093514034", "panda_joint7.q.start=-2.00631550176019",
      "panda_joint7.u.start=0.8195511869488037", "panda_finger_joint1.q.start=0.01108534341554826",
      "panda_finger_joint1.u.start=-0.05373962717470764"},
           0.8, 0.66, 5e-5, 1e-4, 6);
}

}  // namespace
}  // namespace kanesim::stress
