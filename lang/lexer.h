// Lexer for .mech files: Modelica's lexical rules (comments // and /* */, strings with
// escapes, unsigned numbers, keywords).
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "lang/diagnostics.h"
#include "lang/source.h"

namespace kanesim::lang {

// The one table of token kinds: X(enumerator, spelling). Keywords are the entries whose
// spelling is a word; the lexer builds its keyword table from this list.
#define KANESIM_TOKENS(X)                                                                     \
  X(Eof, "end of file")                                                                       \
  X(Ident, "identifier")                                                                      \
  X(Number, "number")                                                                         \
  X(String, "string")                                                                         \
  X(LParen, "(") X(RParen, ")") X(LBracket, "[") X(RBracket, "]") X(LBrace, "{")             \
  X(RBrace, "}") X(Comma, ",") X(Semicolon, ";") X(Dot, ".") X(Colon, ":") X(Assign, "=")     \
  X(ColonAssign, ":=") X(Plus, "+") X(Minus, "-") X(Star, "*") X(Slash, "/") X(Caret, "^")    \
  X(Lt, "<") X(Le, "<=") X(Gt, ">") X(Ge, ">=") X(EqEq, "==") X(Ne, "<>")                     \
  X(KwAlgorithm, "algorithm") X(KwAnd, "and") X(KwAnnotation, "annotation")                   \
  X(KwBlock, "block") X(KwClass, "class") X(KwConnect, "connect") X(KwConnector, "connector") \
  X(KwConstant, "constant") X(KwDiscrete, "discrete") X(KwEach, "each") X(KwElse, "else")     \
  X(KwElseif, "elseif") X(KwEncapsulated, "encapsulated") X(KwEnd, "end")                     \
  X(KwEquation, "equation") X(KwExtends, "extends") X(KwFalse, "false") X(KwFinal, "final")   \
  X(KwFor, "for") X(KwFunction, "function") X(KwIf, "if") X(KwImport, "import")               \
  X(KwIn, "in") X(KwInitial, "initial") X(KwInner, "inner") X(KwInput, "input")               \
  X(KwLoop, "loop") X(KwModel, "model") X(KwNot, "not") X(KwOr, "or") X(KwOuter, "outer")     \
  X(KwOutput, "output") X(KwPackage, "package") X(KwParameter, "parameter")                   \
  X(KwPartial, "partial") X(KwProtected, "protected") X(KwPublic, "public")                   \
  X(KwRecord, "record") X(KwRedeclare, "redeclare") X(KwReplaceable, "replaceable")           \
  X(KwThen, "then") X(KwTrue, "true") X(KwType, "type") X(KwWhen, "when") X(KwWhile, "while") \
  X(KwWithin, "within")

enum class Tok {
#define KANESIM_X(e, s) e,
  KANESIM_TOKENS(KANESIM_X)
#undef KANESIM_X
};

const char* TokSpelling(Tok t);

struct Token {
  Tok kind = Tok::Eof;
  bool is_integer = false;  // Number written without '.' or exponent
  Span span;
  // Identifier name, string contents (unescaped) or number text: a view into the
  // SourceManager's text of the file (valid while that file is neither replaced nor
  // dropped), or into `decoded` for a string literal whose escapes had to be rewritten.
  std::string_view text;
  double number = 0;  // Number
  std::shared_ptr<const std::string> decoded;  // null unless the literal had escapes
};

// Tokenizes a whole file. Errors go to `diags`; the lexer skips the bad character and
// goes on, so the parser still sees the rest. The tokens' texts view the SourceManager's
// text of `file` (see Token::text).
std::vector<Token> Lex(int file, const SourceManager& sm, Diagnostics& diags);

}  // namespace kanesim::lang
