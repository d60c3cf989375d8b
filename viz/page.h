// Assembling the viewer page from its own files (page_files.h), the third-party libraries
// read from Debian's installed files, and the scene JSON (scene_json.h).
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace kanesim::viz {

// A third-party file the page needs.
struct LibraryFile {
  std::string name;     // the name it is served under: /lib/<name>
  std::string path;     // the installed file read
  std::string package;  // the Debian package that installs it
  bool css = false;     // a style sheet (else a script)
  std::string text;     // its contents
};

// Reads three.js, OrbitControls and dygraphs (script and style) from js_root (normally
// /usr/share/javascript). On a missing or unreadable file *error names it and its Debian
// package, and the result is empty.
std::vector<LibraryFile> ReadLibraries(const std::string& js_root, std::string* error);

enum class PageMode {
  kOffline,  // one file: libraries, page script and style, scene JSON inline
  kServed,   // libraries from lib/<name> and the scene from scene.json, on the same origin
};

// The page's HTML. `libraries` and `scene_json` are inlined when offline; when served only the
// libraries' names are used and scene_json is ignored.
std::string RenderPage(PageMode mode, const std::string& title, const std::vector<LibraryFile>& libraries,
                       const std::string& scene_json);

// `text` made safe to place inside <script> or <style>: "</" + end_tag (e.g. "</script")
// becomes "<\/…", which means the same inside JavaScript strings and regular expressions and CSS.
std::string Inlinable(std::string_view text, std::string_view end_tag);

// Text for HTML content or an attribute value: < > & " escaped.
std::string HtmlEscape(std::string_view text);

// The embedded page file `file` (page_files.h) with each marker <!--kanesim:NAME--> replaced
// by what `fill(NAME, out)` appends to out; fill returns false for a name it does not know
// (a std::logic_error then names the file and the marker).
std::string ExpandPageFile(std::string_view file,
                           const std::function<bool(std::string_view name, std::string& out)>& fill);

// Writes `text` to `path` through a temporary beside it (`path`.tmp.<pid>, created
// exclusively, flushed to disk) and a rename, so a reader never sees half a page and a
// failure (a full disk) leaves the previous file whole. A symbolic link is followed (the file
// it names is replaced); a path that exists but is no regular file (a directory, a FIFO, a
// device) is refused. "" or why not.
std::string WriteFileReplacing(const std::string& path, const std::string& text);

// Content-Security-Policy of the page in each mode: nothing outside the file (offline) or the
// origin (served) can be loaded.
const char* PagePolicy(PageMode mode);

}  // namespace kanesim::viz
