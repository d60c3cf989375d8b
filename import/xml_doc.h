// The elements of an XML text as a read-only tree: names, attributes and the line each element
// starts on, what urdf_read.cpp reads (text, comments and processing instructions are skipped).
// expat parses (Debian's libexpat1-dev, linked from its static archive: a C library, so
// the command maps no shared library for it and reading a URDF opens nothing; docs/import.md).
// The accessors are named as tinyxml2's, which read the URDF before.
#pragma once

#include <deque>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace kanesim::import::xml {

inline constexpr int kMaxDepth = 100;  // elements nested deeper are refused (no stack to exhaust)

class Element {
 public:
  const char* Name() const { return name_.c_str(); }
  int GetLineNum() const { return line_; }  // the line of its '<'
  const char* Attribute(const char* name) const;  // its value, or nullptr when absent
  // The first child element (named `name`, or any when nullptr), and the next sibling.
  const Element* FirstChildElement(const char* name = nullptr) const;
  const Element* NextSiblingElement(const char* name = nullptr) const;

 private:
  friend class Document;
  std::string name_;
  int line_ = 0;
  std::vector<std::pair<std::string, std::string>> attributes_;
  Element* first_child_ = nullptr;
  Element* last_child_ = nullptr;
  Element* next_ = nullptr;
};

class Document {
 public:
  // Parses `text` (as UTF-8). False when it is not well formed, nests deeper than kMaxDepth
  // or declares entities; then ErrorLine() and ErrorText() say where and what.
  bool Parse(std::string_view text);
  const Element* Root() const { return root_; }
  int ErrorLine() const { return error_line_; }
  const std::string& ErrorText() const { return error_text_; }
  const std::string& ErrorNeedle() const { return error_needle_; }  // "<name" of an unclosed element, or ""
  bool DeclaresEntities() const { return entities_; }

 private:
  struct Builder;
  std::deque<Element> elements_;  // stable addresses as elements are added
  Element* root_ = nullptr;
  int error_line_ = 0;
  std::string error_text_, error_needle_;
  bool entities_ = false;
};

}  // namespace kanesim::import::xml
