// Recursive-descent parser for .mech (a subset of Modelica 3 syntax). Each parse
// function carries its grammar rule as a comment. The parser recovers at ';' and
// 'end' and reports every error once (capped by Diagnostics::kMaxErrors).
#pragma once

#include <memory>

#include "lang/ast.h"
#include "lang/diagnostics.h"
#include "lang/source.h"

namespace kanesim::lang {

// Limit on syntactic nesting (brackets, nested classes, if/for); deeper input is an
// error (P104), never a stack overflow.
inline constexpr int kMaxNesting = 128;

// Limit on the depth of one expression tree: nodes on its longest root-to-leaf path. An
// operator chain a + b + c + ... is one level per operator (the tree is left-deep), so this
// bounds chains, which kMaxNesting does not count. Deeper input is an error (P106). Every
// walker of the tree (destructor, Clone, Dump, the elaborator's evaluator) handles this
// depth without recursion along chains.
inline constexpr int kMaxExprDepth = 100000;

std::unique_ptr<ast::StoredDefinition> Parse(int file, const SourceManager& sm, Diagnostics& diags);

// Parses a whole file as one expression (values given with --set).
std::unique_ptr<ast::Expr> ParseExpression(int file, const SourceManager& sm, Diagnostics& diags);

}  // namespace kanesim::lang
