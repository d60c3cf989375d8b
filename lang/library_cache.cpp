#include "lang/library_cache.h"

#include <algorithm>
#include <cctype>
#include <cstring>

#include "lang/ast_image.h"
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

// FNV-1a over 8-byte words: the key that ties an image to the files it was made from.
std::uint64_t HashFiles(const std::vector<std::pair<std::string, std::string>>& files) {
  std::uint64_t h = 14695981039346656037ull;
  auto mix = [&h](std::uint64_t w) { h = (h ^ w) * 1099511628211ull; };
  for (const auto& [name, text] : files)
    for (const std::string* s : {&name, &text}) {
      mix(s->size());
      size_t i = 0;
      for (; i + 8 <= s->size(); i += 8) {
        std::uint64_t w;
        std::memcpy(&w, s->data() + i, 8);
        mix(w);
      }
      for (; i < s->size(); ++i) mix(static_cast<unsigned char>((*s)[i]));
    }
  return h;
}

// The image's head: magic, the files' hash, then the unit table, the class index and the
// units' definitions (ast_image.h), all 32-bit integers but the hash.
constexpr std::int32_t kImageMagic = 0x4B4C4942;  // "KLIB"

void PutInt(std::string* out, std::int64_t v) {
  const auto x = static_cast<std::int32_t>(v);
  out->append(reinterpret_cast<const char*>(&x), sizeof x);
}

bool GetInt(std::string_view in, std::size_t* pos, std::int64_t* v) {
  std::int32_t x = 0;
  if (in.size() - *pos < sizeof x) return false;
  std::memcpy(&x, in.data() + *pos, sizeof x);
  *pos += sizeof x;
  *v = x;
  return true;
}

}  // namespace

Library::Library(const std::vector<std::pair<std::string, std::string>>& files, std::string_view image) {
  for (const auto& [name, text] : files) sources_.push_back(MakeSourceFile(name, text));
  hash_ = HashFiles(files);
  if (!image.empty() && ReadImage(image)) return;
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

bool Library::ReadImage(std::string_view image) {
  std::size_t pos = 0;
  std::int64_t magic = 0, n_units = 0, n_names = 0, defs_size = 0;
  std::uint64_t hash = 0;
  if (!GetInt(image, &pos, &magic) || magic != kImageMagic || image.size() - pos < sizeof hash) return false;
  std::memcpy(&hash, image.data() + pos, sizeof hash);
  pos += sizeof hash;
  if (hash != hash_ || !GetInt(image, &pos, &n_units) || !GetInt(image, &pos, &n_names) ||
      !GetInt(image, &pos, &defs_size) || n_units < 0 || n_names < 0 || defs_size < 0)
    return false;
  std::vector<std::unique_ptr<UnitSlot>> units;
  for (std::int64_t u = 0; u < n_units; ++u) {
    auto slot = std::make_unique<UnitSlot>();
    std::int64_t f = 0, header_end = 0, begin = 0, end = 0, at = 0;
    if (!GetInt(image, &pos, &f) || !GetInt(image, &pos, &header_end) || !GetInt(image, &pos, &begin) ||
        !GetInt(image, &pos, &end) || !GetInt(image, &pos, &at) || f < 0 ||
        f >= static_cast<std::int64_t>(sources_.size()) || at < 0 || at >= defs_size)
      return false;
    slot->file = static_cast<int>(f);
    slot->header_end = static_cast<std::int32_t>(header_end);
    slot->begin = static_cast<std::int32_t>(begin);
    slot->end = static_cast<std::int32_t>(end);
    slot->image_at = at;
    units.push_back(std::move(slot));
  }
  std::unordered_map<std::string, int> index;
  for (std::int64_t i = 0; i < n_names; ++i) {
    std::int64_t len = 0, unit = 0;
    if (!GetInt(image, &pos, &len) || len < 0 || static_cast<std::uint64_t>(len) > image.size() - pos) return false;
    std::string name(image.data() + pos, static_cast<size_t>(len));
    pos += static_cast<size_t>(len);
    if (!GetInt(image, &pos, &unit) || unit < 0 || unit >= n_units) return false;
    index.emplace(std::move(name), static_cast<int>(unit));
  }
  if (static_cast<std::uint64_t>(defs_size) != image.size() - pos) return false;
  for (auto& slot : units) slot->image_at += static_cast<std::int64_t>(pos);
  units_ = std::move(units);
  index_ = std::move(index);
  image_ = image;
  return true;
}

std::string Library::Image() const {
  std::string defs, table, names;
  for (size_t u = 0; u < units_.size(); ++u) {
    const UnitSlot& slot = *units_[u];
    ParseUnit(slot);
    if (!slot.def || !slot.diags.empty()) return "";
    PutInt(&table, slot.file);
    PutInt(&table, slot.header_end);
    PutInt(&table, slot.begin);
    PutInt(&table, slot.end);
    PutInt(&table, static_cast<std::int64_t>(defs.size()));
    if (!ast::WriteDefinition(*slot.def, &defs)) return "";
  }
  // Sorted, so that the image is the same bytes whatever the hash map's order.
  std::vector<std::pair<std::string, int>> sorted(index_.begin(), index_.end());
  std::sort(sorted.begin(), sorted.end());
  for (const auto& [name, unit] : sorted) {
    PutInt(&names, static_cast<std::int64_t>(name.size()));
    names += name;
    PutInt(&names, unit);
  }
  std::string out;
  PutInt(&out, kImageMagic);
  out.append(reinterpret_cast<const char*>(&hash_), sizeof hash_);
  PutInt(&out, static_cast<std::int64_t>(units_.size()));
  PutInt(&out, static_cast<std::int64_t>(sorted.size()));
  PutInt(&out, static_cast<std::int64_t>(defs.size()));
  return out + table + names + defs;
}

void Library::ParseUnit(const UnitSlot& slot) const {
  std::call_once(slot.once, [&] {
    if (slot.image_at >= 0) {
      std::size_t pos = static_cast<std::size_t>(slot.image_at);
      slot.def = ast::ReadDefinition(image_, &pos);
      if (slot.def) {
        parsed_.fetch_add(1);
        return;
      }
    }
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

std::shared_ptr<const Library> SharedLibrary(const std::vector<std::pair<std::string, std::string>>& files,
                                             std::string_view image) {
  // Never destroyed: threads may still hold it at exit, and freeing its trees then is
  // work for nothing (the pointer stays reachable, so leak checkers do not count it).
  static std::mutex* const mutex = new std::mutex;
  static auto* const cached = new std::shared_ptr<const Library>;
  static auto* const cached_files = new std::vector<std::pair<std::string, std::string>>;
  if (files.empty()) return nullptr;  // no library (`kanesim check --emit ast`): nothing to share
  std::lock_guard<std::mutex> lock(*mutex);
  if (*cached && (&files == cached_files || files == *cached_files)) return *cached;
  *cached = std::make_shared<const Library>(files, image);
  *cached_files = files;
  return *cached;
}

}  // namespace kanesim::lang
