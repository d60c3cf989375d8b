// `kanesim view` as a user runs it: the offline page (--html), the server (--port, stopped
// by --timeout), errors; and the files the browser test (view_browser_test.py) opens.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "tests/support/cli_util.h"
#include "tests/scene/shapes_model.h"

namespace kanesim {
namespace {

using clitest::Has;
using clitest::Kanesim;

// If this fails, `kanesim view --html` does not write a page of the model, or a failure to
// write it is not an error.
TEST(View, WritesAnOfflinePage) {
  const std::string dir = scenetest::ShapesDir("view_html");
  clitest::Result r = Kanesim("view shapes.mech --html shapes.html", dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_TRUE(Has(r.err, "wrote shapes.html (6 bodies, 101 instants")) << r.err;
  const std::string page = clitest::Slurp(dir + "/shapes.html");
  EXPECT_GT(page.size(), 100000u);                        // three.js and dygraphs are inside
  EXPECT_TRUE(Has(page, "MeshBody link (")) << "labels";  // the hover label of the mesh body
  r = Kanesim("view shapes.mech --html no/such/dir/x.html", dir);
  EXPECT_EQ(r.rc, 1);
  r = Kanesim("view shapes.mech --html x.html --output 'nothing*'", dir);
  EXPECT_EQ(r.rc, 1);
  EXPECT_TRUE(Has(r.err, "nothing*")) << r.err;
}

// If this fails, `kanesim view` does not serve on 127.0.0.1 and say where, or does not stop.
TEST(View, ServesOnLocalhostAndStops) {
  const std::string dir = scenetest::ShapesDir("view_serve");
  clitest::Result r = Kanesim("view shapes.mech --timeout 0.5", dir);
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_TRUE(Has(r.out, "serving Shapes at http://127.0.0.1:")) << r.out;
}

// The files of the browser test (tests/scene/CMakeLists.txt, scene.view_browser): the page,
// the CSV of the same run with every frame origin and body rotation, and a 4x finer run for
// the poses between instants. Runs only when KANESIM_VIEW_DIR says where.
TEST(View, BrowserTestFiles) {
  const char* where = std::getenv("KANESIM_VIEW_DIR");
  if (!where) GTEST_SKIP() << "the fixture of scene.view_browser (KANESIM_VIEW_DIR)";
  const std::string dir = scenetest::ShapesDir(where);
  ASSERT_EQ(Kanesim("view shapes.mech --html shapes.html", dir).rc, 0);
  ASSERT_EQ(Kanesim("run shapes.mech --output '*.r[*]' --output '*.R[*]' -o shapes.csv", dir).rc, 0);
  ASSERT_EQ(Kanesim("run shapes.mech --output '*.r[*]' --output '*.R[*]' --interval 0.0025 -o fine.csv", dir).rc, 0);
}

}  // namespace
}  // namespace kanesim
