// Exceptions thrown at set-up and I/O time. Nothing on a real-time path throws: those paths return
// status values instead.
#pragma once

#include <stdexcept>
#include <string>

namespace deflex {

/// Base of every deflex exception.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A robot description (YAML, URDF) or a configuration file is malformed or inconsistent.
/// The message names the file, the field and what was wrong.
class ModelError : public Error {
 public:
  using Error::Error;
};

/// A data file (CSV) is malformed. The message names the file, the line and the column.
class DataError : public Error {
 public:
  using Error::Error;
};

/// A value given by the caller is out of its domain (NaN, wrong size, unreachable pose ...).
class InputError : public Error {
 public:
  using Error::Error;
};

/// An output could not be written or put in place (a full disk, /dev/full, a failed rename): the job
/// failed, not its input (the command-line program exits with code 1). output_file.hpp guarantees that
/// nothing was left half-written.
class OutputError : public Error {
 public:
  using Error::Error;
};

}  // namespace deflex
