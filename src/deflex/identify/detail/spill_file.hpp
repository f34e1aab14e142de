// A scratch file for numbers too many to hold in memory: made in the temporary directory (TMPDIR,
// else /tmp) and unlinked at once, so it never outlives the process, even on a crash; written and
// read back by offset through the caller's own buffers, or seen in place a piece at a time through a
// read-only map that ends with the piece (what is on disk never counts as the process's memory beyond
// the piece seen).
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

  /// `count` doubles at `offset` seen in place (a read-only map of those pages, unmapped when the view
  /// ends): no copy, unlike read_at, which costs the kernel a copy of every byte (perf: 8 % of a
  /// million-row identification). Throws Error when the map cannot be made.
  class View {
   public:
    View(const SpillFile& file, std::uint64_t offset, std::size_t count);
    ~View();
    View(const View&) = delete;
    View& operator=(const View&) = delete;
    [[nodiscard]] const double* data() const { return data_; }

   private:
    void* map_ = nullptr;
    std::size_t length_ = 0;
    const double* data_ = nullptr;
  };

 private:
  void open();

  std::string what_;
  std::string directory_;
  int fd_ = -1;
  std::uint64_t end_ = 0;
};

}  // namespace deflex
