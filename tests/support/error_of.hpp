// The message of the deflex::Error a call throws, or "no error": for tests that assert what an
// error names (the file, line, field or option).
#pragma once

#include <string>

#include "deflex/text/errors.hpp"

namespace deflex::test {

template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace deflex::test
