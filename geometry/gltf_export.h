// The motion of a mechanism as an animated glTF 2.0 file, written through assimp's exporter
// (loaded lazily: assimp_module.h).
//
// The file: a root node, under it a static node that turns the world W into glTF's frame G
// (Y up: the world's up direction becomes +Y, so gravity points down in ordinary viewers),
// under that one node per body with its mesh and a material, at identity base transform,
// animated by translation and rotation keys (LINEAR) at the given instants, times in seconds.
// A key is the body frame's pose in W: p_G = R_GW (p_WB + R_WB p_B).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/tri_mesh.h"

namespace kanesim::geometry {

struct AnimatedBody {
  std::string name;                            // the body's name; unique names keep their node names readable
  VisualMesh mesh;                             // in the body frame B  (m); may be empty (a node without a mesh)
  std::array<float, 4> rgba{0.7f, 0.7f, 0.75f, 1.0f};  // base colour, linear RGBA in [0, 1]
};

// The poses of every body at every output instant, instant by instant:
// entry k * n_bodies + b is body b at times[k].
struct PoseSequence {
  std::vector<double> times;               // seconds, >= 0, non-decreasing  (n_times)
  std::vector<Vec3> p_WB;                  // B's origin from W's origin, resolved in W  (m)  (n_times · n_bodies)
  std::vector<Eigen::Quaterniond> q_WB;    // B's orientation in W (p_W = R(q) p_B), unit  (n_times · n_bodies)
};

struct ExportOptions {
  Vec3 up_W = Vec3::UnitY();  // the world's up direction (e.g. −g), resolved in W; non-zero
  // Long runs: above this many keys (n_times · n_bodies) the instants are decimated to every
  // stride-th one (the last always kept), stride the smallest that fits.
  uint64_t max_keys = 2'000'000;
};

struct ExportResult {
  bool ok = false;
  std::string error;                    // why not, when !ok (bad input, or assimp's message)
  std::vector<std::string> node_names;  // the node written for body b  (n_bodies)
  uint64_t times_written = 0;           // key count per channel
  uint64_t stride = 1;                  // decimation: every stride-th instant was written
  uint64_t times_merged = 0;            // instants dropped because their time (as a float) did not
                                        // advance: the later pose of equal times is kept
  std::vector<std::string> files;       // what was written: the .glb, or the .gltf and its .bin
};

// Writes `path`: ".glb" (binary glTF) or ".gltf" (JSON, with a .bin beside it, same stem).
// Rotation keys are q or −q (the same rotation), chosen so consecutive keys have a
// non-negative dot product and viewers interpolate the short way.
ExportResult ExportAnimation(const std::string& path, const std::vector<AnimatedBody>& bodies,
                             const PoseSequence& poses, const ExportOptions& options = {});

// The rotation that takes up_W to +Y by the shortest arc (a half turn about x when up_W
// points along −Y): R_GW in ExportAnimation.
Eigen::Quaterniond UpToY(const Vec3& up_W);

// Node names: "body_" + name (a prefix no assimp-internal id has), then "_2", "_3", … until
// unique. Returned in ExportResult::node_names.
std::vector<std::string> UniqueNodeNames(const std::vector<AnimatedBody>& bodies);

}  // namespace kanesim::geometry
