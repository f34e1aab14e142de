# Study module extras: compile the paper's case file in, so `deflex case-study` without --case works
# from the build tree and from an install.
deflex_embed_text(${target} data/cases/paper.yaml kPaperCaseYaml)
find_package(Threads REQUIRED)
target_link_libraries(${target} PUBLIC Threads::Threads)
deflex_module_requires(study "find_dependency(Threads)")
# A study's results are written and read back as JSON (study_tables.hpp).
target_link_libraries(${target} PUBLIC nlohmann_json::nlohmann_json)
deflex_module_requires(study "find_dependency(nlohmann_json 3.10)")
