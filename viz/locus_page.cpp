#include "viz/locus_page.h"

#include <fmt/format.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "viz/page.h"
#include "viz/page_files.h"

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
  return ExpandPageFile("locus.html", [&](std::string_view name, std::string& out) {
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
      return false;
    }
    return true;
  });
}

bool WriteLocusHtml(const LocusData& data, const std::string& path, const std::string& js_root, std::string* error) {
  const std::vector<LibraryFile> libraries = ReadLibraries(js_root, error);
  if (!error->empty()) return false;
  const std::string html = RenderLocusPage(data, libraries);
  *error = WriteFileReplacing(path, html);
  return error->empty();
}

}  // namespace kanesim::viz
