#include "runtime/viz/locus_page.h"

#include <fmt/format.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "runtime/viz/page.h"
#include "runtime/viz/page_files.h"

namespace kanesim::viz {
namespace {

// 17 significant digits (the CSV's, so the page holds the same doubles); null when not finite.
std::string Num(double x) { return std::isfinite(x) ? fmt::format("{:.17g}", x) : "null"; }

// A JSON string that may sit inside <script>: '<' and controls escaped.
std::string JsonString(std::string_view s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\')
      o += std::string("\\") + c;
    else if (static_cast<unsigned char>(c) < 0x20 || c == '<' || c == '>' || c == '&')
      o += fmt::format("\\u{:04x}", static_cast<unsigned char>(c));
    else
      o += c;
  }
  return o + "\"";
}

std::string DataJson(const LocusData& d) {
  std::string o = "{\"title\": " + JsonString(d.title) + ", \"parameter\": " + JsonString(d.parameter) +
                  ", \"values\": [";
  for (size_t i = 0; i < d.values.size(); ++i) o += (i ? ", " : "") + Num(d.values[i]);
  o += "],\n\"eigenvalues\": [";
  for (size_t i = 0; i < d.eigenvalues.size(); ++i) {
    o += i ? ",\n [" : "\n [";
    for (size_t k = 0; k < d.eigenvalues[i].size(); ++k)
      o += (k ? ", " : "") + fmt::format("[{}, {}]", Num(d.eigenvalues[i][k].real()), Num(d.eigenvalues[i][k].imag()));
    o += "]";
  }
  return o + "]}";
}

}  // namespace

std::string RenderLocusPage(const LocusData& data, const std::vector<LibraryFile>& libraries) {
  const std::string_view page = PageFileText("locus.html");
  std::string out;
  constexpr std::string_view kOpen = "<!--kanesim:", kClose = "-->";
  size_t from = 0;
  for (size_t at = page.find(kOpen); at != std::string_view::npos; at = page.find(kOpen, from)) {
    out.append(page.substr(from, at - from));
    const size_t end = page.find(kClose, at);
    if (end == std::string_view::npos) throw std::logic_error("locus.html: an unclosed <!--kanesim: marker");
    const std::string_view name = page.substr(at + kOpen.size(), end - at - kOpen.size());
    if (name == "csp") {
      out += fmt::format("<meta http-equiv=\"Content-Security-Policy\" content=\"{}\">", PagePolicy(PageMode::kOffline));
    } else if (name == "title") {
      out += HtmlEscape(data.title);
    } else if (name == "styles") {
      for (const LibraryFile& lib : libraries)
        if (lib.css && lib.name.rfind("dygraph", 0) == 0)
          out += "<style>\n" + Inlinable(lib.text, "</style") + "\n</style>\n";
    } else if (name == "scripts") {
      for (const LibraryFile& lib : libraries)
        if (!lib.css && lib.name.rfind("dygraph", 0) == 0)
          out += "<script>\n" + Inlinable(lib.text, "</script") + "\n</script>\n";
      out += "<script id=\"kanesim-locus\" type=\"application/json\">" + DataJson(data) + "</script>\n";
      out += "<script>\n" + Inlinable(PageFileText("locus.js"), "</script") + "</script>\n";
    } else {
      throw std::logic_error(fmt::format("locus.html: unknown marker '{}'", name));
    }
    from = end + kClose.size();
  }
  out.append(page.substr(from));
  return out;
}

bool WriteLocusHtml(const LocusData& data, const std::string& path, const std::string& js_root, std::string* error) {
  const std::vector<LibraryFile> libraries = ReadLibraries(js_root, error);
  if (!error->empty()) return false;
  const std::string html = RenderLocusPage(data, libraries);
  const std::string temporary = path + ".part";
  std::FILE* file = std::fopen(temporary.c_str(), "wb");
  if (file == nullptr) {
    *error = fmt::format("cannot write {}: {}", path, std::strerror(errno));
    return false;
  }
  const bool written = std::fwrite(html.data(), 1, html.size(), file) == html.size();
  const bool closed = std::fclose(file) == 0;
  std::error_code ec;
  if (!written || !closed) {
    *error = fmt::format("cannot write {}: {}", path, std::strerror(errno));
    std::filesystem::remove(temporary, ec);
    return false;
  }
  std::filesystem::rename(temporary, path, ec);
  if (ec) {
    *error = fmt::format("cannot write {}: {}", path, ec.message());
    std::filesystem::remove(temporary, ec);
    return false;
  }
  return true;
}

}  // namespace kanesim::viz
