#include "lang/lexer.h"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <unordered_map>

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

static const std::unordered_map<std::string, Tok>& Keywords() {
  static const std::unordered_map<std::string, Tok> table = [] {
    std::unordered_map<std::string, Tok> m;
#define KANESIM_X(e, s) \
  if (std::strncmp(#e, "Kw", 2) == 0) m.emplace(s, Tok::e);
    KANESIM_TOKENS(KANESIM_X)
#undef KANESIM_X
    return m;
  }();
  return table;
}

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

static bool IsIdentStart(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; }
static bool IsDigit(char c) { return c >= '0' && c <= '9'; }

std::vector<Token> Lex(int file, const SourceManager& sm, Diagnostics& diags) {
  const std::string& s = sm.Text(file);
  std::vector<Token> out;
  const std::int32_t n = static_cast<std::int32_t>(s.size());
  std::int32_t i = 0;
  auto span = [&](std::int32_t b, std::int32_t e) { return Span{file, b, e}; };
  auto push = [&](Tok k, std::int32_t b, std::int32_t e) {
    Token t;
    t.kind = k;
    t.span = span(b, e);
    out.push_back(std::move(t));
  };
  if (s.size() > SourceManager::kMaxFileBytes) {
    diags.Error(DiagCode::FileTooLarge, span(0, 1),
                "file is " + std::to_string(s.size()) + " bytes; the limit is " +
                    std::to_string(SourceManager::kMaxFileBytes))
        .hint = "split the model into several files";
    push(Tok::Eof, 0, 0);
    return out;
  }
  while (i < n && !diags.Full()) {
    char c = s[static_cast<size_t>(i)];
    if (c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v') {
      ++i;
      continue;
    }
    std::int32_t b = i;
    if (c == '/' && i + 1 < n && s[static_cast<size_t>(i + 1)] == '/') {
      while (i < n && s[static_cast<size_t>(i)] != '\n') ++i;
      continue;
    }
    if (c == '/' && i + 1 < n && s[static_cast<size_t>(i + 1)] == '*') {
      i += 2;
      while (i + 1 < n && !(s[static_cast<size_t>(i)] == '*' && s[static_cast<size_t>(i + 1)] == '/')) ++i;
      if (i + 1 >= n) {
        diags.Error(DiagCode::UnterminatedComment, span(b, b + 2), "block comment is never closed")
            .hint = "close it with */";
        i = n;
      } else {
        i += 2;
      }
      continue;
    }
    if (IsIdentStart(c)) {
      while (i < n && (IsIdentStart(s[static_cast<size_t>(i)]) || IsDigit(s[static_cast<size_t>(i)]))) ++i;
      std::string word = s.substr(static_cast<size_t>(b), static_cast<size_t>(i - b));
      auto it = Keywords().find(word);
      Token t;
      t.kind = it == Keywords().end() ? Tok::Ident : it->second;
      t.span = span(b, i);
      t.text = std::move(word);
      out.push_back(std::move(t));
      continue;
    }
    if (IsDigit(c) || (c == '.' && i + 1 < n && IsDigit(s[static_cast<size_t>(i + 1)]))) {
      bool integer = true;
      while (i < n && IsDigit(s[static_cast<size_t>(i)])) ++i;
      if (i < n && s[static_cast<size_t>(i)] == '.') {
        integer = false;
        ++i;
        while (i < n && IsDigit(s[static_cast<size_t>(i)])) ++i;
      }
      bool bad = false;
      if (i < n && (s[static_cast<size_t>(i)] == 'e' || s[static_cast<size_t>(i)] == 'E')) {
        integer = false;
        ++i;
        if (i < n && (s[static_cast<size_t>(i)] == '+' || s[static_cast<size_t>(i)] == '-')) ++i;
        if (i >= n || !IsDigit(s[static_cast<size_t>(i)])) bad = true;
        while (i < n && IsDigit(s[static_cast<size_t>(i)])) ++i;
      }
      if (i < n && IsIdentStart(s[static_cast<size_t>(i)])) {
        bad = true;
        while (i < n && (IsIdentStart(s[static_cast<size_t>(i)]) || IsDigit(s[static_cast<size_t>(i)]))) ++i;
      }
      Token t;
      t.kind = Tok::Number;
      t.span = span(b, i);
      t.text = s.substr(static_cast<size_t>(b), static_cast<size_t>(i - b));
      t.is_integer = integer;
      errno = 0;
      t.number = std::strtod(t.text.c_str(), nullptr);
      if (bad || errno == ERANGE) {
        diags.Error(DiagCode::BadNumber, t.span, "malformed number '" + t.text + "'").hint =
            "numbers look like 3, 0.5, 1e-3 or 2.5E+4";
        t.number = 0;
      }
      out.push_back(std::move(t));
      continue;
    }
    if (c == '"') {
      ++i;
      std::string val;
      bool closed = false;
      while (i < n) {
        char d = s[static_cast<size_t>(i)];
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
      Token t;
      t.kind = Tok::String;
      t.span = span(b, i);
      t.text = std::move(val);
      out.push_back(std::move(t));
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
