// The layer import/ (kanesim_import): robots described in URDF become readable `.mech` text
// (docs/import.md). `kanesim import` writes the text; `kanesim run robot.urdf` and
// `kanesim.load("robot.urdf")` load the same text in memory (pipeline/). The XML is read by
// expat (import/xml_doc.h); nothing else of kanesim is used, so the layer sits beside the language.
//
//   UrdfToMech     robot.urdf text -> the model's .mech text, notes and located errors
//
// Example (what `kanesim import robot.urdf -o robot.mech --floating` does):
//   import::Options o;
//   o.floating = true;
//   o.mesh_base_dir = ".";
//   import::Result r = import::UrdfToMech("robot.urdf", ReadFile("robot.urdf"), o);
//   std::cerr << r.diagnostics;
//   if (!r.ok) return 1;
//   Write("robot.mech", r.mech);
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace kanesim::import {

struct Options {
  bool floating = false;  // a free base: FreeMotion between the world and the root link
  // <mimic> joints as exact couplings (JointCoupling); false imports the follower as an
  // independent joint, as Pinocchio's default reading does (its references in tests/import).
  bool mimic = true;
  // <limit lower upper> of revolute and prismatic joints as end stops (q_min, q_max,
  // restitution 0); false (--limits ignore) records them in comments only, as Pinocchio's
  // dynamics ignore them.
  bool stops = true;
  // Where `package://NAME/...` mesh names are looked up, in order: each DIR as DIR/NAME/...
  // (and DIR/... when DIR's own name is NAME); ROS_PACKAGE_PATH's folders follow these.
  std::vector<std::string> package_paths;
  bool use_ros_package_path = true;  // also search the folders of $ROS_PACKAGE_PATH
  // Mesh files are written relative to this folder (the folder of the .mech file that names
  // them); "" writes them as found (absolute when the search path was).
  std::string mesh_base_dir;
  // Whether the notes (collisions ignored, limits recorded, meshes not found) go into
  // Result::diagnostics; errors always do.
  bool notes = true;
};

struct Result {
  bool ok = false;           // false: errors in `diagnostics`, `mech` empty
  std::string mech;          // the model's .mech text (one model; it names the stdlib's classes)
  std::string model_name;    // the model's name in `mech` (the robot's, sanitized)
  // Rendered: "file:line:col: error[U401]: ...", the URDF line with a caret, a hint; notes
  // ("note: ...") in the same form.
  std::string diagnostics;
  int num_errors = 0;
  // Each URDF link and joint by its URDF name, with what stands for it in `mech`: a link's
  // frame ("world.frame_b", "upper_arm.frame_a", "tool0" for a massless link) and a joint's
  // component ("shoulder_pan_joint"; "" for a fixed joint merged into its parent).
  std::vector<std::pair<std::string, std::string>> link_frames;
  std::vector<std::pair<std::string, std::string>> joints;
};

// The largest URDF file read (U409 beyond): callers check a file's size before reading it.
inline constexpr std::size_t kMaxUrdfBytes = std::size_t{64} << 20;
// "PATH: error[U409]: ..." for a file of `bytes` over kMaxUrdfBytes.
std::string TooLargeMessage(const std::string& path, std::uintmax_t bytes);

// `path` names the file in diagnostics and locates relative mesh names; `text` is its content.
Result UrdfToMech(const std::string& path, std::string_view text, const Options& options);

// Whether a file name is a URDF by its extension (".urdf", any case).
bool IsUrdfPath(std::string_view path);

}  // namespace kanesim::import
