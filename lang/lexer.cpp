#include "lang/lexer.h"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string_view>

#include "lang/text.h"

namespace kanesim::lang {

const char* TokSpelling(Tok t) {
  switch (t) {
#define KANESIM_X(e, s) \
  case Tok::e:          \
    return s;
    KANESIM_TOKENS(KANESIM_X)
#undef KANESIM_X
  }
  return "?";
}

namespace {

// The keywords, bucketed by first letter (every keyword is lower-case ASCII): a name is
// a keyword only if its first letter's bucket holds it, so most names cost one compare.
constexpr int kKeywordsPerLetter = 8;

// Whether every letter's keywords fit in a bucket (checked when the token table changes).
constexpr bool KeywordBucketsFit() {
  int count[26] = {};
#define KANESIM_X(e, s) \
  if (#e[0] == 'K' && #e[1] == 'w' && ++count[s[0] - 'a'] > kKeywordsPerLetter) return false;
  KANESIM_TOKENS(KANESIM_X)
#undef KANESIM_X
  return true;
}
static_assert(KeywordBucketsFit(), "a letter begins more than kKeywordsPerLetter keywords: raise it");

struct KeywordTable {
  struct Entry {
    std::string_view word;
    Tok kind;
  };
  Entry bucket[26][kKeywordsPerLetter] = {};
  int size[26] = {};
  KeywordTable() {
    auto add = [this](const char* word, Tok kind) {
      const int letter = word[0] - 'a';
      bucket[letter][size[letter]++] = {word, kind};
    };
#define KANESIM_X(e, s) \
  if (std::strncmp(#e, "Kw", 2) == 0) add(s, Tok::e);
    KANESIM_TOKENS(KANESIM_X)
#undef KANESIM_X
  }
};

Tok KeywordOrIdent(std::string_view word) {
  static const KeywordTable table;
  const int letter = word[0] - 'a';
  if (letter < 0 || letter >= 26) return Tok::Ident;
  for (int k = 0; k < table.size[letter]; ++k)
    if (table.bucket[letter][k].word == word) return table.bucket[letter][k].kind;
  return Tok::Ident;
}

}  // namespace

namespace {

// Characters that are mistaken for ASCII ones (pasted from documents), with the fix.
struct Lookalike {
  char32_t code;
  const char* name;
  const char* hint;
};
const Lookalike kLookalikes[] = {
    {0x00A0, "no-break space", "replace it with an ordinary space"},
    {0x200B, "zero-width space", "delete it: it is invisible"},
    {0xFEFF, "byte-order mark", "a byte-order mark may only open the file; delete this one"},
    {0x2212, "minus sign", "write the ASCII '-'"},
    {0x2013, "en dash", "write the ASCII '-'"},
    {0x2014, "em dash", "write the ASCII '-'"},
    {0x00D7, "multiplication sign", "write '*'"},
    {0x00B7, "middle dot", "write '*'"},
    {0x22C5, "dot operator", "write '*'"},
    {0x00F7, "division sign", "write '/'"},
    {0x2264, "less-than or equal to", "write '<='"},
    {0x2265, "greater-than or equal to", "write '>='"},
    {0x2260, "not equal to", "write '<>'"},
    {0x201C, "left double quotation mark", "strings use the ASCII '\"'"},
    {0x201D, "right double quotation mark", "strings use the ASCII '\"'"},
    {0x2018, "left single quotation mark", "strings use the ASCII '\"'; quoted identifiers are not supported"},
    {0x2019, "right single quotation mark", "strings use the ASCII '\"'; quoted identifiers are not supported"},
    {0x00B2, "superscript two", "write x^2"},
    {0x03C0, "Greek small letter pi", "write pi"},
};

// "control character U+001B (escape)".
std::string ControlName(unsigned char c) {
  const char* name = c == 0x00 ? "null" : c == 0x07 ? "bell" : c == 0x08 ? "backspace" : c == 0x1B ? "escape"
                     : c == 0x7F ? "delete" : nullptr;
  return "control character " + CodePointName(c) + (name ? std::string(" (") + name + ")" : "");
}

// A run of bytes that are not valid UTF-8, from s[i]: its length.
std::int32_t InvalidRun(const std::string& s, std::int32_t i) {
  std::int32_t j = i;
  const auto n = static_cast<std::int32_t>(s.size());
  while (j < n && static_cast<unsigned char>(s[static_cast<size_t>(j)]) >= 0x80 &&
         DecodeUtf8(s, static_cast<size_t>(j)).length == 0)
    ++j;
  return j - i;
}

std::string ByteList(const std::string& s, std::int32_t b, std::int32_t len) {
  std::string out;
  const char* hx = "0123456789abcdef";
  for (std::int32_t k = 0; k < std::min(len, 4); ++k) {
    auto u = static_cast<unsigned char>(s[static_cast<size_t>(b + k)]);
    out += std::string(k ? " " : "") + "0x" + hx[u >> 4] + hx[u & 15];
  }
  if (len > 4) out += " and " + std::to_string(len - 4) + " more";
  return out;
}

const char* const kUtf8Hint = "a .mech file is UTF-8 (or plain ASCII); re-save it as UTF-8 (it may be Latin-1)";

// A character that starts no token, at s[b]: one L001 per character (a whole UTF-8
// sequence, or a run of invalid bytes), saying which it is. Returns its length.
std::int32_t ReportBadCharacter(const std::string& s, std::int32_t b, int file, Diagnostics& diags) {
  const unsigned char uc = static_cast<unsigned char>(s[static_cast<size_t>(b)]);
  auto error = [&](std::int32_t len, const std::string& message) -> Diagnostic& {
    return diags.Error(DiagCode::UnexpectedChar, Span{file, b, b + len}, message);
  };
  if (uc < 0x80 && !IsUnsafeForTerminal(uc)) {
    auto& d = error(1, std::string("unexpected character '") + static_cast<char>(uc) + "'");
    if (uc == '\'') d.hint = "quoted identifiers are not supported; strings use double quotes";
    else if (uc == '#' || uc == '%') d.hint = "comments start with // or /*";
    return 1;
  }
  if (uc < 0x80) {
    error(1, "unexpected " + ControlName(uc)).hint =
        "delete it: only spaces, tabs and line breaks may separate tokens";
    return 1;
  }
  const Utf8Char c = DecodeUtf8(s, static_cast<size_t>(b));
  if (c.length == 0) {
    const std::int32_t len = InvalidRun(s, b);
    error(len, "invalid UTF-8: byte" + std::string(len > 1 ? "s " : " ") + ByteList(s, b, len)).hint = kUtf8Hint;
    return len;
  }
  for (const Lookalike& l : kLookalikes) {
    if (l.code != c.code) continue;
    error(c.length, "unexpected character " + CodePointName(c.code) + " (" + l.name + ")").hint = l.hint;
    return c.length;
  }
  const std::string shown = IsUnsafeForTerminal(c.code) ? std::string(" (invisible or a control character)")
                                                        : " '" + s.substr(static_cast<size_t>(b), static_cast<size_t>(c.length)) + "'";
  error(c.length, "unexpected character " + CodePointName(c.code) + shown).hint =
      "names, keywords and operators are ASCII; other characters may appear only in strings and comments";
  return c.length;
}

// Checks one character inside a string literal at s[i]: control characters (but tab and
// line breaks), bytes that are not UTF-8 and characters that reorder the displayed text
// are errors, so a description never carries them to a terminal. Returns the length to
// copy (0: skip `skip` bytes, already reported).
std::int32_t StringCharacter(const std::string& s, std::int32_t i, int file, Diagnostics& diags, std::int32_t* skip) {
  const unsigned char uc = static_cast<unsigned char>(s[static_cast<size_t>(i)]);
  if (uc == '\t' || uc == '\n' || uc == '\r' || (uc >= 0x20 && uc < 0x7F)) return 1;
  const Utf8Char c = DecodeUtf8(s, static_cast<size_t>(i));
  if (c.length == 0) {
    *skip = InvalidRun(s, i);
    diags.Error(DiagCode::UnexpectedChar, Span{file, i, i + *skip}, "invalid UTF-8 in a string: " + ByteList(s, i, *skip))
        .hint = kUtf8Hint;
    return 0;
  }
  if (!IsUnsafeForTerminal(c.code)) return c.length;
  *skip = c.length;
  diags.Error(DiagCode::UnexpectedChar, Span{file, i, i + c.length},
              (c.code < 0x80 ? ControlName(uc) : "invisible or control character " + CodePointName(c.code)) +
                  " in a string")
      .hint = "delete it: strings may hold printable text, tabs and line breaks (write \\n for a new line)";
  return 0;
}

}  // namespace

namespace {

// Character classes of ASCII bytes (a byte >= 0x80 is in none of them).
enum : unsigned char { kSpace = 1, kIdentStart = 2, kDigit = 4, kPlainInString = 8 };

struct CharClasses {
  unsigned char of[256] = {};
  constexpr CharClasses() {
    for (int c : {' ', '\t', '\r', '\n', '\f', '\v'}) of[c] |= kSpace;
    for (int c = 'a'; c <= 'z'; ++c) of[c] |= kIdentStart;
    for (int c = 'A'; c <= 'Z'; ++c) of[c] |= kIdentStart;
    of[static_cast<unsigned char>('_')] |= kIdentStart;
    for (int c = '0'; c <= '9'; ++c) of[c] |= kDigit;
    // A string literal's characters that need neither a check nor a rewrite.
    for (int c = 0x20; c < 0x7F; ++c)
      if (c != '"' && c != '\\') of[c] |= kPlainInString;
    for (int c : {'\t', '\n', '\r'}) of[c] |= kPlainInString;
  }
};
constexpr CharClasses kClasses;  // built at compile time: usable from any static initializer

bool Is(char c, unsigned char cls) { return (kClasses.of[static_cast<unsigned char>(c)] & cls) != 0; }

// The value of a number literal s[b, e) (its text is already checked by the caller).
double NumberValue(const std::string& s, std::int32_t b, std::int32_t e, bool integer, bool* out_of_range) {
  const auto len = static_cast<size_t>(e - b);
  *out_of_range = false;
  if (integer && len <= 15) {  // exact in a double: no rounding to get wrong
    double v = 0;
    for (size_t k = 0; k < len; ++k) v = 10 * v + (s[static_cast<size_t>(b) + k] - '0');
    return v;
  }
  const std::string text = s.substr(static_cast<size_t>(b), len);
  errno = 0;
  const double v = std::strtod(text.c_str(), nullptr);
  *out_of_range = errno == ERANGE;
  return v;
}

// The contents of the string literal opened by the '"' at s[b] when none of its
// characters needs a rewrite (an escape) or a diagnostic: its end (the closing quote),
// or -1 to take the slow path.
std::int32_t PlainString(const std::string& s, std::int32_t b) {
  const auto n = static_cast<std::int32_t>(s.size());
  std::int32_t j = b + 1;
  while (j < n) {
    const char d = s[static_cast<size_t>(j)];
    if (Is(d, kPlainInString)) {
      ++j;
      continue;
    }
    if (d == '"') return j;
    if (static_cast<unsigned char>(d) < 0x80) return -1;  // '\\' or a control character
    const Utf8Char c = DecodeUtf8(s, static_cast<size_t>(j));
    if (c.length == 0 || IsUnsafeForTerminal(c.code)) return -1;
    j += c.length;
  }
  return -1;  // never closed
}

}  // namespace

std::vector<Token> Lex(int file, const SourceManager& sm, Diagnostics& diags) {
  const std::string& s = sm.Text(file);
  std::vector<Token> out;
  const std::int32_t n = static_cast<std::int32_t>(s.size());
  std::int32_t i = 0;
  auto span = [&](std::int32_t b, std::int32_t e) { return Span{file, b, e}; };
  auto view = [&](std::int32_t b, std::int32_t e) {
    return std::string_view(s.data() + b, static_cast<size_t>(e - b));
  };
  auto push = [&](Tok k, std::int32_t b, std::int32_t e) -> Token& {
    Token& t = out.emplace_back();
    t.kind = k;
    t.span = span(b, e);
    return t;
  };
  if (s.size() > SourceManager::kMaxFileBytes) {
    diags.Error(DiagCode::FileTooLarge, span(0, 1),
                "file is " + std::to_string(s.size()) + " bytes; the limit is " +
                    std::to_string(SourceManager::kMaxFileBytes))
        .hint = "split the model into several files";
    push(Tok::Eof, 0, 0);
    return out;
  }
  out.reserve(static_cast<size_t>(n) / 5 + 16);  // about one token per 5-7 bytes of source
  while (i < n && !diags.Full()) {
    char c = s[static_cast<size_t>(i)];
    if (Is(c, kSpace)) {
      ++i;
      while (i < n && Is(s[static_cast<size_t>(i)], kSpace)) ++i;
      continue;
    }
    std::int32_t b = i;
    if (c == '/' && i + 1 < n && s[static_cast<size_t>(i + 1)] == '/') {
      const size_t eol = s.find('\n', static_cast<size_t>(i));
      i = eol == std::string::npos ? n : static_cast<std::int32_t>(eol);
      continue;
    }
    if (c == '/' && i + 1 < n && s[static_cast<size_t>(i + 1)] == '*') {
      const size_t close = s.find("*/", static_cast<size_t>(i + 2));
      if (close == std::string::npos) {
        diags.Error(DiagCode::UnterminatedComment, span(b, b + 2), "block comment is never closed")
            .hint = "close it with */";
        i = n;
      } else {
        i = static_cast<std::int32_t>(close) + 2;
      }
      continue;
    }
    if (Is(c, kIdentStart)) {
      ++i;
      while (i < n && Is(s[static_cast<size_t>(i)], kIdentStart | kDigit)) ++i;
      const std::string_view word = view(b, i);
      push(KeywordOrIdent(word), b, i).text = word;
      continue;
    }
    if (Is(c, kDigit) || (c == '.' && i + 1 < n && Is(s[static_cast<size_t>(i + 1)], kDigit))) {
      bool integer = true;
      while (i < n && Is(s[static_cast<size_t>(i)], kDigit)) ++i;
      if (i < n && s[static_cast<size_t>(i)] == '.') {
        integer = false;
        ++i;
        while (i < n && Is(s[static_cast<size_t>(i)], kDigit)) ++i;
      }
      bool bad = false;
      if (i < n && (s[static_cast<size_t>(i)] == 'e' || s[static_cast<size_t>(i)] == 'E')) {
        integer = false;
        ++i;
        if (i < n && (s[static_cast<size_t>(i)] == '+' || s[static_cast<size_t>(i)] == '-')) ++i;
        if (i >= n || !Is(s[static_cast<size_t>(i)], kDigit)) bad = true;
        while (i < n && Is(s[static_cast<size_t>(i)], kDigit)) ++i;
      }
      if (i < n && Is(s[static_cast<size_t>(i)], kIdentStart)) {
        bad = true;
        while (i < n && Is(s[static_cast<size_t>(i)], kIdentStart | kDigit)) ++i;
      }
      Token& t = push(Tok::Number, b, i);
      t.text = view(b, i);
      t.is_integer = integer;
      bool out_of_range = false;
      t.number = NumberValue(s, b, i, integer, &out_of_range);
      if (bad || out_of_range) {
        diags.Error(DiagCode::BadNumber, t.span, "malformed number '" + std::string(t.text) + "'").hint =
            "numbers look like 3, 0.5, 1e-3 or 2.5E+4";
        t.number = 0;
      }
      continue;
    }
    if (c == '"') {
      const std::int32_t close = PlainString(s, b);
      if (close >= 0) {  // the common case: the literal's text is its value
        i = close + 1;
        push(Tok::String, b, i).text = view(b + 1, close);
        continue;
      }
      ++i;
      std::string val;
      bool closed = false;
      while (i < n) {
        char d = s[static_cast<size_t>(i)];
        if (Is(d, kPlainInString)) {
          val += d;
          ++i;
          continue;
        }
        if (d == '"') {
          closed = true;
          ++i;
          break;
        }
        std::int32_t skip = 0;
        const std::int32_t escaped = d == '\\' && i + 1 < n ? StringCharacter(s, i + 1, file, diags, &skip) : -1;
        if (escaped == 0) {  // a backslash before a bad character, reported
          i += 1 + skip;
          continue;
        }
        if (escaped == 1) {
          char e = s[static_cast<size_t>(i + 1)];
          switch (e) {
            case 'n': val += '\n'; break;
            case 't': val += '\t'; break;
            case '"': val += '"'; break;
            case '\\': val += '\\'; break;
            case '\'': val += '\''; break;
            default: val += e; break;
          }
          i += 2;
          continue;
        }
        const std::int32_t len = StringCharacter(s, i, file, diags, &skip);
        if (len == 0) {
          i += skip;
          continue;
        }
        val.append(s, static_cast<size_t>(i), static_cast<size_t>(len));
        i += len;
      }
      if (!closed) {
        diags.Error(DiagCode::UnterminatedString, span(b, b + 1), "string literal is never closed").hint =
            "add the closing '\"'";
      }
      Token& t = push(Tok::String, b, i);
      t.decoded = std::make_shared<const std::string>(std::move(val));
      t.text = *t.decoded;
      continue;
    }
    auto next = [&](char d) { return i + 1 < n && s[static_cast<size_t>(i + 1)] == d; };
    Tok k;
    int len = 1;
    switch (c) {
      case '(': k = Tok::LParen; break;
      case ')': k = Tok::RParen; break;
      case '[': k = Tok::LBracket; break;
      case ']': k = Tok::RBracket; break;
      case '{': k = Tok::LBrace; break;
      case '}': k = Tok::RBrace; break;
      case ',': k = Tok::Comma; break;
      case ';': k = Tok::Semicolon; break;
      case '.': k = Tok::Dot; break;
      case ':':
        if (next('=')) { k = Tok::ColonAssign; len = 2; } else { k = Tok::Colon; }
        break;
      case '=':
        if (next('=')) { k = Tok::EqEq; len = 2; } else { k = Tok::Assign; }
        break;
      case '+': k = Tok::Plus; break;
      case '-': k = Tok::Minus; break;
      case '*': k = Tok::Star; break;
      case '/': k = Tok::Slash; break;
      case '^': k = Tok::Caret; break;
      case '<':
        if (next('=')) { k = Tok::Le; len = 2; }
        else if (next('>')) { k = Tok::Ne; len = 2; }
        else { k = Tok::Lt; }
        break;
      case '>':
        if (next('=')) { k = Tok::Ge; len = 2; } else { k = Tok::Gt; }
        break;
      default:
        i += ReportBadCharacter(s, b, file, diags);
        continue;
    }
    push(k, b, b + len);
    i += len;
  }
  push(Tok::Eof, n, n);
  return out;
}

}  // namespace kanesim::lang
