// Files for the controller's side of a link (see controller_file.hpp).
#include "deflex/link/controller_file.hpp"

#include <fstream>

#include <fmt/format.h>

#include "deflex/model/errors.hpp"

namespace deflex {

void write_controller_files(const std::vector<ControllerFile>& files, const std::string& directory) {
  for (const ControllerFile& f : files) {
    const std::string path = directory.empty() ? f.name : directory + "/" + f.name;
    std::ofstream out(path, std::ios::binary);
    out << f.text;
    out.close();
    if (!out) throw Error(fmt::format("{}: cannot write", path));
  }
}

}  // namespace deflex
