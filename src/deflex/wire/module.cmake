# Wire-format module extras: compile egm.proto with protoc (Debian's protobuf, found at the top level)
# into the build tree, as a system include so protoc's generated code is not held to our warnings.
set(wire_out ${PROJECT_BINARY_DIR}/generated/deflex/wire)
file(MAKE_DIRECTORY ${wire_out})
add_library(deflex_egm_proto STATIC ${PROJECT_SOURCE_DIR}/src/deflex/wire/egm.proto)
protobuf_generate(TARGET deflex_egm_proto LANGUAGE cpp APPEND_PATH
                  PROTOC_OUT_DIR ${wire_out})
target_include_directories(deflex_egm_proto SYSTEM PUBLIC ${wire_out})
target_link_libraries(deflex_egm_proto PUBLIC protobuf::libprotobuf)
set_target_properties(deflex_egm_proto PROPERTIES POSITION_INDEPENDENT_CODE ON)
target_link_libraries(${target} PRIVATE deflex_egm_proto)
target_link_libraries(${target} PUBLIC protobuf::libprotobuf)
