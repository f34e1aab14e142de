# Monitor module extras: the HTTP server is cpp-httplib (Debian's libcpp-httplib-dev); the page is
# compiled in, with its charting library, dygraphs, taken from Debian's libjs-dygraphs at configure
# time, so the page opens with no network.
find_package(PkgConfig REQUIRED)
pkg_check_modules(HTTPLIB REQUIRED IMPORTED_TARGET cpp-httplib)
target_link_libraries(${target} PRIVATE PkgConfig::HTTPLIB)
deflex_module_requires(monitor "find_dependency(PkgConfig)" "pkg_check_modules(HTTPLIB REQUIRED IMPORTED_TARGET cpp-httplib)")
deflex_embed_text(${target} src/deflex/monitor/monitor_page.html kMonitorPageHtml)
set(DEFLEX_DYGRAPHS_DIR /usr/share/javascript/dygraphs
    CACHE PATH "Where Debian's libjs-dygraphs installed dygraph.min.js and dygraph.min.css (the monitor page's charts)")
foreach(file dygraph.min.js dygraph.min.css)
  if(NOT EXISTS ${DEFLEX_DYGRAPHS_DIR}/${file})
    message(FATAL_ERROR
      "The monitor page embeds the charting library dygraphs from Debian's package libjs-dygraphs, and "
      "${DEFLEX_DYGRAPHS_DIR}/${file} is missing. Install it: sudo apt-get install libjs-dygraphs "
      "(scripts/install-deps.sh installs every package the build needs), or point DEFLEX_DYGRAPHS_DIR at "
      "a folder holding dygraph.min.js and dygraph.min.css.")
  endif()
endforeach()
deflex_embed_text(${target} ${DEFLEX_DYGRAPHS_DIR}/dygraph.min.js kDygraphsJs)
deflex_embed_text(${target} ${DEFLEX_DYGRAPHS_DIR}/dygraph.min.css kDygraphsCss)
