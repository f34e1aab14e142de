# Runtime module extras: the session's summary as JSON, the reporter's thread.
target_link_libraries(${target} PUBLIC nlohmann_json::nlohmann_json Threads::Threads)
