#include "lang/lexer.h"

#include <cerrno>
#include <cfloat>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string_view>

#include "lang/text.h"
#include "flat/number.h"

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
double NumberValue(const std::string& s, std::int32_t b, std::int32_t e, bool* out_of_range) {
  *out_of_range = false;
  // std::from_chars rounds correctly (the value strtod gives) without copying the text or
  // consulting the locale. Overflow, underflow and subnormals go to strtod below, whose
  // ERANGE decides what is out of range, as flat::ParseNumber decides it for --set.
  double v = 0;
  const auto r = std::from_chars(s.data() + b, s.data() + e, v);
  if (r.ec == std::errc() && r.ptr == s.data() + e && (v == 0 || std::abs(v) >= DBL_MIN)) return v;
  const std::string text = s.substr(static_cast<size_t>(b), static_cast<size_t>(e - b));
  errno = 0;
  v = std::strtod(text.c_str(), nullptr);
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

// The lexer's position in one file's text and the tokens so far; one function per token
// kind below moves `i` past its token.
struct Cursor {
  const std::string& s;
  int file;
  std::int32_t n;  // s.size()
  Diagnostics& diags;
  std::vector<Token>& out;
  std::int32_t i = 0;

  char At(std::int32_t k) const { return s[static_cast<size_t>(k)]; }
  // k <= n: s[n] is the string's terminating '\0', which is in no class, so a scan stops
  // there without comparing k with n at every character.
  bool AtIs(std::int32_t k, unsigned char cls) const { return Is(s.data()[k], cls); }
  Span SpanOf(std::int32_t b, std::int32_t e) const { return Span{file, b, e}; }
  std::string_view View(std::int32_t b, std::int32_t e) const {
    return std::string_view(s.data() + b, static_cast<size_t>(e - b));
  }
  Token& Push(Tok k, std::int32_t b, std::int32_t e) {
    Token& t = out.emplace_back();
    t.kind = k;
    t.span = SpanOf(b, e);
    return t;
  }
};

// '/*' ... '*/', opened at b.
void SkipBlockComment(Cursor& c, std::int32_t b) {
  const size_t close = c.s.find("*/", static_cast<size_t>(b + 2));
  if (close == std::string::npos) {
    c.diags.Error(DiagCode::UnterminatedComment, c.SpanOf(b, b + 2), "block comment is never closed").hint =
        "close it with */";
    c.i = c.n;
  } else {
    c.i = static_cast<std::int32_t>(close) + 2;
  }
}

// IDENT or a keyword, starting at b.
void LexWord(Cursor& c, std::int32_t b) {
  std::int32_t i = b + 1;  // a local: the loop keeps it in a register
  while (c.AtIs(i, kIdentStart | kDigit)) ++i;
  c.i = i;
  const std::string_view word = c.View(b, i);
  c.Push(KeywordOrIdent(word), b, i).text = word;
}

// NUMBER := digits [ '.' digits ] [ ('e' | 'E') [ '+' | '-' ] digits ], starting at b.
void LexNumber(Cursor& c, std::int32_t b) {
  std::int32_t i = b;  // a local: the loops keep it in a register
  const std::int32_t n = c.n;
  bool integer = true;
  while (c.AtIs(i, kDigit)) ++i;
  if (i < n && c.At(i) == '.') {
    integer = false;
    ++i;
    while (c.AtIs(i, kDigit)) ++i;
  }
  bool bad = false;
  if (i < n && (c.At(i) == 'e' || c.At(i) == 'E')) {
    integer = false;
    ++i;
    if (i < n && (c.At(i) == '+' || c.At(i) == '-')) ++i;
    if (!c.AtIs(i, kDigit)) bad = true;
    while (c.AtIs(i, kDigit)) ++i;
  }
  if (c.AtIs(i, kIdentStart)) {
    bad = true;
    while (c.AtIs(i, kIdentStart | kDigit)) ++i;
  }
  c.i = i;
  Token& t = c.Push(Tok::Number, b, i);
  t.text = c.View(b, i);
  t.is_integer = integer;
  bool out_of_range = false;
  t.number = NumberValue(c.s, b, i, &out_of_range);
  if (bad) {
    c.diags.Error(DiagCode::BadNumber, t.span, "malformed number '" + std::string(t.text) + "'").hint =
        "numbers look like 3, 0.5, 1e-3 or 2.5E+4";
    t.number = 0;
  } else if (out_of_range) {
    // Well formed but not a normal double: say which end of the range, in the words the
    // command line uses for the same text (flat::ParseNumber), so that a number means
    // the same in a file and in --set.
    std::string why;
    double unused = 0.0;
    flat::ParseNumber(t.text, &unused, &why);
    const bool tiny = std::abs(t.number) <= 1.0;
    c.diags.Error(DiagCode::BadNumber, t.span, "number " + why).hint =
        tiny ? "the smallest normal double is 2.2250738585072014e-308; write 0 for zero, or rescale the units "
               "(e.g. grams or millimetres) so the value is of ordinary size"
             : "the largest double is 1.7976931348623157e308; rescale the units so the value is of ordinary size";
    t.number = 0;
  }
}

// The character the escape '\' e stands for.
char EscapedCharacter(char e) {
  switch (e) {
    case 'n': return '\n';
    case 't': return '\t';
    default: return e;  // '"', '\\', '\'' and the others stand for themselves
  }
}

// The slow path of LexString: escapes decoded, bad characters reported.
void LexEscapedString(Cursor& c, std::int32_t b) {
  std::int32_t& i = c.i;
  const std::int32_t n = c.n;
  i = b + 1;
  std::string val;
  bool closed = false;
  while (i < n) {
    char d = c.At(i);
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
    const std::int32_t escaped = d == '\\' && i + 1 < n ? StringCharacter(c.s, i + 1, c.file, c.diags, &skip) : -1;
    if (escaped == 0) {  // a backslash before a bad character, reported
      i += 1 + skip;
      continue;
    }
    if (escaped == 1) {
      val += EscapedCharacter(c.At(i + 1));
      i += 2;
      continue;
    }
    const std::int32_t len = StringCharacter(c.s, i, c.file, c.diags, &skip);
    if (len == 0) {
      i += skip;
      continue;
    }
    val.append(c.s, static_cast<size_t>(i), static_cast<size_t>(len));
    i += len;
  }
  if (!closed) {
    c.diags.Error(DiagCode::UnterminatedString, c.SpanOf(b, b + 1), "string literal is never closed").hint =
        "add the closing '\"'";
  }
  Token& t = c.Push(Tok::String, b, i);
  t.decoded = std::make_shared<const std::string>(std::move(val));
  t.text = *t.decoded;
}

// STRING, opened by the '"' at b.
void LexString(Cursor& c, std::int32_t b) {
  const std::int32_t close = PlainString(c.s, b);
  if (close >= 0) {  // the common case: the literal's text is its value
    c.i = close + 1;
    c.Push(Tok::String, b, c.i).text = c.View(b + 1, close);
    return;
  }
  LexEscapedString(c, b);
}

// An operator or punctuation of one or two characters, or a bad character, at b.
void LexOperator(Cursor& c, std::int32_t b) {
  auto next = [&](char d) { return b + 1 < c.n && c.At(b + 1) == d; };
  Tok k;
  int len = 1;
  switch (c.At(b)) {
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
      c.i = b + ReportBadCharacter(c.s, b, c.file, c.diags);
      return;
  }
  c.Push(k, b, b + len);
  c.i = b + len;
}

}  // namespace

std::vector<Token> Lex(int file, const SourceManager& sm, Diagnostics& diags) {
  const std::string& s = sm.Text(file);
  std::vector<Token> out;
  Cursor c{s, file, static_cast<std::int32_t>(s.size()), diags, out};
  if (s.size() > SourceManager::kMaxFileBytes) {
    diags.Error(DiagCode::FileTooLarge, c.SpanOf(0, 1),
                "file is " + std::to_string(s.size()) + " bytes; the limit is " +
                    std::to_string(SourceManager::kMaxFileBytes))
        .hint = "split the model into several files";
    c.Push(Tok::Eof, 0, 0);
    return out;
  }
  out.reserve(static_cast<size_t>(c.n) / 5 + 16);  // about one token per 5-7 bytes of source
  while (c.i < c.n && !diags.Full()) {
    const std::int32_t b = c.i;
    const char ch = c.At(b);
    const bool slash_next = ch == '/' && b + 1 < c.n;
    if (Is(ch, kSpace)) {
      std::int32_t i = b + 1;
      while (c.AtIs(i, kSpace)) ++i;
      c.i = i;
    } else if (slash_next && c.At(b + 1) == '/') {
      const size_t eol = s.find('\n', static_cast<size_t>(b));
      c.i = eol == std::string::npos ? c.n : static_cast<std::int32_t>(eol);
    } else if (slash_next && c.At(b + 1) == '*') {
      SkipBlockComment(c, b);
    } else if (Is(ch, kIdentStart)) {
      LexWord(c, b);
    } else if (Is(ch, kDigit) || (ch == '.' && c.AtIs(b + 1, kDigit))) {
      LexNumber(c, b);
    } else if (ch == '"') {
      LexString(c, b);
    } else {
      LexOperator(c, b);
    }
  }
  c.Push(Tok::Eof, c.n, c.n);
  return out;
}

}  // namespace kanesim::lang
