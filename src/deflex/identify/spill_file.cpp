// Scratch file for the identification's rows beyond its memory budget.
#include "deflex/identify/detail/spill_file.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {

SpillFile::SpillFile(std::string what) : what_(std::move(what)) {}

SpillFile::~SpillFile() {
  if (fd_ >= 0) {
    ::close(fd_);
  }
}

void SpillFile::open() {
  std::error_code ec;
  const std::filesystem::path dir = std::filesystem::temp_directory_path(ec);
  directory_ = ec ? std::string("/tmp") : dir.string();
  std::string name = (std::filesystem::path(directory_) / "deflex-spill-XXXXXX").string();
  std::vector<char> buf(name.begin(), name.end());
  buf.push_back('\0');
  fd_ = ::mkstemp(buf.data());
  if (fd_ < 0) {
    throw Error(
        fmt::format("{}: too many to keep in memory, and no scratch file could be made in {} ({}); set TMPDIR "
                    "to a writable directory",
                    what_, directory_, std::strerror(errno)));
  }
  ::unlink(buf.data());  // gone from the directory now; the space is freed when the process ends
}

std::uint64_t SpillFile::append(const double* values, std::size_t count) {
  if (fd_ < 0) {
    open();
  }
  const std::uint64_t at = end_;
  write_at(at, values, count);
  return at;
}

void SpillFile::write_at(std::uint64_t offset, const double* values, std::size_t count) {
  const auto* p = reinterpret_cast<const char*>(values);
  std::size_t left = count * sizeof(double);
  auto at = static_cast<off_t>(offset);
  while (left > 0) {
    const ssize_t n = ::pwrite(fd_, p, left, at);
    if (n < 0 && errno == EINTR) {
      continue;
    }
    if (n <= 0) {
      throw Error(fmt::format("{}: writing the scratch file in {} failed ({}); free space there or set TMPDIR", what_,
                              directory_, n < 0 ? std::strerror(errno) : "nothing written"));
    }
    p += n;
    left -= static_cast<std::size_t>(n);
    at += n;
  }
  end_ = std::max<std::uint64_t>(end_, static_cast<std::uint64_t>(at));
}

void SpillFile::read_at(std::uint64_t offset, double* values, std::size_t count) const {
  auto* p = reinterpret_cast<char*>(values);
  std::size_t left = count * sizeof(double);
  auto at = static_cast<off_t>(offset);
  while (left > 0) {
    const ssize_t n = ::pread(fd_, p, left, at);
    if (n < 0 && errno == EINTR) {
      continue;
    }
    if (n <= 0) {
      throw Error(fmt::format("{}: reading back the scratch file in {} failed ({})", what_, directory_,
                              n < 0 ? std::strerror(errno) : "it ended early"));
    }
    p += n;
    left -= static_cast<std::size_t>(n);
    at += n;
  }
}

SpillFile::View::View(const SpillFile& file, std::uint64_t offset, std::size_t count) {
  const auto page = static_cast<std::uint64_t>(::sysconf(_SC_PAGESIZE));
  const std::uint64_t start = offset / page * page;
  length_ = static_cast<std::size_t>(offset - start) + count * sizeof(double);
  // MAP_POPULATE: the pages are in the page cache (just written); mapping them all at once is cheaper than a
  // fault per page.
  map_ = ::mmap(nullptr, length_, PROT_READ, MAP_PRIVATE | MAP_POPULATE, file.fd_, static_cast<off_t>(start));
  if (map_ == MAP_FAILED) {
    map_ = nullptr;
    throw Error(fmt::format("{}: reading back the scratch file in {} failed ({})", file.what_, file.directory_,
                            std::strerror(errno)));
  }
  data_ = reinterpret_cast<const double*>(static_cast<const char*>(map_) + (offset - start));
}

SpillFile::View::~View() {
  if (map_ != nullptr) {
    ::munmap(map_, length_);
  }
}

}  // namespace deflex
