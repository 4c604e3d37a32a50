# Code generation for .proto files (used by proto/CMakeLists.txt).
include_guard(GLOBAL)

# cornerpose_proto_generate(OUT_SRCS IMPORT_DIR GEN_DIR PROTOS...) — runs
# protoc with the gRPC plugin over each file; sources land in GEN_DIR at the
# proto's path, so includes read "cornerpose/v1/geometry.pb.h".
function(cornerpose_proto_generate out_srcs import_dir gen_dir)
  set(srcs)
  foreach(proto ${ARGN})
    get_filename_component(dir "${proto}" DIRECTORY)
    get_filename_component(stem "${proto}" NAME_WE)
    set(base "${gen_dir}/${dir}/${stem}")
    set(outs "${base}.pb.cc" "${base}.pb.h" "${base}.grpc.pb.cc" "${base}.grpc.pb.h")
    add_custom_command(
      OUTPUT ${outs}
      COMMAND ${CMAKE_COMMAND} -E make_directory "${gen_dir}"
      COMMAND protobuf::protoc
              --proto_path=${import_dir}
              --cpp_out=${gen_dir}
              --grpc_out=${gen_dir}
              --plugin=protoc-gen-grpc=${CORNERPOSE_GRPC_CPP_PLUGIN}
              "${import_dir}/${proto}"
      DEPENDS "${import_dir}/${proto}" protobuf::protoc
      COMMENT "protoc ${proto}"
      VERBATIM)
    list(APPEND srcs "${base}.pb.cc" "${base}.grpc.pb.cc")
  endforeach()
  set(${out_srcs} ${srcs} PARENT_SCOPE)
endfunction()
