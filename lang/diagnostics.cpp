#include "lang/diagnostics.h"

#include <algorithm>
#include <sstream>

#include "lang/text.h"

namespace kanesim::lang {

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
  if (num_warnings_ >= kMaxWarnings) {
    overflow_ = Diagnostic{};
    return overflow_;
  }
  ++num_warnings_;
  if (num_warnings_ == kMaxWarnings) {
    diags_.push_back({Severity::Warning, DiagCode::TooManyErrors, "too many warnings; the rest are not shown", span,
                      {}, ""});
    overflow_ = Diagnostic{};
    return overflow_;
  }
  diags_.push_back({Severity::Warning, code, std::move(message), span, {}, ""});
  return diags_.back();
}

std::string RenderSnippet(const SourceManager& sm, Span span) {
  if (!span.valid() || span.file >= sm.NumFiles() || span.begin < 0) return "";
  LineCol lc = sm.Locate(span.file, span.begin);
  const std::size_t begin = static_cast<std::size_t>(lc.col - 1);
  const std::size_t end = begin + static_cast<std::size_t>(std::max(1, span.end - span.begin));
  ShownLine shown = ShowLine(sm.LineView(span.file, lc.line), begin, end);
  std::string num = std::to_string(lc.line);
  std::string pad(num.size(), ' ');
  return " " + num + " | " + shown.text + "\n " + pad + " | " + shown.marks + "\n";
}

static std::string Where(const SourceManager& sm, Span span) {
  if (!span.valid() || span.file >= sm.NumFiles()) return "kanesim";
  if (span.begin < 0) return ClipMessage(sm.Name(span.file));  // the file as a whole
  LineCol lc = sm.Locate(span.file, span.begin);
  return ClipMessage(sm.Name(span.file)) + ":" + std::to_string(lc.line) + ":" + std::to_string(lc.col);
}

std::string RenderNote(const SourceManager& sm, Span span, const std::string& message) {
  return Where(sm, span) + ": note: " + ClipMessage(message) + "\n" + RenderSnippet(sm, span);
}

std::string Diagnostics::Render(const Diagnostic& d) const {
  std::ostringstream os;
  os << Where(*sources_, d.span) << ": " << (d.severity == Severity::Error ? "error" : "warning") << "["
     << DiagCodeString(d.code) << "]: " << ClipMessage(d.message) << "\n";
  os << RenderSnippet(*sources_, d.span);
  const std::size_t shown = std::min(d.notes.size(), kMaxNotesShown);
  for (std::size_t i = 0; i < shown; ++i) {
    const DiagNote& n = d.notes[i];
    os << Where(*sources_, n.span) << ": note: " << ClipMessage(n.message) << "\n";
    os << RenderSnippet(*sources_, n.span);
  }
  if (d.notes.size() > shown) os << "  note: " << d.notes.size() - shown << " more notes not shown\n";
  if (!d.hint.empty()) os << "  hint: " << ClipMessage(d.hint) << "\n";
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
