// `kanesim run --animation out.glb|out.gltf` (cli/scene.h AnimationRun): the bodies'
// poses are extra signals of the run, recorded beside the CSV and written after it through
// geometry's glTF export (docs/visualization.md, "Animated glTF").
#include <fcntl.h>
#include <fmt/core.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "cli/scene.h"
#include "batch/file_guard.h"

namespace kanesim::cli {

namespace {

// The files an animation at `path` consists of.
std::vector<std::string> OutputFiles(const std::string& path) {
  std::vector<std::string> files = {path};
  if (std::filesystem::path(path).extension() == ".gltf")
    files.push_back(std::filesystem::path(path).replace_extension(".bin").string());
  return files;
}

bool SyncFile(const std::string& path) {
  int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  const bool ok = ::fsync(fd) == 0;
  ::close(fd);
  return ok;
}

// The export goes into a fresh folder beside the target (<target>.tmp.<host>.<pid>, so a
// killed run's folder is removed by the next one), under the target's own name, so that a
// .gltf names its .bin as it will be called. Every file is fsynced, then renamed over its
// target, the .bin before the .gltf that refers to it. A full disk, a kill or a crash
// before the renames leaves the previous animation whole (issue 38).
bool WriteReplacing(const std::string& path, const SceneBodies& scene, const geometry::PoseSequence& poses,
                    const geometry::ExportOptions& options, geometry::ExportResult* r, std::string* error) {
  namespace fs = std::filesystem;
  const fs::path target(batch::ReplacedFile(path));
  const fs::path folder(batch::TempPathFor(target.string()));
  batch::RemoveStaleTemps(target.string());
  std::error_code ec;
  fs::remove_all(folder, ec);
  if (!fs::create_directory(folder, ec)) {
    *error = "cannot create '" + folder.string() + "': " + ec.message();
    return false;
  }
  *r = geometry::ExportAnimation((folder / target.filename()).string(), scene.bodies, poses, options);
  bool ok = r->ok;
  if (!ok) *error = r->error;
  for (const std::string& f : r->files)
    if (ok && !SyncFile(f)) ok = false, *error = "cannot write '" + f + "': " + std::strerror(errno);
  for (auto it = r->files.rbegin(); ok && it != r->files.rend(); ++it) {
    const fs::path to = target.parent_path() / fs::path(*it).filename();
    if (::rename(it->c_str(), to.c_str()) != 0)
      ok = false, *error = "cannot rename to '" + to.string() + "': " + std::strerror(errno);
  }
  fs::remove_all(folder, ec);
  if (ok) batch::SyncParentDir(target.string());
  return ok;
}

}  // namespace

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
  for (const std::string& file : OutputFiles(path_))
    if (std::string what = batch::NotRegularFile(file); !what.empty()) {
      fmt::print(stderr, "kanesim: error: --animation: '{}' is {}, not a regular file; it would be destroyed\n", file,
                 what);
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
  geometry::ExportResult r;
  std::string error;
  if (!WriteReplacing(path_, scene_, recorder_->poses(), options, &r, &error)) {
    fmt::print(stderr, "kanesim: error: cannot write the animation '{}': {}; the previous file, if any, is unchanged\n",
               path_, error);
    return false;
  }
  if (r.stride > 1)
    fmt::print(stderr, "kanesim: note: the animation has every {}th of the {} instants (limit {} keys)\n", r.stride,
               recorder_->poses().times.size(), options.max_keys);
  return true;
}

}  // namespace kanesim::cli
