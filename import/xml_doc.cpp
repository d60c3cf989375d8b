// The element tree of an XML text, built from expat's callbacks (import/xml_doc.h).
#include "import/xml_doc.h"

#include <expat.h>

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <memory>

namespace kanesim::import::xml {

const char* Element::Attribute(const char* name) const {
  for (const auto& [key, value] : attributes_)
    if (key == name) return value.c_str();
  return nullptr;
}

const Element* Element::FirstChildElement(const char* name) const {
  for (const Element* c = first_child_; c; c = c->next_)
    if (!name || c->name_ == name) return c;
  return nullptr;
}

const Element* Element::NextSiblingElement(const char* name) const {
  for (const Element* c = next_; c; c = c->next_)
    if (!name || c->name_ == name) return c;
  return nullptr;
}

// expat's callbacks: each start tag appends an element under the innermost open one.
struct Document::Builder {
  Document* doc;
  XML_Parser parser;
  std::string_view text;
  std::vector<Element*> open;  // the elements whose end tag is still to come, outermost first
  bool failed = false;
  std::size_t counted = 0;  // newlines of text[0, counted) are in `line`
  int line = 1;

  int Line() const { return static_cast<int>(XML_GetCurrentLineNumber(parser)); }

  // The line of the current event's first byte ('\n' counted on from the last element's, as
  // the diagnostics' renderer counts lines): cheaper than expat's own count, which walks the
  // text character by character (0.3M of Talos's 4.0M instructions of parsing).
  int StartLine() {
    const auto at = static_cast<std::size_t>(XML_GetCurrentByteIndex(parser));
    if (at < counted || at > text.size()) return Line();
    line += static_cast<int>(std::count(text.begin() + static_cast<std::ptrdiff_t>(counted),
                                        text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
    counted = at;
    return line;
  }

  void Fail(std::string words) {
    if (failed) return;
    failed = true;
    doc->error_line_ = Line();
    doc->error_text_ = std::move(words);
    XML_StopParser(parser, XML_FALSE);
  }

  static void XMLCALL Start(void* data, const XML_Char* name, const XML_Char** attributes) {
    auto* b = static_cast<Builder*>(data);
    if (static_cast<int>(b->open.size()) >= kMaxDepth) return b->Fail("elements are nested too deep");
    Element& e = b->doc->elements_.emplace_back();
    e.name_ = name;
    e.line_ = b->StartLine();
    std::size_t n = 0;
    while (attributes[2 * n]) ++n;
    e.attributes_.reserve(n);
    for (const XML_Char** a = attributes; a[0]; a += 2) e.attributes_.emplace_back(a[0], a[1]);
    if (b->open.empty()) {
      b->doc->root_ = &e;
    } else {
      Element* parent = b->open.back();
      (parent->last_child_ ? parent->last_child_->next_ : parent->first_child_) = &e;
      parent->last_child_ = &e;
    }
    b->open.push_back(&e);
  }

  static void XMLCALL End(void* data, const XML_Char*) { static_cast<Builder*>(data)->open.pop_back(); }

  // A file that declares entities expects them expanded (the "billion laughs" is one): refused.
  static void XMLCALL EntityDecl(void* data, const XML_Char*, int, const XML_Char*, int, const XML_Char*,
                                 const XML_Char*, const XML_Char*, const XML_Char*) {
    auto* b = static_cast<Builder*>(data);
    b->doc->entities_ = true;
    b->Fail("the file declares XML entities, which are not expanded");
  }
};

namespace {

// What expat's error means, in words.
std::string ErrorWords(XML_Error e) {
  switch (e) {
    case XML_ERROR_NO_ELEMENTS: return "the file holds no XML element";
    case XML_ERROR_SYNTAX:
    case XML_ERROR_INVALID_TOKEN: return "this is not well-formed XML";
    case XML_ERROR_UNCLOSED_TOKEN: return "an element is malformed or not closed";
    case XML_ERROR_DUPLICATE_ATTRIBUTE: return "an attribute is given twice";
    case XML_ERROR_UNCLOSED_CDATA_SECTION: return "a CDATA section is not closed";
    case XML_ERROR_JUNK_AFTER_DOC_ELEMENT: return "something follows the root element's end";
    case XML_ERROR_UNDEFINED_ENTITY: return "an entity reference (&name;) that is not defined";
    default: return std::string("the XML cannot be parsed (") + XML_ErrorString(e) + ")";
  }
}

}  // namespace

bool Document::Parse(std::string_view text) {
  // UTF-8 whatever the declaration says, as tinyxml2 read it.
  std::unique_ptr<XML_ParserStruct, void (*)(XML_Parser)> parser(XML_ParserCreate("UTF-8"), XML_ParserFree);
  if (!parser) {
    error_line_ = 0;
    error_text_ = "out of memory";
    return false;
  }
  Builder b{this, parser.get(), text, {}, false, 0, 1};
  XML_SetUserData(parser.get(), &b);
  XML_SetElementHandler(parser.get(), &Builder::Start, &Builder::End);
  XML_SetEntityDeclHandler(parser.get(), &Builder::EntityDecl);
  constexpr std::size_t kChunk = std::size_t{1} << 30;  // XML_Parse takes an int length
  std::size_t at = 0;
  do {
    const std::size_t n = std::min(kChunk, text.size() - at);
    const bool last = at + n == text.size();
    if (XML_Parse(parser.get(), text.data() + at, static_cast<int>(n), last) != XML_STATUS_OK) {
      if (b.failed) return false;
      const XML_Error e = XML_GetErrorCode(parser.get());
      error_line_ = b.Line();
      error_text_ = ErrorWords(e);
      // An element left open shows at the tag that ends its parent, or at the file's end: its own line is where to look.
      if (!b.open.empty() && (e == XML_ERROR_TAG_MISMATCH || e == XML_ERROR_NO_ELEMENTS)) {
        const Element& open = *b.open.back();
        error_text_ = "<" + open.name_ + "> is not closed" +
                      (e == XML_ERROR_TAG_MISMATCH ? " (the closing tag on line " + std::to_string(error_line_) +
                                                         " does not match it)"
                                                   : " before the end of the file");
        error_line_ = open.line_;
        error_needle_ = "<" + open.name_;
      }
      return false;
    }
    at += n;
  } while (at < text.size());
  return true;
}

}  // namespace kanesim::import::xml
