// Output files: a temporary file beside the target, renamed into place on commit; streams for
// devices and FIFOs; transactions that put back what they renamed when a later rename fails.
#include "deflex/text/output_file.hpp"

#include <atomic>
#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include <csignal>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"
#include "deflex/text/run_files.hpp"

namespace deflex {
namespace {

constexpr std::size_t kBufferBytes = std::size_t{1} << 16;

std::string parent_of(const std::string& path) {
  const auto slash = path.find_last_of('/');
  if (slash == std::string::npos) {
    return ".";
  }
  return slash == 0 ? "/" : path.substr(0, slash);
}

std::string base_of(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

/// A name beside `target` that no other file has: ".NAME.deflex-TAG-PID-N".
std::string sibling_name(const std::string& dir, const std::string& base, const char* tag) {
  static std::atomic<unsigned> counter{0};
  // Short enough that the name fits NAME_MAX whatever the target's name.
  return fmt::format("{}/.{}.deflex-{}-{}-{}", dir, base.substr(0, 100), tag, ::getpid(), counter++);
}

void sync_folder(const std::string& dir) noexcept {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd >= 0) {
    (void)::fsync(fd);  // best effort: some file systems cannot sync a folder
    ::close(fd);
  }
}

std::atomic<unsigned> g_closed_streams{0};  // bit fd: standard stream fd was closed at start

// The temporary files alive now, for the signal handler to remove: fixed slots, so the handler
// touches no allocator, and unlink() is async-signal-safe. A file without a slot (more than 256
// outputs at once) is still removed on every other way out.
struct TemporarySlot {
  std::atomic<bool> claimed{false};
  std::atomic<bool> live{false};
  std::atomic<bool> folder{false};  // a folder this process created for an output: rmdir, not unlink
  char path[PATH_MAX] = {};
};
TemporarySlot g_temporaries[256];

int claim_slot(const std::string& path, bool folder = false) {
  if (path.size() >= PATH_MAX) {
    return -1;
  }
  for (int i = 0; i < 256; ++i) {
    bool free = false;
    if (g_temporaries[i].claimed.compare_exchange_strong(free, true)) {
      std::memcpy(g_temporaries[i].path, path.c_str(), path.size() + 1);
      g_temporaries[i].folder.store(folder, std::memory_order_relaxed);
      g_temporaries[i].live.store(true, std::memory_order_release);
      return i;
    }
  }
  return -1;
}

void release_slot(int& slot) noexcept {
  if (slot >= 0) {
    g_temporaries[slot].live.store(false, std::memory_order_release);
    g_temporaries[slot].claimed.store(false, std::memory_order_release);
    slot = -1;
  }
}

extern "C" void remove_temporaries_and_die(int signal_number) {
  for (TemporarySlot& t : g_temporaries) {
    if (t.live.load(std::memory_order_acquire) && !t.folder.load(std::memory_order_relaxed)) {
      ::unlink(t.path);
    }
  }
  // Then the folders made for them, emptied now; a nested one first, whatever their slots' order
  // (rmdir of a folder that is not empty fails and leaves it, as it must).
  for (int pass = 0; pass < 8; ++pass) {
    for (TemporarySlot& t : g_temporaries) {
      if (t.live.load(std::memory_order_acquire) && t.folder.load(std::memory_order_relaxed)) {
        ::rmdir(t.path);
      }
    }
  }
  ::signal(signal_number, SIG_DFL);
  ::raise(signal_number);
}

const char* special_kind(mode_t mode) {
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file, character device or FIFO";
}

// The first folder on the way to `path` that is a file (what ENOTDIR means).
std::string file_on_the_way(const std::string& path) {
  std::string p = parent_of(path);
  std::string found = p;
  for (struct stat st{}; p != parent_of(p); p = parent_of(p)) {
    if (::stat(p.c_str(), &st) == 0) {
      if (!S_ISDIR(st.st_mode)) found = p;
      break;
    }
  }
  return found;
}

// The folders `made` for an output: removed, deepest first, unless `keep` (the output is in place and
// they are the user's now). rmdir leaves a folder that holds anything (another program's file).
void remove_folders(std::vector<std::pair<std::string, int>>& made, bool keep) noexcept {
  for (auto it = made.rbegin(); it != made.rend(); ++it) {
    if (!keep) {
      ::rmdir(it->first.c_str());
    }
    release_slot(it->second);
  }
  made.clear();
}

// The folders on the way to `dir` that do not exist, made shallowest first, each with its slot in the
// signal handler's table. A file where a folder should be (`-o notes.txt/x.csv`) is named; a folder
// another process makes meanwhile is not ours. `name` starts the messages ("option -o 'a/b.csv'").
std::vector<std::pair<std::string, int>> make_folders(const std::string& dir, const std::string& name) {
  std::vector<std::string> missing;
  std::string p = dir;
  struct stat st {};
  while (::stat(p.c_str(), &st) != 0) {
    if (errno == ENOTDIR) {
      throw InputError(fmt::format("{}: '{}' is not a directory", name, file_on_the_way(p)));
    }
    if (errno != ENOENT) {
      throw InputError(fmt::format("{}: the folder '{}': {}", name, p, std::strerror(errno)));
    }
    missing.push_back(p);
    const std::string up = parent_of(p);
    if (up == p) break;
    p = up;
  }
  if (!S_ISDIR(st.st_mode)) {
    throw InputError(fmt::format("{}: '{}' is not a directory", name, p));
  }
  std::vector<std::pair<std::string, int>> made;
  for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
    if (::mkdir(it->c_str(), 0777) == 0) {
      made.emplace_back(*it, claim_slot(*it, true));
    } else if (errno != EEXIST) {
      const int err = errno;
      remove_folders(made, false);
      throw InputError(fmt::format("{}: cannot create the folder '{}': {}", name, *it, std::strerror(err)));
    }
  }
  return made;
}

}  // namespace

OutputFile::OutputFile(std::string path, std::string what) : path_(std::move(path)), what_(std::move(what)) {
  const std::string name = fmt::format("{} '{}'", what_, path_);
  if (path_.empty()) {
    throw InputError(fmt::format("{}: no file name given", what_));
  }
  struct stat st {};
  if (::stat(path_.c_str(), &st) != 0) {
    const int err = errno;
    struct stat link {};
    if (::lstat(path_.c_str(), &link) == 0 && S_ISLNK(link.st_mode)) {
      throw InputError(
          fmt::format("{}: a symbolic link to nothing ({}): deflex writes through a link only onto an "
                      "existing file",
                      name, std::strerror(err)));
    }
    if (err == ENOTDIR) {
      throw InputError(fmt::format("{}: '{}' is not a directory", name, file_on_the_way(path_)));
    }
    if (err != ENOENT) {
      throw InputError(fmt::format("{}: cannot be written: {}", name, std::strerror(err)));
    }
    create_temporary(path_, false, 0);
    return;
  }
  if (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode)) {
    for (const int fd : {STDOUT_FILENO, STDERR_FILENO}) {
      struct stat s {};
      if ((g_closed_streams & (1U << fd)) != 0 && ::fstat(fd, &s) == 0 && s.st_dev == st.st_dev &&
          s.st_ino == st.st_ino) {
        throw InputError(
            fmt::format("{}: the program's {} is closed", name, fd == STDOUT_FILENO ? "stdout" : "stderr"));
      }
    }
    open_stream(-1, path_);
    return;
  }
  if (S_ISDIR(st.st_mode)) {
    throw InputError(fmt::format("{}: is a directory (a folder): give a file name", name));
  }
  if (!S_ISREG(st.st_mode)) {
    throw InputError(fmt::format("{}: is {}: deflex writes regular files, character devices and FIFOs only", name,
                                 special_kind(st.st_mode)));
  }
  // A regular file that is this process's stdout or stderr (`-o /dev/stdout > file`): written to
  // that stream, so the shell's redirection keeps everything.
  for (const int fd : {STDOUT_FILENO, STDERR_FILENO}) {
    struct stat s {};
    if (::fstat(fd, &s) == 0 && s.st_dev == st.st_dev && s.st_ino == st.st_ino) {
      open_stream(fd, path_);
      return;
    }
  }
  record_output_file({static_cast<std::uint64_t>(st.st_dev), static_cast<std::uint64_t>(st.st_ino)}, path_, what_);
  // Through symbolic links to the file they name, replaced in its own folder.
  char resolved[PATH_MAX];
  if (::realpath(path_.c_str(), resolved) == nullptr) {
    throw InputError(fmt::format("{}: cannot be written: {}", name, std::strerror(errno)));
  }
  create_temporary(resolved, true, st.st_mode & 07777);
}

void OutputFile::open_stream(int fd_to_dup, const std::string& resolved) {
  stream_ = true;
  target_ = resolved;
  if (fd_to_dup >= 0) {
    fd_ = ::fcntl(fd_to_dup, F_DUPFD_CLOEXEC, 3);
  } else {
    // Never O_TRUNC or O_CREAT: a device is written as it is. O_NONBLOCK: a FIFO nobody reads
    // fails at once (ENXIO) instead of blocking.
    fd_ = ::open(path_.c_str(), O_WRONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  }
  if (fd_ < 0) {
    const int err = errno;
    throw InputError(fmt::format("{} '{}': cannot be written: {}", what_, path_,
                                 err == ENXIO ? "a FIFO that no process reads" : std::strerror(err)));
  }
  ::fcntl(fd_, F_SETFL, ::fcntl(fd_, F_GETFL) & ~O_NONBLOCK);
}

void OutputFile::create_temporary(const std::string& target_path, bool existed, unsigned mode) {
  const std::string base = base_of(target_path);
  if (base.empty() || base == "." || base == "..") {
    throw InputError(fmt::format("{} '{}': names a folder: give a file name", what_, path_));
  }
  const std::string dir = parent_of(target_path);
  char resolved_dir[PATH_MAX];
  if (::realpath(dir.c_str(), resolved_dir) == nullptr && errno == ENOENT) {
    create_missing_folders(dir);
  }
  if (::realpath(dir.c_str(), resolved_dir) == nullptr) {
    if (errno == ENOTDIR) {
      throw InputError(fmt::format("{} '{}': '{}' is not a directory", what_, path_, file_on_the_way(dir + "/x")));
    }
    throw InputError(fmt::format("{} '{}': the folder '{}': {}", what_, path_, dir, std::strerror(errno)));
  }
  const std::string folder = resolved_dir;
  struct stat folder_stat {};
  if (::stat(folder.c_str(), &folder_stat) == 0 && !S_ISDIR(folder_stat.st_mode)) {
    throw InputError(fmt::format("{} '{}': '{}' is not a directory", what_, path_, dir));
  }
  target_ = (folder == "/" ? "" : folder) + "/" + base;
  existed_ = existed;
  for (int attempt = 0; fd_ < 0; ++attempt) {
    temp_ = sibling_name(folder == "/" ? "" : folder, base, "tmp");
    // 0666 less the umask, as any new file; a replaced file keeps its permissions.
    fd_ = ::open(temp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOCTTY, 0666);
    if (fd_ < 0 && (errno != EEXIST || attempt > 100)) {
      const int err = errno;
      temp_.clear();
      throw InputError(
          fmt::format("{} '{}': cannot create a file in the folder '{}': {}", what_, path_, dir, std::strerror(err)));
    }
  }
  slot_ = claim_slot(temp_);
  if (existed) {
    (void)::fchmod(fd_, static_cast<mode_t>(mode));  // best effort: the owner may differ
  }
}

void OutputFile::create_missing_folders(const std::string& dir) {
  created_folders_ = make_folders(dir, fmt::format("{} '{}'", what_, path_));
}

OutputFile::~OutputFile() { discard(); }

void OutputFile::discard() noexcept {
  if (fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
  }
  if (!stream_ && !committed_ && !temp_.empty()) {
    ::unlink(temp_.c_str());  // our own temporary file, never the target
    temp_.clear();
  }
  release_slot(slot_);
  remove_folders(created_folders_, committed_);  // kept once the file is in place
}

void OutputFile::flush_buffer() {
  std::size_t at = 0;
  while (at < buffer_.size()) {
    const ssize_t n = ::write(fd_, buffer_.data() + at, buffer_.size() - at);
    if (n < 0 && errno == EINTR) {
      continue;
    }
    if (n <= 0) {
      const int err = n < 0 ? errno : EIO;
      buffer_.clear();
      throw OutputError(fmt::format("{} '{}': writing failed: {}", what_, path_, std::strerror(err)));
    }
    at += static_cast<std::size_t>(n);
  }
  buffer_.clear();
}

void OutputFile::write(std::string_view bytes) {
  if (finished_ || fd_ < 0) {
    throw std::logic_error("OutputFile::write after finish() or a failure: " + path_);
  }
  buffer_.append(bytes);
  if (buffer_.size() >= kBufferBytes) {
    flush_buffer();
  }
}

void OutputFile::finish() {
  if (finished_) {
    return;
  }
  if (fd_ < 0) {
    throw std::logic_error("OutputFile::finish after a failure: " + path_);
  }
  flush_buffer();
  if (!stream_ && ::fsync(fd_) != 0) {
    throw OutputError(fmt::format("{} '{}': writing failed: {}", what_, path_, std::strerror(errno)));
  }
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0 && errno != EINTR) {
    throw OutputError(fmt::format("{} '{}': writing failed: {}", what_, path_, std::strerror(errno)));
  }
  finished_ = true;
}

void OutputFile::rename_into_place() {
  if (::rename(temp_.c_str(), target_.c_str()) != 0) {
    throw OutputError(
        fmt::format("{} '{}': the written file could not be put in place ({})", what_, path_, std::strerror(errno)));
  }
  committed_ = true;
  temp_.clear();
  release_slot(slot_);
}

void OutputFile::commit() {
  finish();
  if (!stream_) {
    rename_into_place();
    sync_folder(parent_of(target_));
  }
  committed_ = true;
}

std::string OutputFile::keep_previous() const {
  if (stream_ || !existed_) {
    return {};
  }
  for (int attempt = 0; attempt < 100; ++attempt) {
    std::string kept = sibling_name(parent_of(target_), base_of(target_), "old");
    if (::link(target_.c_str(), kept.c_str()) == 0) {
      return kept;
    }
    if (errno != EEXIST) {
      break;  // a file system without hard links: this file cannot be put back
    }
  }
  return {};
}

std::string OutputFile::put_back(const std::string& kept) noexcept {
  if (stream_ || !committed_) {
    return {};
  }
  committed_ = false;
  if (!kept.empty() && ::rename(kept.c_str(), target_.c_str()) == 0) {
    return {};  // the previous file is back under its name
  }
  if (!existed_ && ::unlink(target_.c_str()) == 0) {
    return {};  // new in this run: removed again
  }
  return path_;
}

OutputFile& OutputTransaction::add(const std::string& path, const std::string& what) {
  auto file = std::make_unique<OutputFile>(path, what);
  for (const auto& other : files_) {
    if (!file->stream_ && !other->stream_ && other->target_ == file->target_) {
      throw InputError(fmt::format("{} '{}' and {} '{}' are the same file: give each output its own name", other->what_,
                                   other->path_, file->what_, file->path_));
    }
  }
  files_.push_back(std::move(file));
  return *files_.back();
}

void OutputTransaction::commit() {
  for (const auto& f : files_) {
    f->finish();  // every byte of every output on disk before the first appears
  }
  std::vector<std::string> kept(files_.size());
  std::size_t i = 0;
  try {
    for (; i < files_.size(); ++i) {
      OutputFile& f = *files_[i];
      if (f.stream_) {
        f.committed_ = true;
        continue;
      }
      kept[i] = f.keep_previous();
      f.rename_into_place();
    }
  } catch (const OutputError& e) {
    std::string lost;
    for (std::size_t k = i; k-- > 0;) {
      const std::string l = files_[k]->put_back(kept[k]);
      lost += l.empty() ? "" : (lost.empty() ? "" : ", ") + l;
    }
    for (const std::string& k : kept) {
      if (!k.empty()) {
        ::unlink(k.c_str());  // the hard links made above (gone already when put back)
      }
    }
    throw OutputError(lost.empty() ? fmt::format("{}; no output of this command was put in place", e.what())
                                   : fmt::format("{}; already replaced and not restorable: {}", e.what(), lost));
  }
  for (std::size_t k = 0; k < files_.size(); ++k) {
    if (!kept[k].empty()) {
      ::unlink(kept[k].c_str());
    }
    if (!files_[k]->stream_) {
      sync_folder(parent_of(files_[k]->target_));
    }
  }
}

OutputTransaction::~OutputTransaction() {
  // The last added first: a folder made for the first file may hold the later ones' temporary files.
  while (!files_.empty()) {
    files_.pop_back();
  }
}

OutputFolder::OutputFolder(std::string path, const std::string& what) : path_(std::move(path)) {
  if (path_.empty()) {
    throw InputError(fmt::format("{}: no folder name given", what));
  }
  created_ = make_folders(path_, fmt::format("{} '{}'", what, path_));
}

OutputFolder::~OutputFolder() { remove_folders(created_, kept_); }

void OutputFolder::keep() {
  kept_ = true;
  remove_folders(created_, true);
}

void mark_standard_stream_closed(int fd) { g_closed_streams |= 1U << fd; }

void remove_temporaries_on_signals() {
  for (const int signal_number : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction before {};
    ::sigaction(signal_number, nullptr, &before);
    if (before.sa_handler == SIG_IGN) {
      continue;  // ignored by whoever started us (nohup, a background job): it stays ignored
    }
    struct sigaction action {};
    action.sa_handler = remove_temporaries_and_die;
    sigemptyset(&action.sa_mask);
    ::sigaction(signal_number, &action, nullptr);
  }
}

void write_output_file(const std::string& path, std::string_view text, const std::string& what) {
  OutputFile file(path, what);
  file.write(text);
  file.commit();
}

}  // namespace deflex
