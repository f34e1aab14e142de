# Cell module extras: Boost.Random's normal distribution for the cell's noise and drift draws.
target_link_libraries(${target} PUBLIC Boost::headers)
