# deflex_module(NAME [DEPENDS m1 m2 ...])
# Builds src/deflex/NAME/*.cpp into the static library deflex_NAME (nothing if the folder has no
# sources yet), and tests/NAME/*_test.cpp into the test program deflex_NAME_tests. Adding a file
# to a module needs no edit here: new files are found at configure time (CONFIGURE_DEPENDS).
set(DEFLEX_MODULE_TARGETS "" CACHE INTERNAL "")

function(deflex_module name)
  cmake_parse_arguments(ARG "" "" "DEPENDS" ${ARGN})
  set(dir ${PROJECT_SOURCE_DIR}/src/deflex/${name})
  file(GLOB sources CONFIGURE_DEPENDS ${dir}/*.cpp)
  if(NOT sources)
    return()
  endif()
  set(target deflex_${name})
  add_library(${target} STATIC ${sources})
  target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR}/src ${PROJECT_BINARY_DIR}/generated)
  target_link_libraries(${target} PUBLIC Eigen3::Eigen fmt::fmt PRIVATE deflex_warnings)
  foreach(dep IN LISTS ARG_DEPENDS)
    if(TARGET deflex_${dep})
      target_link_libraries(${target} PUBLIC deflex_${dep})
    endif()
  endforeach()
  # Per-module extras (generated sources, extra packages) live beside the module's sources.
  if(EXISTS ${dir}/module.cmake)
    include(${dir}/module.cmake)
  endif()
  set(DEFLEX_MODULE_TARGETS ${DEFLEX_MODULE_TARGETS} ${target} CACHE INTERNAL "")
endfunction()

# deflex_embed_text(TARGET FILE SYMBOL)
# Compiles the text of FILE (relative to the source tree) into TARGET as
# `extern const char* const deflex::SYMBOL`. The generated source is rewritten only when the text
# changes, so a re-configure does not force a recompile; editing FILE re-runs the configure.
function(deflex_embed_text target file symbol)
  set(src ${PROJECT_SOURCE_DIR}/${file})
  set_property(DIRECTORY ${PROJECT_SOURCE_DIR} APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${src})
  file(READ ${src} text)
  set(out ${PROJECT_BINARY_DIR}/generated/${symbol}.cpp)
  file(CONFIGURE OUTPUT ${out} @ONLY CONTENT
    "// Generated from ${file} by deflex_embed_text (cmake/DeflexModule.cmake).\nnamespace deflex { extern const char* const ${symbol}; const char* const ${symbol} = R\"deflexembed(@text@)deflexembed\"; }\n")
  target_sources(${target} PRIVATE ${out})
endfunction()
