# Online module extras: Boost.Lockfree's single-producer single-consumer ring (header-only) for a force
# sensor driver's own thread (force_handoff.hpp).
target_link_libraries(${target} PUBLIC Boost::headers)
deflex_module_requires(online "find_dependency(Boost 1.74)")
