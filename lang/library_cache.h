// The standard library, parsed on demand, once per process.
//
// Every load (a `kanesim run`, each scenario of a sweep that changes a structural
// parameter, every test, every fuzzer input) needs the same library. Its files' texts
// and line starts are made once per process and shared by every Program's SourceManager;
// its classes are parsed one top-level class at a time, on the first lookup of that
// class's name, and shared read-only by every Program after that, across threads.
//
// A unit is one top-level class of one file, parsed from the file's header (its `within`
// clause and imports) and the class's lines, the rest of the file blanked, so that spans
// and the AST are exactly those of parsing the whole file (tests/lang/library_cache_test).
// The class boundaries come from a scan of the text for declarations at the start of a
// line (`[partial] model Name` ... `end Name;`); a file the scan does not understand is one
// unit holding all its classes, parsed when the library is made.
//
// A library can also come from an image (Image(), lang/ast_image.h): its units already parsed
// when kanesim was built (stdlib/CMakeLists.txt), read one unit at a time on first use instead
// of parsed, with the same spans and AST (tests/lang/library_image_test.cpp).
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "lang/ast.h"
#include "lang/diagnostics.h"
#include "lang/source.h"

namespace kanesim::lang {

class Library {
 public:
  // `files` are (display name, contents); file i becomes source file i + 1 of a Program
  // (file 0 is the model being loaded).
  // `image`, if not empty, is Image() of a library of the same files; it must outlive this
  // library (the standard library's is static). An image of other files, or one that does
  // not read, is ignored: the files are then parsed.
  explicit Library(const std::vector<std::pair<std::string, std::string>>& files, std::string_view image = {});
  Library(const Library&) = delete;
  Library& operator=(const Library&) = delete;

  const std::vector<std::shared_ptr<const SourceFile>>& Sources() const { return sources_; }
  int NumUnits() const { return static_cast<int>(units_.size()); }
  // The unit that declares the top-level class with qualified name `q` ("Kanesim.Revolute"),
  // or -1.
  int FindUnit(std::string_view q) const;
  // Unit u's parse (within, imports and its class or classes); parsed on the first call,
  // then shared. Thread-safe.
  const std::shared_ptr<const ast::StoredDefinition>& Unit(int u) const;
  // The diagnostics of unit u's parse (after Unit(u)): none for the embedded library
  // (tests/lang/library_cache_test.cpp); a library that does not parse reports its errors
  // when elaboration first needs the unit, instead of when the model is loaded.
  const std::vector<Diagnostic>& UnitDiagnostics(int u) const;
  // How many units have been parsed so far (for tests).
  int NumParsed() const;
  // Whether the units come from an image (for tests and benchmarks).
  bool FromImage() const { return !image_.empty(); }
  // Every unit parsed, with its place in its file and the class index, as bytes for the
  // constructor; "" if a unit has diagnostics or does not fit an image. Build time
  // (lang/tools/library_image.cpp).
  std::string Image() const;

 private:
  struct UnitSlot {
    int file = 0;              // index into files (source file file + 1)
    std::int32_t header_end = 0;  // the file's header: [0, header_end)
    std::int32_t begin = 0, end = 0;  // the class: [begin, end); a whole-file unit: [0, size)
    std::int64_t image_at = -1;  // where its definition starts in image_, or -1: parse the text
    mutable std::once_flag once;
    mutable std::shared_ptr<const ast::StoredDefinition> def;
    mutable std::vector<Diagnostic> diags;
  };
  void ParseUnit(const UnitSlot& slot) const;
  bool ReadImage(std::string_view image);

  std::vector<std::shared_ptr<const SourceFile>> sources_;
  std::vector<std::unique_ptr<UnitSlot>> units_;
  std::unordered_map<std::string, int> index_;  // qualified top-level class name -> unit
  std::uint64_t hash_ = 0;                       // of the files' names and texts (an image's key)
  std::string_view image_;                       // the image the units are read from, or empty
  mutable std::atomic<int> parsed_{0};
};

// The library of `files`, made on first use and kept for the process: every call with the
// same files (the embedded standard library, stdlib::Files(), in practice) returns the same
// library. A call with other files makes a new one, which later calls with those files
// share; a Program holding the previous one keeps it. Null for no files. Thread-safe.
// `image` as for Library's constructor (used when the library is made).
std::shared_ptr<const Library> SharedLibrary(const std::vector<std::pair<std::string, std::string>>& files,
                                             std::string_view image = {});

}  // namespace kanesim::lang
