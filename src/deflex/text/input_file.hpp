// Opening the files deflex reads. Every reader (robot, URDF, configuration, program and CSV files)
// opens its file here, so the rules are the same everywhere:
// - regular files only: a FIFO, a device (/dev/zero, /dev/stdin), a folder or a socket is refused
//   naming it. The file is opened with O_NONBLOCK and looked at with fstat before a byte is read, so
//   a FIFO without a writer never blocks deflex, and a symlink to /dev/zero is the device it names;
// - a size limit per kind of file, checked against the file's size before reading and again while
//   reading (a file that grows past it is refused too), so no input fills the memory;
// - a file a command is about to write is never also read (run_files.hpp).
// The limits are listed in docs/robot-file.md ("Input files") and the README.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

namespace deflex {

/// The kinds of file deflex reads, each with its own size limit.
enum class InputKind {
  kRobotFile,  ///< deflex robot YAML
  kUrdf,       ///< URDF
  kConfig,     ///< sensor and case YAML
  kProgram,    ///< RAPID module, KRL .src and .dat
  kCsvTable,   ///< a CSV file read whole (tracker, wrench table, payload poses, trajectories)
  kCsvStream,  ///< a CSV file streamed a row at a time (measurements, pose paths)
  kToolpath,   ///< a CAM toolpath (G-code, APT/CL data) streamed a line at a time
};

struct InputKindInfo {
  std::string_view what;    ///< "robot file", for messages
  std::uint64_t max_bytes;  ///< files larger than this are refused before reading
};

/// The name and the size limit of a kind of file.
[[nodiscard]] const InputKindInfo& input_kind_info(InputKind kind);

/// An input file opened for reading: a regular file within its kind's size limit. Throws DataError
/// "PATH: ..." when the file cannot be opened, is not a regular file (naming what it is), is larger
/// than the limit, or is a file this run writes (InputError, see run_files.hpp).
/// Thread safety: one thread at a time (each read moves its position); files opened on different
/// threads are independent.
class InputFile {
 public:
  /// `updated_as`: the file is read to be rewritten whole by this run's output of that name (a row
  /// added to a poses CSV); it is then recorded as that output, not as an input, so the output may
  /// replace it while any other use of it as an input or output is still refused.
  InputFile(const std::string& path, InputKind kind, const std::string& updated_as = "");
  ~InputFile();
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  [[nodiscard]] const std::string& path() const { return path_; }
  [[nodiscard]] std::uint64_t size() const { return size_; }

  /// The whole content (at most the kind's limit: a file that grew past it is refused).
  [[nodiscard]] std::string read_all();

  /// Reads up to `n` bytes into `buffer`; 0 at the end. Throws DataError on a read error or when the
  /// bytes read pass the kind's limit.
  std::size_t read(char* buffer, std::size_t n);

 private:
  std::string path_;
  InputKind kind_;
  int fd_ = -1;
  std::uint64_t size_ = 0;
  std::uint64_t read_ = 0;
};

/// The whole text of a file of `kind` (InputFile's rules); a leading UTF-8 byte order mark is dropped.
[[nodiscard]] std::string read_input_file(const std::string& path, InputKind kind);
/// The same, for a file this run rewrites whole as its output `what` (InputFile's `updated_as`).
[[nodiscard]] std::string read_file_to_update(const std::string& path, InputKind kind, const std::string& what);

}  // namespace deflex
