# Evaluate module extras: the study results are written as JSON.
target_link_libraries(${target} PUBLIC nlohmann_json::nlohmann_json)
deflex_module_requires(evaluate "find_dependency(nlohmann_json 3.10)")
