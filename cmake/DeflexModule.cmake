# deflex_module(NAME [DEPENDS m1 m2 ...])
# Builds src/deflex/NAME/*.cpp into the static library deflex_NAME (nothing if the folder has no
# sources yet), and tests/NAME/*_test.cpp into the test program deflex_NAME_tests. Adding a file
# to a module needs no edit here: new files are found at configure time (CONFIGURE_DEPENDS).
# Each module is also the target deflex::NAME, in the build tree (an alias) and in the installed
# package (find_package(deflex COMPONENTS NAME), cmake/deflexConfig.cmake.in): it passes on its
# include path and the C++ standard its public headers need (C++17 for the modules in
# DEFLEX_CXX17_MODULES, C++20 for the others; each module itself compiles as C++20), and records what
# a consumer's CMake must find for it (deflex_module_requires).
set(DEFLEX_MODULE_TARGETS "" CACHE INTERNAL "")
set(DEFLEX_MODULE_NAMES "" CACHE INTERNAL "")

# deflex_module_requires(NAME CODE...): CMake code the installed package's config runs for a consumer
# that uses module NAME (find_dependency(...) of what the module links), one call a line.
function(deflex_module_requires name)
  set_property(GLOBAL APPEND PROPERTY DEFLEX_REQUIRES_${name} ${ARGN})
endfunction()

function(deflex_module name)
  cmake_parse_arguments(ARG "" "" "DEPENDS" ${ARGN})
  set(dir ${PROJECT_SOURCE_DIR}/src/deflex/${name})
  file(GLOB sources CONFIGURE_DEPENDS ${dir}/*.cpp)
  if(NOT sources)
    return()
  endif()
  set(target deflex_${name})
  add_library(${target} STATIC ${sources})
  add_library(deflex::${name} ALIAS ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name})
  target_include_directories(
    ${target} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/src> $<BUILD_INTERFACE:${PROJECT_BINARY_DIR}/generated>
                     $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  if(name IN_LIST DEFLEX_CXX17_MODULES)
    target_compile_features(${target} PUBLIC cxx_std_17)
    set_target_properties(${target} PROPERTIES CXX_STANDARD 20 CXX_STANDARD_REQUIRED ON)
  else()
    target_compile_features(${target} PUBLIC cxx_std_20)
  endif()
  # deflex_compat: the deprecated forwarding headers of moved headers (CMakeLists.txt).
  target_link_libraries(${target} PUBLIC Eigen3::Eigen fmt::fmt deflex_compat)
  target_compile_options(${target} PRIVATE ${DEFLEX_WARNING_FLAGS})
  if(DEFLEX_SANITIZE AND name IN_LIST DEFLEX_SANITIZE_EXCEPT)
    target_compile_options(${target} PRIVATE -fno-sanitize=all)
  endif()
  deflex_module_requires(${name} "find_dependency(Eigen3 3.4 NO_MODULE)" "find_dependency(fmt)")
  set(deps "")
  foreach(dep IN LISTS ARG_DEPENDS)
    if(TARGET deflex_${dep})
      target_link_libraries(${target} PUBLIC deflex_${dep})
      list(APPEND deps ${dep})
    endif()
  endforeach()
  set_property(GLOBAL PROPERTY DEFLEX_DEPENDS_${name} ${deps})
  install(TARGETS ${target} EXPORT deflexTargets ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
  # The module's public headers; those under detail/ are its own and are not installed.
  file(GLOB headers CONFIGURE_DEPENDS ${dir}/*.hpp)
  install(FILES ${headers} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/deflex/${name})
  # Per-module extras (generated sources, extra packages) live beside the module's sources.
  if(EXISTS ${dir}/module.cmake)
    include(${dir}/module.cmake)
  endif()
  set(DEFLEX_MODULE_TARGETS ${DEFLEX_MODULE_TARGETS} ${target} CACHE INTERNAL "")
  set(DEFLEX_MODULE_NAMES ${DEFLEX_MODULE_NAMES} ${name} CACHE INTERNAL "")
endfunction()

# deflex_embed_text(TARGET FILE SYMBOL)
# Compiles the text of FILE (relative to the source tree, or an absolute path: a file a Debian package
# installed) into TARGET as `extern const char* const deflex::SYMBOL`. A source-map comment is left
# out (the map is not embedded, and a browser would look for it). The generated source is rewritten
# only when the text changes, so a re-configure does not force a recompile; editing FILE re-runs the
# configure.
function(deflex_embed_text target file symbol)
  if(IS_ABSOLUTE ${file})
    set(src ${file})
  else()
    set(src ${PROJECT_SOURCE_DIR}/${file})
  endif()
  set_property(DIRECTORY ${PROJECT_SOURCE_DIR} APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${src})
  file(READ ${src} text)
  string(REGEX REPLACE "\n?(//# sourceMappingURL=[^\n]*|/\\*# sourceMappingURL=[^\n]*\\*/)" "" text "${text}")
  if(text MATCHES "\\)deflexembed\"")
    message(FATAL_ERROR "${src} holds the raw string's delimiter: it cannot be embedded as it is")
  endif()
  set(out ${PROJECT_BINARY_DIR}/generated/${symbol}.cpp)
  file(CONFIGURE OUTPUT ${out} @ONLY CONTENT
    "// Generated from ${file} by deflex_embed_text (cmake/DeflexModule.cmake).\nnamespace deflex { extern const char* const ${symbol}; const char* const ${symbol} = R\"deflexembed(@text@)deflexembed\"; }\n")
  target_sources(${target} PRIVATE ${out})
endfunction()

# deflex_check_private_headers(): a module's detail/ headers are its own. Any file of another module,
# the program, the Python module, the examples or the benchmarks that includes one fails the
# configure, naming the file and the header (tests may include them: they test the module itself).
function(deflex_check_private_headers)
  file(GLOB_RECURSE files CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/src/deflex/*.hpp ${PROJECT_SOURCE_DIR}/src/deflex/*.cpp
       ${PROJECT_SOURCE_DIR}/apps/*.cpp ${PROJECT_SOURCE_DIR}/apps/*.hpp ${PROJECT_SOURCE_DIR}/python/src/*.cpp
       ${PROJECT_SOURCE_DIR}/python/src/*.hpp ${PROJECT_SOURCE_DIR}/examples/*.cpp ${PROJECT_SOURCE_DIR}/bench/*.cpp)
  set(violations "")
  foreach(f IN LISTS files)
    file(STRINGS ${f} lines REGEX "#include \"deflex/[a-z_]+/detail/")
    foreach(line IN LISTS lines)
      string(REGEX MATCH "deflex/([a-z_]+)/detail/[a-z_0-9.]+" header "${line}")
      set(owner ${CMAKE_MATCH_1})
      if(NOT f MATCHES "/src/deflex/${owner}/")
        file(RELATIVE_PATH rel ${PROJECT_SOURCE_DIR} ${f})
        list(APPEND violations "${rel} includes ${header}")
      endif()
    endforeach()
  endforeach()
  if(violations)
    list(JOIN violations "\n  " text)
    message(FATAL_ERROR "private headers used outside their module (move what is shared to the module's "
                        "public headers):\n  ${text}")
  endif()
endfunction()

# deflex_check_layering(): the DEPENDS lists above are the layering of DESIGN.md, and this holds every
# file to them. A module's file (its sources and headers, detail/ included) may include the headers
# of its own module and of the modules it depends on, directly or through them; an include of any
# other module fails the configure, naming the file, the header and what the module may use. Linking
# alone would not catch it: a header-only use of a module that is not a dependency links fine.
function(deflex_check_layering)
  set(violations "")
  foreach(name IN LISTS DEFLEX_MODULE_NAMES)
    # The modules `name` may use: the closure of its DEPENDS.
    get_property(stack GLOBAL PROPERTY DEFLEX_DEPENDS_${name})
    set(allowed ${name})
    while(stack)
      list(POP_FRONT stack dep)
      if(NOT dep IN_LIST allowed)
        list(APPEND allowed ${dep})
        get_property(more GLOBAL PROPERTY DEFLEX_DEPENDS_${dep})
        list(APPEND stack ${more})
      endif()
    endwhile()
    file(GLOB_RECURSE files CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/src/deflex/${name}/*.hpp
         ${PROJECT_SOURCE_DIR}/src/deflex/${name}/*.cpp)
    foreach(f IN LISTS files)
      file(STRINGS ${f} lines REGEX "^#include \"deflex/[a-z_]+/")
      foreach(line IN LISTS lines)
        string(REGEX MATCH "deflex/([a-z_]+)/[a-z_0-9./]+" header "${line}")
        set(used ${CMAKE_MATCH_1})
        if(used IN_LIST DEFLEX_MODULE_NAMES AND NOT used IN_LIST allowed)
          file(RELATIVE_PATH rel ${PROJECT_SOURCE_DIR} ${f})
          set(others ${allowed})
          list(REMOVE_ITEM others ${name})
          if(others)
            list(JOIN others ", " may)
            set(may "may use only ${may}")
          else()
            set(may "may use no other module")
          endif()
          list(APPEND violations "${rel} includes ${header} (module ${name} ${may})")
        endif()
      endforeach()
    endforeach()
  endforeach()
  if(violations)
    list(JOIN violations "\n  " text)
    message(FATAL_ERROR "includes across the layering (CMakeLists.txt's deflex_module DEPENDS):\n  ${text}")
  endif()
endfunction()

# deflex_check_front_door(): the program (apps/) does online work through runtime/ alone: a file of it
# that includes a header of a controller link, a wire format or a transport fails the configure, naming
# the file and the header. What the program needs of them the runtime offers (the link by kind, its
# controller setup, the session's counters), so the program does not change with a link.
function(deflex_check_front_door)
  set(barred egm rsi simple_message fanuc motoros2 ur wire transport)
  file(GLOB_RECURSE files CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/apps/*.cpp ${PROJECT_SOURCE_DIR}/apps/*.hpp)
  set(violations "")
  foreach(f IN LISTS files)
    file(STRINGS ${f} lines REGEX "^[ \t]*#[ \t]*include[ \t]*[\"<]deflex/[a-z_0-9]+/")
    foreach(line IN LISTS lines)
      string(REGEX MATCH "deflex/([a-z_0-9]+)/[A-Za-z_0-9./]+" header "${line}")
      if(CMAKE_MATCH_1 IN_LIST barred)
        file(RELATIVE_PATH rel ${PROJECT_SOURCE_DIR} ${f})
        list(APPEND violations "${rel} includes ${header}")
      endif()
    endforeach()
  endforeach()
  if(violations)
    list(JOIN violations "\n  " text)
    list(JOIN barred ", " names)
    message(FATAL_ERROR "the program includes what only the runtime may (apps/ includes no header of ${names}; "
                        "reach them through deflex/runtime/):\n  ${text}")
  endif()
endfunction()
