// Files for the controller's side of a link (see controller_file.hpp).
#include "deflex/link/controller_file.hpp"

#include <cctype>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"
#include "deflex/text/output_file.hpp"

namespace deflex {

std::string plain_number(double v) {
  std::string s = fmt::format("{:.6f}", v);
  s.erase(s.find_last_not_of('0') + 1);
  if (s.back() == '.') s.pop_back();
  return s == "-0" ? "0" : s;
}

bool plain_identifier(const std::string& s, std::size_t max_length) {
  if (s.empty() || s.size() > max_length || !std::isalpha(static_cast<unsigned char>(s[0]))) return false;
  for (const char c : s) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
  }
  return true;
}

void write_controller_files(const std::vector<ControllerFile>& files, const std::string& directory) {
  // The files of one link belong together: they appear all or none, and a failure leaves what was in
  // the folder as it was (model/output_file.hpp).
  OutputTransaction transaction;
  for (const ControllerFile& f : files) {
    const std::string path = directory.empty() ? f.name : directory + "/" + f.name;
    transaction.add(path, "controller file").write(f.text);
  }
  transaction.commit();
}

}  // namespace deflex
