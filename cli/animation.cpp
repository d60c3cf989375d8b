// `kanesim run --animation out.glb|out.gltf` (cli/scene.h AnimationRun): the bodies'
// poses are extra signals of the run, recorded beside the CSV and written after it through
// runtime/geometry's glTF export (docs/visualization.md, "Animated glTF").
#include <fmt/core.h>

#include <cstdio>
#include <filesystem>

#include "cli/scene.h"
#include "runtime/batch/file_guard.h"

namespace kanesim::cli {

bool AnimationRun::Prepare(const flat::Mechanism& mech, const rt::Program& program, std::vector<std::string>* signals) {
  if (!enabled()) return true;
  const std::string ext = std::filesystem::path(path_).extension().string();
  if (ext != ".glb" && ext != ".gltf") {
    fmt::print(stderr, "kanesim: error: --animation '{}' must end in .glb (binary glTF) or .gltf (JSON and .bin)\n",
               path_);
    return false;
  }
  if (std::string in = batch::OverwrittenInput(path_, mech.source_files); !in.empty()) {
    fmt::print(stderr, "kanesim: error: --animation '{}' is the model file '{}'; it would be destroyed\n", path_, in);
    return false;
  }
  std::string error;
  if (!BuildSceneBodies(mech, program, &scene_, &error, show_frames_)) {
    fmt::print(stderr, "kanesim: error: {}\n", error);
    return false;
  }
  if (scene_.bodies.empty()) {
    fmt::print(stderr, "kanesim: error: --animation: the model has no moving bodies to animate\n");
    return false;
  }
  if (signals->empty()) *signals = rt::DefaultSignals(program);
  n_shown_ = signals->size();
  signals->insert(signals->end(), scene_.pose_signals.begin(), scene_.pose_signals.end());
  return true;
}

sim::SignalSink& AnimationRun::Wrap(sim::SignalSink& csv) {
  if (!enabled()) return csv;
  recorder_ = std::make_unique<PoseRecorder>(&csv, n_shown_, scene_.bodies.size(), false);
  return *recorder_;
}

bool AnimationRun::Finish() {
  if (!enabled() || !recorder_) return true;
  if (recorder_->poses().times.empty()) {
    fmt::print(stderr, "kanesim: error: --animation: no instants were computed; '{}' not written\n", path_);
    return false;
  }
  geometry::ExportOptions options;
  options.up_W = scene_.up_W;
  const geometry::ExportResult r = geometry::ExportAnimation(path_, scene_.bodies, recorder_->poses(), options);
  if (!r.ok) {
    fmt::print(stderr, "kanesim: error: cannot write the animation '{}': {}\n", path_, r.error);
    return false;
  }
  if (r.stride > 1)
    fmt::print(stderr, "kanesim: note: the animation has every {}th of the {} instants (limit {} keys)\n", r.stride,
               recorder_->poses().times.size(), options.max_keys);
  return true;
}

}  // namespace kanesim::cli
