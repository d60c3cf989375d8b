// The standard library parsed one class at a time, on demand (lang/library_cache.h). The
// independent reference is the eager path: the whole library parsed into the Program's
// files, as before. A failure means the lazy library gives another AST, another flat
// mechanism or another diagnostic than the whole library would, or parses classes the
// model does not use.
#include <gtest/gtest.h>

#include <string>
#include <thread>
#include <vector>

#include "lang/elaborate.h"
#include "lang/library_cache.h"
#include "lang/parser.h"
#include "stdlib/stdlib.h"

namespace kanesim::lang {
namespace {

struct Outcome {
  bool ok = false;
  std::string rendered;  // every diagnostic
  std::string flat;      // the flat mechanism, when it elaborated
};

// `lazy` null: the library parsed whole into the Program (the reference).
Outcome Load(const std::string& text, const std::shared_ptr<const Library>& lazy, const std::string& model = "") {
  Program p;
  Diagnostics diags(&p.sources);
  p.files.push_back(Parse(p.sources.Add("test.mech", text), p.sources, diags));
  if (lazy) {
    p.library = lazy;
    for (const auto& src : lazy->Sources()) p.sources.AddShared(src);
  } else {
    for (const auto& [name, contents] : stdlib::Files())
      p.files.push_back(Parse(p.sources.Add(name, contents), p.sources, diags));
  }
  Outcome out;
  flat::Mechanism m;
  ElaborateOptions options;
  options.model = model;
  out.ok = !diags.HasErrors() && Elaborate(p, options, &m, diags);
  out.rendered = diags.RenderAll();
  if (out.ok) out.flat = flat::DumpFlat(m);
  return out;
}

const char* const kDoublePendulum = R"(model DoublePendulum
  World world(g = {0, -9.81, 0});
  Revolute shoulder(axis = {0, 0, 1}, q(start = 1.5));
  Rod rod1(L = 1, m = 1);
  Revolute elbow(axis = {0, 0, 1});
  Rod rod2(L = 1, m = 1);
equation
  connect(world.frame_b, shoulder.frame_a);
  connect(shoulder.frame_b, rod1.frame_a);
  connect(rod1.frame_b, elbow.frame_a);
  connect(elbow.frame_b, rod2.frame_a);
end DoublePendulum;
)";

// Every top-level class of every library file is a unit of its own (the scan understood
// every file), and the units together are the files: the same within clauses, the same
// classes in the same order, dumped alike, at the same places.
TEST(LazyLibrary, UnitsAreTheFilesClassByClass) {
  const auto& files = stdlib::Files();
  Library lib(files);
  SourceManager sm;
  sm.Add("<model>", "");
  Diagnostics diags(&sm);
  int u = 0;
  for (const auto& [name, text] : files) {
    auto whole = Parse(sm.Add(name, text), sm, diags);
    ASSERT_FALSE(diags.HasErrors()) << diags.RenderAll();
    ast::StoredDefinition header;
    header.within = whole->within;
    const std::string header_dump = ast::Dump(header);
    std::string joined = header_dump;
    for (const auto& c : whole->classes) {
      ASSERT_LT(u, lib.NumUnits());
      ASSERT_EQ(lib.FindUnit(ast::JoinName(whole->within) + "." + c->name), u) << c->name;
      const auto& unit = *lib.Unit(u);
      EXPECT_EQ(unit.file, whole->file);
      EXPECT_EQ(unit.within, whole->within);
      EXPECT_EQ(unit.imports.size(), whole->imports.size());
      ASSERT_EQ(unit.classes.size(), 1u) << name << ": " << c->name;
      const ast::ClassDef& lc = *unit.classes[0];
      EXPECT_EQ(lc.name, c->name);
      EXPECT_EQ(lc.name_span.file, c->name_span.file);
      EXPECT_EQ(lc.name_span.begin, c->name_span.begin) << c->name;
      EXPECT_EQ(lc.name_span.end, c->name_span.end) << c->name;
      const std::string d = ast::Dump(unit);
      ASSERT_EQ(d.compare(0, header_dump.size(), header_dump), 0);
      joined += d.substr(header_dump.size());
      ++u;
    }
    EXPECT_EQ(joined, ast::Dump(*whole)) << name;
  }
  EXPECT_EQ(u, lib.NumUnits());
  EXPECT_EQ(lib.FindUnit("Kanesim.NoSuchClass"), -1);
  EXPECT_EQ(lib.FindUnit("Revolute"), -1);  // names are qualified
}

// The double pendulum parses World, Revolute, Rod, and what those use (Frame and Flange,
// Body and FixedTranslation inside Rod): seven classes of the library's 33, in four of
// its six files; the flat mechanism is the one the whole library gives.
TEST(LazyLibrary, ParsesOnlyTheClassesAModelUses) {
  auto lib = std::make_shared<const Library>(stdlib::Files());
  EXPECT_EQ(lib->NumParsed(), 0);
  Outcome lazy = Load(kDoublePendulum, lib);
  ASSERT_TRUE(lazy.ok) << lazy.rendered;
  EXPECT_EQ(lib->NumParsed(), 7);
  EXPECT_GT(lib->NumUnits(), 25);
  Outcome eager = Load(kDoublePendulum, nullptr);
  EXPECT_EQ(lazy.flat, eager.flat);
  EXPECT_EQ(lazy.rendered, eager.rendered);
  // A second load parses nothing more.
  Outcome again = Load(kDoublePendulum, lib);
  EXPECT_EQ(lib->NumParsed(), 7);
  EXPECT_EQ(again.flat, eager.flat);
}

// Errors whose messages point into library classes parsed on demand (a base class in
// another unit, a final modifier and a range in Forces.mech), hints that list every class,
// imports, and --model: the same text, line for line, as with the whole library.
TEST(LazyLibrary, DiagnosticsAreThoseOfTheWholeLibrary) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"model M\n  World world;\n  Revolut j;\nend M;\n", ""},
      {"model M\n  World world;\n  Body b(m = 1, I = identity(3));\n  Spring s(d = 1, c = -1);\nequation\n"
       "  connect(world.frame_b, s.frame_a);\n  connect(s.frame_b, b.frame_a);\nend M;\n",
       ""},
      {"model M\n  extends Kanesim.Sprin;\nend M;\n", ""},
      {"model M\n  import Kanesim.Rod;\n  import Kanesim.Rodd;\n  World world;\nend M;\n", ""},
      {"import Kanesim.Joints.*;\nmodel M\n  World world;\nend M;\n", ""},
      {kDoublePendulum, "Kanesim.Worl"},
      {kDoublePendulum, "Kanesim.World"},
      {"within Kanesim;\nmodel Rod\n  World world;\nend Rod;\nmodel M\n  World world;\n  Rod r;\nend M;\n", "Kanesim.M"},
  };
  for (const auto& [text, model] : cases) {
    auto lib = std::make_shared<const Library>(stdlib::Files());
    Outcome lazy = Load(text, lib, model);
    Outcome eager = Load(text, nullptr, model);
    EXPECT_EQ(lazy.ok, eager.ok) << text;
    EXPECT_EQ(lazy.rendered, eager.rendered) << text;
    EXPECT_EQ(lazy.flat, eager.flat) << text;
  }
  // The cases do reach into the library: a note in Forces.mech, hints from the whole registry.
  auto lib = std::make_shared<const Library>(stdlib::Files());
  const std::string spring = Load(cases[1].first, lib).rendered;
  EXPECT_NE(spring.find("<stdlib>/Forces.mech:"), std::string::npos) << spring;
  const std::string typo = Load(cases[0].first, lib).rendered;
  EXPECT_NE(typo.find("did you mean 'Revolute'"), std::string::npos) << typo;
  EXPECT_EQ(lib->NumParsed(), lib->NumUnits());  // the hint read every class
}

// The process-wide library is one per set of files (the embedded files or a copy of
// them share one); threads loading at once get the same mechanism.
TEST(LazyLibrary, SharedAcrossThreads) {
  const auto copy = stdlib::Files();
  auto lib = SharedLibrary(copy);
  ASSERT_NE(lib, nullptr);
  EXPECT_EQ(lib, SharedLibrary(stdlib::Files()));
  auto other = copy;
  other.pop_back();
  EXPECT_NE(SharedLibrary(other), lib);
  EXPECT_EQ(SharedLibrary({}), nullptr);

  auto fresh = std::make_shared<const Library>(stdlib::Files());
  const std::string expected = Load(kDoublePendulum, nullptr).flat;
  std::vector<std::string> got(4);
  std::vector<std::thread> threads;
  for (size_t i = 0; i < got.size(); ++i)
    threads.emplace_back([&, i] { got[i] = Load(kDoublePendulum, fresh).flat; });
  for (auto& t : threads) t.join();
  for (const auto& g : got) EXPECT_EQ(g, expected);
  EXPECT_EQ(fresh->NumParsed(), 7);
}

// A library file that does not parse (never the embedded one, which the first test
// parses) still reports its syntax error, with its place and text, when a model first
// needs the class; the whole-library path reports the same message when loading.
TEST(LazyLibrary, ALibraryThatDoesNotParseReportsItsError) {
  auto files = stdlib::Files();
  for (auto& [name, text] : files)
    if (name == "<stdlib>/World.mech") text.replace(text.find("end World;"), 10, "  Real x = ;\nend World;");
  auto lib = std::make_shared<const Library>(files);
  Program lazy;
  Diagnostics lazy_diags(&lazy.sources);
  lazy.files.push_back(Parse(lazy.sources.Add("test.mech", kDoublePendulum), lazy.sources, lazy_diags));
  lazy.library = lib;
  for (const auto& src : lib->Sources()) lazy.sources.AddShared(src);
  flat::Mechanism m;
  EXPECT_FALSE(Elaborate(lazy, {}, &m, lazy_diags));
  Program eager;
  Diagnostics eager_diags(&eager.sources);
  eager.files.push_back(Parse(eager.sources.Add("test.mech", kDoublePendulum), eager.sources, eager_diags));
  for (const auto& [name, contents] : files)
    eager.files.push_back(Parse(eager.sources.Add(name, contents), eager.sources, eager_diags));
  ASSERT_TRUE(eager_diags.HasErrors());
  const std::string expected = eager_diags.Render(eager_diags.All()[0]);
  EXPECT_NE(expected.find("<stdlib>/World.mech:"), std::string::npos) << expected;
  ASSERT_FALSE(lazy_diags.All().empty());
  EXPECT_EQ(lazy_diags.Render(lazy_diags.All()[0]), expected);
}

}  // namespace
}  // namespace kanesim::lang
