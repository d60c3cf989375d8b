// Item 10 of issue 24: a summary records what it was made with (DIR/summary.settings);
// `sweep --resume` refuses to continue it with other settings and `sweep merge` refuses
// shards made with other settings, each naming what differs. Generator: one sweep, then
// a change of each setting that decides the rows.
#include <gtest/gtest.h>

#include <utility>
#include <vector>

#include "tests/support/cli_util.h"

namespace kanesim::clitest {
namespace {

const std::string kBase = " --set F0=0 --grid k=10:20:90 --metric final:slider.q --stop-time 1 --interval 0.01 "
                          "--rtol 1e-8 --no-progress";

// Each member: extra options (or a changed model) and the key the refusal must name.
const std::vector<std::pair<std::string, std::string>> kChanges = {
    {"--set c=0.5", "set"},
    {"--stop-time 2", "stop_time"},
    {"--start-time 0.5", "start_time"},
    {"--interval 0.02", "interval"},
    {"--rtol 1e-7", "rtol"},
    {"--atol 1e-9", "atol"},
    {"--integrator cvode", "integrator"},
    {"--integrator ida", "integrator"},
    {"--solver dense", "solver"},
    {"--linear-solver klu", "linear_solver"},
    {"--reactions min-norm", "reactions"},
    {"--energy-check off", "energy_check"},
    {"--trajectories", "trajectories"},
    {"MODEL", "model_text"},
};

// kBase with `change` (an option and its value) in place of the same option's value.
std::string Options(const std::string& change) {
  if (change == "MODEL") return kBase;
  const std::string flag = change.substr(0, change.find(' '));
  std::string base = kBase;
  if (size_t at = base.find(" " + flag + " "); at != std::string::npos && flag != "--set") {
    const size_t value_end = base.find(' ', at + flag.size() + 2);
    base.erase(at, value_end - at);
  }
  return base + " " + change;
}

// A resumable state: the sweep ran, then lost its last rows (as if interrupted).
void Interrupt(const std::string& summary) {
  std::string text = Slurp(summary);
  size_t cut = 0;
  for (int i = 0; i < 3; ++i) cut = text.find('\n', cut) + 1;
  Write(summary, text.substr(0, cut));
}

TEST(SweepSettings, ResumeRefusesEveryChangedSetting) {
  std::string d = Work("settings_resume");
  Write(d + "/m.mech", Slurp(kSrc + "/examples/spring_mass.mech"));
  for (const auto& [change, key] : kChanges) {
    ASSERT_EQ(Kanesim("sweep m.mech" + kBase + " -o out", d).rc, 0);
    Interrupt(d + "/out/summary.csv");
    const std::string before = Slurp(d + "/out/summary.csv");
    if (change == "MODEL") Write(d + "/m.mech", Slurp(kSrc + "/examples/spring_mass.mech") + "// edited\n");
    Result r = Kanesim("sweep m.mech" + Options(change) + " --resume -o out", d);
    EXPECT_EQ(r.rc, 1) << change << "\n" << r.err;
    EXPECT_TRUE(Has(r.err, "cannot resume") && Has(r.err, "    " + key + ": ")) << change << "\n" << r.err;
    EXPECT_EQ(Slurp(d + "/out/summary.csv"), before) << change << ": the summary was touched";
    Write(d + "/m.mech", Slurp(kSrc + "/examples/spring_mass.mech"));
  }
  // The same settings resume, and a changed grid (other scenarios) is refused too.
  ASSERT_EQ(Kanesim("sweep m.mech" + kBase + " -o out", d).rc, 0);
  Interrupt(d + "/out/summary.csv");
  Result same = Kanesim("sweep m.mech" + kBase + " --resume -o out", d);
  EXPECT_EQ(same.rc, 0) << same.err;
  Interrupt(d + "/out/summary.csv");
  Result grid = Kanesim("sweep m.mech --set F0=0 --grid k=10:20:110 --metric final:slider.q --stop-time 1 "
                        "--interval 0.01 --rtol 1e-8 --no-progress --resume -o out",
                        d);
  EXPECT_EQ(grid.rc, 1) << grid.err;
  EXPECT_TRUE(Has(grid.err, "scenarios: ")) << grid.err;
}

// A summary without its record (older kanesim, or removed) cannot be checked: refused.
TEST(SweepSettings, ResumeWithoutARecordIsRefused) {
  std::string d = Work("settings_missing");
  const std::string m = kSrc + "/examples/spring_mass.mech";
  ASSERT_EQ(Kanesim("sweep " + m + kBase + " -o out", d).rc, 0);
  Interrupt(d + "/out/summary.csv");
  std::filesystem::remove(d + "/out/summary.settings");
  Result r = Kanesim("sweep " + m + kBase + " --resume -o out", d);
  EXPECT_EQ(r.rc, 1) << r.err;
  EXPECT_TRUE(Has(r.err, "no settings record")) << r.err;
}

TEST(SweepSettings, MergeRefusesShardsOfOtherSettings) {
  std::string d = Work("settings_merge");
  const std::string m = kSrc + "/examples/spring_mass.mech";
  for (const auto& [change, key] : kChanges) {
    if (change == "MODEL") continue;
    std::filesystem::remove_all(d + "/out");
    ASSERT_EQ(Kanesim("sweep " + m + kBase + " --shard 1/2 -o out", d).rc, 0);
    ASSERT_EQ(Kanesim("sweep " + m + Options(change) + " --shard 2/2 -o out", d).rc, 0) << change;
    Result r = Kanesim("sweep merge out -o merged.csv", d);
    EXPECT_EQ(r.rc, 1) << change << "\n" << r.err;
    EXPECT_TRUE(Has(r.err, "    " + key + ": ")) << change << "\n" << r.err;
    EXPECT_FALSE(std::filesystem::exists(d + "/merged.csv")) << change;
  }
  std::filesystem::remove_all(d + "/out");
  ASSERT_EQ(Kanesim("sweep " + m + kBase + " --shard 1/2 -o out", d).rc, 0);
  ASSERT_EQ(Kanesim("sweep " + m + kBase + " --shard 2/2 -o out", d).rc, 0);
  Result ok = Kanesim("sweep merge out -o merged.csv", d);
  EXPECT_EQ(ok.rc, 0) << ok.err;
  EXPECT_EQ(CsvRows(d + "/merged.csv"), 5);
  EXPECT_TRUE(std::filesystem::exists(d + "/merged.settings"));
}

}  // namespace
}  // namespace kanesim::clitest
