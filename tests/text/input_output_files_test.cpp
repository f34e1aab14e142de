// The file layer every reader and writer goes through: inputs are regular files within their
// kind's size limit (a FIFO, a device, a folder refused at once, without blocking), outputs appear
// whole on commit or not at all, never destroy the file they replace or the link they write
// through, never delete or rename a device, and a file one run reads is never the file it writes.
// Every check looks at the file system itself (contents, inodes, what else is in the folder).
#include <chrono>
#include <filesystem>
#include <fstream>
#include <set>
#include <thread>

#include <csignal>

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "deflex/text/errors.hpp"
#include "deflex/text/input_file.hpp"
#include "deflex/text/output_file.hpp"
#include "deflex/text/run_files.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

namespace fs = std::filesystem;
using test::error_of;

struct Scratch {
  fs::path dir;
  Scratch() {
    dir = fs::temp_directory_path() / ("deflex_files_" + std::to_string(::getpid()) + "_" +
                                       ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  ~Scratch() { fs::remove_all(dir); }
  [[nodiscard]] std::string at(const std::string& name) const { return (dir / name).string(); }
  void write(const std::string& name, const std::string& text) const {
    std::ofstream(dir / name, std::ios::binary) << text;
  }
  /// The names in the folder: nothing else (no temporary file) may be left behind.
  [[nodiscard]] std::set<std::string> names() const {
    std::set<std::string> out;
    for (const auto& e : fs::directory_iterator(dir)) {
      out.insert(e.path().filename().string());
    }
    return out;
  }
};

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

ino_t inode_of(const std::string& path) {
  struct stat st {};
  EXPECT_EQ(::stat(path.c_str(), &st), 0) << path;
  return st.st_ino;
}

bool is_char_device(const char* path) {
  struct stat st {};
  return ::lstat(path, &st) == 0 && S_ISCHR(st.st_mode);
}

// --- inputs --------------------------------------------------------------------------------------

TEST(InputFile, ReadsARegularFileAndDropsAByteOrderMark) {
  const Scratch s;
  s.write("a.yaml", "\xEF\xBB\xBFname: x\n");
  EXPECT_EQ(read_input_file(s.at("a.yaml"), InputKind::kConfig), "name: x\n");
}

TEST(InputFile, RefusesFifosDevicesAndFoldersWithoutBlocking) {
  const Scratch s;
  ASSERT_EQ(::mkfifo(s.at("pipe.yaml").c_str(), 0600), 0);
  // No writer ever opens the FIFO: a blocking open or read would hang here (the test's timeout).
  const auto started = std::chrono::steady_clock::now();
  const std::string fifo = error_of([&] { (void)read_input_file(s.at("pipe.yaml"), InputKind::kRobotFile); });
  EXPECT_NE(fifo.find("is a FIFO"), std::string::npos) << fifo;
  EXPECT_NE(fifo.find(s.at("pipe.yaml")), std::string::npos) << fifo;
  EXPECT_LT(std::chrono::steady_clock::now() - started, std::chrono::seconds(5));
  EXPECT_NE(error_of([&] { (void)read_input_file("/dev/zero", InputKind::kProgram); }).find("character device"),
            std::string::npos);
  fs::create_symlink("/dev/zero", s.dir / "zero.mod");  // a link is the file it names
  EXPECT_NE(error_of([&] { (void)read_input_file(s.at("zero.mod"), InputKind::kProgram); }).find("character device"),
            std::string::npos);
  EXPECT_NE(error_of([&] { (void)read_input_file(s.dir.string(), InputKind::kCsvTable); }).find("directory"),
            std::string::npos);
  // A missing file, and a missing folder on its way, are said as such.
  EXPECT_NE(error_of([&] { (void)read_input_file(s.at("none.csv"), InputKind::kCsvTable); }).find("does not exist"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              (void)read_input_file(s.at("no-folder/none.csv"), InputKind::kCsvTable);
            }).find("does not exist: there is no folder"),
            std::string::npos);
}

TEST(InputFile, RefusesAFileOverItsKindsLimitBeforeReadingIt) {
  const Scratch s;
  // A sparse file one byte over the robot-file limit: refused from its size, nothing is read.
  const std::uint64_t limit = input_kind_info(InputKind::kRobotFile).max_bytes;
  EXPECT_EQ(limit, 16u << 20);
  s.write("big.yaml", "");
  fs::resize_file(s.dir / "big.yaml", limit + 1);
  const std::string msg = error_of([&] { (void)read_input_file(s.at("big.yaml"), InputKind::kRobotFile); });
  EXPECT_NE(msg.find("16777217 bytes"), std::string::npos) << msg;
  EXPECT_NE(msg.find("up to 16777216 bytes"), std::string::npos) << msg;
  // The same size is well inside a CSV table's limit.
  EXPECT_GT(input_kind_info(InputKind::kCsvTable).max_bytes, limit + 1);
}

// --- outputs -------------------------------------------------------------------------------------

TEST(OutputFile, AppearsOnlyWhenCommittedAndLeavesNothingBehindOtherwise) {
  const Scratch s;
  {
    OutputFile f(s.at("new.csv"), "option -o");
    f.write("a,b\n1,2\n");
    EXPECT_FALSE(fs::exists(s.at("new.csv")));  // written beside it, not yet in place
  }
  EXPECT_EQ(s.names(), std::set<std::string>{});  // dropped: its temporary file removed
  OutputFile f(s.at("new.csv"), "option -o");
  f.write("a,b\n1,2\n");
  f.commit();
  EXPECT_EQ(slurp(s.at("new.csv")), "a,b\n1,2\n");
  EXPECT_EQ(s.names(), std::set<std::string>{"new.csv"});
}

TEST(OutputFile, AFailedRunLeavesTheReplacedFileByteForByteWithItsInode) {
  const Scratch s;
  s.write("out.csv", "the user's data\n");
  ::chmod(s.at("out.csv").c_str(), 0640);
  const ino_t before = inode_of(s.at("out.csv"));
  {
    OutputFile f(s.at("out.csv"));
    f.write(std::string(200000, 'x'));  // past the buffer: bytes reached the temporary file
  }
  EXPECT_EQ(slurp(s.at("out.csv")), "the user's data\n");
  EXPECT_EQ(inode_of(s.at("out.csv")), before);
  EXPECT_EQ(s.names(), std::set<std::string>{"out.csv"});
  // Committed, the file is replaced whole and keeps its permissions.
  write_output_file(s.at("out.csv"), "new\n");
  EXPECT_EQ(slurp(s.at("out.csv")), "new\n");
  EXPECT_EQ(fs::status(s.at("out.csv")).permissions() & fs::perms::all,
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
}

TEST(OutputFile, WritesThroughASymbolicLinkAndKeepsTheLink) {
  const Scratch s;
  fs::create_directories(s.dir / "data");
  s.write("data/run42.csv", "old\n");
  fs::create_symlink("data/run42.csv", s.dir / "out.csv");
  {
    OutputFile f(s.at("out.csv"));
    f.write("half");
  }  // a failed run: neither the link nor the file behind it changes
  EXPECT_TRUE(fs::is_symlink(s.at("out.csv")));
  EXPECT_EQ(slurp(s.at("data/run42.csv")), "old\n");
  write_output_file(s.at("out.csv"), "new\n");
  EXPECT_TRUE(fs::is_symlink(s.at("out.csv")));
  EXPECT_EQ(fs::read_symlink(s.dir / "out.csv"), fs::path("data/run42.csv"));
  EXPECT_EQ(slurp(s.at("data/run42.csv")), "new\n");
  EXPECT_EQ(s.names(), (std::set<std::string>{"data", "out.csv"}));
  std::set<std::string> data;
  for (const auto& e : fs::directory_iterator(s.dir / "data")) data.insert(e.path().filename().string());
  EXPECT_EQ(data, std::set<std::string>{"run42.csv"});  // the temporary file was in the target's folder, and is gone
  // A link to nothing is refused, and left as it is.
  fs::create_symlink("nowhere.csv", s.dir / "dangling.csv");
  EXPECT_NE(error_of([&] { OutputFile f(s.at("dangling.csv"), "option -o"); }).find("symbolic link to nothing"),
            std::string::npos);
  EXPECT_TRUE(fs::is_symlink(s.at("dangling.csv")));
}

TEST(OutputFile, DevicesAreStreamsNeverRenamedOrRemoved) {
  {
    OutputFile null("/dev/null", "option -o");
    EXPECT_TRUE(null.is_stream());
    null.write(std::string(100000, 'x'));
    null.commit();
  }
  EXPECT_TRUE(is_char_device("/dev/null"));
  // /dev/full fails every write: an OutputError naming it, and the device stays.
  const std::string msg = error_of([] {
    OutputFile full("/dev/full", "option -o");
    full.write(std::string(100000, 'x'));
    full.commit();
  });
  EXPECT_NE(msg.find("'/dev/full': writing failed"), std::string::npos) << msg;
  EXPECT_TRUE(is_char_device("/dev/full"));
  try {
    OutputFile full("/dev/full");
    full.write("x");
    full.commit();
    ADD_FAILURE() << "a write to /dev/full succeeded";
  } catch (const OutputError&) {
  }
  EXPECT_TRUE(is_char_device("/dev/full"));
}

TEST(OutputFile, RefusesFoldersFilesOnTheWayAndFifosNobodyReads) {
  const Scratch s;
  EXPECT_NE(error_of([&] { OutputFile f(s.dir.string(), "option -o"); }).find("is a directory"), std::string::npos);
  s.write("afile", "a user's file\n");
  EXPECT_NE(error_of([&] {
              OutputFile f(s.at("afile/o.mod"), "option --rapid");
            }).find("option --rapid '" + s.at("afile/o.mod") + "': '" + s.at("afile") + "' is not a directory"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              OutputFile f(s.at("afile/sub/o.mod"), "option --rapid");
            }).find("'" + s.at("afile") + "' is not a directory"),
            std::string::npos);
  EXPECT_EQ(slurp(s.at("afile")), "a user's file\n");
  fs::remove(s.at("afile"));
  ASSERT_EQ(::mkfifo(s.at("pipe").c_str(), 0600), 0);
  EXPECT_NE(error_of([&] { OutputFile f(s.at("pipe"), "option -o"); }).find("no process reads"), std::string::npos);
  EXPECT_EQ(s.names(), std::set<std::string>{"pipe"});
  // With a reader, a FIFO is a stream.
  std::string got;
  std::thread reader([&] { got = slurp(s.at("pipe")); });
  for (int tries = 0; tries < 200; ++tries) {
    try {
      OutputFile f(s.at("pipe"));
      f.write("through the pipe\n");
      f.commit();
      break;
    } catch (const InputError&) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));  // the reader has not opened it yet
    }
  }
  reader.join();
  EXPECT_EQ(got, "through the pipe\n");
}

// A missing folder is made for an output (every command alike), kept once the output is in place and
// removed again, deepest first, when it is not; a folder deflex did not make is never removed, nor one
// that holds anything else by then.
TEST(OutputFile, MakesMissingFoldersAndRemovesOnlyItsOwnWhenNothingIsWritten) {
  const Scratch s;
  {
    OutputFile f(s.at("new/deeper/o.csv"), "option -o");
    EXPECT_TRUE(fs::is_directory(s.at("new/deeper")));
    f.write("x\n");
  }  // never committed: the folders go with the temporary file
  EXPECT_EQ(s.names(), std::set<std::string>{});
  fs::create_directories(s.at("mine"));
  {
    OutputTransaction t;
    t.add(s.at("mine/a/one.csv"), "option -o").write("1\n");
    t.add(s.at("mine/a/two.csv"), "option --rapid").write("2\n");  // in the folder the first one made
    s.write("mine/a/note.txt", "another program's file\n");        // appears meanwhile
  }
  EXPECT_EQ(slurp(s.at("mine/a/note.txt")), "another program's file\n");  // its folder stays with it
  fs::remove_all(s.at("mine/a"));
  {
    OutputTransaction t;
    t.add(s.at("mine/b/one.csv"), "option -o").write("1\n");
    t.add(s.at("mine/b/c/two.csv"), "option --rapid").write("2\n");
  }
  EXPECT_TRUE(fs::is_directory(s.at("mine")));  // not made by deflex: stays, empty as it was
  EXPECT_TRUE(fs::is_empty(s.at("mine")));
  write_output_file(s.at("kept/x/o.csv"), "o\n", "option -o");
  EXPECT_EQ(slurp(s.at("kept/x/o.csv")), "o\n");
  {
    OutputFolder folder(s.at("report/html"), "option --out");
    EXPECT_TRUE(fs::is_directory(s.at("report/html")));
  }  // not kept: removed
  EXPECT_FALSE(fs::exists(s.at("report")));
  {
    OutputFolder folder(s.at("report/html"), "option --out");
    folder.keep();
  }
  EXPECT_TRUE(fs::is_directory(s.at("report/html")));
  s.write("plain", "x\n");
  EXPECT_NE(error_of([&] { OutputFolder f(s.at("plain"), "option --out"); }).find("is not a directory"),
            std::string::npos);
}

TEST(OutputTransaction, AllOrNoneWhenARenameFails) {
  const Scratch s;
  s.write("a.csv", "old a\n");
  const ino_t a_inode = inode_of(s.at("a.csv"));
  std::string msg;
  {
    OutputTransaction t;
    t.add(s.at("a.csv"), "option -o").write("new a\n");
    t.add(s.at("b.csv"), "option --rapid").write("new b\n");
    t.add(s.at("c.csv"), "option --joint-trajectory").write("new c\n");
    // b.csv becomes a folder before the commit: its rename fails after a.csv's succeeded.
    fs::create_directories(s.dir / "b.csv" / "inside");
    msg = error_of([&] { t.commit(); });
  }
  EXPECT_NE(msg.find("'" + s.at("b.csv") + "'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("no output of this command was put in place"), std::string::npos) << msg;
  EXPECT_EQ(slurp(s.at("a.csv")), "old a\n");                       // put back
  EXPECT_EQ(inode_of(s.at("a.csv")), a_inode);                      // the very file it was
  EXPECT_EQ(s.names(), (std::set<std::string>{"a.csv", "b.csv"}));  // no c.csv, no temporary or kept file
}

TEST(OutputTransaction, CommitsEveryFileAndRefusesTwoOutputsNamingOneFile) {
  const Scratch s;
  s.write("a.csv", "old\n");
  OutputTransaction t;
  t.add(s.at("a.csv"), "option -o").write("1\n");
  t.add(s.at("b.csv"), "option --rapid").write("2\n");
  t.commit();
  EXPECT_EQ(slurp(s.at("a.csv")), "1\n");
  EXPECT_EQ(slurp(s.at("b.csv")), "2\n");
  EXPECT_EQ(s.names(), (std::set<std::string>{"a.csv", "b.csv"}));
  fs::create_directories(s.dir / "sub");
  OutputTransaction u;
  u.add(s.at("c.csv"), "option -o");
  const std::string msg = error_of([&] { u.add(s.at("sub/../c.csv"), "option --rapid"); });
  EXPECT_NE(msg.find("are the same file"), std::string::npos) << msg;
}

TEST(OutputFile, AnInterruptedProgramRemovesItsTemporaryFiles) {
  const Scratch s;
  s.write("out.csv", "the user's data\n");
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // The program: handlers installed, two outputs half written, then Ctrl-C.
    remove_temporaries_on_signals();
    OutputTransaction t;
    t.add(s.at("out.csv"), "option -o").write(std::string(100000, 'x'));
    t.add(s.at("new.csv"), "option --rapid").write("half");
    t.add(s.at("made/for/it.csv"), "option --joint-trajectory").write("half");  // in folders made for it
    ::raise(SIGINT);
    ::_exit(0);  // not reached
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGINT);  // it died of the signal, as without us
  EXPECT_EQ(s.names(), std::set<std::string>{"out.csv"});          // no temporary file, no folder left
  EXPECT_EQ(slurp(s.at("out.csv")), "the user's data\n");
}

// --- one run: inputs and outputs apart -----------------------------------------------------------

TEST(RunFiles, AnOutputThatIsAnInputIsRefusedWhicheverComesFirst) {
  const Scratch s;
  s.write("m.csv", "data\n");
  fs::create_hard_link(s.dir / "m.csv", s.dir / "hard.csv");
  fs::create_symlink("m.csv", s.dir / "link.csv");
  {
    const RunFilesScope run;
    OutputFile out(s.at("hard.csv"), "option --write-robot");  // the output first
    const std::string msg = error_of([&] { (void)read_input_file(s.at("link.csv"), InputKind::kCsvTable); });
    EXPECT_NE(msg.find("the same file"), std::string::npos) << msg;
    EXPECT_NE(msg.find(s.at("hard.csv")), std::string::npos) << msg;
  }
  {
    const RunFilesScope run;
    (void)read_input_file(s.at("m.csv"), InputKind::kCsvTable);  // the input first
    EXPECT_THROW(OutputFile(s.at("hard.csv"), "option -o"), InputError);
  }
  EXPECT_EQ(slurp(s.at("m.csv")), "data\n");
  // Outside a run (the Python module, a library user) a session may read a file and later write it.
  (void)read_input_file(s.at("m.csv"), InputKind::kCsvTable);
  write_output_file(s.at("m.csv"), "rewritten\n");
  EXPECT_EQ(slurp(s.at("m.csv")), "rewritten\n");
}

TEST(RunFiles, AFileReadToBeRewrittenIsItsOutputAndStillNoOtherRunsInput) {
  const Scratch s;
  s.write("poses.csv", "a,b\n1,2\n");
  fs::create_symlink("poses.csv", s.dir / "link.csv");
  {
    const RunFilesScope run;
    const std::string text = read_file_to_update(s.at("poses.csv"), InputKind::kCsvTable, "option --record");
    OutputFile out(s.at("link.csv"), "option --record");  // the same output: allowed
    out.write(text + "3,4\n");
    // The same file as an input, or as another output, is still refused.
    const std::string msg = error_of([&] { (void)read_input_file(s.at("poses.csv"), InputKind::kCsvTable); });
    EXPECT_NE(msg.find("the same file"), std::string::npos) << msg;
    EXPECT_THROW(OutputFile(s.at("poses.csv"), "option -o"), InputError);
    out.commit();
  }
  EXPECT_EQ(slurp(s.at("poses.csv")), "a,b\n1,2\n3,4\n");
  {
    const RunFilesScope run;
    (void)read_input_file(s.at("poses.csv"), InputKind::kCsvTable);  // an input first: no update of it
    EXPECT_THROW((void)read_file_to_update(s.at("link.csv"), InputKind::kCsvTable, "option --record"), InputError);
  }
}

}  // namespace
}  // namespace deflex
