// The strict XML subset scanner (see xml_scanner.hpp). Grammar references are to XML 1.0 (5th ed.).
#include "deflex/wire/detail/xml_scanner.hpp"

namespace deflex {

namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }
bool is_ascii_letter(char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'); }
bool is_digit(char c) { return c >= '0' && c <= '9'; }
bool non_ascii(char c) { return static_cast<unsigned char>(c) >= 0x80; }
// [2] Char, restricted to ASCII: tab, LF, CR and 0x20..0x7F.
bool is_char(char c) {
  const auto u = static_cast<unsigned char>(c);
  return u == 0x09 || u == 0x0A || u == 0x0D || (u >= 0x20 && u < 0x80);
}

bool equal_ignoring_case(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    char x = a[i], y = b[i];
    if (x >= 'a' && x <= 'z') x = static_cast<char>(x - 'a' + 'A');
    if (y >= 'a' && y <= 'z') y = static_cast<char>(y - 'a' + 'A');
    if (x != y) return false;
  }
  return true;
}

}  // namespace

const char* to_string(XmlError e) {
  switch (e) {
    case XmlError::kNone:
      return "none";
    case XmlError::kTruncated:
      return "truncated";
    case XmlError::kSyntax:
      return "not well-formed";
    case XmlError::kUnsupported:
      return "outside the supported XML subset";
    case XmlError::kTooComplex:
      return "too deep or too many attributes";
  }
  return "unknown";
}

XmlToken XmlScanner::fail(XmlError e, const char* at) noexcept {
  error_ = e;
  error_offset_ = static_cast<std::size_t>(at - begin_);
  return XmlToken::kError;
}

bool XmlScanner::attribute(std::string_view name, std::string_view& value) const noexcept {
  for (int i = 0; i < attribute_count_; ++i) {
    if (attributes_[static_cast<std::size_t>(i)].name == name) {
      value = attributes_[static_cast<std::size_t>(i)].value;
      return true;
    }
  }
  return false;
}

bool XmlScanner::skip_space() noexcept {
  const char* from = pos_;
  while (pos_ < end_ && is_space(*pos_)) ++pos_;
  return pos_ != from;
}

// [5] Name, restricted to ASCII letters, digits, '_', '-', '.' (no ':': namespaces are not in the subset).
bool XmlScanner::read_name(std::string_view& out) noexcept {
  if (pos_ == end_) return fail(XmlError::kTruncated, pos_), false;
  const char* from = pos_;
  if (!(is_ascii_letter(*pos_) || *pos_ == '_')) {
    const bool other = non_ascii(*pos_) || *pos_ == ':';
    return fail(other ? XmlError::kUnsupported : XmlError::kSyntax, pos_), false;
  }
  ++pos_;
  while (pos_ < end_ && (is_ascii_letter(*pos_) || is_digit(*pos_) || *pos_ == '_' || *pos_ == '-' || *pos_ == '.')) {
    ++pos_;
  }
  if (pos_ < end_ && (*pos_ == ':' || non_ascii(*pos_))) return fail(XmlError::kUnsupported, pos_), false;
  out = std::string_view(from, static_cast<std::size_t>(pos_ - from));
  return true;
}

// [41] Attribute: Name Eq AttValue, with [25] Eq ::= S? '=' S?. The value may not hold '<' (not
// well-formed) nor '&' (a reference: outside the subset). Also reads the declaration's pseudo-attributes.
bool XmlScanner::read_attribute(Attribute& a) noexcept {
  if (!read_name(a.name)) return false;
  skip_space();
  if (pos_ == end_) return fail(XmlError::kTruncated, pos_), false;
  if (*pos_ != '=') return fail(XmlError::kSyntax, pos_), false;
  ++pos_;
  skip_space();
  if (pos_ == end_) return fail(XmlError::kTruncated, pos_), false;
  const char quote = *pos_;
  if (quote != '"' && quote != '\'') return fail(XmlError::kSyntax, pos_), false;
  const char* v = ++pos_;
  while (pos_ < end_ && *pos_ != quote) {
    const char c = *pos_;
    if (c == '<') return fail(XmlError::kSyntax, pos_), false;
    if (c == '&') return fail(XmlError::kUnsupported, pos_), false;
    if (!is_char(c)) return fail(non_ascii(c) ? XmlError::kUnsupported : XmlError::kSyntax, pos_), false;
    ++pos_;
  }
  if (pos_ == end_) return fail(XmlError::kTruncated, pos_), false;
  a.value = std::string_view(v, static_cast<std::size_t>(pos_ - v));
  ++pos_;
  return true;
}

// [15] Comment: '<!--' ((Char - '-') | ('-' (Char - '-')))* '-->'. Skipped; kDone on success.
XmlToken XmlScanner::comment() noexcept {
  pos_ += 4;
  while (pos_ < end_) {
    const char c = *pos_;
    if (c == '-' && pos_ + 1 < end_ && pos_[1] == '-') {
      if (pos_ + 2 == end_) return fail(XmlError::kTruncated, pos_);
      if (pos_[2] != '>') return fail(XmlError::kSyntax, pos_);  // "--" inside a comment
      pos_ += 3;
      return XmlToken::kDone;
    }
    if (!is_char(c)) return fail(non_ascii(c) ? XmlError::kUnsupported : XmlError::kSyntax, pos_);
    ++pos_;
  }
  return fail(XmlError::kTruncated, pos_);
}

// [23] XMLDecl: '<?xml' VersionInfo EncodingDecl? SDDecl? S? '?>', at the very start only. Version
// 1.0; encodings whose ASCII bytes mean what they say (UTF-8, ISO-8859-1, US-ASCII).
XmlToken XmlScanner::declaration() noexcept {
  pos_ += 5;
  int field = 0;  // 0 version, 1 encoding, 2 standalone
  for (;;) {
    const bool space = skip_space();
    if (pos_ == end_) return fail(XmlError::kTruncated, pos_);
    if (*pos_ == '?') {
      if (pos_ + 1 == end_) return fail(XmlError::kTruncated, pos_);
      if (pos_[1] != '>' || field == 0) return fail(XmlError::kSyntax, pos_);
      pos_ += 2;
      return XmlToken::kDone;
    }
    if (!space) return fail(XmlError::kSyntax, pos_);
    const char* at = pos_;
    Attribute pseudo;
    if (!read_attribute(pseudo)) return XmlToken::kError;
    const std::string_view key = pseudo.name, value = pseudo.value;
    const char* v = value.data();
    if (field == 0 && key == "version") {
      if (value != "1.0") return fail(XmlError::kUnsupported, v);
      field = 1;
    } else if (field <= 1 && field > 0 && key == "encoding") {
      if (!(equal_ignoring_case(value, "UTF-8") || equal_ignoring_case(value, "ISO-8859-1") ||
            equal_ignoring_case(value, "US-ASCII"))) {
        return fail(XmlError::kUnsupported, v);
      }
      field = 2;
    } else if (field >= 1 && field <= 2 && key == "standalone") {
      if (value != "yes" && value != "no") return fail(XmlError::kSyntax, v);
      field = 3;
    } else {
      return fail(XmlError::kSyntax, at);
    }
  }
}

// [40] STag / [44] EmptyElemTag, attributes unique within the tag.
XmlToken XmlScanner::start_tag() noexcept {
  const char* lt = pos_;
  ++pos_;
  std::string_view name;
  if (!read_name(name)) return XmlToken::kError;
  if (depth_ == kMaxDepth) return fail(XmlError::kTooComplex, lt);
  attribute_count_ = 0;
  for (;;) {
    const bool space = skip_space();
    if (pos_ == end_) return fail(XmlError::kTruncated, pos_);
    if (*pos_ == '>' || *pos_ == '/') {
      if (*pos_ == '/') {
        if (pos_ + 1 == end_) return fail(XmlError::kTruncated, pos_);
        if (pos_[1] != '>') return fail(XmlError::kSyntax, pos_);
        pending_end_ = true;
        ++pos_;
      }
      ++pos_;
      name_ = name;
      open_[static_cast<std::size_t>(depth_++)] = name;
      token_depth_ = depth_;
      where_ = Where::kContent;
      return XmlToken::kStart;
    }
    if (!space) return fail(XmlError::kSyntax, pos_);  // attributes are separated by white space
    Attribute a;
    const char* at = pos_;
    if (!read_attribute(a)) return XmlToken::kError;
    for (int i = 0; i < attribute_count_; ++i) {
      if (attributes_[static_cast<std::size_t>(i)].name == a.name)
        return fail(XmlError::kSyntax, at);  // [WFC: Unique Att Spec]
    }
    if (attribute_count_ == kMaxAttributes) return fail(XmlError::kTooComplex, at);
    attributes_[static_cast<std::size_t>(attribute_count_++)] = a;
  }
}

// [42] ETag: '</' Name S? '>', matching the open element [WFC: Element Type Match].
XmlToken XmlScanner::end_tag() noexcept {
  const char* at = pos_;
  pos_ += 2;
  std::string_view name;
  if (!read_name(name)) return XmlToken::kError;
  skip_space();
  if (pos_ == end_) return fail(XmlError::kTruncated, pos_);
  if (*pos_ != '>') return fail(XmlError::kSyntax, pos_);
  ++pos_;
  if (name != open_[static_cast<std::size_t>(depth_ - 1)]) return fail(XmlError::kSyntax, at);
  name_ = name;
  attribute_count_ = 0;
  token_depth_ = depth_--;
  if (depth_ == 0) where_ = Where::kEpilog;
  return XmlToken::kEnd;
}

// [14] CharData: no '<', no ']]>'; '&' would start a reference (outside the subset).
XmlToken XmlScanner::char_data() noexcept {
  const char* from = pos_;
  while (pos_ < end_ && *pos_ != '<') {
    const char c = *pos_;
    if (c == '&') return fail(XmlError::kUnsupported, pos_);
    if (c == '>' && pos_ - from >= 2 && pos_[-1] == ']' && pos_[-2] == ']') return fail(XmlError::kSyntax, pos_);
    if (!is_char(c)) return fail(non_ascii(c) ? XmlError::kUnsupported : XmlError::kSyntax, pos_);
    ++pos_;
  }
  text_ = std::string_view(from, static_cast<std::size_t>(pos_ - from));
  return XmlToken::kText;
}

// How much of `lit` the input at pos_ matches: 1 all of it, 0 not, -1 it ends inside a match.
int XmlScanner::prefix(std::string_view lit) const noexcept {
  for (std::size_t i = 0; i < lit.size(); ++i) {
    if (pos_ + i == end_) return -1;
    if (pos_[i] != lit[i]) return 0;
  }
  return 1;
}

XmlToken XmlScanner::next() noexcept {
  if (error_ != XmlError::kNone) return XmlToken::kError;
  if (pending_end_) {
    pending_end_ = false;
    name_ = open_[static_cast<std::size_t>(depth_ - 1)];
    attribute_count_ = 0;
    token_depth_ = depth_--;
    if (depth_ == 0) where_ = Where::kEpilog;
    return XmlToken::kEnd;
  }
  if (first_) {
    first_ = false;
    if (prefix("<?xml") == 1 && pos_ + 5 < end_ && is_space(pos_[5])) {
      if (declaration() == XmlToken::kError) return XmlToken::kError;
    }
  }
  // A comment is skipped and the scan goes on; anything else is the token.
  for (bool again = true; again;) {
    again = false;
    XmlToken t = XmlToken::kDone;
    switch (where_) {
      case Where::kDone:
        return XmlToken::kDone;
      case Where::kProlog:
      case Where::kEpilog:
        t = outside_root(again);
        break;
      case Where::kContent:
        t = in_content(again);
        break;
    }
    if (!again) return t;
  }
  return XmlToken::kDone;  // not reached: the loop returns
}

// Before and after the root element: space, comments and the root's start tag only.
XmlToken XmlScanner::outside_root(bool& again) noexcept {
  skip_space();
  if (pos_ == end_) {
    if (where_ == Where::kProlog) return fail(XmlError::kTruncated, pos_);
    where_ = Where::kDone;
    return XmlToken::kDone;
  }
  if (*pos_ != '<') return fail(non_ascii(*pos_) ? XmlError::kUnsupported : XmlError::kSyntax, pos_);
  const int comment_start = prefix("<!--");
  if (comment_start == 1) {
    if (comment() == XmlToken::kError) return XmlToken::kError;
    again = true;
    return XmlToken::kDone;
  }
  if (comment_start < 0 || pos_ + 1 == end_) return fail(XmlError::kTruncated, pos_);
  if (pos_[1] == '?' || pos_[1] == '!') return fail(XmlError::kUnsupported, pos_);  // PI, DOCTYPE
  if (where_ == Where::kEpilog) return fail(XmlError::kSyntax, pos_);               // a second root element
  return start_tag();
}

// Inside the root element: text, tags and comments (no CDATA, no processing instructions).
XmlToken XmlScanner::in_content(bool& again) noexcept {
  if (pos_ == end_) return fail(XmlError::kTruncated, pos_);
  if (*pos_ != '<') return char_data();
  if (pos_ + 1 == end_) return fail(XmlError::kTruncated, pos_);
  if (pos_[1] == '/') return end_tag();
  if (pos_[1] == '?') return fail(XmlError::kUnsupported, pos_);
  if (pos_[1] != '!') return start_tag();
  const int comment_start = prefix("<!--");
  if (comment_start < 0) return fail(XmlError::kTruncated, pos_);
  if (comment_start == 0) {
    const int cdata = prefix("<![CDATA[");
    if (cdata < 0) return fail(XmlError::kTruncated, pos_);
    return fail(cdata == 1 ? XmlError::kUnsupported : XmlError::kSyntax, pos_);
  }
  if (comment() == XmlToken::kError) return XmlToken::kError;
  again = true;
  return XmlToken::kDone;
}

}  // namespace deflex
