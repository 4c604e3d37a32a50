# OpenNI2 (libopenni2-dev) for the openni2 frame sources and the virtual
# camera, and a private OpenNI2 runtime in the build tree that also loads the
# virtual camera driver. Included once, from the top-level CMakeLists.txt.
#
# OpenNI2 loads its drivers from OpenNI2/Drivers/lib*.so.0 next to the
# libOpenNI2.so.0 the process loaded (the path as the dynamic loader found
# it, symbolic links not resolved; Debian's /etc/openni2/OpenNI.ini leaves
# the repository at that default). So ${CORNERPOSE_OPENNI2_RUNTIME_DIR} holds
# a link to the system libOpenNI2.so.0 and OpenNI2/Drivers/ with links to the
# system drivers plus libCornerposeVirtualCamera.so.0; a program that loads
# libOpenNI2.so.0 from there (an RPATH, or LD_LIBRARY_PATH) sees the virtual
# camera as well as real cameras and .oni files. No root needed.
include_guard(GLOBAL)

find_path(OPENNI2_INCLUDE_DIR OpenNI.h PATH_SUFFIXES openni2)
find_library(OPENNI2_LIBRARY NAMES OpenNI2)
if(NOT OPENNI2_INCLUDE_DIR OR NOT OPENNI2_LIBRARY)
  message(FATAL_ERROR
    "OpenNI2 not found (OpenNI.h: ${OPENNI2_INCLUDE_DIR}, libOpenNI2: ${OPENNI2_LIBRARY}). "
    "Install it: apt-get install libopenni2-dev (Debian/Ubuntu), or set OPENNI2_INCLUDE_DIR "
    "(the directory holding OpenNI.h) and OPENNI2_LIBRARY.")
endif()
if(NOT TARGET OpenNI2::OpenNI2)
  add_library(OpenNI2::OpenNI2 UNKNOWN IMPORTED GLOBAL)
  set_target_properties(OpenNI2::OpenNI2 PROPERTIES
    IMPORTED_LOCATION "${OPENNI2_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${OPENNI2_INCLUDE_DIR}")
endif()

# Cache entries, so that every directory sees them (the guard above skips
# this file the second time).
set(CORNERPOSE_OPENNI2_RUNTIME_DIR "${CMAKE_BINARY_DIR}/openni2" CACHE INTERNAL "")
set(CORNERPOSE_OPENNI2_DRIVERS_DIR "${CORNERPOSE_OPENNI2_RUNTIME_DIR}/OpenNI2/Drivers" CACHE INTERNAL "")
get_filename_component(_openni2_real "${OPENNI2_LIBRARY}" REALPATH)
get_filename_component(_openni2_dir "${_openni2_real}" DIRECTORY)
file(MAKE_DIRECTORY "${CORNERPOSE_OPENNI2_DRIVERS_DIR}")
# libOpenNI2.so.0 is the library's SONAME, what programs ask the loader for.
file(CREATE_LINK "${_openni2_real}" "${CORNERPOSE_OPENNI2_RUNTIME_DIR}/libOpenNI2.so.0" SYMBOLIC)
file(GLOB _openni2_system_drivers "${_openni2_dir}/OpenNI2/Drivers/lib*.so.0")
foreach(_driver IN LISTS _openni2_system_drivers)
  get_filename_component(_name "${_driver}" NAME)
  file(CREATE_LINK "${_driver}" "${CORNERPOSE_OPENNI2_DRIVERS_DIR}/${_name}" SYMBOLIC)
endforeach()

# Makes `target` (an executable) load OpenNI2 from the private runtime when
# run from the build tree; installed, it uses the system's.
function(cornerpose_use_openni2_runtime target)
  set_property(TARGET ${target} APPEND PROPERTY BUILD_RPATH "${CORNERPOSE_OPENNI2_RUNTIME_DIR}")
endfunction()
