# Runtime module extras: the session's summary as JSON, the reporter's thread.
target_link_libraries(${target} PUBLIC nlohmann_json::nlohmann_json Threads::Threads)
deflex_module_requires(runtime "find_dependency(nlohmann_json 3.10)" "find_dependency(Threads)")
