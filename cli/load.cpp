// Loading a model for any subcommand through the pipeline (pipeline/pipeline.h),
// with its diagnostics on stderr.
#include <fstream>
#include <iostream>
#include <sstream>
#include <vector>

#include "cli/common.h"
#include "batch/csv_util.h"
#include "lang/diagnostics.h"
#include "runtime/program/program.h"
#include "stdlib/stdlib.h"

namespace kanesim::cli {

std::string ReadFileText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

bool ReadFileInto(const std::string& path, std::string* out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::stringstream ss;
  ss << in.rdbuf();
  *out = ss.str();
  return !in.bad();
}

std::string StdlibHash() {
  std::string all;
  for (const auto& [name, text] : stdlib::Files()) all.append(name).append("\n").append(text).append("\n");
  return batch::Fnv1a64Hex(all);
}

const pipeline::Model& LeaveToExit(std::unique_ptr<pipeline::Model> model) {
  static auto* kept = new std::vector<std::unique_ptr<pipeline::Model>>();
  kept->push_back(std::move(model));
  return *kept->back();
}

std::unique_ptr<pipeline::Model> LoadAndCompile(const LoadOptions& options, const pipeline::RunSpec& spec,
                                                bool compile) {
  pipeline::LoadOptions lo;
  lo.model = options.model;
  lo.sets = options.sets;
  lo.compile = compile;
  lo.urdf.floating = options.floating;
  lo.urdf.stops = options.stops;
  lo.urdf.package_paths = options.package_paths;
  lo.leave_to_exit = options.leave_to_exit;
  pipeline::LoadResult r = pipeline::LoadModel(pipeline::Source::File(options.path), lo, spec);
  std::cerr << r.diagnostics;
  return std::move(r.model);
}

}  // namespace kanesim::cli
