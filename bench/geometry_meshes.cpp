// Mesh mass properties and animation export (issue 22's speed targets, docs/benchmarks.md):
//   BM_MassProperties          a closed 100,000-triangle torus already in memory: the volume
//                              integrals and central inertia (target: under 50 ms)
//   BM_CheckSolid              weld + CheckSolid of the same mesh (what LoadMesh adds in memory)
//   BM_LoadAndMassProperties   the torus as a binary STL file (5 MB): LoadMesh (assimp read,
//                              weld, checks) + ComputeMassProperties (target: under 50 ms)
//   BM_ExportAnimation/glb|gltf 10 bodies x 1,000 instants through assimp's glTF exporter
//                              (target: under 50 ms)
//
//   build/bench/geometry_meshes
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "geometry/gltf_export.h"
#include "geometry/mass_properties.h"
#include "geometry/mesh_check.h"
#include "geometry/mesh_load.h"
#include "geometry/primitives.h"

namespace {

using namespace kanesim::geometry;

// A torus (major radius 0.3, minor 0.1) of nu x nv quads, 2 nu nv triangles, outward.
TriMesh Torus(int nu, int nv) {
  TriMesh m;
  const double R = 0.3, r = 0.1, two_pi = 2 * std::numbers::pi;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = two_pi * i / nu, v = two_pi * j / nv;
      m.vertices.emplace_back((R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v));
    }
  auto id = [&](int i, int j) { return static_cast<uint32_t>((i % nu) * nv + (j % nv)); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

const TriMesh& Torus100k() {
  static const TriMesh m = Torus(250, 200);  // 100,000 triangles
  return m;
}

void WriteBinaryStl(const std::string& path, const TriMesh& m) {
  std::ofstream out(path, std::ios::binary);
  std::string header(80, ' ');
  out.write(header.data(), 80);
  const auto n = static_cast<uint32_t>(m.triangles.size());
  out.write(reinterpret_cast<const char*>(&n), 4);
  for (const Tri& t : m.triangles) {
    float f[12] = {0, 0, 0};
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 3; ++i) f[3 + 3 * k + i] = static_cast<float>(m.vertices[t[k]][i]);
    out.write(reinterpret_cast<const char*>(f), sizeof f);
    out.write("\0\0", 2);
  }
}

void BM_MassProperties(benchmark::State& state) {
  const TriMesh& m = Torus100k();
  for (auto _ : state) benchmark::DoNotOptimize(ComputeMassProperties(m, MassSpec::Density(7800)).volume);
  // The inscribed mesh's volume against the round torus's 2 π² R r² (tessellation error).
  const double exact = 2 * std::numbers::pi * std::numbers::pi * 0.3 * 0.1 * 0.1;
  state.counters["triangles"] = static_cast<double>(m.triangles.size());
  state.counters["V_rel_err"] = ComputeMassProperties(m, MassSpec::Density(1)).volume / exact - 1;
}
BENCHMARK(BM_MassProperties)->Unit(benchmark::kMillisecond);

void BM_CheckSolid(benchmark::State& state) {
  const TriMesh& m = Torus100k();
  std::vector<Vec3> corners;
  std::vector<Tri> split;
  for (const Tri& t : m.triangles) {  // as an STL file has it: three vertices per triangle
    const auto base = static_cast<uint32_t>(corners.size());
    for (uint32_t v : t) corners.push_back(m.vertices[v]);
    split.push_back({base, base + 1, base + 2});
  }
  for (auto _ : state) {
    TriMesh welded = WeldByPosition(corners, split);
    const SolidReport r = CheckSolid(welded);
    if (!r.problems.empty()) state.SkipWithError("torus not clean");
    benchmark::DoNotOptimize(r.volume);
  }
}
BENCHMARK(BM_CheckSolid)->Unit(benchmark::kMillisecond);

void BM_LoadAndMassProperties(benchmark::State& state) {
  const std::string path = (std::filesystem::temp_directory_path() / "kanesim_bench_torus.stl").string();
  WriteBinaryStl(path, Torus100k());
  if (!LoadMesh(path).ok()) state.SkipWithError("load failed");  // also loads the assimp module
  for (auto _ : state) {
    const MeshLoadResult r = LoadMesh(path);
    const MassProperties mp = ComputeMassProperties(r.mesh, MassSpec::Density(7800));
    benchmark::DoNotOptimize(mp.volume);
  }
  state.counters["file_MB"] = static_cast<double>(std::filesystem::file_size(path)) / 1e6;
  std::filesystem::remove(path);
}
BENCHMARK(BM_LoadAndMassProperties)->Unit(benchmark::kMillisecond);

void BM_ExportAnimation(benchmark::State& state, const char* extension) {
  const int n_bodies = 10, n_times = 1000;
  std::vector<AnimatedBody> bodies;
  for (int b = 0; b < n_bodies; ++b)
    bodies.push_back({"link" + std::to_string(b), b % 2 ? DrawCylinder(0.02, 0.3) : DrawBox(Vec3(0.3, 0.04, 0.04))});
  PoseSequence poses;
  for (int k = 0; k < n_times; ++k) {
    const double t = 0.01 * k;
    poses.times.push_back(t);
    for (int b = 0; b < n_bodies; ++b) {
      poses.p_WB.emplace_back(0.3 * b * std::cos(t), 0.3 * b * std::sin(t), 0);
      poses.q_WB.emplace_back(Eigen::AngleAxisd(t * (b + 1), Vec3::UnitZ()));
    }
  }
  const std::string path =
      (std::filesystem::temp_directory_path() / (std::string("kanesim_bench_motion") + extension)).string();
  ExportOptions options;
  options.up_W = Vec3::UnitZ();
  if (!ExportAnimation(path, bodies, poses, options).ok) state.SkipWithError("export failed");
  for (auto _ : state) benchmark::DoNotOptimize(ExportAnimation(path, bodies, poses, options).ok);
  state.counters["file_kB"] = static_cast<double>(std::filesystem::file_size(path)) / 1e3;
}
BENCHMARK_CAPTURE(BM_ExportAnimation, glb, ".glb")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ExportAnimation, gltf, ".gltf")->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
