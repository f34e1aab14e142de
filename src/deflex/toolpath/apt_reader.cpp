// APT/CL data read a point at a time: lines into records, records into points.
#include "deflex/toolpath/apt_reader.hpp"

#include <fmt/format.h>

#include "deflex/text/errors.hpp"
#include "deflex/toolpath/detail/apt_interpreter.hpp"
#include "deflex/toolpath/detail/block_points.hpp"
#include "deflex/toolpath/detail/line_reader.hpp"

namespace deflex {

AptReader::AptReader(const std::string& path, const ToolpathOptions& options)
    : machine_(std::make_unique<detail::AptInterpreter>(path, options)),
      block_(std::make_unique<detail::BlockPoints>()),
      record_(std::make_unique<detail::AptRecord>()) {
  lines_ = std::make_unique<detail::LineReader>(path);  // after the options are checked
  records_ = std::make_unique<detail::AptRecordReader>(*lines_);
}

AptReader::AptReader(std::string text, std::string source, const ToolpathOptions& options)
    : machine_(std::make_unique<detail::AptInterpreter>(source, options)),
      block_(std::make_unique<detail::BlockPoints>()),
      record_(std::make_unique<detail::AptRecord>()) {
  lines_ = std::make_unique<detail::LineReader>(std::move(text), std::move(source));
  records_ = std::make_unique<detail::AptRecordReader>(*lines_);
}

AptReader::~AptReader() = default;

const ToolpathSummary& AptReader::summary() const { return machine_->summary(); }

bool AptReader::next(ToolpathPoint& out) {
  while (!ended_) {
    if (block_->next(out)) {
      machine_->count_point(out);
      return true;
    }
    if (!records_->next(*record_)) {
      ended_ = true;
      machine_->finish();
      if (machine_->summary().points == 0) {
        throw DataError(fmt::format("{}: no GOTO: the CL data give no toolpath point", lines_->source()));
      }
      break;
    }
    machine_->interpret(*record_, *block_);
  }
  return false;
}

}  // namespace deflex
