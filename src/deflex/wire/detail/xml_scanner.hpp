// A strict, allocation-free pull scanner of the small subset of XML 1.0 that controller interfaces put
// on the wire (KUKA RSI's <Rob> and <Sen> documents): elements with attributes, character data,
// comments and an optional XML declaration, in ASCII. Everything outside that subset is refused
// (DOCTYPE, CDATA sections, processing instructions, entity and character references, namespace
// prefixes, non-ASCII bytes), as is anything that is not well-formed. So a document the scanner
// accepts is well-formed XML with one plain reading; a document it refuses may still be well-formed
// (a full parser would take it), but a controller link never answers it. It works on spans of the
// caller's buffer: nothing is copied, allocated or thrown. Tests hold it against libxml2.
#pragma once

#include <array>
#include <cstddef>
#include <string_view>

namespace deflex {

enum class XmlToken {
  kStart,  ///< a start tag (or an empty-element tag, followed by its kEnd): name(), attributes
  kEnd,    ///< an end tag: name()
  kText,   ///< character data inside the root element: text(), as it stands (no references in it)
  kDone,   ///< the document ended properly
  kError,  ///< see error(); every later call returns kError again
};

enum class XmlError {
  kNone,
  kTruncated,    ///< the document ends before its root element is closed (or before it begins)
  kSyntax,       ///< not well-formed (bad tag, unmatched end tag, duplicate attribute, text outside the root ...)
  kUnsupported,  ///< well-formed perhaps, but outside the subset (DOCTYPE, CDATA, references, non-ASCII ...)
  kTooComplex,   ///< deeper than kMaxDepth, or more than kMaxAttributes on one element
};
[[nodiscard]] const char* to_string(XmlError e);

class XmlScanner {
 public:
  static constexpr int kMaxDepth = 16;
  static constexpr int kMaxAttributes = 32;

  /// Scans `size` bytes at `data` (which must outlive the scanner).
  XmlScanner(const char* data, std::size_t size) noexcept : begin_(data), pos_(data), end_(data + size) {}

  XmlToken next() noexcept;

  /// The element's name (kStart, kEnd).
  [[nodiscard]] std::string_view name() const { return name_; }
  /// Depth of the element of the last kStart or kEnd: 1 for the root.
  [[nodiscard]] int depth() const { return token_depth_; }
  [[nodiscard]] int attribute_count() const { return attribute_count_; }
  [[nodiscard]] std::string_view attribute_name(int i) const { return attributes_[static_cast<std::size_t>(i)].name; }
  [[nodiscard]] std::string_view attribute_value(int i) const { return attributes_[static_cast<std::size_t>(i)].value; }
  /// The value of the attribute `name` of the last kStart; false when it has none.
  bool attribute(std::string_view name, std::string_view& value) const noexcept;
  /// The character data of the last kText.
  [[nodiscard]] std::string_view text() const { return text_; }

  [[nodiscard]] XmlError error() const { return error_; }
  /// Byte offset where the error was found.
  [[nodiscard]] std::size_t error_offset() const { return error_offset_; }

 private:
  [[nodiscard]] int prefix(std::string_view lit) const noexcept;
  XmlToken outside_root(bool& again) noexcept;
  XmlToken in_content(bool& again) noexcept;
  enum class Where { kProlog, kContent, kEpilog, kDone };
  struct Attribute {
    std::string_view name, value;
  };

  XmlToken fail(XmlError e, const char* at) noexcept;
  bool skip_space() noexcept;  // true when it skipped at least one byte
  bool read_name(std::string_view& out) noexcept;
  bool read_attribute(Attribute& a) noexcept;
  XmlToken comment() noexcept;
  XmlToken declaration() noexcept;
  XmlToken start_tag() noexcept;
  XmlToken end_tag() noexcept;
  XmlToken char_data() noexcept;

  const char* begin_;
  const char* pos_;
  const char* end_;
  Where where_ = Where::kProlog;
  bool first_ = true;
  bool pending_end_ = false;  // an empty-element tag: its kEnd comes next
  std::array<std::string_view, kMaxDepth> open_{};
  int depth_ = 0;
  int token_depth_ = 0;
  std::string_view name_, text_;
  std::array<Attribute, kMaxAttributes> attributes_{};
  int attribute_count_ = 0;
  XmlError error_ = XmlError::kNone;
  std::size_t error_offset_ = 0;
};

}  // namespace deflex
