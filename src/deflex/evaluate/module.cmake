# Evaluate module extras: the study results are written as JSON.
target_link_libraries(${target} PUBLIC nlohmann_json::nlohmann_json)
