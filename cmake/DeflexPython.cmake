# deflex_find_python(OUT_VAR)
# Finds a Python 3 interpreter that can import NumPy, its development headers and pybind11, and sets
# OUT_VAR to TRUE when all are there. A python3 earlier on PATH without NumPy (a pyenv or a virtual
# environment) would build a module that cannot return arrays, so each candidate is asked to import
# numpy and the first that can is used: Python3_EXECUTABLE when given, then python3 on PATH, then
# Debian's /usr/bin/python3. A macro, not a function: pybind11_add_module() needs the variables the
# find_package() calls set, in the caller's scope.
macro(deflex_find_python out)
  set(${out} FALSE)
  if(NOT Python3_EXECUTABLE)
    find_program(DEFLEX_PATH_PYTHON3 NAMES python3)
    foreach(deflex_candidate IN ITEMS ${DEFLEX_PATH_PYTHON3} /usr/bin/python3)
      if(NOT Python3_EXECUTABLE AND EXISTS ${deflex_candidate})
        execute_process(COMMAND ${deflex_candidate} -c "import numpy" RESULT_VARIABLE deflex_rc OUTPUT_QUIET
                        ERROR_QUIET)
        if(deflex_rc EQUAL 0)
          set(Python3_EXECUTABLE ${deflex_candidate} CACHE FILEPATH "Python 3 interpreter with NumPy")
        endif()
      endif()
    endforeach()
  endif()
  if(NOT Python3_EXECUTABLE)
    message(STATUS "deflex Python module: no python3 that can import numpy (Debian: python3-numpy)")
  else()
    find_package(Python3 COMPONENTS Interpreter Development.Module NumPy QUIET)
    if(NOT Python3_FOUND OR NOT Python3_Development.Module_FOUND OR NOT Python3_NumPy_FOUND)
      message(STATUS "deflex Python module: ${Python3_EXECUTABLE} lacks its headers or NumPy's "
                     "(Debian: python3-dev python3-numpy)")
    else()
      find_package(pybind11 2.10 CONFIG QUIET)
      if(NOT pybind11_FOUND)
        message(STATUS "deflex Python module: pybind11 not found (Debian: pybind11-dev)")
      else()
        message(STATUS "deflex Python module: ${Python3_EXECUTABLE} (Python ${Python3_VERSION}, "
                       "NumPy ${Python3_NumPy_VERSION}), pybind11 ${pybind11_VERSION}")
        set(${out} TRUE)
      endif()
    endif()
  endif()
endmacro()
