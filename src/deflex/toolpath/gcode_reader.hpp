// ISO 6983 G-code as CAM posts write it for 3-axis and 5-axis machines, read a point at a time.
// docs/machining.md lists the words read, the 5-axis forms (A B C angles under a RotaryConvention,
// Siemens A3= B3= C3= vectors under TRAORI, Fanuc G43.5 I J K vectors) and what is refused.
#pragma once

#include <memory>
#include <string>

#include "deflex/toolpath/toolpath_reader.hpp"

namespace deflex {

namespace detail {
class LineReader;
class GcodeInterpreter;
class BlockPoints;
}  // namespace detail

/// Thread safety: one thread at a time.
class GcodeReader final : public ToolpathReader {
 public:
  /// Opens the file (InputKind::kToolpath). Throws DataError when it cannot be read, InputError for
  /// options out of range.
  explicit GcodeReader(const std::string& path, const ToolpathOptions& options = {});
  /// Reads a program held in memory; `source` names it in messages.
  GcodeReader(std::string text, std::string source, const ToolpathOptions& options = {});
  ~GcodeReader() override;

  bool next(ToolpathPoint& out) override;
  [[nodiscard]] const ToolpathSummary& summary() const override;

 private:
  std::unique_ptr<detail::LineReader> lines_;
  std::unique_ptr<detail::GcodeInterpreter> machine_;
  std::unique_ptr<detail::BlockPoints> block_;
  bool ended_ = false;
};

}  // namespace deflex
