// A toolpath file a line at a time, with each line's own ending (LF, CRLF or CR), so the G-code
// write-back can copy the lines it does not change byte for byte. Memory: one 1 MiB read buffer.
#pragma once

#include <memory>
#include <string>
#include <string_view>

#include "deflex/text/input_file.hpp"

namespace deflex::detail {

struct SourceLine {
  std::string_view text;    ///< without its ending (valid until the next call)
  std::string_view ending;  ///< "\n", "\r\n", "\r", or "" for a last line without one
  std::size_t number = 0;   ///< 1-based
};

/// Thread safety: one thread at a time.
class LineReader {
 public:
  /// Opens `path` as InputKind::kToolpath (a regular file within the limit).
  explicit LineReader(const std::string& path);
  /// Reads text held in memory; `source` names it in messages.
  LineReader(std::string text, std::string source);
  ~LineReader();
  LineReader(const LineReader&) = delete;
  LineReader& operator=(const LineReader&) = delete;

  /// The next line; false at the end. Throws DataError for a line longer than
  /// toolpath_limits::kMaxLineBytes or a NUL byte (a binary file).
  bool next(SourceLine& out);
  [[nodiscard]] const std::string& source() const { return source_; }
  /// The file began with a UTF-8 byte-order mark (not part of the first line's text).
  [[nodiscard]] bool had_bom() const { return bom_; }

 private:
  bool fill();  // reads a chunk behind the unconsumed bytes; false at the end of the file

  std::string source_;
  std::unique_ptr<InputFile> file_;
  std::string buffer_;
  std::size_t begin_ = 0;
  bool eof_ = false;
  bool first_ = true;
  bool bom_ = false;
  std::size_t line_ = 0;
};

}  // namespace deflex::detail
