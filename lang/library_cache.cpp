#include "lang/library_cache.h"

#include <cctype>
#include <cstring>

#include "lang/diagnostics.h"
#include "lang/parser.h"

namespace kanesim::lang {

namespace {

struct ScannedClass {
  std::string name;
  std::int32_t begin = 0, end = 0;
};

bool IsIdentStart(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool IsIdentChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// The word at the start of `s` (after spaces), moving `s` past it; "" if none.
std::string_view TakeWord(std::string_view& s) {
  size_t i = 0;
  while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
  size_t b = i;
  if (i < s.size() && IsIdentStart(s[i]))
    while (i < s.size() && IsIdentChar(s[i])) ++i;
  std::string_view w = s.substr(b, i - b);
  s.remove_prefix(i);
  return w;
}

bool BlankOrComment(std::string_view s) {
  size_t i = 0;
  while (i < s.size() && (s[i] == ' ' || s[i] == '\t' || s[i] == '\r')) ++i;
  return i == s.size() || s.compare(i, 2, "//") == 0;
}

// Finds the top-level classes of a file written as the standard library is: a header of
// `within`/`import` lines, then classes whose declaration starts a line
// (`[encapsulated] [partial] model Name ...`) and whose `end Name;` starts a line, with
// only blank lines and // comments between them. False for anything else (the file is
// then parsed whole).
bool ScanClasses(const std::string& text, std::int32_t* header_end, std::vector<ScannedClass>* out) {
  static const char* const kClassWords[] = {"model", "connector", "record", "block",
                                            "class", "type",      "function", "package"};
  const std::int32_t n = static_cast<std::int32_t>(text.size());
  std::int32_t pos = 0;
  bool inside = false;
  ScannedClass current;
  *header_end = -1;
  while (pos < n) {
    const char* nl = static_cast<const char*>(std::memchr(text.data() + pos, '\n', static_cast<size_t>(n - pos)));
    const std::int32_t line_end = nl ? static_cast<std::int32_t>(nl - text.data()) : n;
    std::string_view line(text.data() + pos, static_cast<size_t>(line_end - pos));
    const std::int32_t line_begin = pos;
    pos = line_end + 1;
    if (inside) {
      if (line.compare(0, 4, "end ") != 0) continue;
      std::string_view rest = line.substr(3);
      if (TakeWord(rest) != current.name) continue;
      size_t i = 0;
      while (i < rest.size() && (rest[i] == ' ' || rest[i] == '\t')) ++i;
      if (i == rest.size() || rest[i] != ';') return false;
      if (!BlankOrComment(rest.substr(i + 1))) return false;
      current.end = line_begin + static_cast<std::int32_t>(line.size() - rest.size() + i + 1);  // after ';'
      out->push_back(std::move(current));
      current = ScannedClass{};
      inside = false;
      continue;
    }
    if (BlankOrComment(line)) continue;
    if (line[0] == ' ' || line[0] == '\t') return false;
    std::string_view rest = line;
    std::string_view w = TakeWord(rest);
    if (w == "within" || w == "import") {
      if (!out->empty()) return false;
      continue;
    }
    while (w == "encapsulated" || w == "partial") w = TakeWord(rest);
    bool is_class = false;
    for (const char* k : kClassWords) is_class = is_class || w == k;
    if (!is_class) return false;
    std::string_view name = TakeWord(rest);
    if (name.empty()) return false;
    size_t i = 0;
    while (i < rest.size() && (rest[i] == ' ' || rest[i] == '\t')) ++i;
    if (i < rest.size() && rest[i] == '=') return false;  // a short class definition
    if (*header_end < 0) *header_end = line_begin;
    current.name = std::string(name);
    current.begin = line_begin;
    inside = true;
  }
  return !inside && !out->empty();
}

const std::shared_ptr<const SourceFile>& EmptySource() {
  static const std::shared_ptr<const SourceFile> empty = MakeSourceFile("", "");
  return empty;
}

// Parses `text` as source file `file` (the files before it empty); its diagnostics into
// `out` if given.
std::shared_ptr<const ast::StoredDefinition> ParseAs(int file, const std::string& name, std::string text,
                                                     std::vector<Diagnostic>* out = nullptr) {
  SourceManager sm;
  for (int i = 0; i < file; ++i) sm.AddShared(EmptySource());
  sm.Add(name, std::move(text));
  Diagnostics diags(&sm);
  std::shared_ptr<const ast::StoredDefinition> def = Parse(file, sm, diags);
  if (out) *out = diags.All();
  return def;
}

}  // namespace

Library::Library(const std::vector<std::pair<std::string, std::string>>& files) {
  for (const auto& [name, text] : files) sources_.push_back(MakeSourceFile(name, text));
  for (size_t f = 0; f < sources_.size(); ++f) {
    const SourceFile& src = *sources_[f];
    std::int32_t header_end = 0;
    std::vector<ScannedClass> classes;
    if (ScanClasses(src.text, &header_end, &classes)) {
      auto header = ParseAs(static_cast<int>(f) + 1, src.name, src.text.substr(0, static_cast<size_t>(header_end)));
      const std::string prefix = header->within.empty() ? "" : ast::JoinName(header->within) + ".";
      for (const ScannedClass& c : classes) {
        auto slot = std::make_unique<UnitSlot>();
        slot->file = static_cast<int>(f);
        slot->header_end = header_end;
        slot->begin = c.begin;
        slot->end = c.end;
        index_.emplace(prefix + c.name, static_cast<int>(units_.size()));  // the first of a name wins
        units_.push_back(std::move(slot));
      }
      continue;
    }
    // Not in the scanned shape: one unit, the whole file, parsed now for its names.
    auto slot = std::make_unique<UnitSlot>();
    slot->file = static_cast<int>(f);
    slot->end = static_cast<std::int32_t>(src.text.size());
    ParseUnit(*slot);
    const std::string prefix = slot->def->within.empty() ? "" : ast::JoinName(slot->def->within) + ".";
    for (const auto& c : slot->def->classes) index_.emplace(prefix + c->name, static_cast<int>(units_.size()));
    units_.push_back(std::move(slot));
  }
}

void Library::ParseUnit(const UnitSlot& slot) const {
  std::call_once(slot.once, [&] {
    const SourceFile& src = *sources_[static_cast<size_t>(slot.file)];
    std::string text;
    if (slot.begin == 0 && slot.end == static_cast<std::int32_t>(src.text.size())) {
      text = src.text;
    } else {
      // The header, the lines before the class blanked, the class: the class's spans are
      // those of the whole file.
      text.reserve(static_cast<size_t>(slot.end));
      text.append(src.text, 0, static_cast<size_t>(slot.header_end));
      text.append(static_cast<size_t>(slot.begin - slot.header_end), ' ');
      text.append(src.text, static_cast<size_t>(slot.begin), static_cast<size_t>(slot.end - slot.begin));
    }
    slot.def = ParseAs(slot.file + 1, src.name, std::move(text), &slot.diags);
    parsed_.fetch_add(1);
  });
}

int Library::FindUnit(std::string_view q) const {
  auto it = index_.find(std::string(q));
  return it == index_.end() ? -1 : it->second;
}

const std::shared_ptr<const ast::StoredDefinition>& Library::Unit(int u) const {
  const UnitSlot& slot = *units_[static_cast<size_t>(u)];
  ParseUnit(slot);
  return slot.def;
}

int Library::NumParsed() const { return parsed_.load(); }

const std::vector<Diagnostic>& Library::UnitDiagnostics(int u) const {
  const UnitSlot& slot = *units_[static_cast<size_t>(u)];
  ParseUnit(slot);
  return slot.diags;
}

std::shared_ptr<const Library> SharedLibrary(const std::vector<std::pair<std::string, std::string>>& files) {
  // Never destroyed: threads may still hold it at exit, and freeing its trees then is
  // work for nothing (the pointer stays reachable, so leak checkers do not count it).
  static std::mutex* const mutex = new std::mutex;
  static auto* const cached = new std::shared_ptr<const Library>;
  static auto* const cached_files = new std::vector<std::pair<std::string, std::string>>;
  if (files.empty()) return nullptr;  // no library (`kanesim check --emit ast`): nothing to share
  std::lock_guard<std::mutex> lock(*mutex);
  if (*cached && (&files == cached_files || files == *cached_files)) return *cached;
  *cached = std::make_shared<const Library>(files);
  *cached_files = files;
  return *cached;
}

}  // namespace kanesim::lang
