# Monitor module extras: the HTTP server is cpp-httplib (Debian's libcpp-httplib-dev), the page is
# compiled in.
find_package(PkgConfig REQUIRED)
pkg_check_modules(HTTPLIB REQUIRED IMPORTED_TARGET cpp-httplib)
target_link_libraries(${target} PRIVATE PkgConfig::HTTPLIB)
deflex_module_requires(monitor "find_dependency(PkgConfig)" "pkg_check_modules(HTTPLIB REQUIRED IMPORTED_TARGET cpp-httplib)")
deflex_embed_text(${target} src/deflex/monitor/monitor_page.html kMonitorPageHtml)
