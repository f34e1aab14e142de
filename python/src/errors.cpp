// deflex's exceptions as Python exceptions with the same message text (which names the file, line
// and field): deflex.Error (a RuntimeError) and its subclasses ModelError, DataError and
// InputError; InputError is also a ValueError, since it means a bad argument (bad arrays included).
#include <Python.h>

#include <new>
#include <regex>
#include <string>
#include <utility>
#include <vector>

#include "bindings.hpp"
#include "deflex/text/errors.hpp"

namespace deflex::python {
namespace {

// Created once with the module and never freed: the translator may run until the interpreter exits.
PyObject* g_error = nullptr;
PyObject* g_model_error = nullptr;
PyObject* g_data_error = nullptr;
PyObject* g_input_error = nullptr;

PyObject* new_exception(py::module_& m, const char* name, PyObject* bases, const char* doc) {
  const std::string full = std::string("deflex.") + name;
  PyObject* type = PyErr_NewExceptionWithDoc(full.c_str(), doc, bases, nullptr);
  if (type == nullptr) throw py::error_already_set();
  m.attr(name) = py::handle(type);
  return type;
}

}  // namespace

std::string python_message(std::string text) {
  // The library's messages name the command line's options where a setting is at fault; from Python
  // the same setting is an argument, named as the call takes it (SI units: --lever-mm is lever_m).
  static const std::vector<std::pair<std::string, std::string>> kNames = {
      {"option --tracker-units", "argument length_unit"},
      {"--tracker-units", "length_unit"},
      {"option --tracker-angle-units", "argument angle_unit"},
      {"--tracker-angle-units", "angle_unit"},
      {"option --sa-columns", "argument columns"},
      {"--sa-columns", "columns"},
      {"(--lever-mm)", "(lever_m)"},
      {"deflex register --max-rms-mm", "register_frames(max_rms_m=...)"},
      {"give --force", "give force_model"},
      {"option --tooldata", "argument tooldata"},
      {"option --wobjdata", "argument wobjdata"},
      {"--tooldata", "tooldata"},
      {"--wobjdata", "wobjdata"},
  };
  for (const auto& [cli, python] : kNames) {
    for (std::size_t at = text.find(cli); at != std::string::npos; at = text.find(cli, at + python.size())) {
      text.replace(at, cli.size(), python);
    }
  }
  // Settings named as the option with underscores (a Session's keyword arguments: --stop-ramp-s is
  // stop_ramp_s).
  static const std::regex kOption("option --([a-z0-9-]+)");
  std::string out;
  std::sregex_iterator it(text.begin(), text.end(), kOption), end;
  std::size_t from = 0;
  for (; it != end; ++it) {
    std::string name = (*it)[1].str();
    for (char& c : name) c = c == '-' ? '_' : c;
    out.append(text, from, static_cast<std::size_t>(it->position()) - from).append("argument ").append(name);
    from = static_cast<std::size_t>(it->position() + it->length());
  }
  return out.append(text, from, std::string::npos);
}

std::vector<std::string> python_messages(std::vector<std::string> texts) {
  for (std::string& t : texts) t = python_message(std::move(t));
  return texts;
}

void bind_errors(py::module_& m) {
  g_error = new_exception(m, "Error", PyExc_RuntimeError, "Base of every deflex error.");
  g_model_error = new_exception(m, "ModelError", g_error,
                                "A robot description or configuration file is malformed: names the file and field.");
  g_data_error =
      new_exception(m, "DataError", g_error, "A data file (CSV) is malformed: names the file, line and column.");
  py::tuple input_bases = py::make_tuple(py::handle(g_error), py::handle(PyExc_ValueError));
  g_input_error =
      new_exception(m, "InputError", input_bases.ptr(),
                    "A value given is out of its domain (bad array shape or dtype, NaN, unreachable pose).");
  // pybind11's translator type takes the exception_ptr by value.
  // NOLINTNEXTLINE(performance-unnecessary-value-param)
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      PyErr_SetString(g_input_error, python_message(e.what()).c_str());
    } catch (const DataError& e) {
      PyErr_SetString(g_data_error, python_message(e.what()).c_str());
    } catch (const ModelError& e) {
      PyErr_SetString(g_model_error, python_message(e.what()).c_str());
    } catch (const Error& e) {
      PyErr_SetString(g_error, python_message(e.what()).c_str());
    } catch (const py::builtin_exception&) {
      throw;  // pybind11's own (IndexError, StopIteration, TypeError, ...): its translator raises them
    } catch (const py::error_already_set&) {
      throw;
    } catch (const std::bad_alloc&) {
      throw;  // MemoryError
    } catch (const std::exception& e) {
      // Anything else the library or the standard library throws (a file system error, an Eigen
      // size check) is still a deflex.Error, never a bare RuntimeError.
      PyErr_SetString(g_error, python_message(e.what()).c_str());
    }
  });
}

}  // namespace deflex::python
