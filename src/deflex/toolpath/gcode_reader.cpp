// G-code read a point at a time: lines through the interpreter, blocks into points.
#include "deflex/toolpath/gcode_reader.hpp"

#include <fmt/format.h>

#include "deflex/text/errors.hpp"
#include "deflex/toolpath/detail/block_points.hpp"
#include "deflex/toolpath/detail/gcode_interpreter.hpp"
#include "deflex/toolpath/detail/line_reader.hpp"

namespace deflex {

GcodeReader::GcodeReader(const std::string& path, const ToolpathOptions& options)
    : machine_(std::make_unique<detail::GcodeInterpreter>(path, options)),
      block_(std::make_unique<detail::BlockPoints>()) {
  lines_ = std::make_unique<detail::LineReader>(path);  // after the options are checked
}

GcodeReader::GcodeReader(std::string text, std::string source, const ToolpathOptions& options)
    : machine_(std::make_unique<detail::GcodeInterpreter>(source, options)),
      block_(std::make_unique<detail::BlockPoints>()) {
  lines_ = std::make_unique<detail::LineReader>(std::move(text), std::move(source));
}

GcodeReader::~GcodeReader() = default;

const ToolpathSummary& GcodeReader::summary() const { return machine_->summary(); }

bool GcodeReader::next(ToolpathPoint& out) {
  while (!ended_) {
    if (block_->next(out)) {
      machine_->count_point(out);
      return true;
    }
    detail::SourceLine line;
    if (!lines_->next(line)) {
      ended_ = true;
      if (machine_->summary().points == 0) {
        throw DataError(
            fmt::format("{}: no motion to a known position: the program gives no toolpath point", lines_->source()));
      }
      break;
    }
    machine_->interpret(line, *block_);
  }
  return false;
}

}  // namespace deflex
