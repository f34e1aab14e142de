# Cell module extras: compile the paper's case file in, so `deflex case-study` without --case works
# from the build tree and from an install.
set(paper_case_yaml ${PROJECT_SOURCE_DIR}/data/cases/paper.yaml)
set_property(DIRECTORY ${PROJECT_SOURCE_DIR} APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${paper_case_yaml})
file(READ ${paper_case_yaml} DEFLEX_PAPER_CASE_YAML)
file(WRITE ${PROJECT_BINARY_DIR}/generated/paper_case.cpp
  "// Generated from data/cases/paper.yaml by src/deflex/cell/module.cmake.\n"
  "namespace deflex { extern const char* const kPaperCaseYaml; "
  "const char* const kPaperCaseYaml = R\"deflexcase(${DEFLEX_PAPER_CASE_YAML})deflexcase\"; }\n")
target_sources(${target} PRIVATE ${PROJECT_BINARY_DIR}/generated/paper_case.cpp)
find_package(Threads REQUIRED)
target_link_libraries(${target} PUBLIC Threads::Threads)
