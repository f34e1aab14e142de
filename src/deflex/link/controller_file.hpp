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

/// Writes each file into `directory` (which must exist). Throws Error naming the file it cannot write.
void write_controller_files(const std::vector<ControllerFile>& files, const std::string& directory);

}  // namespace deflex
