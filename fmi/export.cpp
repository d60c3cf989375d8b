// `kanesim export --fmi 2|3`: the FMU file, zipped with Debian's minizip.
#include <zip.h>

#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "fmi/fmi.h"
#include "fmi/instance.h"

#ifndef KANESIM_FMU_BUILD_DIR
#define KANESIM_FMU_BUILD_DIR ""
#endif
#ifndef KANESIM_INSTALLED_FMU_DIR
#define KANESIM_INSTALLED_FMU_DIR "../lib/kanesim/fmu"
#endif

namespace kanesim::fmi {
namespace {

namespace fs = std::filesystem;

// FNV-1a, 64 bits: the GUID names this text with these settings, so an FMU's library
// refuses a modelDescription.xml that was not written with its resources.
std::uint64_t Hash(const std::string& text, std::uint64_t h = 1469598103934665603ull) {
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ull;
  return h;
}

std::string Guid(const std::string& text) {
  const std::uint64_t a = Hash(text), b = Hash(text, a ^ 0x9e3779b97f4a7c15ull);
  char buf[40];
  std::snprintf(buf, sizeof buf, "{%08x-%04x-%04x-%04x-%012llx}", unsigned(a >> 32), unsigned(a >> 16) & 0xffff,
                unsigned(a) & 0xffff, unsigned(b >> 48), static_cast<unsigned long long>(b & 0xffffffffffffull));
  return buf;
}

bool ReadFile(const fs::path& path, std::string* out) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return false;
  std::ostringstream s;
  s << f.rdbuf();
  *out = s.str();
  return true;
}

// One zip archive being written; every entry deflated.
class Zip {
 public:
  explicit Zip(const std::string& path) : zf_(zipOpen64(path.c_str(), APPEND_STATUS_CREATE)) {}
  ~Zip() {
    if (zf_) zipClose(zf_, nullptr);
  }
  bool ok() const { return zf_ != nullptr; }
  bool Add(const std::string& name, const std::string& data) {
    zip_fileinfo info{};
    info.tmz_date.tm_mday = 1;  // 1980-01-01: a fixed date, so the same export gives the same bytes
    info.external_fa = 0644u << 16;
    if (zipOpenNewFileInZip64(zf_, name.c_str(), &info, nullptr, 0, nullptr, 0, nullptr, Z_DEFLATED,
                              Z_DEFAULT_COMPRESSION, data.size() > 0xffffffffu) != ZIP_OK)
      return false;
    const bool written = zipWriteInFileInZip(zf_, data.data(), unsigned(data.size())) == ZIP_OK;
    return zipCloseFileInZip(zf_) == ZIP_OK && written;
  }
  bool Close() {
    const bool closed = zipClose(zf_, nullptr) == ZIP_OK;
    zf_ = nullptr;
    return closed;
  }

 private:
  zipFile zf_;
};

// The data files the model read (its meshes) go into resources/files/ (an FMU carries what
// it reads): their entries and names into *settings, their bytes into *contents.
std::string CarryDataFiles(const flat::Mechanism& mech, FmuSettings* settings, std::vector<std::string>* contents) {
  if (mech.data_files.empty()) return "";
  settings->main = mech.source_files.front();
  for (const std::string& path : mech.data_files) {
    if (path.find('\n') != std::string::npos || settings->main.find('\n') != std::string::npos)
      return "cannot export a file name with a line break: " + path;
    std::string entry = fs::path(path).filename().string();
    for (char& c : entry)
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '-' && c != '_') c = '_';
    settings->files.emplace_back("files/" + std::to_string(settings->files.size() + 1) + "-" + entry, path);
    contents->emplace_back();
    if (!ReadFile(path, &contents->back())) return "cannot read " + path + ", a file the model reads";
  }
  return "";
}

}  // namespace

std::string FmuBinariesDir(std::string* error) {
  std::vector<fs::path> tried;
  if (const char* env = std::getenv("KANESIM_FMU_DIR")) {
    tried.push_back(env);
  } else {
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec) tried.push_back(exe.parent_path() / KANESIM_INSTALLED_FMU_DIR);
    if (*KANESIM_FMU_BUILD_DIR) tried.push_back(KANESIM_FMU_BUILD_DIR);
  }
  std::string list;
  for (const fs::path& dir : tried) {
    if (fs::exists(dir / "kanesim_fmu.so")) return fs::weakly_canonical(dir).string();
    list += "\n  " + (dir / "kanesim_fmu.so").string();
  }
  *error = "the FMU library kanesim_fmu.so is not installed; looked for:" + list;
  return "";
}

std::string ExportFmu(const pipeline::Model& model, const std::string& model_text, const ExportOptions& options) {
  if (options.version != 2 && options.version != 3) return "FMI " + std::to_string(options.version) + " does not exist";
  std::string error;
  const std::string bin = options.binaries_dir.empty() ? FmuBinariesDir(&error) : options.binaries_dir;
  if (bin.empty()) return error;

  FmuSettings settings;
  settings.model = options.model.empty() ? model.mech->model_name : options.model;
  settings.sets = options.sets;
  settings.integrator = options.integrator;
  std::vector<std::string> contents;
  if (std::string e = CarryDataFiles(*model.mech, &settings, &contents); !e.empty()) return e;
  std::string hashed = model_text + "\n" + FormatSettings(settings) + std::to_string(options.version);
  for (const std::string& c : contents) hashed += c;
  settings.guid = Guid(hashed);
  const std::string id = Identifier(model.mech->model_name);

  Zip zip(options.output);
  if (!zip.ok()) return "cannot write " + options.output;
  const std::string description = options.version == 3 ? ModelDescription3(model, options, settings.guid)
                                                       : ModelDescription(model, options, settings.guid);
  const std::string platform = options.version == 3 ? "binaries/x86_64-linux/" : "binaries/linux64/";
  bool ok = zip.Add("modelDescription.xml", description) &&
            zip.Add("resources/model.mech", model_text) && zip.Add("resources/settings.txt", FormatSettings(settings));
  for (size_t i = 0; i < contents.size(); ++i) ok = ok && zip.Add("resources/" + settings.files[i].first, contents[i]);
  // The model's library under the FMU's name, and beside it the shared libraries it needs
  // that are not the system's (its RPATH is $ORIGIN).
  for (const fs::directory_entry& entry : fs::directory_iterator(bin)) {
    std::string data;
    const std::string name = entry.path().filename().string();
    if (!entry.is_regular_file() || !ReadFile(entry.path(), &data)) continue;
    ok = ok && zip.Add(platform + (name == "kanesim_fmu.so" ? id + ".so" : name), data);
  }
  if (!zip.Close() || !ok) {
    std::error_code ec;
    fs::remove(options.output, ec);  // no half-written FMU left behind
    return "cannot write " + options.output;
  }
  return "";
}

}  // namespace kanesim::fmi
