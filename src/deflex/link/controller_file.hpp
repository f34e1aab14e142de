// A file `deflex controller-setup` writes for the robot controller's side of a link (a RAPID module, a
// configuration fragment, an RSI context ...): its name, its text, and where on the controller it goes.
#pragma once

#include <string>
#include <vector>

namespace deflex {

struct ControllerFile {
  std::string name;     ///< file name, no directory
  std::string text;     ///< the whole file
  std::string install;  ///< one sentence: where it goes on the controller and how
};

/// A number as controller languages write it (RAPID num, KRL, RSI parameters): fixed notation, at most
/// 6 decimals, no trailing zeros ("0.1", "20", "-0.35").
[[nodiscard]] std::string plain_number(double v);

/// True for a name RAPID and KRL both take: a letter, then letters, digits or '_', 1..max_length long.
[[nodiscard]] bool plain_identifier(const std::string& s, std::size_t max_length);

/// Writes the files into `directory` (which must exist), all or none, never destroying what was there
/// on a failure (model/output_file.hpp). Throws InputError for a path that cannot be an output and
/// OutputError naming the file it cannot write.
void write_controller_files(const std::vector<ControllerFile>& files, const std::string& directory);

}  // namespace deflex
