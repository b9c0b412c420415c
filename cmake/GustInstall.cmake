# Install package: `cmake --install` puts the `gust` library, the two public headers (gust/gust.hpp,
# gust/gust.h) and a CMake package under the prefix, so that an engine writes
#   find_package(gust CONFIG REQUIRED)
#   target_link_libraries(game PRIVATE gust::gust)
# Every library is static, and a static archive names its private dependencies for the final link, so
# the internal archives (gust_core, solver, voxelizer, gpu, the OpenVDB writer) are installed and exported
# too; the embedded-shader targets are empty at the consumer's side (the SPIR-V is compiled into the archives)
# and are exported only because the archives name them. The module headers are not installed: gust.hpp
# needs none of them. docs/dependencies.md ("Install package") says what a consumer needs.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(GUST_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/gust)

if(NOT TARGET gust::gust)
  add_library(gust::gust ALIAS gust)
endif()
# gust.hpp uses std::span, so whoever includes it compiles as C++20.
target_compile_features(gust INTERFACE cxx_std_20)

get_property(gust_shader_targets GLOBAL PROPERTY GUST_SHADER_TARGETS)
set(gust_internal_targets gust_core gust_solver gust_voxelizer gust_gpu ${gust_shader_targets})
# Built with OpenVDB, System::export_vdb links it, so the consumer's link needs it: gustConfig.cmake finds it
# with the same FindOpenVDB module (and its sibling modules) this build used. Built without
# (GUST_WITH_OPENVDB=OFF), there is no gust_vdb and the package asks for no OpenVDB.
set(GUST_PACKAGE_OPENVDB_MODULE_DIR "")
if(TARGET gust_vdb)
  list(APPEND gust_internal_targets gust_vdb)
  find_file(GUST_FIND_OPENVDB_MODULE FindOpenVDB.cmake PATHS ${CMAKE_MODULE_PATH} NO_DEFAULT_PATH REQUIRED)
  get_filename_component(GUST_PACKAGE_OPENVDB_MODULE_DIR ${GUST_FIND_OPENVDB_MODULE} DIRECTORY)
endif()

install(TARGETS gust
  EXPORT gustTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS ${gust_internal_targets}
  EXPORT gustTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(FILES
    ${PROJECT_SOURCE_DIR}/plugin/include/gust/gust.hpp
    ${PROJECT_SOURCE_DIR}/plugin/include/gust/gust.h
    ${PROJECT_SOURCE_DIR}/plugin/include/gust/gust_wind.glsl
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/gust)
install(EXPORT gustTargets NAMESPACE gust:: DESTINATION ${GUST_INSTALL_CMAKEDIR})

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/gustConfig.cmake.in
  ${PROJECT_BINARY_DIR}/gustConfig.cmake
  INSTALL_DESTINATION ${GUST_INSTALL_CMAKEDIR})
# While the version is 0.x a minor release may break the API (gust.hpp's VersionMismatch says the same).
write_basic_package_version_file(${PROJECT_BINARY_DIR}/gustConfigVersion.cmake
  VERSION ${PROJECT_VERSION}
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/gustConfig.cmake ${PROJECT_BINARY_DIR}/gustConfigVersion.cmake
  DESTINATION ${GUST_INSTALL_CMAKEDIR})
