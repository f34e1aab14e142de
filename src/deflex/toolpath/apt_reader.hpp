// APT / CL data (ISO 4343 records as CAM systems export them: NX CLSF, CATIA APT, Fusion and SprutCAM
// CLDATA) read a point at a time. docs/machining.md lists the records read and what is refused.
#pragma once

#include <memory>
#include <string>

#include "deflex/toolpath/toolpath_reader.hpp"

namespace deflex {

namespace detail {
class LineReader;
class AptRecordReader;
struct AptRecord;
class AptInterpreter;
class BlockPoints;
}  // namespace detail

/// Thread safety: one thread at a time.
class AptReader final : public ToolpathReader {
 public:
  /// Opens the file (InputKind::kToolpath). Throws DataError when it cannot be read, InputError for
  /// options out of range.
  explicit AptReader(const std::string& path, const ToolpathOptions& options = {});
  /// Reads CL data held in memory; `source` names it in messages.
  AptReader(std::string text, std::string source, const ToolpathOptions& options = {});
  ~AptReader() override;

  bool next(ToolpathPoint& out) override;
  [[nodiscard]] const ToolpathSummary& summary() const override;

 private:
  std::unique_ptr<detail::LineReader> lines_;
  std::unique_ptr<detail::AptRecordReader> records_;
  std::unique_ptr<detail::AptInterpreter> machine_;
  std::unique_ptr<detail::BlockPoints> block_;
  std::unique_ptr<detail::AptRecord> record_;
  bool ended_ = false;
};

}  // namespace deflex
