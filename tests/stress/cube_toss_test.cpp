// A cube tossed spinning onto a frictionless floor (models/tossed_cube.mech: eight corner
// PlaneContacts, restitution e), from tosses of a random sweep that stopped a run before
// (exit 2, "an impact was missed (two crossings within one step are not handled)": ARKODE,
// stepping one step at a time beside resting corners, took a graze guard's root inside a
// step, no event, and served the rows after it from the step's interpolant without
// searching the rest of the step, where a corner crossed the floor). What must hold, in
// every integrator: the run completes; the floor, pushing only along its normal, keeps the
// speed along it (0 across, vx along) and the vertical spin (the cube's inertia is
// isotropic: the world angular velocity's vertical component) through every impact; no
// corner goes below the floor beyond the tolerance's reach.
// Measured (Release): the spin to 3e-9, the speeds to round-off, corners >= -2e-8.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "run_kanesim.h"

namespace kanesim::stress {
namespace {

struct Toss {
  const char* what;
  std::vector<std::string> sets;  // --set NAME=VALUE of the model's parameters
};

// The tosses (parameters of models/tossed_cube.mech) whose ARKODE runs missed an impact.
const Toss kTosses[] = {
    {"e=0.8 spin", {"e=0.8", "h=0.6029369475335373", "th=2.3630682556196203", "ax=-0.9957878932977786",
                    "ay=-0.10922561189039715", "az=0.44308006468156513", "wx=-4.339804459672758", "wy=7.124331128862757",
                    "wz=6.422839321783737", "vx=-0.9388200339328929"}},
    {"e=0.5 edge pair", {"e=0.5", "h=0.6213922123374678", "th=0.8347663800684059", "ax=0.09599261893249778",
                         "ay=0.9142325629204537", "az=-0.9885817410992142", "wx=4.538483721846237", "wy=5.127774590807711",
                         "wz=6.178873293216132", "vx=0.4810068236663927"}},
    {"e=0.2 low", {"e=0.2", "h=0.6630747984661014", "th=1.740209380812975", "ax=-0.14781864062369965",
                   "ay=-0.8877534049585192", "az=0.7400203103532796", "wx=1.119989342022084", "wy=-4.802569277165711",
                   "wz=0.07552747886181344", "vx=-0.030149775544531687"}},
};

TEST(CubeToss, EveryIntegratorKeepsWhatTheFloorCannotChange) {
  for (const Toss& toss : kTosses) {
    double vx = 0.0;
    for (const std::string& s : toss.sets)
      if (s.rfind("vx=", 0) == 0) vx = std::stod(s.substr(3));
    for (const char* how : {"dop853", "cvode", "ida", "arkode"}) {
      std::vector<std::string> args = {"--integrator", how, "--stop-time", "2", "--rtol", "1e-8",
                                       "--output", "free.frame_b.v[1]", "--output", "free.frame_b.v[3]",
                                       "--output", "free.frame_b.w[2]"};
      for (int k = 1; k <= 8; ++k) args.insert(args.end(), {"--output", "c" + std::to_string(k) + ".frame_b.r[2]"});
      for (const std::string& s : toss.sets) args.insert(args.end(), {"--set", s});
      const RunResult r = RunKanesim("tests/stress/models/tossed_cube.mech", args);
      ASSERT_EQ(r.exit_code, 0) << toss.what << " " << how << ": " << r.stderr_text;
      const std::vector<double> v1 = r.Column("free.frame_b.v[1]"), v3 = r.Column("free.frame_b.v[3]"),
                                w2 = r.Column("free.frame_b.w[2]");
      ASSERT_GT(w2.size(), 100u);
      double low = 0.0;
      for (int k = 1; k <= 8; ++k)
        for (double y : r.Column("c" + std::to_string(k) + ".frame_b.r[2]")) low = std::min(low, y);
      for (size_t i = 0; i < w2.size(); ++i) {
        EXPECT_NEAR(v1[i], vx, 1e-9) << toss.what << " " << how << " row " << i;
        EXPECT_NEAR(v3[i], 0.0, 1e-9) << toss.what << " " << how << " row " << i;
        EXPECT_NEAR(w2[i], w2[0], 1e-6) << toss.what << " " << how << " row " << i;
      }
      EXPECT_GE(low, -2e-7) << toss.what << " " << how << ": a corner below the floor";
    }
  }
}

}  // namespace
}  // namespace kanesim::stress
