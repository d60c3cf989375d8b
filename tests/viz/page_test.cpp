// The offline page (viz/viewer.h, viz/page.h): self-contained, every marker replaced, the
// libraries read from the Debian files (and a missing one named with its package), no
// half-written file on failure. What the page shows is tested in a browser (browser_test.py).
#include <gtest/gtest.h>

#include <sys/resource.h>
#include <sys/stat.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "viz/page.h"
#include "viz/scene_json.h"
#include "viz/viewer.h"
#include "tests/viz/circling_scene.h"

namespace kanesim::viz {
namespace {

namespace fs = std::filesystem;

std::string TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("kanesim_viz_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

std::string Read(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

size_t Count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// The page without the contents of its <script> and <style> elements: the markup a browser
// would follow references in.
std::string Markup(const std::string& html) {
  std::string out;
  size_t from = 0;
  while (true) {
    const size_t script = html.find("<script", from), style = html.find("<style", from);
    const size_t open = std::min(script, style);
    if (open == std::string::npos) break;
    const size_t body = html.find('>', open) + 1;
    const size_t close = html.find(open == script ? "</script>" : "</style>", body);
    out.append(html, from, body - from);
    from = close;
  }
  return out + html.substr(from);
}

// Wrong if the page would load anything from outside itself, or a marker or a library were
// left out.
TEST(WriteViewerHtml, SelfContained) {
  const std::string dir = TempDir("page");
  ViewerScene scene = testing::CirclingScene('z', 11);
  scene.bodies[0].name = "a</script><b>";  // must not end the scene's element
  scene.title = "T <&>";
  const PageResult r = WriteViewerHtml(scene, dir + "/page.html");
  ASSERT_TRUE(r.ok) << r.error;
  const std::string html = Read(dir + "/page.html");
  EXPECT_EQ(r.bytes, html.size());
  EXPECT_EQ(r.instants, 11u);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);  // no temporary left
  EXPECT_EQ(Count(html, "<!--kanesim:"), 0u);
  EXPECT_EQ(Count(html, "<title>T &lt;&amp;&gt;</title>"), 1u);
  EXPECT_EQ(Count(html, std::string("content=\"") + PagePolicy(PageMode::kOffline) + "\""), 1u);
  // Nothing referenced: no src or href attribute but the empty icon (which stops a browser
  // asking for /favicon.ico), no sourceMappingURL.
  EXPECT_EQ(Count(html, "<link rel=\"icon\" href=\"data:,\">"), 1u);
  const std::string markup = Markup(html);
  const std::regex reference(R"((src|href)\s*=)", std::regex::icase);
  EXPECT_EQ(std::distance(std::sregex_iterator(markup.begin(), markup.end(), reference), std::sregex_iterator()), 1)
      << markup;
  EXPECT_EQ(Count(html, "sourceMappingURL"), 0u);
  // Every <script> closes once: the body name cannot end an element early.
  EXPECT_EQ(Count(html, "<script"), Count(html, "</script>"));
  EXPECT_EQ(Count(html, "<script"), 7u);  // 3 libraries, the scene, 3 page scripts
  std::string error;
  const std::string json = EncodeScene(scene, {}, &error).json;
  EXPECT_EQ(Count(html, json), 1u);
  // The libraries, as Debian installs them.
  const std::vector<LibraryFile> libraries = ReadLibraries(kDebianJavaScriptRoot, &error);
  ASSERT_EQ(libraries.size(), 4u) << error;
  for (const LibraryFile& lib : libraries) EXPECT_NE(html.find(lib.text.substr(0, 2000)), std::string::npos) << lib.name;
}

// Wrong if a missing library gave a broken page or an unhelpful message.
TEST(WriteViewerHtml, MissingLibraryNamesTheDebianPackage) {
  const std::string dir = TempDir("nolib");
  PageOptions options;
  options.js_root = dir + "/js";
  const ViewerScene scene = testing::CirclingScene('z', 3);
  PageResult r = WriteViewerHtml(scene, dir + "/page.html", options);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find(dir + "/js/three/build/three.min.js (not found); install the Debian package libjs-three"),
            std::string::npos)
      << r.error;
  EXPECT_FALSE(fs::exists(dir + "/page.html"));
  // three.js present, dygraphs missing.
  for (const char* f : {"three/build/three.min.js", "three/examples/js/controls/OrbitControls.js"}) {
    fs::create_directories((fs::path(options.js_root) / f).parent_path());
    std::ofstream(fs::path(options.js_root) / f) << "// stand-in\n";
  }
  r = WriteViewerHtml(scene, dir + "/page.html", options);
  EXPECT_NE(r.error.find("dygraph.min.js (not found); install the Debian package libjs-dygraphs"), std::string::npos)
      << r.error;
}

// Wrong if a failed write left a file that looks like a page.
TEST(WriteViewerHtml, UnwritablePathIsAnError) {
  const std::string dir = TempDir("unwritable");
  const PageResult r = WriteViewerHtml(testing::CirclingScene('z', 3), dir + "/missing/page.html");
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("cannot write " + dir + "/missing/page.html"), std::string::npos) << r.error;
  const PageResult bad = WriteViewerHtml(ViewerScene{}, dir + "/empty.html");
  EXPECT_EQ(bad.error, "no instants to show");
  EXPECT_FALSE(fs::exists(dir + "/empty.html"));
}

// Wrong if a write that fails half-way (a full disk: here a file-size limit, EFBIG) touched
// the previous page or left its temporary, or if a special file or a directory at the path
// were replaced by a page, or a symbolic link by a file (the file it names is the page).
TEST(WriteFileReplacing, KeepsThePreviousFileAndSpecialFiles) {
  const std::string dir = TempDir("replacing");
  const std::string page = dir + "/page.html";
  ASSERT_EQ(WriteFileReplacing(page, "previous"), "");
  struct rlimit before {};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &before), 0);
  struct rlimit small = before;
  small.rlim_cur = 4096;
  auto* previous_handler = std::signal(SIGXFSZ, SIG_IGN);  // write() then fails with EFBIG
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  const std::string error = WriteFileReplacing(page, std::string(100000, 'x'));
  ::setrlimit(RLIMIT_FSIZE, &before);
  std::signal(SIGXFSZ, previous_handler);
  EXPECT_NE(error.find("cannot write " + page), std::string::npos) << error;
  EXPECT_EQ(Read(page), "previous");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);

  const std::string fifo = dir + "/fifo.html";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_NE(WriteFileReplacing(fifo, "page").find("not a regular file"), std::string::npos);
  EXPECT_TRUE(fs::is_fifo(fifo));
  fs::create_directory(dir + "/sub.html");
  EXPECT_NE(WriteFileReplacing(dir + "/sub.html", "page"), "");
  EXPECT_TRUE(fs::is_directory(dir + "/sub.html"));

  fs::create_symlink("page.html", dir + "/link.html");
  ASSERT_EQ(WriteFileReplacing(dir + "/link.html", "through the link"), "");
  EXPECT_TRUE(fs::is_symlink(dir + "/link.html"));
  EXPECT_EQ(Read(page), "through the link");
}

// Wrong if the served page inlined the libraries or pointed anywhere but its own origin.
TEST(RenderPage, ServedPageLinksItsOwnOrigin) {
  std::string error;
  const std::vector<LibraryFile> libraries = ReadLibraries(kDebianJavaScriptRoot, &error);
  ASSERT_TRUE(error.empty()) << error;
  const std::string html = RenderPage(PageMode::kServed, "t", libraries, "");
  std::vector<std::string> refs;
  const std::regex reference(R"((src|href)="([^"]*)\")");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), reference);
       it != std::sregex_iterator(); ++it)
    refs.push_back((*it)[2]);
  EXPECT_EQ(refs, (std::vector<std::string>{"data:,", "lib/dygraph.min.css", "lib/three.min.js", "lib/OrbitControls.js",
                                            "lib/dygraph.min.js", "scene.json"}));
  EXPECT_NE(html.find("data-src=\"scene.json\""), std::string::npos);
  EXPECT_LT(html.size(), 200'000u);  // no library inlined
}

}  // namespace
}  // namespace kanesim::viz
