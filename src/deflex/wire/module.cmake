# Wire-format module extras: compile egm.proto with protoc (Debian's protobuf, found at the top level)
# into the build tree, as a system include so protoc's generated code is not held to our warnings.
set(wire_out ${PROJECT_BINARY_DIR}/generated/deflex/wire)
file(MAKE_DIRECTORY ${wire_out})
add_library(deflex_egm_proto STATIC ${PROJECT_SOURCE_DIR}/src/deflex/wire/egm.proto)
protobuf_generate(TARGET deflex_egm_proto LANGUAGE cpp APPEND_PATH
                  PROTOC_OUT_DIR ${wire_out})
target_include_directories(deflex_egm_proto SYSTEM PUBLIC $<BUILD_INTERFACE:${wire_out}>)
target_link_libraries(deflex_egm_proto PUBLIC protobuf::libprotobuf)
set_target_properties(deflex_egm_proto PROPERTIES POSITION_INDEPENDENT_CODE ON EXPORT_NAME egm_proto)
# The generated code is the wire module's own (no public header includes it): installed as a library
# the wire module links, never as headers.
install(TARGETS deflex_egm_proto EXPORT deflexTargets ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
target_link_libraries(${target} PRIVATE deflex_egm_proto protobuf::libprotobuf)
deflex_module_requires(wire "find_dependency(Protobuf)")
