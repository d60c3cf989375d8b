// What the bodies look like and how they moved, for the commands that show motion:
// `kanesim check`'s mesh report (mesh_report.cpp), `run --animation` (animation.cpp) and
// `kanesim view` (cmd_view.cpp). docs/visualization.md, "The language side".
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

#include "runtime/runtime.h"
#include "flat/mechanism.h"
#include "geometry/gltf_export.h"
#include "sim/csv.h"

namespace CLI {
class App;
}

namespace kanesim::cli {

// `kanesim check`: each MeshBody's file, volume, mass, centre of mass and central inertia.
void PrintMeshBodies(const flat::Mechanism& mech, std::ostream& out);

// The drawn bodies of a mechanism: one per flat::Body whose pose the program reports, drawn
// as its shape (Rod, Box, Cylinder, Sphere, MeshBody: flat::Shape) or, for a bare Body, as
// its inertia-equivalent box (primitives.h InertiaBox; a point mass as a small sphere).
struct SceneBodies {
  std::vector<geometry::AnimatedBody> bodies;  // name = the flat body's name; mesh in its frame B  (n_bodies)
  std::vector<std::string> labels;             // "Box link, model.mech:7"  (n_bodies)
  // The signals giving each body's pose, 12 per body: its frame's origin r[1..3] (p_WB, m) and
  // its rotation R[1,1] .. R[3,3] (R_WB, row-major)  (12 n_bodies)
  std::vector<std::string> pose_signals;
  geometry::Vec3 up_W = geometry::Vec3::UnitY();  // −g normalised (+y without gravity)
};

// Builds the drawings with the parameter values of this run; false with a message when a
// mesh cannot be read for drawing (it was read at elaboration, so only if it changed since).
// With `show_frames` (--show-frames), every joint's frame_a and frame_b that moves with a body
// is drawn as small axes too: three nodes "axes_<frame>_x|y|z" (red, green, blue rods of
// `frame_axes_length`, or a tenth of the largest drawing when 0), placed at the frame's
// origin <frame>.r[*] and turned with it.
bool BuildSceneBodies(const flat::Mechanism& mech, const rt::Program& program, SceneBodies* out, std::string* error,
                      bool show_frames = false, double frame_axes_length = 0);

// A sink in front of another: the first `n_shown` signals of each row go on to `inner` (the
// CSV), the rest are the pose signals, kept. Optionally keeps the shown values too (the
// viewer's plots).
class PoseRecorder final : public sim::SignalSink {
 public:
  PoseRecorder(sim::SignalSink* inner, size_t n_shown, size_t n_bodies, bool keep_shown)
      : inner_(inner), n_shown_(n_shown), n_bodies_(n_bodies), keep_shown_(keep_shown) {}
  bool Begin(const std::vector<std::string>& names) override;
  bool Row(double t, const double* values, size_t count) override;
  bool End() override { return inner_ ? inner_->End() : true; }

  const geometry::PoseSequence& poses() const { return poses_; }
  const std::vector<std::string>& shown_names() const { return shown_names_; }
  // values of shown signal i at instant k: shown_[k * n_shown + i]
  const std::vector<double>& shown_values() const { return shown_; }

 private:
  sim::SignalSink* inner_;
  size_t n_shown_, n_bodies_;
  bool keep_shown_;
  std::vector<std::string> shown_names_;
  geometry::PoseSequence poses_;
  std::vector<double> shown_;
};

// `kanesim run --animation out.glb|out.gltf`: the poses ride along with the CSV's signals
// and are written through geometry's glTF export after the run.
class AnimationRun {
 public:
  explicit AnimationRun(std::string path, bool show_frames = false)
      : path_(std::move(path)), show_frames_(show_frames) {}
  bool enabled() const { return !path_.empty(); }
  // Adds the pose signals to `signals` (the CSV's; filled with the defaults when empty).
  // False, with a message on stderr, when the path or the drawings are unusable.
  bool Prepare(const flat::Mechanism& mech, const rt::Program& program, std::vector<std::string>* signals);
  // The sink to simulate into: the recorder in front of `csv`, or `csv` when disabled.
  sim::SignalSink& Wrap(sim::SignalSink& csv);
  // Writes the file from the rows recorded (all of them, or those before a failure). False,
  // with a message on stderr, when it cannot.
  bool Finish();

 private:
  std::string path_;
  bool show_frames_ = false;
  SceneBodies scene_;
  std::unique_ptr<PoseRecorder> recorder_;
  size_t n_shown_ = 0;
};

// `kanesim view` (cmd_view.cpp).
void AddViewCommand(CLI::App& app, int* exit_code, bool options = true);

}  // namespace kanesim::cli
