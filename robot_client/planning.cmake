# The daemon's configuration and pure planning logic (no sockets, no
# threads): the config file, pick selection, the place pattern, the five
# waypoints and the URScript program of one pick. Included from
# robot_client/CMakeLists.txt, so sources are relative to robot_client/.
add_library(cornerpose_robot_planning
  grasp_geometry.cc
  pick_plan.cc
  pick_selection.cc
  place_pattern.cc
  robot_config.cc
  straight_move.cc
  urscript_program.cc
)
target_include_directories(cornerpose_robot_planning PUBLIC ${PROJECT_SOURCE_DIR})
target_link_libraries(cornerpose_robot_planning
  PUBLIC cornerpose_ur cornerpose_perception Eigen3::Eigen absl::status absl::statusor
         absl::strings
  PRIVATE cornerpose_config cornerpose_proto absl::str_format)
cornerpose_warnings(cornerpose_robot_planning)
