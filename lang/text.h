// Source text as characters: UTF-8 decoding for the lexer, and making user text safe to
// echo on a terminal (escaped control characters, clipped long lines and messages) for the
// one diagnostic renderer (lang/diagnostics.cpp). Limits stated in docs/language.md §10.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace kanesim::lang {

// One UTF-8 character at s[i]: its code point and its length in bytes (1-4), or length 0
// when the bytes there are not valid UTF-8 (a stray continuation byte, a truncated
// sequence, an overlong form, a surrogate, or a value above U+10FFFF). RFC 3629 §4.
struct Utf8Char {
  char32_t code = 0;
  int length = 0;
};
Utf8Char DecodeUtf8(std::string_view s, std::size_t i);

// "U+00E9".
std::string CodePointName(char32_t c);

// Characters a terminal must not receive raw: C0 and C1 control characters but tab, DEL,
// and the bidirectional overrides/isolates that reorder the displayed text (U+202A-U+202E,
// U+2066-U+2069), plus invisible ones (U+200B-U+200F, U+FEFF).
bool IsUnsafeForTerminal(char32_t c);

// `s` with every unsafe character written as an escape: "\x1b" for a control byte,
// "\u202e" for an unsafe code point, "\xff" for a byte that is not valid UTF-8. Tabs are
// kept (the caret line copies them). Everything else is copied unchanged.
std::string EscapeForTerminal(std::string_view s);

// The display form of one message: escaped, and if longer than kMaxMessageBytes, its head
// and tail joined by "…" (a 4 MiB identifier inside a message stays a few hundred bytes).
inline constexpr std::size_t kMaxMessageBytes = 400;
std::string ClipMessage(std::string_view s);

// A source line as shown under a diagnostic: at most about kLineWindow bytes of it around
// the marked range, with "…" where the line was clipped, escaped; and the marker line
// (spaces, '^' under mark_begin, '~' to mark_end) aligned with it.
inline constexpr std::size_t kLineWindow = 150;   // bytes of a long line shown
inline constexpr std::size_t kLineContext = 60;   // of them before the caret
struct ShownLine {
  std::string text;
  std::string marks;
};
ShownLine ShowLine(std::string_view line, std::size_t mark_begin, std::size_t mark_end);

}  // namespace kanesim::lang
