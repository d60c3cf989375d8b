#include "viz/page.h"

#include <fmt/format.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fcntl.h>
#include <unistd.h>

#include "viz/page_files.h"
#include "viz/scene_json.h"
#include "viz/viewer.h"

namespace kanesim::viz {
namespace {

struct LibrarySpec {
  const char* name;
  const char* path;  // relative to the JavaScript root
  const char* package;
  bool css;
};

// The third-party files, in the order the page loads them (OrbitControls extends THREE).
constexpr LibrarySpec kLibraries[] = {
    {"three.min.js", "three/build/three.min.js", "libjs-three", false},
    {"OrbitControls.js", "three/examples/js/controls/OrbitControls.js", "libjs-three", false},
    {"dygraph.min.js", "dygraphs/dygraph.min.js", "libjs-dygraphs", false},
    {"dygraph.min.css", "dygraphs/dygraph.min.css", "libjs-dygraphs", true},
};

// The page's own files, in load order.
constexpr const char* kOwnStyles[] = {"viewer.css"};
constexpr const char* kOwnScripts[] = {"scene.js", "plots.js", "viewer.js"};

// A source map comment makes a browser with developer tools open look for a file that is not
// there; the inlined copy drops it.
std::string WithoutSourceMap(std::string text) {
  for (const char* marker : {"//# sourceMappingURL=", "/*# sourceMappingURL="}) {
    const size_t at = text.rfind(marker);
    if (at != std::string::npos && text.find('\n', at) == std::string::npos) text.erase(at);
  }
  return text;
}

void AppendStyles(std::string& out, PageMode mode, const std::vector<LibraryFile>& libraries) {
  for (const LibraryFile& lib : libraries) {
    if (!lib.css) continue;
    if (mode == PageMode::kOffline)
      out += "<style>\n" + Inlinable(lib.text, "</style") + "\n</style>\n";
    else
      out += fmt::format("<link rel=\"stylesheet\" href=\"lib/{}\">\n", lib.name);
  }
  for (const char* name : kOwnStyles) out += "<style>\n" + Inlinable(PageFileText(name), "</style") + "</style>\n";
}

void AppendScripts(std::string& out, PageMode mode, const std::vector<LibraryFile>& libraries,
                   const std::string& scene_json) {
  for (const LibraryFile& lib : libraries) {
    if (lib.css) continue;
    if (mode == PageMode::kOffline)
      out += "<script>\n" + Inlinable(lib.text, "</script") + "\n</script>\n";
    else
      out += fmt::format("<script src=\"lib/{}\"></script>\n", lib.name);
  }
  if (mode == PageMode::kOffline) {
    out += "<script id=\"kanesim-scene\" type=\"application/json\">";
    out += scene_json;  // JsonString escapes '<': no end tag inside
    out += "</script>\n";
  } else {
    out += "<script id=\"kanesim-scene\" type=\"application/json\" data-src=\"scene.json\"></script>\n";
  }
  for (const char* name : kOwnScripts) out += "<script>\n" + Inlinable(PageFileText(name), "</script") + "</script>\n";
}

}  // namespace

// Text placed inside <script> or <style> must not contain its end tag; "<\/" means the same
// inside JavaScript strings, regular expressions and CSS.
std::string Inlinable(std::string_view text, std::string_view end_tag) {
  std::string out;
  out.reserve(text.size());
  size_t from = 0;
  for (size_t i = 0; i + end_tag.size() <= text.size(); ++i) {
    if (text[i] != '<') continue;
    bool match = true;
    for (size_t j = 0; j < end_tag.size() && match; ++j)
      match = std::tolower(static_cast<unsigned char>(text[i + j])) == end_tag[j];
    if (!match) continue;
    out.append(text.substr(from, i - from));
    out += "<\\";
    from = i + 1;
  }
  out.append(text.substr(from));
  return out;
}

std::string HtmlEscape(std::string_view text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string_view PageFileText(std::string_view name) {
  for (const PageFile* f = kPageFiles; f->name != nullptr; ++f)
    if (name == f->name) return {f->data, f->size};
  throw std::logic_error(fmt::format("viewer page file '{}' was not embedded", name));
}

std::vector<LibraryFile> ReadLibraries(const std::string& js_root, std::string* error) {
  std::vector<LibraryFile> out;
  for (const LibrarySpec& spec : kLibraries) {
    LibraryFile lib{spec.name, (std::filesystem::path(js_root) / spec.path).string(), spec.package, spec.css, ""};
    std::ifstream in(lib.path, std::ios::binary);
    std::error_code ec;
    if (!in || std::filesystem::is_directory(lib.path, ec)) {
      *error = fmt::format("the viewer needs {} ({}); install the Debian package {}", lib.path,
                           std::filesystem::exists(lib.path, ec) ? "cannot read it" : "not found", lib.package);
      return {};
    }
    std::ostringstream text;
    text << in.rdbuf();
    lib.text = WithoutSourceMap(std::move(text).str());
    out.push_back(std::move(lib));
  }
  return out;
}

const char* PagePolicy(PageMode mode) {
  if (mode == PageMode::kOffline)
    return "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; img-src data: blob:";
  return "default-src 'none'; script-src 'self' 'unsafe-inline'; style-src 'self' 'unsafe-inline'; "
         "img-src 'self' data: blob:; connect-src 'self'";
}

std::string ExpandPageFile(std::string_view file,
                           const std::function<bool(std::string_view name, std::string& out)>& fill) {
  const std::string_view page = PageFileText(file);
  std::string out;
  constexpr std::string_view kOpen = "<!--kanesim:", kClose = "-->";
  size_t from = 0;
  for (size_t at = page.find(kOpen); at != std::string_view::npos; at = page.find(kOpen, from)) {
    out.append(page.substr(from, at - from));
    const size_t end = page.find(kClose, at);
    if (end == std::string_view::npos)
      throw std::logic_error(fmt::format("{}: an unclosed <!--kanesim: marker", file));
    const std::string_view name = page.substr(at + kOpen.size(), end - at - kOpen.size());
    if (!fill(name, out)) throw std::logic_error(fmt::format("{}: unknown marker '{}'", file, name));
    from = end + kClose.size();
  }
  out.append(page.substr(from));
  return out;
}

std::string WriteFileReplacing(const std::string& path, const std::string& text) {
  namespace fs = std::filesystem;
  std::error_code ec;
  // The file a symbolic link names is the one replaced; the link stays.
  const fs::path target = fs::is_symlink(fs::symlink_status(path, ec)) ? fs::weakly_canonical(path, ec) : fs::path(path);
  const fs::file_status status = fs::status(target, ec);
  if (fs::exists(status) && !fs::is_regular_file(status))
    return fmt::format("cannot write {}: it exists and is not a regular file", path);
  const std::string temporary = target.string() + ".tmp." + std::to_string(::getpid());
  fs::remove(temporary, ec);  // a leftover of an earlier process with this id
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd < 0) return fmt::format("cannot write {}: {}", path, std::strerror(errno));
  size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n <= 0) break;
    done += static_cast<size_t>(n);
  }
  const int write_errno = errno;
  const bool written = done == text.size() && ::fsync(fd) == 0;
  const bool closed = ::close(fd) == 0;
  if (!written || !closed) {
    fs::remove(temporary, ec);
    return fmt::format("cannot write {}: {} (the previous file, if any, is unchanged)", path,
                       std::strerror(written ? errno : write_errno));
  }
  fs::rename(temporary, target, ec);
  if (ec) {
    std::string why = fmt::format("cannot write {}: {}", path, ec.message());
    fs::remove(temporary, ec);
    return why;
  }
  return "";
}

// The template has markers <!--kanesim:NAME--> for csp, title, styles and scripts.
std::string RenderPage(PageMode mode, const std::string& title, const std::vector<LibraryFile>& libraries,
                       const std::string& scene_json) {
  return ExpandPageFile("viewer.html", [&](std::string_view name, std::string& out) {
    if (name == "csp")
      out += fmt::format("<meta http-equiv=\"Content-Security-Policy\" content=\"{}\">", PagePolicy(mode));
    else if (name == "title")
      out += HtmlEscape(title);
    else if (name == "styles")
      AppendStyles(out, mode, libraries);
    else if (name == "scripts")
      AppendScripts(out, mode, libraries, scene_json);
    else
      return false;
    return true;
  });
}

PageResult WriteViewerHtml(const ViewerScene& scene, const std::string& path, const PageOptions& options) {
  PageResult result;
  EncodedScene encoded = EncodeScene(scene, options, &result.error);
  if (!result.error.empty()) return result;
  const std::vector<LibraryFile> libraries = ReadLibraries(options.js_root, &result.error);
  if (!result.error.empty()) return result;
  const std::string html = RenderPage(PageMode::kOffline, scene.title, libraries, encoded.json);

  result.error = WriteFileReplacing(path, html);
  if (!result.error.empty()) return result;
  result.ok = true;
  result.stride = encoded.stride;
  result.instants = encoded.instants;
  result.bytes = html.size();
  return result;
}

}  // namespace kanesim::viz
