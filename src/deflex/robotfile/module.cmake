# Robot-file module extras: compile the built-in robot file in, and link the URDF parser (YAML comes with
# text/).
deflex_embed_text(${target} data/robots/abb_irb6700_300_270.yaml kBuiltinIrb6700Yaml)
target_link_libraries(${target} PRIVATE urdfdom::urdfdom_model)
deflex_module_requires(robotfile "find_dependency(urdfdom CONFIG)")
# TinyXML (a dependency of urdfdom, Debian's libtinyxml-dev) reads the URDF tree with line numbers.
find_package(PkgConfig REQUIRED)
pkg_check_modules(TINYXML REQUIRED IMPORTED_TARGET tinyxml)
target_link_libraries(${target} PRIVATE PkgConfig::TINYXML)
deflex_module_requires(robotfile "find_dependency(PkgConfig)" "pkg_check_modules(TINYXML REQUIRED IMPORTED_TARGET tinyxml)")
