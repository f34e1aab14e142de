// The registry behind RunFilesScope: a list per run, under a mutex (the case study writes from its
// worker threads).
#include "deflex/text/run_files.hpp"

#include <mutex>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

struct Entry {
  FileId id;
  std::string path;
  std::string what;  // outputs: the option that names them
};

struct Registry {
  std::mutex mutex;
  bool active = false;
  std::vector<Entry> inputs;
  std::vector<Entry> outputs;
};

Registry& registry() {
  static Registry r;
  return r;
}

const Entry* find(const std::vector<Entry>& list, const FileId& id) {
  for (const Entry& e : list) {
    if (e.id == id) {
      return &e;
    }
  }
  return nullptr;
}

}  // namespace

RunFilesScope::RunFilesScope() {
  Registry& r = registry();
  const std::lock_guard lock(r.mutex);
  if (r.active) {
    throw std::logic_error("RunFilesScope: a run is already recorded");
  }
  r.active = true;
}

RunFilesScope::~RunFilesScope() {
  Registry& r = registry();
  const std::lock_guard lock(r.mutex);
  r.active = false;
  r.inputs.clear();
  r.outputs.clear();
}

void record_input_file(const FileId& id, const std::string& path) {
  Registry& r = registry();
  const std::lock_guard lock(r.mutex);
  if (!r.active) {
    return;
  }
  if (const Entry* out = find(r.outputs, id)) {
    throw InputError(
        fmt::format("{}: this input is the file {} '{}' writes (the same file): deflex never writes a "
                    "file it reads; give the output another name",
                    path, out->what, out->path));
  }
  if (find(r.inputs, id) == nullptr) {
    r.inputs.push_back({id, path, {}});
  }
}

void record_output_file(const FileId& id, const std::string& path, const std::string& what) {
  Registry& r = registry();
  const std::lock_guard lock(r.mutex);
  if (!r.active) {
    return;
  }
  if (const Entry* in = find(r.inputs, id)) {
    throw InputError(
        fmt::format("{} '{}': this output is the input '{}' (the same file): deflex never writes a file "
                    "it reads; give the output another name",
                    what, path, in->path));
  }
  if (const Entry* other = find(r.outputs, id)) {
    // The same output written again (a fault dump rewritten at each episode) is that output's own
    // business; two outputs naming one file would lose one of them.
    if (other->what == what) return;
    throw InputError(fmt::format("{} '{}' and {} '{}' are the same file: give each output its own name", other->what,
                                 other->path, what, path));
  }
  r.outputs.push_back({id, path, what});
}

}  // namespace deflex
