#include "lang/text.h"

#include <algorithm>

namespace kanesim::lang {

namespace {

bool IsContinuation(unsigned char b) { return (b & 0xC0) == 0x80; }

const char kHex[] = "0123456789abcdef";

std::string ByteEscape(unsigned char b) { return std::string("\\x") + kHex[b >> 4] + kHex[b & 15]; }

std::string CodeEscape(char32_t c) {
  std::string s = "\\u";
  for (int shift = 12; shift >= 0; shift -= 4) s += kHex[(c >> shift) & 15];
  return s;
}

// One displayed unit of text starting at s[i]: how many bytes it takes, what is shown and
// how many columns that is.
struct Unit {
  std::size_t bytes = 1;
  std::string shown;
  std::size_t columns = 1;
};

Unit NextUnit(std::string_view s, std::size_t i) {
  Unit u;
  const unsigned char b = static_cast<unsigned char>(s[i]);
  if (b < 0x80) {
    if (b == '\t' || !IsUnsafeForTerminal(b)) {
      u.shown.assign(1, static_cast<char>(b));
    } else {
      u.shown = ByteEscape(b);
      u.columns = u.shown.size();
    }
    return u;
  }
  const Utf8Char c = DecodeUtf8(s, i);
  if (c.length == 0) {
    u.shown = ByteEscape(b);
    u.columns = u.shown.size();
    return u;
  }
  u.bytes = static_cast<std::size_t>(c.length);
  if (IsUnsafeForTerminal(c.code)) {
    u.shown = CodeEscape(c.code);
    u.columns = u.shown.size();
  } else {
    u.shown.assign(s.substr(i, u.bytes));
  }
  return u;
}

}  // namespace

// RFC 3629 §4: 1 byte 0xxxxxxx; 2 bytes 110xxxxx 10xxxxxx (>= U+0080); 3 bytes 1110xxxx
// + 2 continuations (>= U+0800, not U+D800-U+DFFF); 4 bytes 11110xxx + 3 (U+10000-U+10FFFF).
Utf8Char DecodeUtf8(std::string_view s, std::size_t i) {
  if (i >= s.size()) return {};
  const unsigned char b0 = static_cast<unsigned char>(s[i]);
  if (b0 < 0x80) return {b0, 1};
  int len = 0;
  char32_t c = 0, min = 0;
  if ((b0 & 0xE0) == 0xC0) {
    len = 2, c = b0 & 0x1F, min = 0x80;
  } else if ((b0 & 0xF0) == 0xE0) {
    len = 3, c = b0 & 0x0F, min = 0x800;
  } else if ((b0 & 0xF8) == 0xF0) {
    len = 4, c = b0 & 0x07, min = 0x10000;
  } else {
    return {};
  }
  if (i + static_cast<std::size_t>(len) > s.size()) return {};
  for (int k = 1; k < len; ++k) {
    const unsigned char b = static_cast<unsigned char>(s[i + static_cast<std::size_t>(k)]);
    if (!IsContinuation(b)) return {};
    c = (c << 6) | (b & 0x3F);
  }
  if (c < min || c > 0x10FFFF || (c >= 0xD800 && c <= 0xDFFF)) return {};
  return {c, len};
}

std::string CodePointName(char32_t c) {
  std::string s = "U+";
  const int digits = c > 0xFFFFF ? 6 : c > 0xFFFF ? 5 : 4;  // at least 4 digits, as Unicode writes them
  for (int shift = 4 * (digits - 1); shift >= 0; shift -= 4) s += "0123456789ABCDEF"[(c >> shift) & 15];
  return s;
}

bool IsUnsafeForTerminal(char32_t c) {
  if (c == '\t') return false;
  if (c < 0x20 || c == 0x7F) return true;           // C0 controls, DEL
  if (c >= 0x80 && c <= 0x9F) return true;          // C1 controls (0x9B is CSI)
  if (c >= 0x200B && c <= 0x200F) return true;      // zero-width and direction marks
  if (c >= 0x202A && c <= 0x202E) return true;      // bidirectional embeddings/overrides
  if (c >= 0x2066 && c <= 0x2069) return true;      // bidirectional isolates
  return c == 0xFEFF || c == 0x2028 || c == 0x2029;  // BOM, line/paragraph separators
}

std::string EscapeForTerminal(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (std::size_t i = 0; i < s.size();) {
    const unsigned char b = static_cast<unsigned char>(s[i]);
    if (b >= 0x20 && b < 0x7F) {  // the common case, without building a Unit
      out += static_cast<char>(b);
      ++i;
      continue;
    }
    Unit u = NextUnit(s, i);
    out += u.shown;
    i += u.bytes;
  }
  return out;
}

std::string ClipMessage(std::string_view s) {
  std::string e = EscapeForTerminal(s);
  if (e.size() <= kMaxMessageBytes) return e;
  constexpr std::size_t kTail = 80;
  std::size_t head = kMaxMessageBytes - kTail;
  while (head > 0 && IsContinuation(static_cast<unsigned char>(e[head]))) --head;
  std::size_t tail = e.size() - kTail;
  while (tail < e.size() && IsContinuation(static_cast<unsigned char>(e[tail]))) ++tail;
  return e.substr(0, head) + "…" + e.substr(tail);
}

ShownLine ShowLine(std::string_view line, std::size_t mark_begin, std::size_t mark_end) {
  const std::size_t n = line.size();
  const std::size_t mb = std::min(mark_begin, n);
  std::size_t ws = 0, we = n;
  if (n > kLineWindow) {
    ws = mb > kLineContext ? mb - kLineContext : 0;
    we = std::min(n, ws + kLineWindow);
    if (we - ws < kLineWindow) ws = we - kLineWindow;  // near the end: show more before
    while (ws > 0 && IsContinuation(static_cast<unsigned char>(line[ws]))) --ws;
    while (we < n && IsContinuation(static_cast<unsigned char>(line[we]))) ++we;
  }
  ShownLine out;
  if (ws > 0) {
    out.text = "…";
    out.marks = " ";
  }
  bool caret = false;
  for (std::size_t i = ws; i < we;) {
    Unit u = NextUnit(line, i);
    out.text += u.shown;
    if (i + u.bytes <= mb) {
      out.marks += u.shown == "\t" ? std::string("\t") : std::string(u.columns, ' ');
    } else if (i < std::max(mark_end, mb + 1)) {
      out.marks += caret ? '~' : '^';
      out.marks.append(u.columns - 1, '~');
      caret = true;
    }
    i += u.bytes;
  }
  if (we < n) out.text += "…";
  if (!caret) out.marks += '^';  // the mark is past the end of the line (a missing ';')
  return out;
}

}  // namespace kanesim::lang
