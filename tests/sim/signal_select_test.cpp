// `--output PATTERN` globs: if these fail, users get the wrong columns (brackets taken
// as character classes, `*` stopping at dots, columns out of order or repeated) or an
// unhelpful error for a typo.
#include "sim/signal_select.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace kanesim::sim {
namespace {

TEST(SimGlob, StarMatchesAnyRunIncludingDotsAndBrackets) {
  EXPECT_TRUE(GlobMatch("*", ""));
  EXPECT_TRUE(GlobMatch("*", "link2.frame_b.r[1]"));
  EXPECT_TRUE(GlobMatch("*.q", "shoulder.q"));
  EXPECT_FALSE(GlobMatch("*.q", "shoulder.u"));
  EXPECT_TRUE(GlobMatch("link*", "link2.frame_b.r[1]"));
  EXPECT_TRUE(GlobMatch("a*b*c", "axxbyyc"));
  EXPECT_FALSE(GlobMatch("a*b*c", "axxbyy"));
  EXPECT_TRUE(GlobMatch("*ab", "aab"));  // needs backtracking
  EXPECT_FALSE(GlobMatch("a*a", "a"));
  EXPECT_TRUE(GlobMatch("**q", "q"));
}

TEST(SimGlob, BracketsAreLiteral) {
  EXPECT_TRUE(GlobMatch("j[*].q", "j[1].q"));
  EXPECT_TRUE(GlobMatch("j[*].q", "j[12].q"));
  EXPECT_FALSE(GlobMatch("j[*].q", "j1.q"));
  EXPECT_FALSE(GlobMatch("j[12].q", "j1.q"));  // not a class of '1' or '2'
  EXPECT_TRUE(GlobMatch("j[12].q", "j[12].q"));
  EXPECT_TRUE(GlobMatch("[", "["));
}

TEST(SimGlob, QuestionMarkIsExactlyOneCharacter) {
  EXPECT_TRUE(GlobMatch("ball.q[?]", "ball.q[2]"));
  EXPECT_FALSE(GlobMatch("ball.q[?]", "ball.q[12]"));
  EXPECT_FALSE(GlobMatch("?", ""));
  EXPECT_TRUE(GlobMatch("?", "a"));
  EXPECT_FALSE(GlobMatch("shoulder.Q", "shoulder.q"));  // case-sensitive
}

const std::vector<std::string> kAvailable = {"shoulder.q", "shoulder.u", "elbow.q", "elbow.u",
                                              "j[1].q",     "j[2].q",     "j[1].u",  "kinetic_energy"};

TEST(SimSelect, KeepsTheOrderOfAvailableSignalsAndTakesEachOnce) {
  std::vector<std::string> out;
  std::string error;
  ASSERT_TRUE(SelectSignals(kAvailable, {"elbow.*", "*.q"}, &out, &error)) << error;
  EXPECT_EQ(out, (std::vector<std::string>{"shoulder.q", "elbow.q", "elbow.u", "j[1].q", "j[2].q"}));
  ASSERT_TRUE(SelectSignals(kAvailable, {"j[*].u", "kinetic_energy"}, &out, &error));
  EXPECT_EQ(out, (std::vector<std::string>{"j[1].u", "kinetic_energy"}));
}

TEST(SimSelect, UnmatchedPatternIsAnErrorNamingCloseSignals) {
  std::vector<std::string> out;
  std::string error;
  EXPECT_FALSE(SelectSignals(kAvailable, {"*.q", "shouldr.q"}, &out, &error));
  EXPECT_NE(error.find("'shouldr.q'"), std::string::npos) << error;
  EXPECT_NE(error.find("did you mean 'shoulder.q'"), std::string::npos) << error;
  EXPECT_FALSE(SelectSignals(kAvailable, {"elbow.w"}, &out, &error));
  EXPECT_NE(error.find("'elbow.q'"), std::string::npos) << error;
  EXPECT_FALSE(SelectSignals(kAvailable, {"zzzzzzzzzzzzzzz"}, &out, &error));
  EXPECT_NE(error.find("available signals include"), std::string::npos) << error;
}

}  // namespace
}  // namespace kanesim::sim
