# The simulated cell (tests/support/cell_sim): a world of boxes the UR
# controller emulator acts on (suction, carrying, collisions through FCL, with the
# daemon's own shapes: robot_client/collision) and
# a depth camera rendering it into a frame directory; library, tests and the
# `cell_sim` binary (scripts/demo). Included from tests/CMakeLists.txt after
# the emulator (tests/ur).
set(CORNERPOSE_CELL_SIM_DIR ${PROJECT_SOURCE_DIR}/tests/support/cell_sim)
add_library(cornerpose_cell_sim
  ${CORNERPOSE_CELL_SIM_DIR}/cell_world.cc
  ${CORNERPOSE_CELL_SIM_DIR}/geometry.cc
  ${CORNERPOSE_CELL_SIM_DIR}/sim_camera.cc
  ${CORNERPOSE_CELL_SIM_DIR}/sim_cell.cc
  # The camera writes PNGs with the project's png_io alone (cornerpose_io
  # would bring PCL).
  ${PROJECT_SOURCE_DIR}/common/io/png_io.cc
)
target_link_libraries(cornerpose_cell_sim PUBLIC cornerpose_test_support cornerpose_ur_emulator
                      cornerpose_collision PNG::PNG)
cornerpose_warnings(cornerpose_cell_sim)
add_executable(cell_sim ${CORNERPOSE_CELL_SIM_DIR}/cell_sim_main.cc)
target_link_libraries(cell_sim PRIVATE cornerpose_cell_sim absl::flags absl::flags_parse
                      absl::flags_usage nlohmann_json::nlohmann_json)
cornerpose_warnings(cell_sim)
cornerpose_test(cell_world_test SOURCES ${PROJECT_SOURCE_DIR}/tests/cell_sim/cell_world_test.cc
                LIBS cornerpose_cell_sim)
# The closed loop through scripts/demo (cell_sim, the service over gRPC with
# the virtual OpenNI2 camera, the daemon over TCP), one case per test.
foreach(case pallet bin protective_stop)
  add_test(NAME closed_loop_${case}
           COMMAND python3 ${PROJECT_SOURCE_DIR}/tests/cell_sim/closed_loop_test.py
                   ${PROJECT_SOURCE_DIR} ${case})
  set_tests_properties(closed_loop_${case} PROPERTIES
                       ENVIRONMENT "CORNERPOSE_BUILD_DIR=${PROJECT_BINARY_DIR}"
                       TIMEOUT 480 LABELS "closed_loop" RUN_SERIAL TRUE)
endforeach()
