// The one number syntax (flat/number.h): what flat::ParseNumber accepts from an
// option, a grid value or a list file is exactly what the lexer accepts as a number
// literal in a model, with the same value. Generator: every string of up to five
// characters over an alphabet of digits, '.', exponent letters, signs and look-alikes
// (hex, inf, nan, separators), and random longer ones (fixed seed).
#include <gtest/gtest.h>

#include <climits>
#include <functional>
#include <random>
#include <string>

#include "lang/diagnostics.h"
#include "lang/lexer.h"
#include "lang/source.h"
#include "flat/number.h"

namespace kanesim::clitest {
namespace {

// The lexer's verdict on `text` as a whole number literal: a single Number token and no
// error; its value in *value.
bool LexesAsNumber(const std::string& text, double* value) {
  lang::SourceManager sm;
  int file = sm.Add("n.mech", text);
  lang::Diagnostics diags(&sm);
  std::vector<lang::Token> toks = lang::Lex(file, sm, diags);
  std::vector<lang::Token> real;
  for (const auto& t : toks)
    if (t.kind != lang::Tok::Eof) real.push_back(t);
  if (diags.HasErrors() || real.size() != 1 || real[0].kind != lang::Tok::Number) return false;
  *value = real[0].number;
  return true;
}

void Agree(const std::string& text) {
  double lexed = 0, parsed = 0;
  std::string why;
  const bool lex_ok = LexesAsNumber(text, &lexed);
  const bool parse_ok = flat::ParseNumber(text, &parsed, &why);
  ASSERT_EQ(parse_ok, lex_ok) << "'" << text << "': " << why;
  if (lex_ok) {
    ASSERT_EQ(parsed, lexed) << "'" << text << "'";
  }
  // The grammar alone (NumberPrefix) fails a literal only for its range (1e999, 1e-999).
  if (flat::NumberPrefix(text) == text.size() && !lex_ok) {
    ASSERT_TRUE(why.find("range") != std::string::npos || why.find("too small") != std::string::npos) << text;
  }
}

TEST(NumberSyntax, ParserAgreesWithTheLexerOnEveryShortString) {
  const std::string alphabet = "019.eE+-x_";  // (spaces: around a token in a model, refused in an option)
  std::string s;
  std::function<void(int)> all = [&](int len) {
    if (len == 0) {
      if (!s.empty() && s[0] != '+' && s[0] != '-') Agree(s);  // a sign is an operator in a model
      return;
    }
    for (char c : alphabet) {
      s.push_back(c);
      all(len - 1);
      s.pop_back();
    }
  };
  for (int len = 1; len <= 5; ++len) all(len);
}

TEST(NumberSyntax, ParserAgreesWithTheLexerOnRandomLiterals) {
  std::mt19937 rng(24);
  const char* pieces[] = {"0", "7", "12", ".", "e", "E", "+", "-", "e-3", "e400", "e-400", "inf", "nan", "0x1f", "_"};
  for (int k = 0; k < 20000; ++k) {
    std::string s;
    const int n = 1 + static_cast<int>(rng() % 6);
    for (int i = 0; i < n; ++i) s += pieces[rng() % (sizeof pieces / sizeof *pieces)];
    if (s[0] == '+' || s[0] == '-') continue;
    Agree(s);
  }
}

TEST(NumberSyntax, SignsAndLimits) {
  double v = 0;
  std::string why;
  EXPECT_TRUE(flat::ParseNumber("-2.5e-3", &v, &why) && v == -2.5e-3);
  EXPECT_TRUE(flat::ParseNumber("+4", &v, &why) && v == 4);
  EXPECT_FALSE(flat::ParseNumber("--4", &v, &why));
  EXPECT_FALSE(flat::ParseNumber("1e400", &v, &why));
  EXPECT_NE(why.find("out of range"), std::string::npos) << why;
  EXPECT_FALSE(flat::ParseNumber("1e-320", &v, &why));
  EXPECT_NE(why.find("too small"), std::string::npos) << why;
  EXPECT_TRUE(flat::ParseNumber("0e-400", &v, &why) && v == 0.0) << why;  // exactly zero is no underflow
  long long i = 0;
  EXPECT_TRUE(flat::ParseInteger("-12", -100, 100, &i, &why) && i == -12);
  EXPECT_FALSE(flat::ParseInteger("101", -100, 100, &i, &why));
  EXPECT_FALSE(flat::ParseInteger("99999999999999999999", LLONG_MIN, LLONG_MAX, &i, &why));
  EXPECT_FALSE(flat::ParseInteger("1e3", 0, 10000, &i, &why));
  EXPECT_FALSE(flat::ParseInteger("0x10", 0, 100, &i, &why));
}

}  // namespace
}  // namespace kanesim::clitest
