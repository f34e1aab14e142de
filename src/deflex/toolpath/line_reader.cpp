// Toolpath lines with their endings, streamed from the file.
#include "deflex/toolpath/detail/line_reader.hpp"

#include <cstring>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"
#include "deflex/toolpath/toolpath_options.hpp"

namespace deflex::detail {
namespace {
constexpr std::size_t kLineReadChunk = std::size_t{1} << 20;
}  // namespace

LineReader::LineReader(const std::string& path)
    : source_(path), file_(std::make_unique<InputFile>(path, InputKind::kToolpath)) {}

LineReader::LineReader(std::string text, std::string source)
    : source_(std::move(source)), buffer_(std::move(text)), eof_(true) {}

LineReader::~LineReader() = default;

bool LineReader::fill() {
  if (eof_) {
    return false;
  }
  buffer_.erase(0, begin_);
  begin_ = 0;
  const std::size_t kept = buffer_.size();
  buffer_.resize(kept + kLineReadChunk);
  const std::size_t got = file_->read(buffer_.data() + kept, kLineReadChunk);
  buffer_.resize(kept + got);
  eof_ = got == 0;
  return got != 0;
}

bool LineReader::next(SourceLine& out) {
  if (first_) {
    while (buffer_.size() - begin_ < 3 && fill()) {
    }
    first_ = false;
    if (buffer_.compare(begin_, 3, "\xEF\xBB\xBF") == 0) {
      begin_ += 3;
      bom_ = true;
    }
  }
  while (true) {
    const char* data = buffer_.data();
    const std::size_t size = buffer_.size();
    const void* nl = std::memchr(data + begin_, '\n', size - begin_);
    std::size_t end = nl != nullptr ? static_cast<std::size_t>(static_cast<const char*>(nl) - data) : size;
    if (const void* cr = std::memchr(data + begin_, '\r', end - begin_)) {
      end = static_cast<std::size_t>(static_cast<const char*>(cr) - data);
    }
    // A '\r' as the last byte read may be the first half of "\r\n": read on before deciding.
    const bool need_more = end == size || (data[end] == '\r' && end + 1 == size);
    if (need_more && !eof_) {
      if (size - begin_ > toolpath_limits::kMaxLineBytes) {
        throw DataError(fmt::format("{}:{}: a line longer than {} bytes: not a toolpath program", source_, line_ + 1,
                                    toolpath_limits::kMaxLineBytes));
      }
      fill();
      continue;
    }
    if (begin_ >= size) {
      return false;
    }
    std::size_t ending = 0;
    if (end < size) {
      ending = data[end] == '\r' && end + 1 < size && data[end + 1] == '\n' ? 2 : 1;
    }
    if (end - begin_ > toolpath_limits::kMaxLineBytes) {
      throw DataError(fmt::format("{}:{}: a line longer than {} bytes: not a toolpath program", source_, line_ + 1,
                                  toolpath_limits::kMaxLineBytes));
    }
    out.text = std::string_view(data + begin_, end - begin_);
    out.ending = std::string_view(data + end, ending);
    out.number = ++line_;
    if (out.text.find('\0') != std::string_view::npos) {
      throw DataError(fmt::format("{}:{}: a NUL byte: a binary file, not a toolpath program", source_, line_));
    }
    begin_ = end + ending;
    return true;
  }
}

}  // namespace deflex::detail
