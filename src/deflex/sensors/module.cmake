# Sensors module extras: TinyXML (Debian's libtinyxml-dev, already the URDF reader's) for a sensor's
# netftapi2.xml page, and libcurl (Debian's libcurl4-openssl-dev) to fetch that page from the sensor.
find_package(PkgConfig REQUIRED)
pkg_check_modules(TINYXML REQUIRED IMPORTED_TARGET tinyxml)
find_package(CURL REQUIRED)
target_link_libraries(${target} PRIVATE PkgConfig::TINYXML CURL::libcurl)
deflex_module_requires(sensors "find_dependency(PkgConfig)" "pkg_check_modules(TINYXML REQUIRED IMPORTED_TARGET tinyxml)"
                       "find_dependency(CURL)")
