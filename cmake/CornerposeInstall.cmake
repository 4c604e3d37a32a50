# Install rules (`cmake --install BUILD [--prefix P] [--strip]`), used by the
# container image (docker/Dockerfile) and for a native install on a cell's
# computer:
#
#   P/bin/                      cornerpose_server, cornerpose, cornerpose_robot_client, ur_emulator
#   P/share/cornerpose/deploy/config/*.textproto   the shipped configurations
#   P/share/cornerpose/data/frames/                the bundled recorded frames
#
# The configurations name their frame directories relative to their own
# directory (../../data/frames/...), so the two trees keep the repository's
# relative layout under share/cornerpose/.
#
# Included last from the top-level CMakeLists.txt, so every target is known.
# A binary whose target is not defined (a module not yet built, the emulator
# with CORNERPOSE_BUILD_TESTS off) is simply not installed. Install only after
# building the targets installed here: `cmake --install` needs their files.
include(GNUInstallDirs)

set(CORNERPOSE_INSTALL_DATADIR "${CMAKE_INSTALL_DATADIR}/cornerpose"
    CACHE STRING "Where the configurations and frames go, relative to the prefix")

foreach(target cornerpose_server cornerpose cornerpose_robot_client ur_emulator)
  if(TARGET ${target})
    install(TARGETS ${target} RUNTIME DESTINATION "${CMAKE_INSTALL_BINDIR}")
  endif()
endforeach()

install(DIRECTORY "${PROJECT_SOURCE_DIR}/deploy/config/"
        DESTINATION "${CORNERPOSE_INSTALL_DATADIR}/deploy/config"
        FILES_MATCHING PATTERN "*.textproto")
install(DIRECTORY "${PROJECT_SOURCE_DIR}/data/frames/"
        DESTINATION "${CORNERPOSE_INSTALL_DATADIR}/data/frames"
        PATTERN ".*" EXCLUDE)
