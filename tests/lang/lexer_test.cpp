// Lexer: token kinds (from the one token table), comments, strings, numbers, and the
// lexical diagnostics L001-L005 with their spans. A failure here means the parser is fed
// wrong tokens or a user gets a lexical error at the wrong place.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "lang_test_util.h"

namespace kanesim::lang {
namespace {

using testing::LexText;

std::vector<Tok> Kinds(const std::vector<Token>& toks) {
  std::vector<Tok> k;
  for (const auto& t : toks) k.push_back(t.kind);
  return k;
}

// Every fixed-spelling entry of KANESIM_TOKENS lexes, alone, to exactly its own kind:
// a keyword or operator missing from the lexer (or spelled twice) fails here.
TEST(Lexer, EveryTokenKindOfTheTableLexesFromItsSpelling) {
  struct Entry {
    Tok kind;
    const char* name;
    const char* spelling;
  };
  const Entry table[] = {
#define KANESIM_X(e, s) {Tok::e, #e, s},
      KANESIM_TOKENS(KANESIM_X)
#undef KANESIM_X
  };
  int checked = 0;
  for (const Entry& e : table) {
    if (e.kind == Tok::Eof || e.kind == Tok::Ident || e.kind == Tok::Number || e.kind == Tok::String) continue;
    auto r = LexText(e.spelling);
    ASSERT_EQ(r->tokens.size(), 2u) << e.name;
    EXPECT_EQ(r->tokens[0].kind, e.kind) << e.name << " from '" << e.spelling << "'";
    EXPECT_EQ(r->tokens[0].span.begin, 0) << e.name;
    EXPECT_EQ(r->tokens[0].span.end, static_cast<int>(std::strlen(e.spelling))) << e.name;
    EXPECT_EQ(r->tokens[1].kind, Tok::Eof);
    EXPECT_FALSE(r->diags.HasErrors()) << e.name;
    EXPECT_STREQ(TokSpelling(e.kind), e.spelling);
    ++checked;
  }
  EXPECT_EQ(checked, static_cast<int>(std::size(table)) - 4);  // all but Eof, Ident, Number, String
}

TEST(Lexer, IdentifiersNumbersStringsAndEof) {
  auto r = LexText("abc _x1 A_B2 42 \"s\"");
  EXPECT_EQ(Kinds(r->tokens),
            (std::vector<Tok>{Tok::Ident, Tok::Ident, Tok::Ident, Tok::Number, Tok::String, Tok::Eof}));
  EXPECT_EQ(r->tokens[0].text, "abc");
  EXPECT_EQ(r->tokens[1].text, "_x1");
  EXPECT_EQ(r->tokens[2].text, "A_B2");
  EXPECT_EQ(r->tokens[4].text, "s");
  EXPECT_FALSE(r->diags.HasErrors());
}

TEST(Lexer, KeywordsAreCaseSensitiveAndWholeWords) {
  auto r = LexText("Model model models end_ endfor");
  EXPECT_EQ(Kinds(r->tokens),
            (std::vector<Tok>{Tok::Ident, Tok::KwModel, Tok::Ident, Tok::Ident, Tok::Ident, Tok::Eof}));
}

// Longest match for two-character operators; the pieces are not glued across spaces.
TEST(Lexer, TwoCharacterOperatorsUseLongestMatch) {
  auto r = LexText("<= <> < = >= > == = := : a.b");
  EXPECT_EQ(Kinds(r->tokens),
            (std::vector<Tok>{Tok::Le, Tok::Ne, Tok::Lt, Tok::Assign, Tok::Ge, Tok::Gt, Tok::EqEq, Tok::Assign,
                              Tok::ColonAssign, Tok::Colon, Tok::Ident, Tok::Dot, Tok::Ident, Tok::Eof}));
}

TEST(Lexer, LineAndBlockCommentsAreSkipped) {
  auto r = LexText("a // line comment b\n c /* block\n d * / */ e /**/ f // at eof");
  EXPECT_EQ(Kinds(r->tokens), (std::vector<Tok>{Tok::Ident, Tok::Ident, Tok::Ident, Tok::Ident, Tok::Eof}));
  EXPECT_EQ(r->tokens[1].text, "c");
  EXPECT_EQ(r->tokens[2].text, "e");
  EXPECT_EQ(r->tokens[3].text, "f");
  EXPECT_FALSE(r->diags.HasErrors());
}

TEST(Lexer, CommentMarkersInsideStringsAreText) {
  auto r = LexText("\"a // b /* c\" x");
  ASSERT_EQ(r->tokens.size(), 3u);
  EXPECT_EQ(r->tokens[0].text, "a // b /* c");
  EXPECT_EQ(r->tokens[1].text, "x");
}

TEST(Lexer, StringEscapesAreUnescaped) {
  auto r = LexText(R"("q\"b\\s\nn\tt\'a\qz" "")");
  ASSERT_EQ(r->tokens.size(), 3u);
  EXPECT_EQ(r->tokens[0].kind, Tok::String);
  EXPECT_EQ(r->tokens[0].text, "q\"b\\s\nn\tt'aqz");
  EXPECT_EQ(r->tokens[1].text, "");
  EXPECT_FALSE(r->diags.HasErrors());
}

// A literal without escapes is taken as it is from the source; one with escapes is decoded
// character by character: both give the same value for the same characters, UTF-8 included.
TEST(Lexer, StringValueIsTheSameWithOrWithoutEscapes) {
  const std::string body = "a \xC2\xB0 b\t\xE2\x80\x94 c";  // a ° b<tab>— c
  auto plain = LexText("\"" + body + "\"");
  auto escaped = LexText("\"" + body + "\\n\"");
  ASSERT_EQ(plain->tokens.size(), 2u);
  ASSERT_EQ(escaped->tokens.size(), 2u);
  EXPECT_EQ(plain->tokens[0].text, body);
  EXPECT_EQ(escaped->tokens[0].text, body + "\n");
  EXPECT_EQ(escaped->tokens[0].span.end, static_cast<int>(body.size()) + 4);
  EXPECT_FALSE(plain->diags.HasErrors());
  EXPECT_FALSE(escaped->diags.HasErrors());
  // A copy of a token (the parser's, a test's) keeps its decoded text.
  const Token copy = escaped->tokens[0];
  escaped->tokens.clear();
  EXPECT_EQ(copy.text, body + "\n");
}

TEST(Lexer, StringsMaySpanLines) {
  auto r = LexText("\"two\nlines\" x");
  ASSERT_EQ(r->tokens.size(), 3u);
  EXPECT_EQ(r->tokens[0].text, "two\nlines");
  EXPECT_EQ(r->sm.Locate(r->file, r->tokens[1].span.begin).line, 2);
}

TEST(Lexer, IntegersAreToldApartFromReals) {
  struct Case {
    const char* text;
    double value;
    bool integer;
  };
  const Case cases[] = {{"0", 0, true},        {"42", 42, true},    {"3.", 3, false},  {"3.25", 3.25, false},
                        {".5", 0.5, false},    {"1e3", 1e3, false}, {"1E3", 1e3, false}, {"2.5E+4", 2.5e4, false},
                        {"1e-3", 1e-3, false}, {"1.e2", 100, false}, {"007", 7, true}};
  for (const Case& c : cases) {
    auto r = LexText(c.text);
    ASSERT_EQ(r->tokens.size(), 2u) << c.text;
    EXPECT_EQ(r->tokens[0].kind, Tok::Number) << c.text;
    EXPECT_DOUBLE_EQ(r->tokens[0].number, c.value) << c.text;
    EXPECT_EQ(r->tokens[0].is_integer, c.integer) << c.text;
    EXPECT_EQ(r->tokens[0].text, c.text);
    EXPECT_FALSE(r->diags.HasErrors()) << c.text;
  }
}

// Every number literal's value is the double strtod gives, bit for bit: the lexer's fast
// path for short decimals (digits divided or multiplied by an exact power of ten) must round
// as strtod does. Literals at its edges (15 and 16 significant digits, powers of ten of 22
// and 23, leading and trailing zeros) and random ones of up to 20 digits and exponents.
TEST(Lexer, NumberValuesAreStrtodsBitForBit) {
  std::vector<std::string> lits{"0.1", "0.3", "1.7976931348623157e308", "2.2250738585072014e-308", "9007199254740993",
                                "123456789012345", "1234567890123456", "0.000000000000000000001",
                                "0.0000000000000000000001", "1e22", "1e23", "1e-22", "1e-23", "4.35e-22",
                                "999999999999999e22", "999999999999999e-22", "0000000000000000001.5", "1.500000000000000000",
                                "3.", ".5", "1.e2", "0e5", "0.0", "7e+0", "12.5E-3"};
  std::mt19937 rng(40);
  std::uniform_int_distribution<int> digit(0, 9), count(1, 20), exp(-30, 30), choice(0, 3);
  for (int k = 0; k < 20000; ++k) {
    std::string s;
    const int n = count(rng), point = choice(rng) == 0 ? -1 : std::uniform_int_distribution<int>(0, n)(rng);
    for (int i = 0; i < n; ++i) {
      if (i == point) s += '.';
      s += static_cast<char>('0' + digit(rng));
    }
    if (point == n) s += ".0";
    if (choice(rng) != 0) s += "e" + std::to_string(exp(rng));
    lits.push_back(s);
  }
  std::string text;
  for (const std::string& l : lits) text += l + " ";
  auto r = LexText(text);
  ASSERT_FALSE(r->diags.HasErrors());
  ASSERT_EQ(r->tokens.size(), lits.size() + 1);
  for (size_t i = 0; i < lits.size(); ++i) {
    const double want = std::strtod(lits[i].c_str(), nullptr), got = r->tokens[i].number;
    EXPECT_EQ(std::memcmp(&want, &got, sizeof want), 0) << lits[i] << ": " << got << " != " << want;
  }
}

// A component access after a subscript, x[1].y, must not glue "1]" or ".y" into a number.
TEST(Lexer, DotAfterNumberAndBracket) {
  auto r = LexText("x[1].y");
  EXPECT_EQ(Kinds(r->tokens), (std::vector<Tok>{Tok::Ident, Tok::LBracket, Tok::Number, Tok::RBracket, Tok::Dot,
                                                Tok::Ident, Tok::Eof}));
}

TEST(Lexer, SpansMapToLineAndColumn) {
  auto r = LexText("model M\n  Real  x;\nend M;");
  // tokens: model M Real x ; end M ; Eof
  ASSERT_EQ(r->tokens.size(), 9u);
  LineCol real = r->sm.Locate(r->file, r->tokens[2].span.begin);
  EXPECT_EQ(real.line, 2);
  EXPECT_EQ(real.col, 3);
  LineCol x = r->sm.Locate(r->file, r->tokens[3].span.begin);
  EXPECT_EQ(x.line, 2);
  EXPECT_EQ(x.col, 9);
  EXPECT_EQ(r->tokens[3].span.end - r->tokens[3].span.begin, 1);
  LineCol eof = r->sm.Locate(r->file, r->tokens.back().span.begin);
  EXPECT_EQ(eof.line, 3);
  EXPECT_EQ(eof.col, 7);
}

// --- L001 .. L005 ------------------------------------------------------------------

const Diagnostic& OnlyError(const testing::Lexed& r) {
  EXPECT_EQ(r.diags.All().size(), 1u) << r.diags.RenderAll();
  return r.diags.All().front();
}

TEST(LexerErrors, L001UnexpectedCharacterIsSkippedAndPointedAt) {
  auto r = LexText("a $ b");
  const Diagnostic& d = OnlyError(*r);
  EXPECT_EQ(d.code, DiagCode::UnexpectedChar);
  EXPECT_STREQ(DiagCodeString(d.code), "L001");
  EXPECT_EQ(d.span.begin, 2);
  EXPECT_EQ(d.span.end, 3);
  EXPECT_NE(d.message.find("'$'"), std::string::npos) << d.message;
  // The lexer goes on after the bad character.
  EXPECT_EQ(Kinds(r->tokens), (std::vector<Tok>{Tok::Ident, Tok::Ident, Tok::Eof}));
}

TEST(LexerErrors, L001HintsForQuotesAndHashComments) {
  auto q = LexText("'x'");
  ASSERT_GE(q->diags.All().size(), 1u);
  EXPECT_NE(q->diags.All()[0].hint.find("quoted identifiers"), std::string::npos);
  auto h = LexText("# note");
  ASSERT_GE(h->diags.All().size(), 1u);
  EXPECT_NE(h->diags.All()[0].hint.find("//"), std::string::npos);
}

// A control byte is named by its code point, a byte that is not UTF-8 says so; neither is
// echoed raw in the message.
TEST(LexerErrors, L001ControlAndInvalidBytesAreNamed) {
  auto r = LexText(std::string("a \x01 \xff b"));
  ASSERT_EQ(r->diags.All().size(), 2u);
  EXPECT_NE(r->diags.All()[0].message.find("U+0001"), std::string::npos) << r->diags.All()[0].message;
  EXPECT_NE(r->diags.All()[1].message.find("invalid UTF-8: byte 0xff"), std::string::npos);
  EXPECT_EQ(r->diags.All()[1].span.begin, 4);
}

std::string Utf8(char32_t c) {
  std::string s;
  if (c < 0x80) return std::string(1, static_cast<char>(c));
  if (c < 0x800) {
    s += static_cast<char>(0xC0 | (c >> 6));
  } else if (c < 0x10000) {
    s += static_cast<char>(0xE0 | (c >> 12));
    s += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
  } else {
    s += static_cast<char>(0xF0 | (c >> 18));
    s += static_cast<char>(0x80 | ((c >> 12) & 0x3F));
    s += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
  }
  s += static_cast<char>(0x80 | (c & 0x3F));
  return s;
}

std::string Hex4(char32_t c) {
  char buffer[16];
  std::snprintf(buffer, sizeof buffer, "U+%04X", static_cast<unsigned>(c));
  return buffer;
}

// Non-ASCII characters of every UTF-8 length, outside strings and comments: one L001 per
// character (not per byte) naming its code point and spanning its bytes, and the tokens
// around it intact. Inside strings and comments they are text.
TEST(LexerEncoding, OneErrorPerNonAsciiCharacterNamingItsCodePoint) {
  for (char32_t c : {0x00E9, 0x00A0, 0x03C0, 0x2212, 0x4E2D, 0xFEFF, 0x1F600, 0x10FFFF}) {
    const std::string ch = Utf8(c);
    for (int copies : {1, 3}) {
      std::string run;
      for (int k = 0; k < copies; ++k) run += ch;
      auto r = LexText("a " + run + " b");
      ASSERT_EQ(r->diags.NumErrors(), copies) << Hex4(c) << "\n" << r->diags.RenderAll();
      const Diagnostic& d = r->diags.All()[0];
      EXPECT_EQ(d.code, DiagCode::UnexpectedChar);
      EXPECT_NE(d.message.find(Hex4(c)), std::string::npos) << d.message;
      EXPECT_FALSE(d.hint.empty());
      EXPECT_EQ(d.span.begin, 2);
      EXPECT_EQ(d.span.end, 2 + static_cast<int>(ch.size()));
      EXPECT_EQ(Kinds(r->tokens), (std::vector<Tok>{Tok::Ident, Tok::Ident, Tok::Eof}));
    }
    if (c == 0xFEFF) continue;  // invisible: an error in a string too (ControlCharactersAreNamedNeverEchoed)
    auto text = LexText("a \"" + ch + "\" // " + ch + "\n /* " + ch + " */ b");
    EXPECT_FALSE(text->diags.HasErrors()) << Hex4(c) << "\n" << text->diags.RenderAll();
    EXPECT_EQ(text->tokens.at(1).text, ch);
  }
}

// Byte sequences that are not UTF-8, of every kind (RFC 3629): a stray continuation byte,
// an overlong form, a surrogate, a value past U+10FFFF, a truncated sequence, bytes that
// never occur. One L001 "invalid UTF-8" per run, outside and inside strings; comments may
// hold anything.
TEST(LexerEncoding, InvalidUtf8IsNamedOncePerRun) {
  for (const char* bad : {"\x80", "\xbf\xbf", "\xc0\xaf", "\xe0\x80\xaf", "\xed\xa0\x80", "\xf4\x90\x80\x80",
                          "\xe2\x88", "\xf0\x9f", "\xfe", "\xff\xff\xff\xff\xff\xff"}) {
    auto r = LexText(std::string("a ") + bad + " b");
    ASSERT_EQ(r->diags.NumErrors(), 1) << r->diags.RenderAll();
    EXPECT_NE(r->diags.All()[0].message.find("invalid UTF-8"), std::string::npos) << r->diags.All()[0].message;
    EXPECT_EQ(Kinds(r->tokens), (std::vector<Tok>{Tok::Ident, Tok::Ident, Tok::Eof}));
    auto in_string = LexText(std::string("\"x") + bad + "y\"");
    ASSERT_EQ(in_string->diags.NumErrors(), 1) << in_string->diags.RenderAll();
    EXPECT_NE(in_string->diags.All()[0].message.find("invalid UTF-8 in a string"), std::string::npos);
    EXPECT_EQ(in_string->tokens.at(0).text, "xy");
    auto in_comment = LexText(std::string("a // ") + bad + "\n/* " + bad + " */ b");
    EXPECT_FALSE(in_comment->diags.HasErrors()) << in_comment->diags.RenderAll();
  }
}

// Every control character (C0 but the separators tab, LF, CR, FF, VT; DEL), outside and
// inside strings, and the C1 controls and text-reordering characters inside strings: one
// L001 naming its code point, and no raw control byte in the message.
TEST(LexerEncoding, ControlCharactersAreNamedNeverEchoed) {
  std::vector<char32_t> controls;
  for (char32_t c = 0; c < 0x20; ++c)
    if (c != '\t' && c != '\n' && c != '\r' && c != '\f' && c != '\v') controls.push_back(c);
  controls.push_back(0x7F);
  for (char32_t c : controls) {
    const std::string ch = Utf8(c);
    auto r = LexText("a " + ch + " b");
    ASSERT_EQ(r->diags.NumErrors(), 1) << Hex4(c);
    EXPECT_NE(r->diags.All()[0].message.find(Hex4(c)), std::string::npos) << r->diags.All()[0].message;
    EXPECT_EQ(r->diags.All()[0].message.find(ch), std::string::npos) << Hex4(c);
  }
  for (char32_t c : controls) {
    if (c == '\t') continue;
    auto r = LexText("\"a" + Utf8(c) + "b\"");
    ASSERT_EQ(r->diags.NumErrors(), 1) << Hex4(c);
    EXPECT_NE(r->diags.All()[0].message.find("in a string"), std::string::npos) << r->diags.All()[0].message;
    EXPECT_EQ(r->tokens.at(0).text, "ab");
  }
  for (char32_t c : {0x85, 0x9B, 0x202E, 0x2066, 0x200F}) {
    auto r = LexText("\"a" + Utf8(c) + "b\\" + Utf8(c) + "\"");
    ASSERT_EQ(r->diags.NumErrors(), 2) << Hex4(c) << r->diags.RenderAll();
    EXPECT_NE(r->diags.All()[0].message.find(Hex4(c)), std::string::npos) << r->diags.All()[0].message;
    EXPECT_EQ(r->tokens.at(0).text, "ab");
  }
}

// A byte-order mark opening the file is accepted (editors write one); anywhere else it is
// an L001 that names it.
TEST(LexerEncoding, ByteOrderMarkAcceptedOnlyAtTheStart) {
  auto r = LexText("\xEF\xBB\xBFmodel M end M;");
  EXPECT_FALSE(r->diags.HasErrors()) << r->diags.RenderAll();
  EXPECT_EQ(r->tokens.at(0).kind, Tok::KwModel);
  EXPECT_EQ(r->sm.Locate(r->file, r->tokens.at(0).span.begin).col, 1);
  auto twice = LexText("\xEF\xBB\xBF\xEF\xBB\xBFmodel");
  ASSERT_EQ(twice->diags.NumErrors(), 1);
  EXPECT_NE(twice->diags.All()[0].message.find("byte-order mark"), std::string::npos);
}

TEST(LexerErrors, L002UnterminatedStringPointsAtTheOpeningQuote) {
  auto r = LexText("x = \"never closed\n y");
  const Diagnostic& d = OnlyError(*r);
  EXPECT_EQ(d.code, DiagCode::UnterminatedString);
  EXPECT_EQ(d.span.begin, 4);
  EXPECT_EQ(d.span.end, 5);
  EXPECT_EQ(r->tokens.back().kind, Tok::Eof);
}

TEST(LexerErrors, L002BackslashAtEndOfFile) {
  auto r = LexText("\"abc\\");
  const Diagnostic& d = OnlyError(*r);
  EXPECT_EQ(d.code, DiagCode::UnterminatedString);
}

TEST(LexerErrors, L003UnterminatedBlockCommentPointsAtItsStart) {
  auto r = LexText("a\n  /* never closed *");
  const Diagnostic& d = OnlyError(*r);
  EXPECT_EQ(d.code, DiagCode::UnterminatedComment);
  LineCol lc = r->sm.Locate(d.span.file, d.span.begin);
  EXPECT_EQ(lc.line, 2);
  EXPECT_EQ(lc.col, 3);
  EXPECT_EQ(d.span.end - d.span.begin, 2);
  EXPECT_EQ(Kinds(r->tokens), (std::vector<Tok>{Tok::Ident, Tok::Eof}));
}

TEST(LexerErrors, L004MalformedNumbersCoverTheWholeLiteral) {
  const char* cases[] = {"1e", "1e+", ".5E-", "12abc", "3.0x1", "1e999"};
  for (const char* c : cases) {
    auto r = LexText(std::string("y = ") + c + ";");
    const Diagnostic& d = OnlyError(*r);
    EXPECT_EQ(d.code, DiagCode::BadNumber) << c;
    EXPECT_EQ(d.span.begin, 4) << c;
    EXPECT_EQ(d.span.end, 4 + static_cast<int>(std::strlen(c))) << c;
    // Still one Number token, so the parser sees a well-formed statement.
    ASSERT_EQ(r->tokens.size(), 5u) << c;
    EXPECT_EQ(r->tokens[2].kind, Tok::Number) << c;
    EXPECT_EQ(r->tokens[3].kind, Tok::Semicolon) << c;
  }
}

TEST(LexerErrors, L005FileTooLargeIsOneErrorAndNoTokens) {
  std::string big(SourceManager::kMaxFileBytes + 1, ' ');
  auto r = LexText(big);
  const Diagnostic& d = OnlyError(*r);
  EXPECT_EQ(d.code, DiagCode::FileTooLarge);
  EXPECT_EQ(d.span.begin, 0);
  ASSERT_EQ(r->tokens.size(), 1u);
  EXPECT_EQ(r->tokens[0].kind, Tok::Eof);
}

TEST(LexerErrors, FileExactlyAtTheLimitIsAccepted) {
  std::string text(SourceManager::kMaxFileBytes, ' ');
  text[0] = 'a';
  auto r = LexText(text);
  EXPECT_FALSE(r->diags.HasErrors());
  EXPECT_EQ(Kinds(r->tokens), (std::vector<Tok>{Tok::Ident, Tok::Eof}));
}

// Thousands of bad characters stop at the error cap (P105) instead of flooding.
TEST(LexerErrors, ErrorsAreCapped) {
  auto r = LexText(std::string(10000, '$'));
  EXPECT_EQ(r->diags.NumErrors(), Diagnostics::kMaxErrors);
  EXPECT_EQ(r->diags.All().back().code, DiagCode::TooManyErrors);
  EXPECT_EQ(r->tokens.back().kind, Tok::Eof);
}

TEST(LexerErrors, RenderedDiagnosticHasLocationCaretAndHint) {
  auto r = LexText("model M\n  Real x = 1 # mass\nend M;");
  ASSERT_EQ(r->diags.All().size(), 1u);
  std::string s = r->diags.Render(r->diags.All()[0]);
  EXPECT_NE(s.find("test.mech:2:14: error[L001]"), std::string::npos) << s;
  EXPECT_NE(s.find(" 2 |   Real x = 1 # mass\n"), std::string::npos) << s;
  EXPECT_NE(s.find("   |              ^\n"), std::string::npos) << s;
  EXPECT_NE(s.find("hint: "), std::string::npos) << s;
}

}  // namespace
}  // namespace kanesim::lang
