# Model module extras: compile the built-in robot file in, and link the YAML and URDF parsers.
deflex_embed_text(${target} data/robots/abb_irb6700_300_270.yaml kBuiltinIrb6700Yaml)
target_link_libraries(${target} PUBLIC yaml-cpp PRIVATE urdfdom::urdfdom_model)
