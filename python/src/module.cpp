// The deflex Python module (_deflex, re-exported by the package deflex): NumPy arrays in and out,
// SI units (m, rad, N, Nm, s), the names of the C++ API. docs/python.md lists it.
#include "bindings.hpp"

PYBIND11_MODULE(_deflex, m) {
  m.doc() = "deflex: elastic deflection of industrial robots (lumped joint compliance), SI units";
  m.attr("__version__") = DEFLEX_VERSION;
  deflex::python::bind_errors(m);
  deflex::python::bind_model(m);
  deflex::python::bind_identify(m);
  deflex::python::bind_offline(m);
  deflex::python::bind_machining(m);
  deflex::python::bind_evaluate(m);
  deflex::python::bind_online(m);
  deflex::python::bind_study(m);
  deflex::python::bind_machining_study(m);
  deflex::python::bind_runtime(m);
}
