// The importer's text and its diagnostics (import/import.h). If these fail, a hostile or
// mistaken URDF is accepted, crashes, or is refused without its line, a caret and a hint;
// or the written model loses a URDF name, a mimic joint or a dropped element silently.
#include "import/import.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "pipeline/pipeline.h"
#include "runtime/runtime.h"

namespace kanesim {
namespace {

const std::string kData = std::string(KANESIM_SOURCE_DIR) + "/tests/import/data";

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

import::Result Import(const std::string& text, bool floating = false) {
  import::Options o;
  o.floating = floating;
  o.use_ros_package_path = false;
  return import::UrdfToMech("bad.urdf", text, o);
}

// A robot of two links around `joint` (a <joint> element's text).
std::string TwoLinks(const std::string& joint, const std::string& extra = "") {
  return "<robot name=\"r\">\n"
         "  <link name=\"a\"><inertial><mass value=\"1\"/><inertia ixx=\"1\" iyy=\"1\" izz=\"1\"/></inertial></link>\n"
         "  <link name=\"b\"><inertial><mass value=\"1\"/><inertia ixx=\"1\" iyy=\"1\" izz=\"1\"/></inertial></link>\n" +
         joint + "\n" + extra + "</robot>\n";
}
const std::string kJoint = "  <joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/></joint>";

struct Hostile {
  const char* what;
  std::string text;
  const char* code;
  const char* where;  // "bad.urdf:LINE:COL"
};

class HostileUrdf : public ::testing::TestWithParam<Hostile> {};

TEST_P(HostileUrdf, IsRefusedAtItsLineWithACaret) {
  const Hostile& h = GetParam();
  import::Result r = Import(h.text);
  EXPECT_FALSE(r.ok) << h.what;
  EXPECT_TRUE(r.mech.empty());
  EXPECT_GE(r.num_errors, 1);
  EXPECT_NE(r.diagnostics.find(std::string("error[") + h.code + "]"), std::string::npos) << h.what << "\n"
                                                                                           << r.diagnostics;
  EXPECT_NE(r.diagnostics.find(std::string(h.where) + ": error"), std::string::npos) << h.what << "\n"
                                                                                        << r.diagnostics;
  EXPECT_NE(r.diagnostics.find("^\n"), std::string::npos) << "no caret:\n" << r.diagnostics;
}

std::string NumberIn(const std::string& value) {
  return TwoLinks("  <joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/>"
                  "<origin xyz=\"" + value + "\"/></joint>");
}

INSTANTIATE_TEST_SUITE_P(
    Cases, HostileUrdf,
    ::testing::Values(
        Hostile{"unclosed element", "<robot name=\"r\">\n  <link name=\"a\">\n</robot>\n", "U401", "bad.urdf:2:3"},
        Hostile{"not XML", "this is not xml", "U401", "bad.urdf:1:1"},
        Hostile{"empty", "", "U401", "bad.urdf:1:1"},
        Hostile{"not a robot", "<?xml version=\"1.0\"?>\n<model name=\"m\"/>\n", "U402", "bad.urdf:2:1"},
        Hostile{"no links", "<robot name=\"r\">\n</robot>\n", "U402", "bad.urdf:1:1"},
        Hostile{"missing parent link", TwoLinks("  <joint name=\"j\" type=\"fixed\"><parent link=\"x\"/><child link=\"b\"/></joint>"),
                "U406", "bad.urdf:4:3"},
        Hostile{"no parent element", TwoLinks("  <joint name=\"j\" type=\"fixed\"><child link=\"b\"/></joint>"), "U403",
                "bad.urdf:4:3"},
        Hostile{"two roots", TwoLinks(""), "U407", "bad.urdf:3:3"},
        Hostile{"cycle", TwoLinks(kJoint, "  <joint name=\"k\" type=\"fixed\"><parent link=\"b\"/><child link=\"a\"/></joint>\n"),
                "U407", "bad.urdf:5:3"},
        Hostile{"self loop", TwoLinks("  <joint name=\"j\" type=\"fixed\"><parent link=\"a\"/><child link=\"a\"/></joint>"),
                "U407", "bad.urdf:4:3"},
        Hostile{"two parents",
                TwoLinks(kJoint, "  <link name=\"c\"/>\n  <joint name=\"k\" type=\"fixed\"><parent link=\"c\"/><child link=\"b\"/></joint>\n"),
                "U407", "bad.urdf:6:3"},
        Hostile{"NaN", NumberIn("0 nan 0"), "U404", "bad.urdf:4:78"},
        Hostile{"infinite", NumberIn("0 0 inf"), "U404", "bad.urdf:4:78"},
        Hostile{"huge", NumberIn("1e300 0 0"), "U404", "bad.urdf:4:78"},
        Hostile{"below the normal range", NumberIn("0 1e-315 0"), "U404", "bad.urdf:4:78"},  // fuzz_urdf
        Hostile{"tiny mass",
                "<robot name=\"r\">\n  <link name=\"a\"><inertial><mass value=\"1e-309\"/></inertial></link>\n</robot>\n",
                "U404", "bad.urdf:2:34"},
        Hostile{"two numbers", NumberIn("1 2"), "U404", "bad.urdf:4:78"},
        Hostile{"junk number", NumberIn("1 2 3x"), "U404", "bad.urdf:4:78"},
        Hostile{"negative mass",
                "<robot name=\"r\">\n  <link name=\"a\"><inertial><mass value=\"-1\"/></inertial></link>\n</robot>\n",
                "U404", "bad.urdf:2:34"},
        Hostile{"zero axis", TwoLinks("  <joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/><axis xyz=\"0 0 0\"/></joint>"),
                "U404", "bad.urdf:4:76"},
        Hostile{"unknown joint type", TwoLinks("  <joint name=\"j\" type=\"hinge\"><parent link=\"a\"/><child link=\"b\"/></joint>"),
                "U408", "bad.urdf:4:19"},
        Hostile{"duplicate link", TwoLinks(kJoint, "  <link name=\"b\"/>\n"), "U405", "bad.urdf:5:3"},
        Hostile{"duplicate joint", TwoLinks(kJoint, "  <link name=\"c\"/>\n  <joint name=\"j\" type=\"fixed\"><parent link=\"b\"/><child link=\"c\"/></joint>\n"),
                "U405", "bad.urdf:6:3"},
        Hostile{"nameless link", "<robot name=\"r\">\n  <link/>\n</robot>\n", "U403", "bad.urdf:2:3"},
        Hostile{"mimic of an unknown joint",
                TwoLinks("  <joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/><mimic joint=\"x\"/></joint>"),
                "U406", "bad.urdf:4:70"},
        Hostile{"mimic of itself",
                TwoLinks("  <joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/><mimic joint=\"j\"/></joint>"),
                "U412", "bad.urdf:4:70"},
        Hostile{"entity expansion",
                "<?xml version=\"1.0\"?>\n<!DOCTYPE robot [\n  <!ENTITY a \"aaaaaaaaaa\">\n  <!ENTITY b \"&a;&a;&a;&a;&a;&a;&a;&a;\">\n]>\n"
                "<robot name=\"&b;\"><link name=\"x\"/></robot>\n",
                "U410", "bad.urdf:3:3"},
        Hostile{"nested too deep", "<robot name=\"r\">" + [] {
                  std::string s;
                  for (int i = 0; i < 200; ++i) s += "<a>";
                  for (int i = 0; i < 200; ++i) s += "</a>";
                  return s;
                }() + "</robot>", "U401", "bad.urdf:1:1"}),
    [](const ::testing::TestParamInfo<Hostile>& param) {
      std::string s = param.param.what;
      for (char& c : s)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      return s;
    });

// A chain of n links on revolute joints.
std::string Chain(int n) {
  std::string s = "<robot name=\"chain\">\n<link name=\"l0\"/>\n";
  for (int i = 1; i <= n; ++i) {
    s += "<link name=\"l" + std::to_string(i) + "\"><inertial><mass value=\"1\"/><inertia ixx=\"1\" iyy=\"1\" izz=\"1\"/></inertial></link>\n";
    s += "<joint name=\"j" + std::to_string(i) + "\" type=\"revolute\"><parent link=\"l" + std::to_string(i - 1) +
         "\"/><child link=\"l" + std::to_string(i) + "\"/><origin xyz=\"0.1 0 0\"/></joint>\n";
  }
  return s + "</robot>\n";
}

TEST(ImportLimits, LongChainsImportWithoutRecursionAndTooManyElementsAreRefused) {
  const auto t0 = std::chrono::steady_clock::now();
  import::Result r = Import(Chain(20000));  // 40 001 elements: within the limit
  EXPECT_TRUE(r.ok) << r.diagnostics.substr(0, 500);
  // A bound against quadratic work (a hang), not a benchmark: ~0.3 s in a Release build.
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 30.0);
  import::Result big = Import(Chain(50001));  // 100 003 elements
  EXPECT_FALSE(big.ok);
  EXPECT_NE(big.diagnostics.find("error[U409]"), std::string::npos) << big.diagnostics.substr(0, 500);
}

TEST(ImportText, KeepsNamesAndSaysWhatItDropsOrCannotImpose) {
  import::Result r = Import(ReadText(kData + "/every_joint.urdf"));
  ASSERT_TRUE(r.ok) << r.diagnostics;
  // Names that are not identifiers: sanitized, the URDF name in a comment.
  EXPECT_NE(r.mech.find("Revolute rev_1(axis = {0, 0.6, 0.8}, q_min = -2, q_max = 2)"), std::string::npos) << r.mech;
  EXPECT_NE(r.mech.find("(URDF name 'rev-1')"), std::string::npos);
  EXPECT_NE(r.mech.find("BodyShape arm_1(m = 2.5"), std::string::npos);  // drawn by its visual, not its inertia box
  EXPECT_NE(r.mech.find("model every_joint "), std::string::npos);
  // rpy origins as FixedRPY; the fixed joint is the fixed frame itself; the massless leaf a Frame.
  EXPECT_NE(r.mech.find("FixedRPY rev_1_origin(r = {0.1, -0.05, 0.2}, rpy = {-1.5707963267948966, 0, 1.5707963267948966})"),
            std::string::npos);
  EXPECT_NE(r.mech.find("FixedRPY weld(r = {0.35, 0, 0.02}, rpy = {0.1, 0.2, 0.3})"), std::string::npos);
  EXPECT_NE(r.mech.find("Frame tool_tip"), std::string::npos);
  // The mimic joint: an exact coupling, no warning.
  EXPECT_NE(r.mech.find("JointCoupling follow_mimic(ratio = -1, offset = 0.01)"), std::string::npos) << r.mech;
  EXPECT_NE(r.mech.find("// <mimic joint=\"slide\"> of joint 'follow' (bad.urdf:64): follow.q = -1 * slide.q + 0.01"),
            std::string::npos);
  EXPECT_EQ(r.diagnostics.find("warning"), std::string::npos) << r.diagnostics;
  // <dynamics>, limits, collisions and the missing mesh.
  EXPECT_NE(r.mech.find("slide.tau = -(0.2 * slide.u);"), std::string::npos) << r.mech;
  EXPECT_NE(r.mech.find("friction_force = 0.1, friction_exact = true"), std::string::npos) << r.mech;
  EXPECT_NE(r.mech.find("limit lower 0 upper 0.2 effort 100 velocity 1 (the end stops q_min, q_max, with its <mimic> followers')"),
            std::string::npos);
  EXPECT_NE(r.diagnostics.find("note: 1 <collision> elements ignored"), std::string::npos) << r.diagnostics;
  EXPECT_NE(r.diagnostics.find("note: mesh 'package://no_such_package/meshes/arm2.stl' not found"), std::string::npos);
  // Visual primitives: the URDF's centred shapes moved onto the stdlib's end-face frames.
  EXPECT_NE(r.mech.find("Box arm_1_visual(lx = 0.4, ly = 0.05, lz = 0.05, m = 0, color = \"#cc1a1a\")"),
            std::string::npos);
  EXPECT_NE(r.mech.find("Cylinder base_visual(length = 0.1, radius = 0.2, m = 0, color = \"#9999a6\")"),
            std::string::npos);
}

// URDF names reach comments and description strings: a newline must not end a comment (the
// rest of the name would become model text), a quote must not end a string.
TEST(ImportText, NamesCannotInjectModelText) {
  const std::string urdf = TwoLinks(
      "  <joint name=\"j&#10;World second;&#10;//\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/></joint>",
      "  <link name=\"c&quot;d\\\"/>\n  <joint name=\"k\" type=\"fixed\"><parent link=\"b\"/><child link=\"c&quot;d\\\"/></joint>\n");
  import::Result r = Import(urdf);
  ASSERT_TRUE(r.ok) << r.diagnostics;
  pipeline::LoadResult lr = pipeline::LoadModel(pipeline::Source::Text("inject.urdf.mech", r.mech), {}, {});
  EXPECT_TRUE(lr.model) << lr.diagnostics << "\n" << r.mech;  // one World, and the text parses
  EXPECT_NE(r.mech.find("(URDF name 'j?World second;?//')"), std::string::npos) << r.mech;
}

// A value the importer computes below the normal range of doubles is written as 0: the
// language refuses such literals (L004), and the fuzzer found the written model refused.
// Here the inertia turned by a tiny angle has off-diagonal terms of about 1e-310 kg m^2.
TEST(ImportText, ComputedValuesBelowTheNormalRangeAreWrittenAsZero) {
  const std::string urdf =
      "<robot name=\"r\">\n  <link name=\"a\"><inertial><mass value=\"1\"/><origin rpy=\"1e-10 0 0\"/>"
      "<inertia ixx=\"3e-300\" iyy=\"2e-300\" izz=\"1e-300\"/></inertial></link>\n</robot>\n";
  import::Result r = Import(urdf);
  ASSERT_TRUE(r.ok) << r.diagnostics;
  EXPECT_NE(r.mech.find("I = [3e-300, 0, 0; 0, 2e-300, 0; 0, 0, 1e-300]"), std::string::npos) << r.mech;
  // The text parses; the compiler then refuses inertias this small (K317), as it should.
  pipeline::LoadResult lr = pipeline::LoadModel(pipeline::Source::Text("tiny.urdf.mech", r.mech), {}, {});
  EXPECT_EQ(lr.diagnostics.find("error[L"), std::string::npos) << lr.diagnostics << "\n" << r.mech;
  EXPECT_NE(lr.diagnostics.find("error[K317]"), std::string::npos) << lr.diagnostics;
}

TEST(ImportText, FloatingGivesTheRootAFreeBase) {
  import::Result fixed = Import(ReadText(kData + "/ur5_robot.urdf"));
  import::Result free = Import(ReadText(kData + "/ur5_robot.urdf"), true);
  ASSERT_TRUE(fixed.ok && free.ok);
  EXPECT_EQ(fixed.mech.find("FreeMotion"), std::string::npos);
  EXPECT_NE(free.mech.find("FreeMotion root_joint"), std::string::npos);
  EXPECT_NE(free.mech.find("connect(world.frame_b, root_joint.frame_a);"), std::string::npos);
}

// The pipeline loads a .urdf by the same translation, and its errors keep their location.
TEST(ImportPipeline, LoadsUrdfFilesAndReportsTheirErrors) {
  pipeline::LoadResult ok = pipeline::LoadModel(pipeline::Source::File(kData + "/every_joint.urdf"), {}, {});
  ASSERT_TRUE(ok.model) << ok.diagnostics;
  EXPECT_EQ(ok.diagnostics.find("note:"), std::string::npos);  // notes only from `import`
  pipeline::LoadResult bad =
      pipeline::LoadModel(pipeline::Source::Text("x.urdf", "<robot name=\"r\">\n  <link>\n</robot>\n"), {}, {});
  EXPECT_FALSE(bad.model);
  EXPECT_NE(bad.diagnostics.find("x.urdf:2:3: error[U401]"), std::string::npos) << bad.diagnostics;
}

}  // namespace
}  // namespace kanesim

namespace kanesim {
namespace {

// FixedRPY (stdlib/Parts.mech) against three FixedRotations (Rodrigues' formula) about z by
// yaw, then y by pitch, then x by roll: R = Rz Ry Rx. If this fails, every imported origin
// with an rpy is turned wrongly.
TEST(FixedRPY, EqualsRotationsAboutZThenYThenX) {
  const std::string text =
      "model T\n"
      "  World world;\n"
      "  FixedRPY rpy(r = {0.1, 0.2, 0.3}, rpy = {0.7, -1.1, 2.9});\n"
      "  FixedRotation yaw(r = {0.1, 0.2, 0.3}, n = {0, 0, 1}, angle = 2.9);\n"
      "  FixedRotation pitch(n = {0, 1, 0}, angle = -1.1);\n"
      "  FixedRotation roll(n = {1, 0, 0}, angle = 0.7);\n"
      "  Revolute j;\n"
      "  Body b(m = 1, I = identity(3));\n"
      "  output Real[3, 3] R1 = rpy.frame_b.R;\n"
      "  output Real[3, 3] R2 = roll.frame_b.R;\n"
      "  output Real[3] p1 = rpy.frame_b.r;\n"
      "  output Real[3] p2 = roll.frame_b.r;\n"
      "equation\n"
      "  connect(world.frame_b, rpy.frame_a);\n"
      "  connect(world.frame_b, yaw.frame_a);\n"
      "  connect(yaw.frame_b, pitch.frame_a);\n"
      "  connect(pitch.frame_b, roll.frame_a);\n"
      "  connect(world.frame_b, j.frame_a);\n"
      "  connect(j.frame_b, b.frame_a);\n"
      "end T;\n";
  pipeline::LoadResult r = pipeline::LoadModel(pipeline::Source::Text("rpy.mech", text), {}, {});
  ASSERT_TRUE(r.model) << r.diagnostics;
  const rt::Program& p = *r.model->program;
  std::vector<std::string> names;
  for (const char* v : {"R1", "R2"})
    for (int k = 1; k <= 9; ++k) names.push_back(std::string(v) + "[" + std::to_string(k) + "]");
  for (const char* v : {"p1", "p2"})
    for (int k = 1; k <= 3; ++k) names.push_back(std::string(v) + "[" + std::to_string(k) + "]");
  std::string err;
  auto plan = rt::PlanSignals(p, names, &err);
  ASSERT_TRUE(plan) << err;
  auto ws = rt::MakeWorkspace(p);
  std::vector<double> y(static_cast<std::size_t>(rt::StateSize(p)), 0.0), out(names.size());
  ASSERT_EQ(rt::EvalSignals(p, *plan, *ws, 0.0, y.data(), out.data()), 0);
  for (int k = 0; k < 9; ++k) EXPECT_NEAR(out[static_cast<std::size_t>(k)], out[static_cast<std::size_t>(9 + k)], 1e-15) << k;
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(out[static_cast<std::size_t>(18 + k)], out[static_cast<std::size_t>(21 + k)], 1e-15);
  EXPECT_NEAR(out[6], -std::sin(-1.1), 1e-15);  // R[3,1] = -sin(pitch): not the identity
}

}  // namespace
}  // namespace kanesim
