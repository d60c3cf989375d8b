// Issue 38: what a sweep's rows depend on beyond its settings.
//  - The files the model reads (meshes now, tables later): the settings record hashes
//    their contents (input_file:PATH), so `--resume` refuses to mix rows of an old mesh
//    with rows of a new one (before: the old rows were kept as done).
//  - Each row's parameter values belong to its scenario id: `sweep merge` rebuilds the
//    scenarios from the sources recorded beside each summary (summary.scenarios) and
//    refuses a row that disagrees, as `--resume` does (before: merge accepted it).
#include <gtest/gtest.h>

#include <cstdio>
#include <sstream>

#include "tests/support/cli_util.h"

namespace kanesim::clitest {
namespace {

// An ASCII STL box, x from 0 to lx, centred in y and z.
std::string BoxStl(double lx, double ly, double lz) {
  const double x[2] = {0, lx}, y[2] = {-ly / 2, ly / 2}, z[2] = {-lz / 2, lz / 2};
  auto v = [&](int i) { return std::to_string(x[i >> 2]) + " " + std::to_string(y[(i >> 1) & 1]) + " " +
                               std::to_string(z[i & 1]); };
  const int f[12][3] = {{0, 1, 3}, {0, 3, 2}, {4, 6, 7}, {4, 7, 5}, {0, 4, 5}, {0, 5, 1},
                        {2, 3, 7}, {2, 7, 6}, {0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3}};
  std::string s = "solid b\n";
  for (const auto& t : f) {
    s += " facet normal 0 0 0\n  outer loop\n";
    for (int k : t) s += "   vertex " + v(k) + "\n";
    s += "  endloop\n endfacet\n";
  }
  return s + "endsolid b\n";
}

// A pendulum whose link is a mesh (its mass and inertia come from the file).
std::string MeshPendulum(const std::string& file) {
  return "model MeshPendulum\n  parameter String f = \"" + file +
         "\";\n  parameter Real q0 = 0.3;\n  World world(g = {0, -9.81, 0});\n"
         "  Revolute hinge(axis = {0, 0, 1}, q(start = q0));\n  MeshBody link(file = f, density = 1000);\n"
         "equation\n  connect(world.frame_b, hinge.frame_a);\n  connect(hinge.frame_b, link.frame_a);\n"
         "  annotation(experiment(StopTime = 1, Interval = 0.1));\nend MeshPendulum;\n";
}

const std::string kGrid = " --grid q0=0.1:0.1:0.6 --metric final:hinge.q --no-progress";

// Keeps the header and the first `rows` rows: a sweep interrupted there.
void Interrupt(const std::string& summary, int rows) {
  std::istringstream in(Slurp(summary));
  std::string line, kept;
  for (int i = 0; i <= rows && std::getline(in, line); ++i) kept += line + "\n";
  Write(summary, kept);
}

// Wrong if --resume keeps rows made with another mesh (the reproducer's class), for the mesh
// named in the model, named by --set, and in a folder beside the model; the same files resume.
TEST(SweepInputs, ResumeRefusesAChangedMesh) {
  const std::string d = Work("inputs_mesh");
  std::filesystem::create_directories(d + "/model/meshes");
  Write(d + "/model/m.mech", MeshPendulum("meshes/box.stl"));
  Write(d + "/model/meshes/box.stl", BoxStl(1.0, 0.1, 0.05));
  Write(d + "/model/meshes/other.stl", BoxStl(1.0, 0.1, 0.05));
  for (const std::string set : {"", " --set f=\\\"model/meshes/other.stl\\\""}) {
    const std::string mesh = d + (set.empty() ? "/model/meshes/box.stl" : "/model/meshes/other.stl");
    const std::string key = set.empty() ? "input_file:meshes/box.stl" : "input_file:meshes/other.stl";
    Write(mesh, BoxStl(1.0, 0.1, 0.05));
    ASSERT_EQ(Kanesim("sweep model/m.mech" + set + kGrid + " -o out", d).rc, 0) << set;
    EXPECT_TRUE(Has(Slurp(d + "/out/summary.settings"), key + " = fnv1a64:")) << Slurp(d + "/out/summary.settings");
    const std::string finished = Slurp(d + "/out/summary.csv");
    Interrupt(d + "/out/summary.csv", 2);
    // The same mesh: resumes to the same rows.
    Result same = Kanesim("sweep model/m.mech" + set + kGrid + " --resume -o out", d);
    EXPECT_EQ(same.rc, 0) << same.err;
    EXPECT_EQ(CsvRows(d + "/out/summary.csv"), 6);
    // The part redesigned: 2 m instead of 1 m. Refused, naming the file; nothing touched.
    Interrupt(d + "/out/summary.csv", 2);
    const std::string interrupted = Slurp(d + "/out/summary.csv");
    Write(mesh, BoxStl(2.0, 0.1, 0.05));
    Result changed = Kanesim("sweep model/m.mech" + set + kGrid + " --resume -o out", d);
    EXPECT_EQ(changed.rc, 1) << set << "\n" << changed.err;
    EXPECT_TRUE(Has(changed.err, "cannot resume") && Has(changed.err, "    " + key + ": fnv1a64:"))
        << set << "\n" << changed.err;
    EXPECT_EQ(Slurp(d + "/out/summary.csv"), interrupted);
    // A fresh sweep on the new mesh gives other numbers: the refusal mattered.
    ASSERT_EQ(Kanesim("sweep model/m.mech" + set + kGrid + " -o fresh", d).rc, 0);
    EXPECT_NE(Slurp(d + "/fresh/summary.csv"), finished);
    // Shards made with different meshes do not merge either.
    std::filesystem::remove_all(d + "/shards");
    ASSERT_EQ(Kanesim("sweep model/m.mech" + set + kGrid + " --shard 1/2 -o shards", d).rc, 0);
    Write(mesh, BoxStl(1.0, 0.1, 0.05));
    ASSERT_EQ(Kanesim("sweep model/m.mech" + set + kGrid + " --shard 2/2 -o shards", d).rc, 0);
    Result merge = Kanesim("sweep merge shards -o merged.csv", d);
    EXPECT_EQ(merge.rc, 1) << merge.err;
    EXPECT_TRUE(Has(merge.err, key)) << merge.err;
    std::filesystem::remove_all(d + "/out");
  }
}

// The row's parameter fields disagree with its id: `sweep merge` refuses, naming the file
// and the scenario; also an id beyond the sweep, and sources edited after the sweep.
TEST(SweepInputs, MergeChecksEveryRowAgainstItsScenario) {
  const std::string d = Work("inputs_merge");
  const std::string spring = kSrc + "/examples/spring_mass.mech";
  const std::string args = " --grid k=10:10:60 --grid c=0,0.5 --metric final:slider.q --stop-time 0.5 --no-progress";
  ASSERT_EQ(Kanesim("sweep " + spring + args + " --shard 1/2 -o s", d).rc, 0);
  ASSERT_EQ(Kanesim("sweep " + spring + args + " --shard 2/2 -o s", d).rc, 0);
  ASSERT_EQ(Kanesim("sweep merge s -o good.csv", d).rc, 0);
  EXPECT_EQ(CsvRows(d + "/good.csv"), 12);
  // A merged summary merges again (its sources are beside it).
  EXPECT_EQ(Kanesim("sweep merge good.csv -o again.csv", d).rc, 0);
  EXPECT_EQ(Slurp(d + "/again.csv"), Slurp(d + "/good.csv"));

  const std::string shard = d + "/s/summary.shard-2-of-2.csv";
  const std::string original = Slurp(shard);
  // Scenario 3 is k = 20, c = 0.5; the edits keep the id and change a value.
  const std::vector<std::pair<std::string, std::string>> edits = {
      {"\n3,20,0.5,", "\n3,30,0.5,"},   // another k
      {"\n3,20,0.5,", "\n3,20,0,"},     // another c
      {"\n3,20,0.5,", "\n3,20.000000000000004,0.5,"},  // one ulp away: still another value
      {"\n3,20,0.5,", "\n13,20,0.5,"},  // an id the sweep does not have
  };
  for (const auto& [from, to] : edits) {
    std::string text = original;
    ASSERT_NE(text.find(from), std::string::npos) << text;
    text.replace(text.find(from), from.size(), to);
    Write(shard, text);
    std::filesystem::remove(d + "/bad.csv");
    Result r = Kanesim("sweep merge s -o bad.csv", d);
    EXPECT_EQ(r.rc, 1) << to << "\n" << r.err;
    EXPECT_TRUE(Has(r.err, "summary.shard-2-of-2.csv': the row of scenario ")) << to << "\n" << r.err;
    EXPECT_FALSE(std::filesystem::exists(d + "/bad.csv")) << to;
    // --resume refuses the same file (it already did before the fix: the two agree now).
    if (to.starts_with("\n3,")) {
      Result resume = Kanesim("sweep " + spring + args + " --shard 2/2 --resume -o s", d);
      EXPECT_EQ(resume.rc, 1) << to << "\n" << resume.err;
    }
  }
  Write(shard, original);
  // Sources edited (another grid) or removed: refused, never trusted.
  const std::string sources = d + "/s/summary.shard-1-of-2.scenarios";
  const std::string text = Slurp(sources);
  std::string edited = text;
  edited.replace(edited.find("\n20\n"), 4, "\n25\n");
  Write(sources, edited);
  Result e = Kanesim("sweep merge s -o bad.csv", d);
  EXPECT_EQ(e.rc, 1) << e.err;
  EXPECT_TRUE(Has(e.err, "does not hold the scenarios its settings record names")) << e.err;
  std::filesystem::remove(sources);
  std::filesystem::remove(d + "/s/summary.shard-2-of-2.scenarios");
  Result m = Kanesim("sweep merge s -o bad.csv", d);
  EXPECT_EQ(m.rc, 1) << m.err;
  EXPECT_TRUE(Has(m.err, "is missing")) << m.err;
}

}  // namespace
}  // namespace kanesim::clitest
