// Writes the animation files that check_gltf.py parses back and the Khronos validator checks
// (tests/geometry/CMakeLists.txt), and with each group of files an expected*.json holding the
// poses given, so that the check does not trust the writer:
//   motion.glb, motion.gltf (+ motion.bin)  → expected.json
//   decimated.glb (101 instants, at most 26 keys per body: every 4th) → expected_decimated.json
//
// Three bodies named "crank", "crank" (a duplicate) and "material_0" (an assimp-internal id),
// the world's up along +z (so the Y-up rotation is not the identity), 101 instants over 2 s,
// rotations turning through more than a half turn (so q and −q both occur).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <string>

#include "geometry/gltf_export.h"
#include "geometry/primitives.h"

using namespace kanesim::geometry;

namespace {

constexpr int kBodies = 3;

Vec3 Position(int b, double t) { return {b + std::sin(t), std::cos(2 * t), 0.1 * t + 1}; }

Eigen::Quaterniond Rotation(int b, double t) {
  const Vec3 axis = Vec3(1, b, 2 - b).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(2.0 * t + b, axis));
}

// Writes each file of `names`; returns false (with a message) on failure.
bool WriteFiles(const std::string& dir, const std::vector<std::string>& names, const std::vector<AnimatedBody>& bodies,
                const PoseSequence& poses, const ExportOptions& options, std::vector<std::vector<std::string>>& nodes) {
  for (const std::string& name : names) {
    const ExportResult r = ExportAnimation(dir + "/" + name, bodies, poses, options);
    if (!r.ok) {
      std::fprintf(stderr, "%s: %s\n", name.c_str(), r.error.c_str());
      return false;
    }
    nodes.push_back(r.node_names);
  }
  return true;
}

// expected.json: up, colours, the files with their node names, and the instants `kept`.
void WriteExpected(const std::string& path, const std::vector<std::string>& names,
                   const std::vector<std::vector<std::string>>& nodes, const PoseSequence& poses,
                   const std::vector<int>& kept) {
  std::ofstream json(path);
  json << std::setprecision(17) << "{\"up\": [0, 0, 1], \"files\": {";
  for (size_t f = 0; f < names.size(); ++f) {
    json << (f ? ", " : "") << '"' << names[f] << "\": [";
    for (size_t b = 0; b < nodes[f].size(); ++b) json << (b ? ", " : "") << '"' << nodes[f][b] << '"';
    json << "]";
  }
  json << "}, \"colors\": [[0.8, 0.2, 0.2, 1], [0.2, 0.8, 0.2, 1], [0.2, 0.2, 0.8, 1]], \"times\": [";
  for (size_t i = 0; i < kept.size(); ++i) json << (i ? ", " : "") << poses.times[kept[i]];
  json << "], \"poses\": [";
  for (size_t i = 0; i < kept.size(); ++i) {
    json << (i ? ", " : "") << "[";
    for (int b = 0; b < kBodies; ++b) {
      const Vec3& p = poses.p_WB[kept[i] * kBodies + b];
      const Eigen::Quaterniond& q = poses.q_WB[kept[i] * kBodies + b];
      json << (b ? ", " : "") << "[" << p.x() << ", " << p.y() << ", " << p.z() << ", " << q.w() << ", " << q.x()
           << ", " << q.y() << ", " << q.z() << "]";
    }
    json << "]";
  }
  json << "]}\n";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUTDIR\n", argv[0]);
    return 1;
  }
  const std::string dir = argv[1];
  std::filesystem::create_directories(dir);
  const std::vector<AnimatedBody> bodies = {{"crank", DrawBox(Vec3(0.4, 0.1, 0.05)), {0.8f, 0.2f, 0.2f, 1}},
                                            {"crank", DrawCylinder(0.05, 0.3), {0.2f, 0.8f, 0.2f, 1}},
                                            {"material_0", DrawSphere(0.1, 2), {0.2f, 0.2f, 0.8f, 1}}};
  PoseSequence poses;
  const int n = 101;
  std::vector<int> all, every_fourth;
  for (int k = 0; k < n; ++k) {
    const double t = 2.0 * k / (n - 1);
    poses.times.push_back(t);
    for (int b = 0; b < kBodies; ++b) {
      poses.p_WB.push_back(Position(b, t));
      poses.q_WB.push_back(Rotation(b, t));
    }
    all.push_back(k);
    if (k % 4 == 0) every_fourth.push_back(k);
  }
  ExportOptions options;
  options.up_W = Vec3(0, 0, 1);
  std::vector<std::vector<std::string>> nodes;
  const std::vector<std::string> full = {"motion.glb", "motion.gltf"};
  if (!WriteFiles(dir, full, bodies, poses, options, nodes)) return 1;
  WriteExpected(dir + "/expected.json", full, nodes, poses, all);

  options.max_keys = kBodies * 26;  // stride ceil(100 / 25) = 4: instants 0, 4, …, 100
  nodes.clear();
  if (!WriteFiles(dir, {"decimated.glb"}, bodies, poses, options, nodes)) return 1;
  WriteExpected(dir + "/expected_decimated.json", {"decimated.glb"}, nodes, poses, every_fourth);
  return 0;
}
