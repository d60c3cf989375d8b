#include "lang/diagnostics.h"

#include <algorithm>
#include <sstream>

namespace kanesim::lang {

const char* DiagCodeString(DiagCode c) {
  switch (c) {
#define KANESIM_X(e, code, summary) \
  case DiagCode::e:                 \
    return code;
    KANESIM_DIAGNOSTICS(KANESIM_X)
#undef KANESIM_X
  }
  return "?";
}

const char* DiagCodeSummary(DiagCode c) {
  switch (c) {
#define KANESIM_X(e, code, summary) \
  case DiagCode::e:                 \
    return summary;
    KANESIM_DIAGNOSTICS(KANESIM_X)
#undef KANESIM_X
  }
  return "?";
}

Diagnostic& Diagnostics::Error(DiagCode code, Span span, std::string message) {
  if (num_errors_ >= kMaxErrors) {
    overflow_ = Diagnostic{};
    return overflow_;
  }
  ++num_errors_;
  if (num_errors_ == kMaxErrors) {
    diags_.push_back({Severity::Error, DiagCode::TooManyErrors, "too many errors; stopping here", span, {}, ""});
    overflow_ = Diagnostic{};
    return overflow_;
  }
  diags_.push_back({Severity::Error, code, std::move(message), span, {}, ""});
  return diags_.back();
}

Diagnostic& Diagnostics::Warning(DiagCode code, Span span, std::string message) {
  if (diags_.size() > 4 * kMaxErrors) {
    overflow_ = Diagnostic{};
    return overflow_;
  }
  diags_.push_back({Severity::Warning, code, std::move(message), span, {}, ""});
  return diags_.back();
}

std::string RenderSnippet(const SourceManager& sm, Span span) {
  if (!span.valid() || span.file >= sm.NumFiles()) return "";
  LineCol lc = sm.Locate(span.file, span.begin);
  std::string text = sm.LineText(span.file, lc.line);
  std::ostringstream os;
  std::string num = std::to_string(lc.line);
  std::string pad(num.size(), ' ');
  os << " " << num << " | " << text << "\n";
  os << " " << pad << " | ";
  for (int i = 1; i < lc.col && static_cast<size_t>(i - 1) < text.size(); ++i)
    os << (text[static_cast<size_t>(i - 1)] == '\t' ? '\t' : ' ');
  os << '^';
  // Underline the rest of the span on this line.
  int len = std::max(1, span.end - span.begin);
  int room = static_cast<int>(text.size()) - (lc.col - 1);
  for (int i = 1; i < std::min(len, room); ++i) os << '~';
  os << "\n";
  return os.str();
}

static std::string Where(const SourceManager& sm, Span span) {
  if (!span.valid() || span.file >= sm.NumFiles()) return "kanesim";
  LineCol lc = sm.Locate(span.file, span.begin);
  return sm.Name(span.file) + ":" + std::to_string(lc.line) + ":" + std::to_string(lc.col);
}

std::string Diagnostics::Render(const Diagnostic& d) const {
  std::ostringstream os;
  os << Where(*sources_, d.span) << ": " << (d.severity == Severity::Error ? "error" : "warning") << "["
     << DiagCodeString(d.code) << "]: " << d.message << "\n";
  os << RenderSnippet(*sources_, d.span);
  for (const auto& n : d.notes) {
    os << Where(*sources_, n.span) << ": note: " << n.message << "\n";
    os << RenderSnippet(*sources_, n.span);
  }
  if (!d.hint.empty()) os << "  hint: " << d.hint << "\n";
  return os.str();
}

std::string Diagnostics::RenderAll() const {
  std::string s;
  for (const auto& d : diags_) s += Render(d);
  return s;
}

static size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      size_t sub = prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, sub});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

std::string ClosestName(const std::string& name, const std::vector<std::string>& candidates) {
  std::string best;
  size_t best_d = std::max<size_t>(2, name.size() / 3) + 1;
  for (const auto& c : candidates) {
    if (c.size() > name.size() + 64) continue;
    size_t d = EditDistance(name, c);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  return best;
}

}  // namespace kanesim::lang
