// Array concatenation (lang/elab_concat.cpp): cat(k, ...), [A, B; C, D] and the array
// constructor {a, b}, against results computed by hand from Modelica 3.5 section 10.4,
// and their size, type, element-limit (E209) and work-limit (E228) diagnostics.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "tests/elab/elab_text.h"

namespace kanesim::lang::test {
namespace {

// Elaborates `decls` and expects every element of the 2-D parameter `name` (rows x cols,
// row-major `want`).
void ExpectMatrix(const std::string& decls, const std::string& name, int rows, int cols,
                  const std::vector<double>& want) {
  auto e = ElaborateText(ModelWith(decls));
  ASSERT_TRUE(e->ok) << e->errors;
  ASSERT_EQ(want.size(), static_cast<size_t>(rows * cols));
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) {
      const std::string n = name + "[" + std::to_string(i + 1) + "," + std::to_string(j + 1) + "]";
      EXPECT_EQ(e->P(n), want[static_cast<size_t>(i * cols + j)]) << decls << "\n" << n;
    }
  // No element beyond the declared size.
  EXPECT_TRUE(std::isnan(e->P(name + "[" + std::to_string(rows + 1) + ",1]")));
}

void ExpectVector(const std::string& decls, const std::string& name, const std::vector<double>& want) {
  auto e = ElaborateText(ModelWith(decls));
  ASSERT_TRUE(e->ok) << e->errors;
  for (size_t i = 0; i < want.size(); ++i)
    EXPECT_EQ(e->P(name + "[" + std::to_string(i + 1) + "]"), want[i]) << decls << " element " << i + 1;
  EXPECT_TRUE(std::isnan(e->P(name + "[" + std::to_string(want.size() + 1) + "]")));
}

// Subscripts select the cartesian product of each dimension's indices, row-major, a scalar
// index dropping its dimension (Modelica 3.5 section 10.5); X[i, j, k] = 100 i + 10 j + k
// gives every selected element's value by hand.
TEST(Concat, SubscriptsSelectTheProductOfEachDimensionsIndices) {
  const std::string X = "  parameter Real X[3, 3, 3] = {{{100 * i + 10 * j + k for k in 1:3} for j in 1:3} for i in 1:3};\n";
  // Y[a, b] = X[{3, 1}[a], b, 3]; Z[a, b] = X[2, a, {1, 3}[b]]
  ExpectMatrix(X + "  parameter Real Y[2, 3] = X[{3, 1}, :, end];", "Y", 2, 3, {313, 323, 333, 113, 123, 133});
  ExpectMatrix(X + "  parameter Real Z[3, 2] = X[2, :, {1, 3}];", "Z", 3, 2, {211, 213, 221, 223, 231, 233});
  ExpectVector(X + "  parameter Real v[3] = X[:, 2, 1];", "v", {121, 221, 321});
  ExpectVector(X + "  parameter Real s[1] = {X[1, 2, 3]};", "s", {123});
}

// If this fails, cat joins along the wrong dimension or interleaves the blocks wrongly.
TEST(Concat, CatAlongEachDimension) {
  ExpectVector("  parameter Real v[5] = cat(1, {1, 2}, {3}, {4, 5});", "v", {1, 2, 3, 4, 5});
  // Parameters stay symbols: the values follow a and b.
  ExpectVector("  parameter Real a = 7;\n  parameter Real b[2] = {a, 2 * a};\n  parameter Real v[4] = cat(1, b, {a + 1, 0});",
               "v", {7, 14, 8, 0});
  const std::string AB = "  parameter Real A[2, 2] = [1, 2; 3, 4];\n  parameter Real B[2, 1] = [5; 6];\n";
  // cat(2, A, B) = [1 2 5; 3 4 6]
  ExpectMatrix(AB + "  parameter Real C[2, 3] = cat(2, A, B);", "C", 2, 3, {1, 2, 5, 3, 4, 6});
  // cat(1, A, transpose(B)... ) : [1 2; 3 4; 5 6]
  ExpectMatrix(AB + "  parameter Real C[3, 2] = cat(1, A, transpose(B));", "C", 3, 2, {1, 2, 3, 4, 5, 6});
  // Three dimensions: X[2,2,2] with X[i,j,k] = 100 i + 10 j + k; cat(3, X, X) doubles the last.
  const std::string X = "  parameter Real X[2, 2, 2] = {{{100 * i + 10 * j + k for k in 1:2} for j in 1:2} for i in 1:2};\n";
  auto e = ElaborateText(ModelWith(X + "  parameter Real Y[2, 2, 4] = cat(3, X, X);\n"
                                       "  parameter Real Z[2, 4, 2] = cat(2, X, X);"));
  ASSERT_TRUE(e->ok) << e->errors;
  for (int i = 1; i <= 2; ++i)
    for (int j = 1; j <= 2; ++j)
      for (int k = 1; k <= 4; ++k) {
        const double want = 100 * i + 10 * j + (k - 1) % 2 + 1;
        EXPECT_EQ(e->P("Y[" + std::to_string(i) + "," + std::to_string(j) + "," + std::to_string(k) + "]"), want);
      }
  for (int i = 1; i <= 2; ++i)
    for (int j = 1; j <= 4; ++j)
      for (int k = 1; k <= 2; ++k) {
        const double want = 100 * i + 10 * ((j - 1) % 2 + 1) + k;
        EXPECT_EQ(e->P("Z[" + std::to_string(i) + "," + std::to_string(j) + "," + std::to_string(k) + "]"), want);
      }
  // Empty parts vanish; Integer parts give an Integer.
  ExpectVector("  parameter Integer n[2] = cat(1, zeros(0), {3, 4});", "n", {3, 4});
}

// If this fails, [A, B; C, D] does not build block matrices as Modelica does.
TEST(Concat, BlockMatrices) {
  const std::string ABCD =
      "  parameter Real A[2, 2] = [1, 2; 3, 4];\n  parameter Real B[2, 1] = {{5}, {6}};\n"
      "  parameter Real C[1, 2] = [7, 8];\n  parameter Real D = 9;\n";
  // [A, B; C, D] = [1 2 5; 3 4 6; 7 8 9]
  ExpectMatrix(ABCD + "  parameter Real M[3, 3] = [A, B; C, D];", "M", 3, 3, {1, 2, 5, 3, 4, 6, 7, 8, 9});
  // Vectors are columns: [u, v] is 3 x 2, [u; v] is 6 x 1.
  const std::string UV = "  parameter Real u[3] = {1, 2, 3};\n  parameter Real v[3] = {4, 5, 6};\n";
  ExpectMatrix(UV + "  parameter Real M[3, 2] = [u, v];", "M", 3, 2, {1, 4, 2, 5, 3, 6});
  ExpectMatrix(UV + "  parameter Real M[6, 1] = [u; v];", "M", 6, 1, {1, 2, 3, 4, 5, 6});
  // A rotation's columns from three axes, and a row appended to it.
  ExpectMatrix("  parameter Real R[4, 3] = [{0, 1, 0}, {-1, 0, 0}, {0, 0, 1}; 0, 0, 2];", "R", 4, 3,
               {0, -1, 0, 1, 0, 0, 0, 0, 1, 0, 0, 2});
  // Scalars still make plain matrices, and matrices of matrices nest.
  ExpectMatrix("  parameter Real M[2, 4] = [[1, 2; 3, 4], identity(2)];", "M", 2, 4, {1, 2, 1, 0, 3, 4, 0, 1});
  // {a, b} of vectors is the array constructor: the vectors become rows.
  ExpectMatrix(UV + "  parameter Real M[2, 3] = {u, v};", "M", 2, 3, {1, 2, 3, 4, 5, 6});
}

// The codes and places of the mistakes.
struct Bad {
  const char* decl;
  const char* code;
  const char* text;  // a piece of the rendered diagnostic
};

// If this fails, a size or type mismatch in a concatenation is not a diagnostic at the
// offending part (or names the wrong rule).
TEST(Concat, MismatchesAreDiagnostics) {
  const Bad cases[] = {
      {"parameter Real M[2, 2] = [{1, 2}, {3}];", "E205", "row 1 of [...]: block 2 is [1, 1] but block 1 is [2, 1]"},
      {"parameter Real M[2, 2] = [1, 2; 3];", "E205", "[...]: row 2 is [1, 1] but row 1 is [1, 2]"},
      {"parameter Real M[2, 3] = cat(2, [1, 2], [3; 4]);", "E205", "they must agree in every dimension but 2"},
      {"parameter Real v[3] = cat(1, {1, 2}, 3);", "E205", "argument 3 has 0 dimension(s)"},
      {"parameter Real v[3] = cat(1, 1, {2, 3});", "E205", "'cat' joins arrays, but argument 2 is a scalar"},
      {"parameter Real v[3] = cat(2, {1, 2}, {3});", "E219", "dimension 2 of 'cat' is out of range 1..1"},
      {"parameter Real v[3] = cat(1.5, {1, 2}, {3});", "E204", "must be an Integer"},
      {"parameter Real v[3] = cat(1);", "E214", "'cat' needs a dimension and at least one array"},
      {"parameter Real v[3] = cat(1, {1, 2}, {true});", "E204", "argument 3 is Boolean but argument 2 is Integer"},
      {"parameter Real M[2, 3] = {{1, 2}, {3, 4, 5}};", "E205", "to join arrays end to end write cat(1, a, b)"},
      {"parameter Real v[3] = cat(1, {1, 2}, {3, 4});", "E205", "declared"},
  };
  for (const Bad& c : cases) {
    auto e = ElaborateText(ModelWith(std::string("  ") + c.decl));
    EXPECT_FALSE(e->ok) << c.decl;
    EXPECT_TRUE(e->HasCode(c.code)) << c.decl << "\n" << e->errors;
    EXPECT_NE(e->errors.find(c.text), std::string::npos) << c.decl << "\n" << e->errors;
    EXPECT_NE(e->errors.find("test.mech:3:"), std::string::npos) << e->errors;
  }
}

// A grid of scalars [a, b; c, d] is built directly (ScalarGrid); this pins what the general
// joins give it. If this fails, a grid of Integers is not Integer, a Real among them does not
// make it Real, Booleans or Strings lose their kind or order, or a grid that is not one (a
// ragged row, a vector among scalars, mixed kinds) skips the general rules and their messages.
TEST(Concat, ScalarGridsAsTheJoinsDefineThem) {
  ExpectMatrix("  parameter Integer K[2, 3] = [1, 2, 3; 4, 5, 6];", "K", 2, 3, {1, 2, 3, 4, 5, 6});
  ExpectMatrix("  parameter Integer K[1, 1] = [7];", "K", 1, 1, {7});
  ExpectMatrix("  parameter Real M[2, 2] = [1, 2.5; 3, 4];", "M", 2, 2, {1, 2.5, 3, 4});
  ExpectMatrix("  parameter Boolean B[2, 2] = [true, false; false, true];", "B", 2, 2, {1, 0, 0, 1});
  auto s = ElaborateText(ModelWith("  parameter String S[2, 2] = [\"a\", \"b\"; \"c\", \"d\"];"));
  ASSERT_TRUE(s->ok) << s->errors;
  const char* want[] = {"a", "b", "c", "d"};
  for (int k = 0; k < 4; ++k) {
    const int i = s->mech.FindParam("S[" + std::to_string(k / 2 + 1) + "," + std::to_string(k % 2 + 1) + "]");
    ASSERT_GE(i, 0);
    EXPECT_EQ(s->mech.params[static_cast<size_t>(i)].string_value, want[k]);
  }
  auto real_in_integer = ElaborateText(ModelWith("  parameter Integer K[1, 2] = [1, 2.5];"));
  EXPECT_FALSE(real_in_integer->ok);
  const Bad cases[] = {
      {"parameter Real M[2, 2] = [1, true; 3, 4];", "E204", "row 1 of [...]: block 2 is Boolean but block 1 is Integer"},
      {"parameter Real M[2, 2] = [1, 2; true, false];", "E204", "[...]: row 2 is Boolean but row 1 is Integer"},
      {"parameter Real M[2, 2] = [1, 2; 3];", "E205", "[...]: row 2 is [1, 1] but row 1 is [1, 2]"},
      {"parameter Real M[2, 2] = [1, {2, 3}; 4, 5];", "E205", "row 1 of [...]: block 2 is [2, 1] but block 1 is [1, 1]"},
  };
  for (const Bad& c : cases) {
    auto e = ElaborateText(ModelWith(std::string("  ") + c.decl));
    EXPECT_TRUE(e->HasCode(c.code)) << c.decl << "\n" << e->errors;
    EXPECT_NE(e->errors.find(c.text), std::string::npos) << c.decl << "\n" << e->errors;
  }
}

// If this fails, a concatenation can exceed the element limit or escape the work budget.
TEST(Concat, LimitsHold) {
  // 60 000 + 60 000 elements: over the 100 000-element limit.
  auto big = ElaborateText(ModelWith("  parameter Real v[:] = cat(1, zeros(60000), ones(60000));"));
  EXPECT_TRUE(big->HasCode("E209")) << big->errors;
  auto blocks = ElaborateText(ModelWith("  parameter Real v[:, :] = [zeros(60000), ones(60000)];"));
  EXPECT_TRUE(blocks->HasCode("E209")) << blocks->errors;
  // 400 concatenations of 50 000 elements each: 2e7 steps, over the 1e7 budget.
  auto work = ElaborateText(ModelWith("  parameter Real s = sum({sum(cat(1, zeros(25000), ones(25000))) for i in 1:400});"));
  EXPECT_TRUE(work->HasCode("E228")) << work->errors.substr(0, 2000);
  EXPECT_FALSE(work->HasCode("E209"));
}

}  // namespace
}  // namespace kanesim::lang::test

#include "tests/support/load_util.h"

namespace kanesim::test {
namespace {

// A pendulum whose joint axis and centre of mass are written with cat and whose inertia is a
// block matrix: body of mass m, centre of mass at distance d below the pivot, central
// inertia Izz about the axis. Its angular acceleration (the signal j.a) is, at every
// instant, qdd = -m g d sin q / (Izz + m d^2).
// If this fails, the concatenated vectors or the block inertia reach the mechanism wrongly
// (Izz in the wrong place gives 0.02 or 0.03 instead of 0.045, the axis another joint).
TEST(Concat, ModelWithConcatenatedAxisAndInertiaRuns) {
  const double m = 2, d = 0.5, Izz = 0.045, g = 9.81;
  const std::string text = R"(
model CatPendulum
  parameter Real m = 2;
  parameter Real d = 0.5;
  World world(g = {0, -9.81, 0});
  Revolute j(axis = cat(1, zeros(2), {1}), q(start = 1.2), u(start = 0));
  Body body(m = m, r_CM = cat(1, {0, -d}, {0}),
            I = [diagonal({0.02, 0.03}), zeros(2, 1); zeros(1, 2), 0.045]);
equation
  connect(world.frame_b, j.frame_a);
  connect(j.frame_b, body.frame_a);
end CatPendulum;
)";
  auto l = LoadModel(text, {}, {}, /*is_text=*/true);
  ASSERT_TRUE(l && l->prog);
  auto s = RunModel(*l->prog, 2.0, 0.01, 1e-10, {"j.q", "j.a"});
  ASSERT_GT(s.rows.size(), 100u);
  const size_t cq = Col(s, "j.q"), ca = Col(s, "j.a");
  double err = 0, amax = 0;
  for (const auto& r : s.rows) {
    const double want = -m * g * d * std::sin(r[cq]) / (Izz + m * d * d);
    err = std::max(err, std::fabs(r[ca] - want));
    amax = std::max(amax, std::fabs(want));
  }
  EXPECT_GT(amax, 5.0);  // the pendulum swings: q0 = 1.2 rad gives |qdd| up to ~8.2
  EXPECT_LT(err, 1e-9 * amax);
}

}  // namespace
}  // namespace kanesim::test
