# Text module extras: the YAML parser its field reader wraps.
target_link_libraries(${target} PUBLIC yaml-cpp)
deflex_module_requires(text "find_dependency(yaml-cpp)")
