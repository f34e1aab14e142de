# Online module extras: Boost.Lockfree's single-producer single-consumer ring (header-only) for a force
# sensor driver's own thread (force_handoff.cpp; no public header includes Boost). The installed
# package still finds Boost for this module: its static library's link interface names the target.
target_link_libraries(${target} PRIVATE Boost::headers)
deflex_module_requires(online "find_dependency(Boost 1.74)")
