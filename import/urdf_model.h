// The URDF as read (urdf_read.cpp), checked as a tree (urdf_tree.cpp) and written as .mech
// (mech_write.cpp). Internal to import/. Units are the URDF's (SI); every pose is the URDF's
// <origin xyz rpy>: the child frame from the parent frame, R = Rz(yaw) Ry(pitch) Rx(roll).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "import/diagnostics.h"

namespace kanesim::import {

using Vec3 = std::array<double, 3>;

struct Pose {
  Vec3 xyz{0, 0, 0};
  Vec3 rpy{0, 0, 0};
  bool IsIdentity() const { return xyz == Vec3{0, 0, 0} && rpy == Vec3{0, 0, 0}; }
};

struct Inertial {
  double mass = 0.0;
  Pose origin;                                   // the centre of mass frame C in the link frame
  double ixx = 0, ixy = 0, ixz = 0, iyy = 0, iyz = 0, izz = 0;  // about C, resolved in C
};

enum class Shape { kMesh, kBox, kCylinder, kSphere };

struct Visual {
  Shape shape = Shape::kBox;
  Pose origin;          // the visual frame in the link frame
  std::string mesh;     // kMesh: the filename attribute as written (package://, file://, relative)
  Vec3 scale{1, 1, 1};  // kMesh
  Vec3 size{0, 0, 0};   // kBox
  double radius = 0, length = 0;  // kCylinder (along z, centred), kSphere
  std::string color;    // "#rrggbb" from <material><color rgba>, or ""
  int line = 0;
};

struct Link {
  std::string name;
  bool has_inertial = false;
  Inertial inertial;
  std::vector<Visual> visuals;
  int num_collisions = 0;
  int line = 0;
};

enum class JointType { kRevolute, kContinuous, kPrismatic, kFixed, kFloating, kPlanar };

struct Joint {
  std::string name;
  JointType type = JointType::kFixed;
  std::string parent, child;  // link names
  Pose origin;                // the joint frame J in the parent link frame; the child link frame is J moved
  Vec3 axis{1, 0, 0};         // in J (the URDF default)
  bool has_limit = false;
  double lower = 0, upper = 0, effort = 0, velocity = 0;
  double damping = 0, friction = 0;  // <dynamics>
  bool has_mimic = false;
  std::string mimic_joint;
  double multiplier = 1, offset = 0;
  int mimic_leader = -1;  // index into joints (urdf_tree.cpp)
  int line = 0;
};

struct Robot {
  std::string name;
  std::vector<Link> links;
  std::vector<Joint> joints;
  int root = -1;                         // index into links (urdf_tree.cpp)
  std::vector<int> parent_joint;         // per link: the joint whose child it is, -1 for the root
  std::vector<int> order;                // joints, parents before children
  int line = 0;
};

// The limits hostile files meet (docs/import.md "Limits").
inline constexpr int kMaxElements = 100000;   // links + joints
inline constexpr double kMaxMagnitude = 1e9;  // any number (SI units: a 1000 km robot is a typo)

// Reads the XML into *robot (urdf_read.cpp); false with errors in diags.
bool ReadUrdf(std::string_view text, Robot* robot, Diags& diags);
// Finds the root and the order, rejects cycles, several roots and unknown links (urdf_tree.cpp).
bool BuildTree(Robot* robot, Diags& diags);

}  // namespace kanesim::import
