// The standard library parsed at build time (lang/library_cache.h, lang/ast_image.h): its
// image read back must be what parsing the text gives. The independent reference is the
// parser itself: the same dump (ast::Dump) and the same spans, node for node, for every
// class; the same flat mechanisms and diagnostics for models. A failure means a process now
// sees another standard library than its text, or a stale image was built in.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "lang/ast_image.h"
#include "lang/elaborate.h"
#include "lang/library_cache.h"
#include "lang/parser.h"
#include "stdlib/stdlib.h"

namespace kanesim::lang {
namespace {

// Every span of a definition, in a fixed walk order: Dump leaves spans out.
class Spans {
 public:
  std::vector<int> out;
  void Add(const Span& s) { out.insert(out.end(), {s.file, s.begin, s.end}); }
  void E(const ast::ExprPtr& e) {
    if (!e) return out.push_back(-7);
    Add(e->span);
    for (const auto& p : e->parts) Add(p.span);
    for (const auto& n : e->named_args) Add(n.span);
    ast::ForEachChild(*e, [this](const ast::ExprPtr& c) { E(c); });
  }
  void M(const std::unique_ptr<ast::Modification>& m) {
    if (!m) return out.push_back(-9);
    Add(m->span);
    for (const auto& a : m->args) {
      Add(a.span);
      Add(a.name_span);
      M(a.mod);
    }
    E(m->value);
  }
  void Q(const std::vector<ast::Equation>& eqs) {
    for (const auto& q : eqs) {
      Add(q.span);
      E(q.lhs);
      E(q.rhs);
      E(q.range);
      Q(q.body);
      for (const auto& c : q.conditions) E(c);
      for (const auto& b : q.branches) Q(b);
    }
  }
  void C(const ast::ClassDef& c) {
    Add(c.span);
    Add(c.name_span);
    for (const auto& el : c.elements) {
      if (el.component) {
        const auto& k = *el.component;
        Add(k.span);
        Add(k.name_span);
        Add(k.type_span);
        for (const auto& d : k.type_dims) E(d);
        for (const auto& d : k.dims) E(d);
        M(k.mod);
        E(k.condition);
        M(k.annotation);
      }
      if (el.extends) Add(el.extends->span), M(el.extends->mod);
      if (el.import) Add(el.import->span);
      if (el.class_def) {
        EXPECT_EQ(el.class_def->parent, &c) << el.class_def->name;
        C(*el.class_def);
      }
    }
    Q(c.equations);
    M(c.annotation);
    M(c.short_mod);
  }
};

std::vector<int> SpansOf(const ast::StoredDefinition& def) {
  Spans s;
  for (const auto& i : def.imports) s.Add(i.span);
  for (const auto& c : def.classes) {
    EXPECT_EQ(c->parent, nullptr);
    s.C(*c);
  }
  return s.out;
}

// The image built into this binary is the one this build's parser makes of the embedded
// files, byte for byte (a stale image would fail here), and it is read, not parsed.
TEST(LibraryImage, TheBuiltInImageIsCurrent) {
  const Library parsed(stdlib::Files());
  ASSERT_FALSE(stdlib::Image().empty());
  EXPECT_EQ(parsed.Image(), std::string(stdlib::Image()));
  const Library read(stdlib::Files(), stdlib::Image());
  EXPECT_TRUE(read.FromImage());
  EXPECT_FALSE(parsed.FromImage());
}

// Every unit read from the image dumps alike and has the same spans as its parse, under
// the same qualified names.
TEST(LibraryImage, EveryClassReadsAsItParses) {
  const Library parsed(stdlib::Files());
  const Library read(stdlib::Files(), stdlib::Image());
  ASSERT_TRUE(read.FromImage());
  ASSERT_EQ(read.NumUnits(), parsed.NumUnits());
  int names = 0;
  for (int u = 0; u < parsed.NumUnits(); ++u) {
    const ast::StoredDefinition& p = *parsed.Unit(u);
    const ast::StoredDefinition& r = *read.Unit(u);
    EXPECT_TRUE(read.UnitDiagnostics(u).empty());
    EXPECT_EQ(r.file, p.file);
    EXPECT_EQ(ast::Dump(r), ast::Dump(p)) << u;
    EXPECT_EQ(SpansOf(r), SpansOf(p)) << u;
    for (const auto& c : p.classes) {
      const std::string q = (p.within.empty() ? "" : ast::JoinName(p.within) + ".") + c->name;
      EXPECT_EQ(read.FindUnit(q), parsed.FindUnit(q)) << q;
      ++names;
    }
  }
  EXPECT_GT(names, 25);
  EXPECT_EQ(read.FindUnit("Kanesim.NoSuchClass"), -1);
}

// Models through the whole front end: the same flat mechanism and the same diagnostics
// (some pointing into library files) with the image as with the text.
TEST(LibraryImage, ModelsElaborateAsWithTheText) {
  const std::vector<std::string> models = {
      "model M\n  World world(g = {0, -9.81, 0});\n  Revolute j(axis = {0, 0, 1});\n  Rod r(L = 1, m = 1);\n"
      "equation\n  connect(world.frame_b, j.frame_a);\n  connect(j.frame_b, r.frame_a);\nend M;\n",
      "model M\n  World world;\n  Body b(m = 1, I = identity(3));\n  Spring s(d = 1, c = -1);\nequation\n"
      "  connect(world.frame_b, s.frame_a);\n  connect(s.frame_b, b.frame_a);\nend M;\n",
      "model M\n  World world;\n  Revolut j;\nend M;\n",
  };
  for (const std::string& text : models) {
    std::string outcome[2];
    for (int with_image = 0; with_image < 2; ++with_image) {
      auto lib = std::make_shared<const Library>(stdlib::Files(), with_image ? stdlib::Image() : "");
      ASSERT_EQ(lib->FromImage(), with_image == 1);
      Program p;
      Diagnostics diags(&p.sources);
      p.files.push_back(Parse(p.sources.Add("test.mech", text), p.sources, diags));
      p.library = lib;
      for (const auto& src : lib->Sources()) p.sources.AddShared(src);
      flat::Mechanism m;
      const bool ok = Elaborate(p, {}, &m, diags);
      outcome[with_image] = diags.RenderAll() + (ok ? flat::DumpFlat(m) : "failed");
    }
    EXPECT_EQ(outcome[1], outcome[0]) << text;
  }
}

// An image of other files, or a damaged one, is not used: the text is parsed instead.
TEST(LibraryImage, AnImageOfOtherFilesOrDamagedIsNotUsed) {
  auto files = stdlib::Files();
  files.back().second += "\n// one more line\n";
  EXPECT_FALSE(Library(files, stdlib::Image()).FromImage());
  std::string cut(stdlib::Image());
  cut.resize(cut.size() / 2);
  EXPECT_FALSE(Library(stdlib::Files(), cut).FromImage());
  // A unit whose definition does not read (the first one's magic number, "KAST" as a
  // little-endian integer, spoiled) falls back to its text.
  const Library parsed(stdlib::Files());
  std::string damaged(stdlib::Image());
  const size_t magic = damaged.find("TSAK");
  ASSERT_NE(magic, std::string::npos);
  damaged[magic] = 'X';
  const Library read(stdlib::Files(), damaged);
  EXPECT_TRUE(read.FromImage());
  for (int u = 0; u < parsed.NumUnits(); ++u) EXPECT_EQ(ast::Dump(*read.Unit(u)), ast::Dump(*parsed.Unit(u))) << u;
}

}  // namespace
}  // namespace kanesim::lang
