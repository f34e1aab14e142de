// One case of the bad-input sweep and the helpers its generators share. A case runs deflex once in
// a scratch folder of its own ({D}) with files written there first (and special ones - FIFOs, links,
// sparse files - made by `setup`); it must end with its exit code (2: bad input, 1: a failed write)
// and a message holding every `expect` fragment, and leave every file of the folder as it was.
#pragma once

#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "cross/cli_runner.hpp"

namespace deflex::test {

struct BadInput {
  std::string name = {};
  std::string args = {};                                        ///< {D}: scratch directory, {S}: source tree
  std::vector<std::pair<std::string, std::string>> files = {};  ///< written into {D} first
  std::vector<std::string> expect = {};                         ///< each must appear in stderr
  int exit_code = 2;
  std::function<void(const std::filesystem::path& dir)> setup = {};  ///< FIFOs, links, sparse files
  std::string stdout_to = {};  ///< "": captured; "-": closed (>&-); else a file such as /dev/full
};

inline std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (std::size_t p = s.find(from); p != std::string::npos; p = s.find(from, p + to.size())) {
    s.replace(p, from.size(), to);
  }
  return s;
}

/// The 1-based line of the first `anchor` in `text` (lines counted by '\n'); the anchor must be there.
inline int line_number_of(const std::string& text, const std::string& anchor) {
  const auto p = text.find(anchor);
  if (p == std::string::npos) throw std::runtime_error("sweep: anchor not found: " + anchor);
  int line = 1;
  for (std::size_t i = 0; i < p; ++i) line += text[i] == '\n' ? 1 : 0;
  return line;
}

/// A file of the source tree.
inline std::string source_file(const std::string& rel) { return slurp(std::string(DEFLEX_SOURCE_DIR) + "/" + rel); }

/// The text with the first `from` replaced by `to` (the anchor must be there: the case would test
/// nothing otherwise).
std::string with(const std::string& text, const std::string& from, const std::string& to);

// The generators, one per class of bad input (file_safety_cases.cpp, program_cases.cpp, toolpath_cases.cpp).
std::vector<BadInput> output_cases();          ///< outputs that are inputs, links, devices, folders
std::vector<BadInput> input_file_cases();      ///< FIFOs, devices, folders, oversize files as inputs
std::vector<BadInput> program_cases();         ///< malformed RAPID modules and KRL programs
std::vector<BadInput> limit_cases();           ///< URDF limits, YAML rules, value ranges, repeated keys
std::vector<BadInput> tracker_sensor_cases();  ///< tracker files, registration, RDT calibration pages
std::vector<BadInput> toolpath_cases();        ///< malformed toolpaths, milling options, stock, reach

}  // namespace deflex::test
