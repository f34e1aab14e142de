// Input files: regular files within their kind's size limit, opened without blocking.
#include "deflex/text/input_file.hpp"

#include <filesystem>

#include <cerrno>
#include <cstring>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"
#include "deflex/text/run_files.hpp"

namespace deflex {
namespace {

constexpr std::uint64_t kMiB = std::uint64_t{1} << 20;

/// What a file that is not a regular file is, for the message.
const char* kind_of_file(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory (a folder)";
  if (S_ISFIFO(mode)) return "a FIFO (a named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

[[noreturn]] void refuse(const std::string& path, const std::string& what) {
  throw DataError(fmt::format("{}: {}", path, what));
}

void check_stat(const std::string& path, const InputKindInfo& info, const struct stat& st) {
  if (!S_ISREG(st.st_mode)) {
    refuse(path, fmt::format("is {}, not a regular file: deflex reads the {} from a regular file",
                             kind_of_file(st.st_mode), info.what));
  }
  if (static_cast<std::uint64_t>(st.st_size) > info.max_bytes) {
    refuse(path, fmt::format("the {} is {} bytes; deflex reads a {} of up to {} bytes ({} MiB)", info.what, st.st_size,
                             info.what, info.max_bytes, info.max_bytes / kMiB));
  }
}

}  // namespace

const InputKindInfo& input_kind_info(InputKind kind) {
  // Wide on purpose: each is many times the largest such file a cell has (a robot file is some
  // kilobytes, a CAM-generated RAPID module of 500,000 targets some 60 MB), small enough that
  // reading one never exhausts the memory of a small PC.
  static const InputKindInfo kRobot{"robot file", 16 * kMiB};
  static const InputKindInfo kUrdf{"URDF file", 64 * kMiB};
  static const InputKindInfo kConfig{"configuration file", 16 * kMiB};
  static const InputKindInfo kProgram{"robot program", 64 * kMiB};
  static const InputKindInfo kTable{"data file", 1024 * kMiB};
  static const InputKindInfo kStream{"data file", 16384 * kMiB};  // streamed: memory is not the bound
  // Streamed too; a CAM program of ten million blocks is some 300 MB.
  static const InputKindInfo kToolpath{"toolpath", 4096 * kMiB};
  switch (kind) {
    case InputKind::kRobotFile:
      return kRobot;
    case InputKind::kUrdf:
      return kUrdf;
    case InputKind::kConfig:
      return kConfig;
    case InputKind::kProgram:
      return kProgram;
    case InputKind::kCsvTable:
      return kTable;
    case InputKind::kCsvStream:
      return kStream;
    case InputKind::kToolpath:
      return kToolpath;
  }
  return kConfig;
}

InputFile::InputFile(const std::string& path, InputKind kind, const std::string& updated_as)
    : path_(path), kind_(kind) {
  const InputKindInfo& info = input_kind_info(kind);
  if (path.empty()) {
    refuse("<empty path>", fmt::format("no file name given for the {}", info.what));
  }
  // stat first: a device is never opened (opening some has side effects), a FIFO never waited on.
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    const int err = errno;
    if (err == ENOENT) {
      // Say which part is missing: the file, or a folder on its way.
      const std::filesystem::path parent = std::filesystem::path(path).parent_path();
      std::error_code ec;
      if (!parent.empty() && !std::filesystem::is_directory(parent, ec)) {
        refuse(path, fmt::format("the {} does not exist: there is no folder '{}'", info.what, parent.string()));
      }
      refuse(path, fmt::format("the {} does not exist", info.what));
    }
    refuse(path, fmt::format("cannot read the {}: {}", info.what, std::strerror(err)));
  }
  check_stat(path, info, st);
  fd_ = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd_ < 0) {
    refuse(path, fmt::format("cannot read the {}: {}", info.what, std::strerror(errno)));
  }
  try {
    // What was opened, not what the path named a moment before.
    if (::fstat(fd_, &st) != 0) {
      refuse(path, fmt::format("cannot read the {}: {}", info.what, std::strerror(errno)));
    }
    check_stat(path, info, st);
    ::fcntl(fd_, F_SETFL, ::fcntl(fd_, F_GETFL) & ~O_NONBLOCK);
    size_ = static_cast<std::uint64_t>(st.st_size);
    const FileId id{static_cast<std::uint64_t>(st.st_dev), static_cast<std::uint64_t>(st.st_ino)};
    if (updated_as.empty()) {
      record_input_file(id, path);
    } else {
      record_output_file(id, path, updated_as);
    }
  } catch (...) {
    ::close(fd_);
    throw;
  }
}

InputFile::~InputFile() {
  if (fd_ >= 0) {
    ::close(fd_);
  }
}

std::size_t InputFile::read(char* buffer, std::size_t n) {
  while (true) {
    const ssize_t got = ::read(fd_, buffer, n);
    if (got < 0 && errno == EINTR) {
      continue;
    }
    if (got < 0) {
      throw DataError(
          fmt::format("{}: reading the {} failed: {}", path_, input_kind_info(kind_).what, std::strerror(errno)));
    }
    read_ += static_cast<std::uint64_t>(got);
    if (read_ > input_kind_info(kind_).max_bytes) {
      throw DataError(fmt::format("{}: the {} grew past {} bytes while it was read", path_, input_kind_info(kind_).what,
                                  input_kind_info(kind_).max_bytes));
    }
    return static_cast<std::size_t>(got);
  }
}

std::string InputFile::read_all() {
  std::string text;
  text.resize(static_cast<std::size_t>(size_) + 1);  // one more: a file that grew is noticed
  std::size_t at = 0;
  while (true) {
    if (at == text.size()) {
      text.resize(text.size() + 65536);
    }
    const std::size_t got = read(text.data() + at, text.size() - at);
    if (got == 0) {
      break;
    }
    at += got;
  }
  text.resize(at);
  return text;
}

namespace {
std::string read_text(InputFile& file) {
  std::string text = file.read_all();
  // A UTF-8 byte order mark (Excel and some editors write one) is not part of the content.
  if (text.rfind("\xEF\xBB\xBF", 0) == 0) {
    text.erase(0, 3);
  }
  return text;
}
}  // namespace

std::string read_input_file(const std::string& path, InputKind kind) {
  InputFile file(path, kind);
  return read_text(file);
}

std::string read_file_to_update(const std::string& path, InputKind kind, const std::string& what) {
  InputFile file(path, kind, what);
  return read_text(file);
}

}  // namespace deflex
