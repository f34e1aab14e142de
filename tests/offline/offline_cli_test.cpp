// `deflex offline` option checks that need the program itself (skipped when it is not built).
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>
#include <sys/wait.h>

namespace deflex {
namespace {

struct CliResult {
  int exit_code = -1;
  std::string err;
};

CliResult offline(const std::string& args) {
  const std::string err_path = ::testing::TempDir() + "/deflex_offline_cli_err.txt";
  const std::string cmd = std::string(DEFLEX_CLI) + " offline " + args + " >/dev/null 2>" + err_path + " </dev/null";
  const int status = std::system(cmd.c_str());
  CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (std::FILE* f = std::fopen(err_path.c_str(), "r")) {
    char buf[4096];
    const std::size_t n = std::fread(buf, 1, sizeof(buf), f);
    r.err.assign(buf, n);
    std::fclose(f);
  }
  return r;
}

TEST(DeflexOfflineProgram, ConfdataMustBeFourWholeNumbers) {
  if (!std::filesystem::exists(DEFLEX_CLI)) {
    GTEST_SKIP() << "the deflex program is not built: " << DEFLEX_CLI;
  }
  const std::string common = "--circle --force ldbb:phi_deg=45,force_N=625 ";
  for (const char* bad : {"0,0,0,2.5", "1e12,0,0,1", "0,-0.5,0,1"}) {
    const CliResult r = offline(common + "--config " + bad);
    EXPECT_EQ(r.exit_code, 2) << bad << "\n" << r.err;
    EXPECT_NE(r.err.find("option --config"), std::string::npos) << bad << "\n" << r.err;
  }
  EXPECT_EQ(offline(common + "--config 0,0,0,9").exit_code, 2);  // cfx 0..7, as before
  EXPECT_EQ(offline(common + "--config 0,0,0,0").exit_code, 0) << offline(common + "--config 0,0,0,0").err;
}

}  // namespace
}  // namespace deflex
