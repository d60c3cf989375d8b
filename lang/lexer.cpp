#include "lang/lexer.h"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <unordered_map>

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
        if (d == '\\' && i + 1 < n) {
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
        val += d;
        ++i;
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
      default: {
        unsigned char uc = static_cast<unsigned char>(c);
        std::string shown = (uc >= 32 && uc < 127) ? std::string("'") + c + "'" : "byte 0x" + [&] {
          const char* hx = "0123456789abcdef";
          return std::string{hx[uc >> 4], hx[uc & 15]};
        }();
        auto& d = diags.Error(DiagCode::UnexpectedChar, span(b, b + 1), "unexpected character " + shown);
        if (c == '\'') d.hint = "quoted identifiers are not supported; strings use double quotes";
        else if (c == '#' || c == '%') d.hint = "comments start with // or /*";
        ++i;
        continue;
      }
    }
    push(k, b, b + len);
    i += len;
  }
  push(Tok::Eof, n, n);
  return out;
}

}  // namespace kanesim::lang
