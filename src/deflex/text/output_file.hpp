// Writing the files deflex produces so that no run ever destroys data. Every output of every
// command and of the Python module is written here:
// - into a new temporary file beside the target (".NAME.deflex-tmp-PID-N" in the target's folder),
//   every write checked, flushed and fsync'd, and renamed onto the target only when the whole
//   command has succeeded; several outputs of one command (OutputTransaction) appear all or none;
// - deflex never deletes or truncates a path it did not create: on any failure only its own
//   temporary files are removed, and the target is left as it was, byte for byte, same inode;
// - a symbolic link is written through: the file it points to is replaced in that file's own
//   folder (the link stays a link); a link to nothing is refused;
// - a character device or a FIFO (/dev/null, /dev/stdout, a pipe) is written in place as a stream,
//   never renamed, truncated or removed; what was written to a stream cannot be taken back;
// - a folder, a block device or a socket is refused; a missing folder on the way is created (every
//   command alike: `-o out/run1/x.csv` needs no mkdir first), and removed again, when still empty,
//   if the output is not committed: deflex removes only folders it created itself;
// - a file the same run reads is refused before it is written (run_files.hpp);
// - interrupted by a signal, a program that called remove_temporaries_on_signals() removes the
//   temporary files it was writing.
// Problems with the path itself are InputError (exit code 2), failed writes OutputError (exit
// code 1), both naming the file.
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace deflex {

/// One output file. Nothing appears at the path until commit() (or the transaction's commit());
/// destroyed uncommitted, it removes its temporary file and leaves the target untouched.
/// Thread safety: one thread at a time; outputs on different threads are independent (the signal
/// handler's table of temporary files is atomic).
class OutputFile {
 public:
  /// Prepares `path` (creates the temporary file, or opens a stream). `what` names the output in
  /// messages ("option -o"). Throws InputError when the path cannot be an output (see above).
  explicit OutputFile(std::string path, std::string what = "output");
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  /// Appends bytes (buffered). Throws OutputError naming the file when a write fails.
  void write(std::string_view bytes);
  /// Everything written reaches the file: flushed, fsync'd and closed. Throws OutputError.
  void finish();
  /// finish(), then the file renamed onto its target (a stream: finish() only). Throws OutputError.
  void commit();

  [[nodiscard]] const std::string& path() const { return path_; }
  [[nodiscard]] const std::string& what() const { return what_; }
  /// A device or FIFO written in place.
  [[nodiscard]] bool is_stream() const { return stream_; }

 private:
  friend class OutputTransaction;
  void open_stream(int fd_to_dup, const std::string& resolved);
  void create_temporary(const std::string& target_path, bool existed, unsigned mode);
  void create_missing_folders(const std::string& dir);
  void flush_buffer();
  void rename_into_place();
  [[nodiscard]] std::string keep_previous() const;  // a hard link to the file being replaced, or ""
  [[nodiscard]] std::string put_back(const std::string& kept) noexcept;  // undoes rename_into_place()
  void discard() noexcept;

  std::string path_;
  std::string what_;
  std::string target_;  // the file replaced: the path with its links resolved
  std::string temp_;
  int fd_ = -1;
  bool stream_ = false;
  bool existed_ = false;
  bool finished_ = false;
  bool committed_ = false;
  int slot_ = -1;  // in the table the signal handler removes temporary files from
  std::vector<std::pair<std::string, int>> created_folders_;  // made for this output (shallowest first), slot
  std::string buffer_;
};

/// The outputs of one command, committed together: every file is finished (written and fsync'd)
/// before the first is renamed into place, and a rename that fails puts back the files already
/// renamed (the previous file from a hard link kept for the purpose; a file new in this run is
/// removed again), so the outputs appear all or none.
/// Thread safety: one thread at a time, its files included.
class OutputTransaction {
 public:
  OutputTransaction() = default;
  ~OutputTransaction();
  OutputTransaction(const OutputTransaction&) = delete;
  OutputTransaction& operator=(const OutputTransaction&) = delete;

  /// A new output of the transaction (the OutputFile constructor's rules); a second output naming
  /// the same file is refused (InputError).
  OutputFile& add(const std::string& path, const std::string& what);
  /// Finishes every file, then renames each into place. Throws OutputError; nothing is in place then.
  void commit();

  [[nodiscard]] std::size_t size() const { return files_.size(); }

 private:
  std::vector<std::unique_ptr<OutputFile>> files_;
};

/// A folder an option names for several outputs (`case-study --out DIR`): made, with any missing folder
/// on its way, as OutputFile makes a file's; removed again (the ones made here, when empty) unless
/// keep() is called once the outputs are in place. Throws InputError naming `what` when a file stands
/// where a folder should, or a folder cannot be made.
/// Thread safety: one thread at a time.
class OutputFolder {
 public:
  OutputFolder(std::string path, const std::string& what);
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;
  /// The outputs are in place: the folders stay.
  void keep();
  [[nodiscard]] const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::vector<std::pair<std::string, int>> created_;  // shallowest first, with their signal-table slots
  bool kept_ = false;
};

/// Tells the output layer that standard stream `fd` (1 or 2) was closed when the program started and
/// now holds a placeholder that fails every write: an output naming it (/dev/stdout) is refused then.
void mark_standard_stream_closed(int fd);

/// Installs handlers for SIGINT, SIGTERM and SIGHUP that remove the temporary files of the outputs
/// being written, then end the process as the signal would: an interrupted run leaves no trace in
/// the outputs' folders. For programs (the command-line program calls it); a library leaves the
/// signals to its host.
void remove_temporaries_on_signals();

/// `text` as the whole content of `path`, committed at once (an OutputFile of its own).
void write_output_file(const std::string& path, std::string_view text, const std::string& what = "output");

}  // namespace deflex
