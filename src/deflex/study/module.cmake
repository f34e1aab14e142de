# Study module extras: compile the paper's case file in, so `deflex case-study` without --case works
# from the build tree and from an install.
deflex_embed_text(${target} data/cases/paper.yaml kPaperCaseYaml)
find_package(Threads REQUIRED)
target_link_libraries(${target} PUBLIC Threads::Threads)
deflex_module_requires(study "find_dependency(Threads)")
