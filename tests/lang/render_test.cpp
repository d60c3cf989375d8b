// The one diagnostic renderer (lang/diagnostics.cpp with lang/text.h): whatever the input,
// its output stays bounded (long lines clipped around the caret, long messages clipped,
// warnings and notes capped) and safe for a terminal (no control character, bidirectional
// override or invalid UTF-8 reaches it raw), and the caret still points at the character
// the diagnostic is about. A failure means output bloat, an escape sequence sent to the
// user's terminal, or a caret under the wrong character.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "lang/text.h"
#include "lang_test_util.h"

namespace kanesim::lang {
namespace {

// The shown line and the marker line of a rendered snippet " N | text\n   | marks\n".
struct Snippet {
  std::string text, marks;
};
Snippet SplitSnippet(const std::string& rendered) {
  Snippet s;
  size_t bar1 = rendered.find(" | ");
  size_t nl1 = rendered.find('\n', bar1);
  size_t bar2 = rendered.find(" | ", nl1);
  size_t nl2 = rendered.find('\n', bar2);
  s.text = rendered.substr(bar1 + 3, nl1 - bar1 - 3);
  s.marks = rendered.substr(bar2 + 3, nl2 - bar2 - 3);
  return s;
}

// Splits UTF-8 text into characters (independently of lang/text.cpp: by lead bytes).
std::vector<std::string> Columns(const std::string& s) {
  std::vector<std::string> out;
  for (size_t i = 0; i < s.size();) {
    unsigned char b = static_cast<unsigned char>(s[i]);
    size_t len = b < 0x80 ? 1 : b >= 0xF0 ? 4 : b >= 0xE0 ? 3 : 2;
    out.push_back(s.substr(i, len));
    i += len;
  }
  return out;
}

// Every line length around the window, every caret position (first, second, middle,
// last, past the end): the shown line is at most the window plus two "…" marks, "…"
// appears exactly when the line is longer than the window, and the '^' stands under the
// character the span starts at.
TEST(RenderClip, LongLinesAreClippedAroundTheCaretAtEveryLengthAndPosition) {
  const std::string alphabet = "abcdefghijklmnopqrstuvwxyz0123456789";
  for (size_t n : {size_t{1}, kLineWindow - 1, kLineWindow, kLineWindow + 1, size_t{1000}, size_t{1} << 20}) {
    std::string line(n, ' ');
    for (size_t i = 0; i < n; ++i) line[i] = alphabet[i % alphabet.size()];
    SourceManager sm;
    int f = sm.Add("long.mech", line);
    for (size_t at : {size_t{0}, size_t{1}, n / 2, n - 1, n}) {
      if (at > n) continue;
      const auto b = static_cast<std::int32_t>(at);
      const Snippet s = SplitSnippet(RenderSnippet(sm, Span{f, b, b + 1}));
      const std::vector<std::string> cols = Columns(s.text);
      const std::string what = "n=" + std::to_string(n) + " at=" + std::to_string(at);
      EXPECT_LE(cols.size(), kLineWindow + 2) << what;
      EXPECT_EQ(s.text.find("…") != std::string::npos, n > kLineWindow) << what << ": " << s.text;
      const size_t caret = s.marks.find('^');
      ASSERT_NE(caret, std::string::npos) << what;
      EXPECT_EQ(s.marks.find_first_not_of(' '), caret) << what;
      if (at < n) {
        ASSERT_LT(caret, cols.size()) << what;
        EXPECT_EQ(cols[caret], std::string(1, line[at])) << what << ": " << s.text << "\n" << s.marks;
      } else {
        EXPECT_EQ(caret, cols.size() - (s.text.size() >= 3 && s.text.substr(s.text.size() - 3) == "…" ? 1 : 0))
            << what;
      }
    }
  }
}

// A 1 MiB one-line file full of mistakes: 50 errors, each echoing a clipped window of the
// line, so the whole report stays small (it used to repeat the whole line each time).
TEST(RenderClip, OneHugeLineWithManyErrorsRendersInBoundedSpace) {
  std::string text = "model M parameter Real x = 1";
  while (text.size() < (1u << 20)) text += " $";
  text += "; end M;";
  auto r = testing::ParseText(text);
  EXPECT_EQ(r->diags.NumErrors(), Diagnostics::kMaxErrors);
  const std::string all = r->diags.RenderAll();
  EXPECT_LT(all.size(), 64u * 1024u) << all.substr(0, 1000);
}

// A strict UTF-8 check written for the test (RFC 3629 table 1), and the characters a
// terminal must not get: C0/C1 controls but tab and newline, DEL, bidirectional controls,
// invisible marks, line/paragraph separators, BOM.
bool SafeForTerminal(const std::string& s, std::string* why) {
  for (size_t i = 0; i < s.size();) {
    const unsigned char b = static_cast<unsigned char>(s[i]);
    if (b < 0x80) {
      if ((b < 0x20 && b != '\n' && b != '\t') || b == 0x7F) return *why = "control byte at " + std::to_string(i), false;
      ++i;
      continue;
    }
    size_t len = (b >= 0xC2 && b <= 0xDF) ? 2 : (b >= 0xE0 && b <= 0xEF) ? 3 : (b >= 0xF0 && b <= 0xF4) ? 4 : 0;
    if (len == 0 || i + len > s.size()) return *why = "invalid UTF-8 at " + std::to_string(i), false;
    char32_t c = b & (len == 2 ? 0x1F : len == 3 ? 0x0F : 0x07);
    for (size_t k = 1; k < len; ++k) {
      unsigned char x = static_cast<unsigned char>(s[i + k]);
      if ((x & 0xC0) != 0x80) return *why = "invalid UTF-8 at " + std::to_string(i), false;
      c = (c << 6) | (x & 0x3F);
    }
    if ((len == 3 && c < 0x800) || (len == 4 && (c < 0x10000 || c > 0x10FFFF)) || (c >= 0xD800 && c <= 0xDFFF))
      return *why = "invalid UTF-8 at " + std::to_string(i), false;
    if ((c >= 0x80 && c <= 0x9F) || (c >= 0x200B && c <= 0x200F) || (c >= 0x202A && c <= 0x202E) ||
        (c >= 0x2066 && c <= 0x2069) || c == 0x2028 || c == 0x2029 || c == 0xFEFF)
      return *why = "unsafe character at " + std::to_string(i), false;
    i += len;
  }
  return true;
}

std::string Utf8(char32_t c) {
  std::string s;
  if (c < 0x80) {
    s += static_cast<char>(c);
  } else if (c < 0x800) {
    s += static_cast<char>(0xC0 | (c >> 6));
    s += static_cast<char>(0x80 | (c & 0x3F));
  } else {
    s += static_cast<char>(0xE0 | (c >> 12));
    s += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
    s += static_cast<char>(0x80 | (c & 0x3F));
  }
  return s;
}

// Every unsafe character, and bytes that are not UTF-8, placed in each thing the renderer
// echoes: the source line (in a comment, in a string, as a stray character), the file
// name, a message, a note and a hint. Nothing unsafe comes out.
TEST(RenderEscape, NoControlCharacterOrInvalidByteReachesTheTerminal) {
  std::vector<std::string> bad;
  for (char32_t c = 0; c < 0x20; ++c)
    if (c != '\n') bad.push_back(Utf8(c));
  bad.push_back("\x7f");
  for (char32_t c = 0x80; c <= 0x9F; ++c) bad.push_back(Utf8(c));
  for (char32_t c : {0x200B, 0x200C, 0x200D, 0x200E, 0x200F, 0x202A, 0x202B, 0x202C, 0x202D, 0x202E, 0x2066,
                     0x2067, 0x2068, 0x2069, 0x2028, 0x2029, 0xFEFF})
    bad.push_back(Utf8(c));
  for (const char* invalid : {"\x80", "\xbf", "\xc0\x80", "\xc1\xbf", "\xed\xa0\x80", "\xf4\x90\x80\x80", "\xe2\x88",
                              "\xf8\x88\x80\x80\x80", "\xff", "\xfe"})
    bad.push_back(invalid);
  for (const std::string& x : bad) {
    const std::string shown = EscapeForTerminal(x);
    const std::string texts[] = {
        "model M\n  parameter Real a = 1 " + x + " ;  // " + x + "\nend M;\n",
        "model M \"" + x + "\"\n  parameter Real a = $;  // " + x + x + "\nend M;\n",
    };
    for (const std::string& text : texts) {
      SourceManager sm;
      Diagnostics diags(&sm);
      int f = sm.Add("name" + x + ".mech", text);
      auto def = Parse(f, sm, diags);
      auto& d = diags.Error(DiagCode::UnknownName, Span{f, 10, 12}, "message " + x);
      d.notes.push_back({Span{f, 0, 1}, "note " + x});
      d.hint = "hint " + x;
      const std::string out = diags.RenderAll();
      std::string why;
      EXPECT_TRUE(SafeForTerminal(out, &why)) << "escape " << shown << ": " << why << "\n" << EscapeForTerminal(out);
    }
  }
}

// At most kMaxWarnings warnings are kept (the last one says the rest are not shown), and a
// diagnostic renders at most kMaxNotesShown notes.
TEST(RenderCaps, WarningsAndNotesAreCapped) {
  SourceManager sm;
  Diagnostics diags(&sm);
  int f = sm.Add("w.mech", "model M end M;\n");
  for (int i = 0; i < 10000; ++i) diags.Warning(DiagCode::UnconnectedFrame, Span{f, 0, 5}, "w" + std::to_string(i));
  ASSERT_EQ(diags.All().size(), static_cast<size_t>(Diagnostics::kMaxWarnings));
  EXPECT_EQ(diags.All().back().code, DiagCode::TooManyErrors);
  EXPECT_FALSE(diags.HasErrors());

  Diagnostics notes(&sm);
  auto& d = notes.Error(DiagCode::Duplicate, Span{f, 0, 5}, "duplicate");
  for (int i = 0; i < 1000; ++i) d.notes.push_back({Span{f, 6, 7}, "also here"});
  const std::string out = notes.Render(d);
  size_t shown = 0;
  for (size_t at = out.find("note: also here"); at != std::string::npos; at = out.find("note: also here", at + 1)) ++shown;
  EXPECT_EQ(shown, Diagnostics::kMaxNotesShown);
  EXPECT_NE(out.find("992 more notes not shown"), std::string::npos) << out;
}

// A message quoting a 1 MiB name keeps its head and tail and stays a few hundred bytes.
TEST(RenderCaps, LongMessagesAreClipped) {
  SourceManager sm;
  Diagnostics diags(&sm);
  const std::string name = "start" + std::string(1 << 20, 'n') + "end";
  auto& d = diags.Error(DiagCode::UnknownName, Span{}, "unknown name '" + name + "'");
  d.hint = "did you mean '" + name + "'?";
  const std::string out = diags.Render(d);
  EXPECT_LT(out.size(), 3 * kMaxMessageBytes);
  EXPECT_NE(out.find("unknown name 'startnnn"), std::string::npos);
  EXPECT_NE(out.find("nnnend'"), std::string::npos);
  EXPECT_NE(out.find("…"), std::string::npos);
}

}  // namespace
}  // namespace kanesim::lang
