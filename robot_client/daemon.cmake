# The daemon itself: the perception subscription, the controller link, the
# cell's main loop and its status service (library cornerpose_robot_daemon,
# linked by the end-to-end tests), and the cornerpose_robot_client binary.
# Included from robot_client/CMakeLists.txt: sources are relative to it.
add_library(cornerpose_robot_daemon
  cell_controller.cc
  cell_state.cc
  perception_subscriber.cc
  robot_link.cc
  status_service.cc
)
target_include_directories(cornerpose_robot_daemon PUBLIC ${PROJECT_SOURCE_DIR})
target_link_libraries(cornerpose_robot_daemon
  PUBLIC cornerpose_robot_planning cornerpose_ur cornerpose_proto gRPC::grpc++ absl::time
         Threads::Threads
  PRIVATE cornerpose_client_conversion gRPC::grpc++_reflection absl::strings absl::str_format)
cornerpose_warnings(cornerpose_robot_daemon)

add_executable(cornerpose_robot_client robot_client_main.cc)
target_link_libraries(cornerpose_robot_client
  PRIVATE cornerpose_robot_daemon absl::flags absl::flags_parse absl::flags_usage absl::strings
          absl::time)
cornerpose_warnings(cornerpose_robot_client)
