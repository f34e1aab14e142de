// A scratch file for numbers too many to hold in memory: made in the temporary directory (TMPDIR,
// else /tmp) and unlinked at once, so it never outlives the process, even on a crash; written and
// read back by offset through the caller's own buffers (plain read/write, not a memory map, so what
// is on disk never counts as the process's memory).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace deflex {

class SpillFile {
 public:
  /// `what` names the data in messages ("identification rows").
  explicit SpillFile(std::string what);
  ~SpillFile();
  SpillFile(const SpillFile&) = delete;
  SpillFile& operator=(const SpillFile&) = delete;

  /// Appends `count` doubles; returns their offset (bytes). Throws Error naming the directory when
  /// the file cannot be made or the disk is full.
  std::uint64_t append(const double* values, std::size_t count);
  /// Overwrites `count` doubles at `offset` (from append).
  void write_at(std::uint64_t offset, const double* values, std::size_t count);
  /// Reads `count` doubles at `offset` into `values`.
  void read_at(std::uint64_t offset, double* values, std::size_t count) const;
  [[nodiscard]] std::uint64_t bytes() const { return end_; }

 private:
  void open();

  std::string what_;
  std::string directory_;
  int fd_ = -1;
  std::uint64_t end_ = 0;
};

}  // namespace deflex
