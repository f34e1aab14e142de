# Cell module extras: Boost.Random's normal distribution for the cell's noise and drift draws.
target_link_libraries(${target} PUBLIC Boost::headers)
deflex_module_requires(cell "find_dependency(Boost 1.74)")
