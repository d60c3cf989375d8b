// The viewer page (viz, docs/benchmarks.md "Viewer page"):
//   BM_EncodeScene      10 bodies x 1,000 instants and 10 signals: the scene JSON alone
//   BM_WriteViewerHtml  the same written as the offline page: the JSON, the libraries read from
//                       /usr/share/javascript (~1 MB), the file written and renamed
//                       (target: well under a second)
//
//   build/bench/viewer_page
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "geometry/primitives.h"
#include "viz/scene_json.h"
#include "viz/viewer.h"

namespace {

using namespace kanesim;
using geometry::Vec3;

viz::ViewerScene Scene(int n_bodies, int n_times, int n_signals) {
  viz::ViewerScene s;
  s.up_W = Vec3::UnitZ();
  for (int b = 0; b < n_bodies; ++b)
    s.bodies.push_back({"link" + std::to_string(b), "",
                        b % 2 ? geometry::DrawCylinder(0.02, 0.3) : geometry::DrawBox(Vec3(0.3, 0.04, 0.04)),
                        {0.7f, 0.7f, 0.75f, 1}});
  s.decorations.push_back({"ground", -1, geometry::DrawGrid(Vec3::UnitZ(), 2, 0.25, 0.01), {0.5f, 0.5f, 0.5f, 1}});
  for (int i = 0; i < n_signals; ++i) s.signals.push_back({"q" + std::to_string(i), "rad", {}, i < 3});
  for (int k = 0; k < n_times; ++k) {
    const double t = 0.01 * k;
    s.poses.times.push_back(t);
    for (int b = 0; b < n_bodies; ++b) {
      s.poses.p_WB.emplace_back(0.3 * b * std::cos(t), 0.3 * b * std::sin(t), 0);
      s.poses.q_WB.emplace_back(Eigen::AngleAxisd(t * (b + 1), Vec3::UnitZ()));
    }
    for (int i = 0; i < n_signals; ++i) s.signals[i].values.push_back(std::sin(t * (i + 1)));
  }
  return s;
}

void BM_EncodeScene(benchmark::State& state) {
  const viz::ViewerScene scene = Scene(10, 1000, 10);
  std::string error;
  size_t bytes = 0;
  for (auto _ : state) bytes = viz::EncodeScene(scene, {}, &error).json.size();
  if (!error.empty()) state.SkipWithError(error.c_str());
  state.counters["json_kB"] = static_cast<double>(bytes) / 1e3;
}
BENCHMARK(BM_EncodeScene)->Unit(benchmark::kMillisecond);

void BM_WriteViewerHtml(benchmark::State& state) {
  const viz::ViewerScene scene = Scene(10, static_cast<int>(state.range(0)), 10);
  const std::string path = (std::filesystem::temp_directory_path() / "kanesim_bench_viewer.html").string();
  viz::PageResult r;
  for (auto _ : state) {
    r = viz::WriteViewerHtml(scene, path);
    if (!r.ok) state.SkipWithError(r.error.c_str());
  }
  state.counters["page_kB"] = static_cast<double>(r.bytes) / 1e3;
  state.counters["stride"] = static_cast<double>(r.stride);
  std::filesystem::remove(path);
}
BENCHMARK(BM_WriteViewerHtml)->Arg(1000)->Arg(100000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
