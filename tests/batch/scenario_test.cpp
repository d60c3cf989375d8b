// Scenario sources: grids, lists, samples, Latin hypercube, their product.
#include <gtest/gtest.h>

#include <cstring>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "batch/scenario.h"

namespace kanesim::batch {
namespace {

// Wrong if a range drops its end point to rounding or accumulates the step.
TEST(ParseValues, RangeIncludesEndWithoutAccumulation) {
  std::vector<double> v;
  std::string err;
  ASSERT_TRUE(ParseValues("0:0.1:1", &v, &err)) << err;
  ASSERT_EQ(v.size(), 11u);
  EXPECT_EQ(v[3], 0.1 * 3);  // a + i*step, not 0.1+0.1+0.1
  EXPECT_EQ(v.back(), 0.1 * 10);
  ASSERT_TRUE(ParseValues("3:-1:1", &v, &err));
  EXPECT_EQ(v, (std::vector<double>{3, 2, 1}));
  ASSERT_TRUE(ParseValues("0.5, 1.0,2e3", &v, &err));
  EXPECT_EQ(v, (std::vector<double>{0.5, 1.0, 2000}));
}

// Wrong if malformed text is accepted silently.
TEST(ParseValues, RejectsMalformed) {
  std::vector<double> v;
  std::string err;
  EXPECT_FALSE(ParseValues("1:0:3", &v, &err));
  EXPECT_FALSE(ParseValues("1:-1:3", &v, &err));
  EXPECT_FALSE(ParseValues("1:2", &v, &err));
  EXPECT_FALSE(ParseValues("1,x", &v, &err));
  EXPECT_FALSE(ParseValues("0:1e-9:1", &v, &err));  // a billion values
  Block b;
  EXPECT_FALSE(ParseGrid("=1,2", &b, &err));
  EXPECT_FALSE(ParseGrid("k", &b, &err));
}

// Wrong if the product order (first source slowest) or the ids change: --resume and
// --shard rely on ids that depend only on the sweep's definition.
TEST(CombineBlocks, CartesianProductFirstSlowest) {
  Block m, L;
  std::string err;
  ASSERT_TRUE(ParseGrid("m=1:1:3", &m, &err));
  ASSERT_TRUE(ParseGrid("L=0.5,1", &L, &err));
  std::vector<std::string> names;
  std::vector<Scenario> s;
  ASSERT_TRUE(CombineBlocks({m, L}, &names, &s, &err));
  EXPECT_EQ(names, (std::vector<std::string>{"m", "L"}));
  ASSERT_EQ(s.size(), 6u);
  const double want[6][2] = {{1, 0.5}, {1, 1}, {2, 0.5}, {2, 1}, {3, 0.5}, {3, 1}};
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(s[static_cast<size_t>(i)].id, i);
    EXPECT_EQ(s[static_cast<size_t>(i)].values, (std::vector<double>{want[i][0], want[i][1]}));
  }
  EXPECT_FALSE(CombineBlocks({m, m}, &names, &s, &err));  // one parameter, two sources
}

// Wrong if the list reader mixes up columns, misses run overrides or empty fields.
TEST(ReadListCsv, ColumnsAndRunOverrides) {
  std::string path = ::testing::TempDir() + "/list_test.csv";
  {
    std::ofstream f(path);
    f << "# scenarios\nk, stop_time ,c\n10,2,0.5\n\n20,,0.7\n";
  }
  Block b;
  std::string err;
  ASSERT_TRUE(ReadListCsv(path, &b, &err)) << err;
  EXPECT_EQ(b.names, (std::vector<std::string>{"k", "c"}));
  ASSERT_EQ(b.rows.size(), 2u);
  EXPECT_EQ(b.rows[1], (std::vector<double>{20, 0.7}));
  ASSERT_EQ(b.run.size(), 2u);
  EXPECT_EQ(b.run[0].stop_time, 2.0);
  EXPECT_TRUE(std::isnan(b.run[1].stop_time));
  {
    std::ofstream f(path);
    f << "k,c\n10\n";
  }
  EXPECT_FALSE(ReadListCsv(path, &b, &err));
  std::remove(path.c_str());
}

// Wrong if a seed does not reproduce its draws, or if different seeds coincide.
TEST(SampleBlock, ReproducibleFromSeed) {
  SampleSpec spec;
  spec.n = 50;
  spec.seed = 7;
  std::string err;
  Distribution u, g;
  ASSERT_TRUE(ParseDistribution("k=10:100", Distribution::Kind::Uniform, &u, &err));
  ASSERT_TRUE(ParseDistribution("c=0.5,0.05", Distribution::Kind::Normal, &g, &err));
  spec.dists = {u, g};
  Block a = SampleBlock(spec), b = SampleBlock(spec);
  EXPECT_EQ(a.rows, b.rows);
  spec.seed = 8;
  EXPECT_NE(SampleBlock(spec).rows, a.rows);
  for (const auto& row : a.rows) {
    EXPECT_GE(row[0], 10.0);
    EXPECT_LT(row[0], 100.0);
  }
}

// Wrong if the normal sampler is biased: mean and standard deviation of 20000 draws
// within 5 standard errors (fixed seed, so this is deterministic).
TEST(SampleBlock, NormalMoments) {
  SampleSpec spec;
  spec.n = 20000;
  spec.seed = 3;
  spec.dists = {Distribution{"c", Distribution::Kind::Normal, 0.5, 0.05}};
  Block b = SampleBlock(spec);
  double sum = 0, sq = 0;
  for (const auto& r : b.rows) sum += r[0], sq += r[0] * r[0];
  const double n = spec.n, mean = sum / n, sd = std::sqrt(sq / n - mean * mean);
  EXPECT_NEAR(mean, 0.5, 5 * 0.05 / std::sqrt(n));
  EXPECT_NEAR(sd, 0.05, 5 * 0.05 / std::sqrt(2 * n));
}

// Wrong if the Latin hypercube leaves a stratum empty or fills one twice.
TEST(SampleBlock, LatinHypercubeOnePointPerStratum) {
  SampleSpec spec;
  spec.n = 40;
  spec.seed = 11;
  spec.latin_hypercube = true;
  spec.dists = {Distribution{"a", Distribution::Kind::Uniform, 0, 1},
                Distribution{"b", Distribution::Kind::Uniform, -2, 2},
                Distribution{"c", Distribution::Kind::Normal, 0, 1}};
  Block blk = SampleBlock(spec);
  for (size_t j = 0; j < 3; ++j) {
    std::vector<int> count(40, 0);
    for (const auto& r : blk.rows) {
      double u = j == 0 ? r[0] : j == 1 ? (r[1] + 2) / 4 : 0.5 * std::erfc(-r[2] / std::sqrt(2.0));
      count[static_cast<size_t>(std::min(39.0, std::floor(u * 40)))]++;
    }
    EXPECT_TRUE(std::all_of(count.begin(), count.end(), [](int c) { return c == 1; })) << "dimension " << j;
  }
}

// Wrong if the inverse CDF is off: known quantiles of the standard normal.
TEST(InverseNormalCdf, KnownQuantiles) {
  EXPECT_NEAR(InverseNormalCdf(0.5), 0.0, 1e-15);
  EXPECT_NEAR(InverseNormalCdf(0.975), 1.959963984540054, 1e-13);
  EXPECT_NEAR(InverseNormalCdf(0.001), -3.090232306167814, 1e-12);
  EXPECT_NEAR(InverseNormalCdf(1e-10), -6.361340902404056, 1e-12);  // lower tail: p exact
}

// Wrong if the scenario sources written beside a summary (what `sweep merge` rebuilds the
// scenarios from) do not give back every scenario bit for bit: a grid, a list with NaN
// (model value) and per-row settings, a Latin-hypercube sample of normals, awkward values.
TEST(FormatBlocks, RoundTripRebuildsEveryScenarioExactly) {
  Block grid;
  std::string err;
  ASSERT_TRUE(ParseGrid("k=0.1:0.1:0.7", &grid, &err)) << err;
  Block list;
  list.names = {"a b", "c,d"};  // names that need CSV quoting
  list.rows = {{-0.0, kUnset}, {1e-300, 0.1 + 0.2}, {5e-324, -1.7976931348623157e308}};
  list.run = {RunOverride{}, RunOverride{2.5, 1e-9, kUnset}, RunOverride{kUnset, kUnset, 1e-12}};
  SampleSpec spec;
  spec.n = 9;
  spec.seed = 3;
  spec.latin_hypercube = true;
  spec.dists = {Distribution{"n", Distribution::Kind::Normal, 1.0, 0.3}};
  const std::vector<Block> blocks = {grid, list, SampleBlock(spec)};
  std::vector<std::string> names, names2;
  std::vector<Scenario> a, b;
  ASSERT_TRUE(CombineBlocks(blocks, &names, &a, &err)) << err;
  std::vector<Block> parsed;
  ASSERT_TRUE(ParseBlocks(FormatBlocks(blocks), &parsed, &err)) << err;
  ASSERT_TRUE(CombineBlocks(parsed, &names2, &b, &err)) << err;
  EXPECT_EQ(names, names2);
  ASSERT_EQ(a.size(), 7u * 3u * 9u);
  ASSERT_EQ(a.size(), b.size());
  auto same = [](double x, double y) { return std::memcmp(&x, &y, sizeof x) == 0 || (x != x && y != y); };
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].values.size(), b[i].values.size());
    for (size_t j = 0; j < a[i].values.size(); ++j) EXPECT_TRUE(same(a[i].values[j], b[i].values[j])) << i << " " << j;
    EXPECT_TRUE(same(a[i].run.stop_time, b[i].run.stop_time) && same(a[i].run.rtol, b[i].run.rtol) &&
                same(a[i].run.atol, b[i].run.atol))
        << i;
  }
  EXPECT_EQ(ScenarioDefinitionsDigest(names, a), ScenarioDefinitionsDigest(names2, b));
  // A changed value changes the digest (what merge compares with the settings record).
  b[5].values[0] = std::nextafter(b[5].values[0], 1.0);
  EXPECT_NE(ScenarioDefinitionsDigest(names, a), ScenarioDefinitionsDigest(names2, b));
  // Malformed sources are errors with a line, never a partial rebuild.
  for (const std::string bad : {"block 1 2 0\nk\n1\n", "block 1 1 0\nk\nx\n", "block 2 1 0\nk\n1\n",
                                "blocks 1 1 0\nk\n1\n", "block 1 1 1\nk\n1\n"}) {
    EXPECT_FALSE(ParseBlocks(bad, &parsed, &err)) << bad;
    EXPECT_NE(err.find("line "), std::string::npos) << err;
  }
}

}  // namespace
}  // namespace kanesim::batch
