// Helpers shared by the lang tests: lex or parse a string held by a fresh SourceManager.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "lang/ast.h"
#include "lang/diagnostics.h"
#include "lang/lexer.h"
#include "lang/parser.h"
#include "lang/source.h"

namespace kanesim::lang::testing {

// Owns the sources, the diagnostics and whatever was produced from them.
struct Lexed {
  SourceManager sm;
  Diagnostics diags{&sm};
  int file = -1;
  std::vector<Token> tokens;
};

inline std::unique_ptr<Lexed> LexText(const std::string& text) {
  auto r = std::make_unique<Lexed>();
  r->file = r->sm.Add("test.mech", text);
  r->tokens = Lex(r->file, r->sm, r->diags);
  return r;
}

struct Parsed {
  SourceManager sm;
  Diagnostics diags{&sm};
  int file = -1;
  std::unique_ptr<ast::StoredDefinition> def;

  int NumErrors(DiagCode code) const {
    int n = 0;
    for (const auto& d : diags.All())
      if (d.severity == Severity::Error && d.code == code) ++n;
    return n;
  }
  LineCol Where(const Diagnostic& d) const { return sm.Locate(d.span.file, d.span.begin); }
};

inline std::unique_ptr<Parsed> ParseText(const std::string& text) {
  auto r = std::make_unique<Parsed>();
  r->file = r->sm.Add("test.mech", text);
  r->def = Parse(r->file, r->sm, r->diags);
  return r;
}

}  // namespace kanesim::lang::testing
