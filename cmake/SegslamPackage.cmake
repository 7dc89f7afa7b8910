# `cmake --install` of the core as a CMake package: the libraries marked INSTALL in
# segslam_add_library, their headers under include/segslam/<folder>/, the segslam tool,
# and segslamConfig.cmake, so that another project's find_package(segslam) links
# segslam::mutual and the rest (docs/library.md; tests/package builds such a project).
include(CMakePackageConfigHelpers)

set(SEGSLAM_CMAKE_INSTALL_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/segslam)
install(TARGETS segslam RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(EXPORT segslamTargets NAMESPACE segslam:: DESTINATION ${SEGSLAM_CMAKE_INSTALL_DIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/segslamConfig.cmake.in
  ${PROJECT_BINARY_DIR}/segslamConfig.cmake
  INSTALL_DESTINATION ${SEGSLAM_CMAKE_INSTALL_DIR})
# 0.x: a minor version may change the API.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/segslamConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/segslamConfig.cmake ${PROJECT_BINARY_DIR}/segslamConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/MujocoIncludeFix.cmake
        DESTINATION ${SEGSLAM_CMAKE_INSTALL_DIR})
