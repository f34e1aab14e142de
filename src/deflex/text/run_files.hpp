// The files one run of deflex reads and the files it writes, kept apart. While a RunFilesScope is
// alive (the command-line program holds one around each command), every input opened through
// input_file.hpp and every output prepared through output_file.hpp is recorded by device and
// inode, so "the same file" holds through symlinks, hard links and different spellings of a path;
// a file that is both an input and an output is refused (InputError, exit code 2) whichever of the
// two comes first, before the output is written. Outside a scope (the Python module, library use)
// nothing is recorded: a session that reads a file and later writes it is not one run.
#pragma once

#include <cstdint>
#include <string>

namespace deflex {

/// Records the inputs and outputs of one run until it is destroyed. Scopes do not nest: a second
/// scope while one is alive is a programming error (std::logic_error).
/// Thread safety: made and destroyed on one thread; while it lives, files may be opened on any
/// thread (the record is kept under a mutex: the case study writes from its worker threads).
class RunFilesScope {
 public:
  RunFilesScope();
  ~RunFilesScope();
  RunFilesScope(const RunFilesScope&) = delete;
  RunFilesScope& operator=(const RunFilesScope&) = delete;
};

/// A file identity: device and inode.
struct FileId {
  std::uint64_t device = 0;
  std::uint64_t inode = 0;
  friend bool operator==(const FileId& a, const FileId& b) { return a.device == b.device && a.inode == b.inode; }
  friend bool operator!=(const FileId& a, const FileId& b) { return !(a == b); }
};

/// Notes an input file; throws InputError naming both when this run writes it.
void record_input_file(const FileId& id, const std::string& path);

/// Notes an output file that exists already (`what` names it: "option -o"); throws InputError naming
/// both when this run reads it or another output (another `what`) is the same file. The same output
/// written again (a fault dump, rewritten at each fault episode) is not refused.
void record_output_file(const FileId& id, const std::string& path, const std::string& what);

}  // namespace deflex
