# Model module extras: compile the built-in robot file in, and link the YAML and URDF parsers.
set(builtin_yaml ${PROJECT_SOURCE_DIR}/data/robots/abb_irb6700_300_270.yaml)
set_property(DIRECTORY ${PROJECT_SOURCE_DIR} APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${builtin_yaml})
file(READ ${builtin_yaml} DEFLEX_BUILTIN_YAML)
file(WRITE ${PROJECT_BINARY_DIR}/generated/builtin_irb6700.cpp
  "// Generated from data/robots/abb_irb6700_300_270.yaml by src/deflex/model/module.cmake.\n"
  "namespace deflex { extern const char* const kBuiltinIrb6700Yaml; "
  "const char* const kBuiltinIrb6700Yaml = R\"deflexyaml(${DEFLEX_BUILTIN_YAML})deflexyaml\"; }\n")
target_sources(${target} PRIVATE ${PROJECT_BINARY_DIR}/generated/builtin_irb6700.cpp)
target_link_libraries(${target} PUBLIC yaml-cpp PRIVATE urdfdom::urdfdom_model)
